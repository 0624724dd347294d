"""What the side panel says, in a class's words: the scenario's heading, the Euler / simulated /
modern table with units and verdicts, the run's warnings, the text to read, the live plot's axis.

Pure text and HTML (no viser here): `app/session.py` puts it in the panel's tabs. Nothing a script
uses as a key (a metric's snake_case name, a parameter's key, the scenario's slug) is shown: a
metric is named in words by `metric_label`, a parameter by its `Param.display()`.
"""
from __future__ import annotations

import html
import math
import re

import numpy as np

from ..scenarios.units import NAME_SUFFIXES, unit_in_name
from . import gallery
from .format import capitalised, human_number, readable, superscript

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
    # uPlot's y range: the data padded by a tenth of their span, out to a multiple of a tenth of
    # its power of ten (its rangeNum): data down to -700 get a tick at "-1,000"
    grid = 10 ** np.floor(np.log10(span)) / 10
    lo, hi = np.floor((lo - 0.1 * span) / grid) * grid, np.ceil((hi + 0.1 * span) / grid) * grid
    step = 10 ** np.floor(np.log10(span / 5))
    decimals = int(max(0, -np.floor(np.log10(step))))
    widest = 0
    for x in (lo, hi):
        text = f"{x:,.{decimals}f}"
        widest = max(widest, len(text))
    return int(max(min_px, np.ceil(widest * px_per_char + 15)))


_PREFIXED_SECONDS = {3: "ms", 6: "µs", 9: "ns"}


def time_axis(x: np.ndarray, words: str) -> tuple[np.ndarray, str]:
    """A plot's time axis in a unit its ticks can show: uPlot labels ticks with at most three
    decimals, so a run of 0.001 s read "0 0 0 0.001 0.001 0.001"; a span under 0.05 is shown in
    thousandths (ms, µs for seconds; "10⁻³ days" for others). Returns the values and the unit's
    words."""
    x = np.asarray(x, float)
    finite = x[np.isfinite(x)]
    span = float(finite.max() - finite.min()) if finite.size else 0.0
    if not 0.0 < span < 0.05:
        return x, words
    e = int(3 * math.ceil(-math.log10(span) / 3))
    if words == "s" and e in _PREFIXED_SECONDS:
        return x * 10.0 ** e, _PREFIXED_SECONDS[e]
    return x * 10.0 ** e, f"10{superscript(-e)} {words}".strip()


def value_axis(series_values) -> tuple[list[np.ndarray], int]:
    """A plot's values in a unit its ticks can show: uPlot labels ticks with at most three
    decimals, so a drift from 10⁻¹² to 8 × 10⁻⁶ (a satellite leaving L2) read "0 0 0". Values all
    under 0.05 in size are scaled by a power of ten (a multiple of three) that brings the largest
    to 1–1000; the axis says "×10⁻⁶". Values that are nothing but rounding (under 10⁻¹²: a
    libration locked at ζ = 0 to 10⁻¹⁴) are left as they are: scaled up, they would show noise as
    a motion. Returns the values and the exponent e (the shown values are value × 10⁻ᵉ; 0: as given)."""
    arrays = [np.asarray(a, float) for a in series_values]
    v = np.concatenate([a.ravel() for a in arrays]) if arrays else np.zeros(0)
    v = np.abs(v[np.isfinite(v)])
    m = float(v.max()) if v.size else 0.0
    if not 1e-12 <= m < 0.05:
        return arrays, 0
    e = int(3 * math.floor(math.log10(m) / 3))
    return [a * 10.0 ** -e for a in arrays], e


# ---- numbers as a person reads them ----------------------------------------------------------

def percent(rel: float) -> str:
    """A relative difference as a percentage with two significant digits ("0.0012 %")."""
    p = 100.0 * rel
    if p >= 10:
        return f"{p:.0f} %"
    return f"{p:.2g} %"


