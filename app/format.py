"""How numbers and tables look wherever a person reads them (panel, replay, recording, terminal,
`theoria bench`). JSON output never goes through here: it keeps every digit (null for missing)."""
from __future__ import annotations

import math
from numbers import Integral

import numpy as np

MISSING = "–"


def number(x, digits: int = 6) -> str:
    """A table cell: `digits` significant digits, MISSING ("–") for a missing, NaN or infinite
    value; integers with all their digits, booleans as True/False, a sequence (a vector, a
    quaternion) as a comma list of cells."""
    if isinstance(x, np.ndarray) and x.ndim == 0:
        x = x.item()
    if x is None:
        return MISSING
    if isinstance(x, str):
        return x
    if isinstance(x, (bool, np.bool_)):
        return str(bool(x))
    if isinstance(x, Integral):
        return str(int(x))
    if isinstance(x, (list, tuple, np.ndarray)):
        return ", ".join(number(v, digits) for v in x)
    try:
        v = float(x)
    except (TypeError, ValueError):
        return str(x)
    if not math.isfinite(v):
        return MISSING
    return f"{v:.{digits}g}"


def comparison_rows(comparisons, digits: int = 6) -> list[tuple[str, str, str, str, str]]:
    """The Euler / simulated / modern table as text cells: (what, Euler, simulated, modern, unit)."""
    out = []
    for c in comparisons:
        label = c.label + (f" ({c.note})" if c.note else "")
        out.append((label, number(c.euler, digits), number(c.simulated, digits), number(c.modern, digits), c.unit))
    return out
