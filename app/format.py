"""How numbers and tables look wherever a person reads them (panel, replay, recording, terminal,
`theoria bench`). JSON output never goes through here: it keeps every digit (null for missing)."""
from __future__ import annotations

import math
import re
from numbers import Integral

import numpy as np

from ..physics.params import SUPERSCRIPT

MISSING = "–"
MINUS = "−"


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


def superscript(n: int) -> str:
    """An exponent as it is written: −3 → "⁻³"."""
    return str(int(n)).translate(SUPERSCRIPT)


def human_number(x, digits: int = 4) -> str:
    """`digits` significant digits; plain decimals from 10⁻³ to 10⁶, else "2.80 × 10⁻¹¹"; a true
    minus sign; "–" for a missing or non-finite value. Vectors: comma-separated."""
    if x is None:
        return MISSING
    if isinstance(x, (tuple, list, np.ndarray)):
        return ", ".join(human_number(v, digits) for v in x)
    try:
        v = float(x)
    except (TypeError, ValueError):
        return str(x)
    if not math.isfinite(v):
        return MISSING
    if v == 0:
        return "0"
    a = abs(v)
    if 1e-3 <= a < 1e6:
        text = f"{v:.{digits}g}"
        if "e" in text:  # .4g of 123456 gives 1.235e+05: write it out
            text = f"{v:.0f}"
    else:
        mant, exp = f"{v:.{digits - 1}e}".split("e")
        mant = mant.rstrip("0").rstrip(".") if "." in mant else mant
        text = f"{mant} × 10{superscript(int(exp))}"
    return text.replace("-", MINUS, 1) if text.startswith("-") else text


def exact(x) -> str:
    """A float as the shortest of 12 significant digits or repr that reads back exactly."""
    x = float(x)
    text = f"{x:.12g}"
    return text if float(text) == x else repr(x)


def comparison_rows(comparisons, digits: int = 6) -> list[tuple[str, str, str, str, str]]:
    """The Euler / simulated / modern table as text cells: (what, Euler, simulated, modern, unit)."""
    out = []
    for c in comparisons:
        label = c.label + (f" ({c.note})" if c.note else "")
        out.append((label, number(c.euler, digits), number(c.simulated, digits), number(c.modern, digits), c.unit))
    return out


def capitalised(text: str) -> str:
    """The first letter as a capital, for a label that starts a line; a Greek letter stays as it
    is (ω and Ω are different quantities: "Ω and L arrows" read as the node's longitude)."""
    return text[:1].upper() + text[1:] if text[:1].isascii() else text


_E_NUMBER = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?[eE][+\-−]?\d+)(?![\w.])")
_LEADING_MINUS = re.compile(r"(?<![\w)\]])-(?=\.?\d)")


def readable(text: str) -> str:
    """Text for the panel as a person writes it: numbers in a programmer's e-notation as powers of
    ten ("1e-06" → "1 × 10⁻⁶"), "≥" and "≤" for ">=" and "<=", a true minus sign ("−0.45")."""
    text = _E_NUMBER.sub(lambda m: human_number(float(m[1].replace(MINUS, "-")), 6), str(text))
    text = text.replace(">=", "≥").replace("<=", "≤")
    return _LEADING_MINUS.sub(MINUS, text)


def human_size(n: int) -> str:
    """A file size as a person reads it: "840 KB", "1.2 MB"."""
    for unit, k in (("GB", 1e9), ("MB", 1e6), ("KB", 1e3)):
        if n >= k:
            v = n / k
            return f"{v:.1f} {unit}" if v < 10 else f"{v:.0f} {unit}"
    return f"{n} bytes"