def verdict(c) -> tuple[str, str]:
    """(words, tone) comparing Euler's value with the simulated one (without Euler's, the simulated
    with the modern one): tone "good" (agree to 0.1 %), "close" (within 5 %), "far" (more), or ""
    when there is nothing to compare or one side is exactly 0 (no percentage of a zero: a residual
    against DE421's 0, a run's outcome 0 beside a probability)."""
    e, s = c.euler, c.simulated
    if "probability" in str(c.label).lower() and _finite(s) and float(s) in (0.0, 1.0) and not _finite(e):
        # one run's outcome (captured or not) beside a probability over many: no percentage of that
        return (f"This run: {'yes' if float(s) == 1.0 else 'no'} (1 or 0); the probability is over many starts "
                f"(a sweep measures it)"), ""
    if not _finite(e) or not _finite(s):
        if _finite(s) and _finite(c.modern):
            return _versus(("the simulation", "the modern value"), s, c.modern)
        if _finite(e) and getattr(c, "missing", ""):
            return f"No simulated value: {c.missing}", ""
        return ("Euler gives no value here" if not _finite(e) else "no simulated value"), ""
    return _versus(("Euler", "the simulation"), e, s)


def _versus(names: tuple[str, str], a: float, b: float) -> tuple[str, str]:
    both = f"{names[0]} and {names[1]}"
    if a == b:
        return f"{capitalised(both)} agree exactly", "good"
    if a == 0 or b == 0:
        zero, other, v = (names[0], names[1], b) if a == 0 else (names[1], names[0], a)
        return f"{capitalised(zero)}: exactly 0; {other}: {human_number(v)}", ""
    rel = abs(a - b) / max(abs(a), abs(b))
    if rel < 1e-9:
        return f"{capitalised(both)} agree to 10⁻⁹", "good"
    if rel < 1e-4:
        return f"{capitalised(both)} agree to {human_number(rel, 2)} (relative)", "good"
    if rel < 1e-3:
        return f"{capitalised(both)} agree to {percent(rel)}", "good"
    if rel < 0.05:
        return f"{capitalised(both)} are within {percent(rel)}", "close"
    return f"{capitalised(both)} differ by {percent(rel)}", "far"


def _finite(x) -> bool:
    try:
        return x is not None and math.isfinite(float(x))
    except (TypeError, ValueError):
        return False


# ---- metric keys in words --------------------------------------------------------------------

_WORDS = {"rel": "relative", "abs": "absolute", "err": "error", "max": "largest", "min": "smallest",
          "num": "number of", "n": "number of", "dt": "step", "std": "spread", "rms": "rms", "obs": "observed",
          "sim": "simulated", "euler": "Euler's", "iau": "IAU", "llr": "LLR", "freq": "frequency",
          "amp": "amplitude", "init": "initial", "nut": "nutation", "prec": "precession", "lon": "longitude",
          "lat": "latitude", "ecc": "eccentricity", "incl": "inclination", "omega": "ω", "zeta": "ζ",
          "eta": "η", "phi": "φ", "theta": "θ", "psi": "ψ", "eps": "ε", "delta": "δ", "alpha": "α",
          "beta": "β", "gamma": "γ", "L": "L", "gp": "Goldreich–Peale", "k2": "k²", "mprime": "M′ term",
          "peale": "Peale's", "de421": "DE421", "iau2000": "IAU 2000", "iau2006": "IAU 2006", "vondrak": "Vondrák",
          "me": "mean-Earth axes", "plus": "+", "minus": "−", "floquet": "Floquet"}
# pieces of a key read as one (before the key is cut at its underscores)
_FORMS = [(re.compile(r"(?<![a-z0-9])(\d+)_(\d+)(yr|d)(?=_|$)"),  # 18_6yr: the 18.6-year term
           lambda m: f"{m[1]}.{m[2]}-{'year' if m[3] == 'yr' else 'day'}"),
          (re.compile(r"(?<![a-z0-9.])([1-9])_([1-9])(?=_|$)"), lambda m: f"{m[1]}:{m[2]}"),  # resonance 3_2
          (re.compile(r"(?<![a-z])psi_a(?=_|$)"), lambda m: "ψA"), (re.compile(r"(?<=_)p_a(?=_|$)"), lambda m: "pA"),
          (re.compile(r"zeta_dot"), lambda m: "ζ̇"), (re.compile(r"sub_earth"), lambda m: "sub-Earth")]


