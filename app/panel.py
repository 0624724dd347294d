"""What the side panel shows besides the controls: the scenario's text, the Euler / simulated /
modern table, the metrics and notes, the live plot's axis."""
from __future__ import annotations

import numpy as np

from . import gallery
from .format import number

UPLOT_POINTS = 2000  # points per series in the live plot


def y_axis_px(series_values, px_per_char: float = 7.2, min_px: int = 50) -> int:
    """Width (CSS px) of a uPlot y axis for these series: uPlot labels ticks with en-US grouping
    ("-250,000", "0.0005") at about five ticks; the longest label's characters × the 12 px font's
    width, plus ticks and gap (15 px)."""
    v = np.concatenate([np.asarray(a, float).ravel() for a in series_values]) if len(series_values) else np.zeros(1)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return min_px
    lo, hi = float(v.min()), float(v.max())
    span = hi - lo or abs(hi) or 1.0
    step = 10 ** np.floor(np.log10(span / 5))
    decimals = int(max(0, -np.floor(np.log10(step))))
    widest = 0
    for x in (lo, hi):
        text = f"{x:,.{decimals}f}"
        widest = max(widest, len(text))
    return int(max(min_px, np.ceil(widest * px_per_char + 15)))


def info_markdown(spec, result=None) -> str:
    lines = [f"### {spec.title}", f"**{spec.section}** · {spec.group} · `{spec.name}`", "", spec.summary, ""]
    if spec.euler_formula:  # plain Unicode text: viser's markdown renders no TeX
        lines += [gallery.formula_markdown(spec.euler_formula), ""]
    return "\n".join(lines)


def comparison_markdown(result) -> str:
    if result is None:
        return ""
    lines = []
    if result.comparisons:
        lines += ["| | Euler says | simulated | modern | unit |", "|---|---|---|---|---|"]
        for c in result.comparisons:
            note = f" ({c.note})" if c.note else ""
            label = (c.label + note).replace("|", "\\|")  # a | in a label (|H(p,e)|) would split the row
            lines.append(f"| {label} | {number(c.euler)} | {number(c.simulated)} | {number(c.modern)} | {c.unit} |")
        lines.append("")
    if result.metrics:
        lines.append("**Metrics:** " + ", ".join(f"{k} = {number(v)}" for k, v in result.metrics.items()))
    for n in result.notes:
        lines.append(f"\n*{n}*")
    return "\n".join(lines)
