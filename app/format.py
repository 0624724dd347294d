"""How numbers and tables look wherever a person reads them (panel, replay, recording, terminal)."""
from __future__ import annotations

import math


def number(x, digits: int = 6) -> str:
    """A table cell: `digits` significant digits, "–" for a missing, NaN or infinite value."""
    if x is None:
        return "–"
    if isinstance(x, (tuple, list)):
        return ", ".join(number(v, digits) for v in x)
    try:
        v = float(x)
    except (TypeError, ValueError):
        return str(x)
    if not math.isfinite(v):
        return "–"
    return f"{v:.{digits}g}"


def comparison_rows(comparisons, digits: int = 6) -> list[tuple[str, str, str, str, str]]:
    """The Euler / simulated / modern table as text cells: (what, Euler, simulated, modern, unit)."""
    out = []
    for c in comparisons:
        label = c.label + (f" ({c.note})" if c.note else "")
        out.append((label, number(c.euler, digits), number(c.simulated, digits), number(c.modern, digits), c.unit))
    return out