def metric_label(key: str, unit: str | None = None) -> str:
    """A metric's name in words with its unit: "polhode_period_s" → "Polhode period (s)",
    "energy_rel_drift" → "Energy relative drift". `unit` is the scenario's (`Scenario.metric_unit`);
    without it the unit is read from the name."""
    found = unit_in_name(key)
    if found is not None and unit in (None, found[1]):
        key, unit = found
    elif unit:  # the unit inside the name, before a qualifier: pole_direction_deg_euler
        for suffix, u in NAME_SUFFIXES:
            if u == unit and f"_{suffix}_" in key:
                key = key.replace(f"_{suffix}_", "_", 1)
                break
    unit = gallery.pretty_unit(unit or "")
    key = re.sub(r"^d([a-z]+)_dt(?=_|$)", r"rate_of_change_of_\1", key)  # dspin_dt: not the spin rate itself
    for form, words in _FORMS:
        key = form.sub(words, key)
    words = []
    for w in re.split(r"_+", key):
        if not w:
            continue
        if re.fullmatch(r"\d{3,4}", w):  # a § number (polhode_period_euler_808) or a year
            words.append(f"§{w}" if len(w) == 3 else w)
        else:
            words.append(_WORDS.get(w, w))
    if len(words) > 1 and words[-1] == "Euler's":
        if words[-2] in ("from", "to", "of", "vs", "than", "with"):  # axis_angle_from_euler: from Euler
            words[-1] = "Euler"
        else:  # pole_speed_euler: Euler's pole speed
            words = [words[-1], *words[:-1]]
    text = " ".join(words)
    text = capitalised(text)  # β stays β
    return f"{text} ({unit})" if unit else text


def _unit_not_in(label: str, unit: str) -> bool:
    """A unit to add after a comparison's label ("… max (°)" already says it: not "(°) (°)")."""
    return bool(unit) and not label.rstrip().endswith(f"({unit})")


# ---- the panel's texts -----------------------------------------------------------------------

def heading_markdown(spec) -> str:
    """The scenario's name and its place in Euler (Explore tab)."""
    return f"**{_md(spec.title)}**  \n{_md(spec.section)} · {_md(spec.group)}"


def read_markdown(spec) -> str:
    """The Read tab: what to look for, Euler's own words, where in the book."""
    lines = ["**What to look for**", "", _md(spec.summary), ""]
    if spec.euler_formula:  # plain Unicode text: viser's markdown renders no TeX
        lines += [gallery.formula_markdown(spec.euler_formula), ""]
    lines += [f"*Where: {_md(spec.section)}, {_md(spec.group)} of Euler's texts.*"]
    return "\n".join(lines)


def _md(text: str) -> str:
    """Plain text inside markdown: no emphasis from * or _ in formulas."""
    return str(text).replace("*", "\\*").replace("_", "\\_")


TONE_COLOR = {"good": "#2b8a3e", "close": "#b08800", "far": "#c92a2a", "": "#666"}


def _orbit_clock(result):
    """The run's clock when its time is read out in orbits (scale: orbits per time unit), else None."""
    from theoria.scenarios.drawing import clock_of

    try:
        clock = clock_of(result) if result.trajectory is not None else None
    except Exception:  # noqa: BLE001 — a run without the parts a clock needs: shown as it is
        return None
    return clock if clock is not None and clock.words == "orbits" and clock.scale != 1.0 else None


