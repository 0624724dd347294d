"""The one number formatter (app/format.py) that the CLI, the app's panel, the replays and
`theoria bench` use."""
from __future__ import annotations

import math

import numpy as np

from theoria.app.format import MISSING, number


def test_cells():
    assert number(math.pi, 4) == "3.142" and number(-17.2064161, 9) == "-17.2064161"
    assert number(6.02214076e23, 3) == "6.02e+23" and number(1e-12, 2) == "1e-12"
    for missing in (None, math.nan, math.inf, -math.inf, np.float32("nan")):
        assert number(missing) == MISSING == "–"
    assert number(123456789) == "123456789"  # integers keep every digit
    assert number(np.int64(7)) == "7" and number(np.float32(2.5)) == "2.5" and number(np.array(3.25)) == "3.25"
    assert number(True) == "True" and number(np.bool_(False)) == "False"
    assert number("circulating") == "circulating"


def test_vectors():
    assert number([1.0, None, 2, math.nan], 3) == "1, –, 2, –"
    assert number(np.array([0.5, 1 / 3]), 3) == "0.5, 0.333" == number((0.5, 1 / 3), 3)


def test_text_for_the_panel_is_written_as_a_person_writes_it():
    """Refusals and notes reached the panel in a programmer's notation: "allowed range (0, 1e+06] s",
    "at least 1e-100 rad/s", "needs A+B >= C", "θ = -0.00"."""
    from theoria.app.format import readable

    assert readable("allowed range (0, 1e+06] s") == "allowed range (0, 1 × 10⁶] s"
    assert readable("at least 1e-100 rad/s") == "at least 1 × 10⁻¹⁰⁰ rad/s"
    assert readable("keeps the ratio to 3.3e-04") == "keeps the ratio to 3.3 × 10⁻⁴"
    assert readable("needs A+B >= C, x <= 1") == "needs A+B ≥ C, x ≤ 1"
    assert readable("[-50, 50] rad/s; θ = -0.00") == "[−50, 50] rad/s; θ = −0.00"
    # left as they are: years, names with digits, a hyphen between words
    assert readable("1900-2100, DE421, k2, x-1, middle-axis") == "1900-2100, DE421, k2, x-1, middle-axis"