def compare_html(result, preview: bool = False) -> str:
    """The Compare tab: each comparison as its label (with unit), the three values side by side and
    a verdict in words; the run's warnings first, as a visible note. A quick `preview`'s warnings
    are its own (a Moon of one year cannot measure its annual term): said of the preview, not of
    the run the class asked for, which follows."""
    if result is None:
        return "<p style='color:#666;padding:0 12px'>Computing…</p>"
    top = ("<p style='color:#666'>A quick, shorter preview: the numbers and notes of the run asked for "
           "follow in a moment.</p>") if preview else warnings_html(result)
    parts = ["<div style='padding:0 12px'>", top]
    if not result.comparisons:
        parts.append("<p style='color:#666'>This scene has no Euler / simulated / modern values to compare.</p></div>")
        return "".join(parts)
    th = "padding:2px 4px;text-align:right;font-weight:600;color:#555;font-size:0.85em"
    rows = [f"<table style='width:100%;border-collapse:collapse;font-size:0.92em'>"
            f"<tr><th></th><th style='{th}'>Euler</th><th style='{th}'>simulated</th><th style='{th}'>modern</th></tr>"]
    clock = _orbit_clock(result)
    for c in result.comparisons:
        unit = gallery.pretty_unit(c.unit)
        shown = (c.euler, c.simulated, c.modern)
        if clock is not None and c.unit == result.trajectory.time_unit:
            # a time in the run's own unit, read out above as orbits: the same orbits here (a class
            # read "libration period 16.73 time units" beside "t = 1.87 of 10.65 orbits")
            shown = tuple(x * clock.scale if _finite(x) else x for x in shown)
            unit = "orbits"
        label = html.escape(readable(c.label)) + (f" <span style='color:#666'>({html.escape(unit)})</span>"
                                        if _unit_not_in(c.label, unit) else "")
        words, tone = verdict(c)
        note = f"<div style='color:#666;font-size:0.85em'>{html.escape(readable(c.note))}</div>" if c.note else ""
        cell = "padding:1px 4px;text-align:right;white-space:nowrap;font-variant-numeric:tabular-nums"
        rows.append(
            f"<tr><td colspan='4' style='padding:8px 0 1px 0;border-top:1px solid #ddd'><b>{label}</b></td></tr>"
            f"<tr><td></td><td style='{cell}'>{human_number(shown[0])}</td>"
            f"<td style='{cell};font-weight:600'>{human_number(shown[1])}</td>"
            f"<td style='{cell}'>{human_number(shown[2])}</td></tr>"
            f"<tr><td colspan='4' style='font-size:0.85em;color:{TONE_COLOR[tone]}'>{html.escape(words)}{note}</td></tr>")
    rows.append("</table></div>")
    parts.append("".join(rows))
    return "".join(parts)


def warnings_html(result) -> str:
    """The run's warnings (outside a formula's validity, diverged, …) as a yellow note; "" if none."""
    if result is None or not result.warnings:
        return ""
    items = "".join(f"<li>{html.escape(readable(w))}</li>" for w in result.warnings)
    return ("<div style='background:#fff4d6;border-left:4px solid #e0a800;padding:4px 8px;margin:0 0 6px 0;"
            f"font-size:0.9em'><b>Note</b><ul style='margin:2px 0 2px 16px;padding:0'>{items}</ul></div>")


def numbers_markdown(result) -> str:
    """The run's other numbers (its metrics), each named in words with its unit."""
    if result is None or not result.metrics:
        return ""
    lines = []
    units = result.metric_units
    for k, v in result.metrics.items():
        lines.append(f"- {_md(metric_label(k, units[k]))}: {human_number(v, 6)}")
    return "\n".join(lines)


def notes_markdown(result) -> str:
    """Notes of the run that are not already among its warnings."""
    if result is None:
        return ""
    notes = [n for n in result.notes if n not in result.warnings]
    return "\n\n".join(f"*{_md(readable(n))}*" for n in notes)


def comparison_markdown(result) -> str:
    """The table and notes as markdown (a notebook, the HTML replay's page): the same words as the
    panel's Compare tab."""
    if result is None:
        return ""
    lines = []
    for w in result.warnings:
        lines.append(f"> **Note:** {_md(readable(w))}")
    if result.warnings:
        lines.append("")
    if result.comparisons:
        lines += ["| | Euler | simulated | modern | |", "|---|---|---|---|---|"]
        for c in result.comparisons:
            unit = gallery.pretty_unit(c.unit)
            label = (readable(c.label) + (f" ({unit})" if _unit_not_in(c.label, unit) else "")).replace("|", "\\|")
            lines.append(f"| {label} | {human_number(c.euler)} | {human_number(c.simulated)} | "
                         f"{human_number(c.modern)} | {verdict(c)[0]} |")
        lines.append("")
    for n in result.notes:
        if n not in result.warnings:
            lines.append(f"\n*{_md(readable(n))}*")
    return "\n".join(lines)


def info_markdown(spec, result=None) -> str:
    """Heading and the text to read, in one block (the HTML replay's page)."""
    return heading_markdown(spec) + "\n\n" + read_markdown(spec)
