"""physics/constants.py: each constant written once, and the derived ones against the values
the almanacs and the IAU publish (typed here from those sources, not computed by the module)."""
from __future__ import annotations

import ast
import io
import math
import tokenize

import pytest
from conftest import ROOT

from theoria.physics import constants as C

CONSTANTS = ROOT / "physics" / "constants.py"
# the numerical code; app/ draws with these numbers but its drawing modules are being rewritten
SCANNED = ("physics", "scenarios", "benchmarks", "theoria")


def _defining_literals() -> dict[float, str]:
    """Every number written as (part of) a module-level literal in constants.py: value → name."""
    out = {}
    for node in ast.parse(CONSTANTS.read_text()).body:
        if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name):
            v = node.value
            items = v.elts if isinstance(v, ast.Tuple) else [v]
            for it in items:
                if isinstance(it, ast.UnaryOp) and isinstance(it.op, ast.USub):
                    it = it.operand
                if isinstance(it, ast.Constant) and isinstance(it.value, float):
                    out[abs(it.value)] = node.targets[0].id
    return out


def test_no_constant_is_written_twice():
    """No number of constants.py stands as a literal anywhere else in the numerical code (a
    quoted table, like the translator's inputs in collinear.py, says so in a string key)."""
    literals = _defining_literals()
    assert len(literals) > 30
    found = []
    for folder in SCANNED:
        for path in sorted((ROOT / folder).rglob("*.py")):
            if path == CONSTANTS:
                continue
            for tok in tokenize.generate_tokens(io.StringIO(path.read_text()).readline):
                if tok.type == tokenize.NUMBER:
                    try:
                        value = abs(float(tok.string.replace("_", "")))
                    except ValueError:  # complex literals
                        continue
                    if value in literals:
                        found.append(f"{path.relative_to(ROOT)}:{tok.start[0]} {tok.string} ({literals[value]})")
    assert not found, "\n".join(found)


def test_derived_constants_against_published_values():
    # GM☉ from Gauss's k and the 2012 AU: the IAU 2009 TDB-compatible value
    # 1.32712440041e20 ± 1e10 m³/s² (Luzum et al. 2011, Table 1)
    assert abs(C.GM_SUN_KM3_S2 - 1.32712440041e11) <= 10.0
    # M☉/M⊕ of the IAU 2009 system, 332946.0487 (a ratio of GM's with different time scales: 1e-8)
    assert C.GM_SUN_KM3_S2 / C.GM_EARTH_KM3_S2 == pytest.approx(332946.0487, rel=2e-8)
    # M⊕/M☾ = 81.30056907 in DE421 (EMRAT), the same within the IAU 2009 uncertainty of M☾/M⊕
    # (1.23000371e-2 ± 4e-10, i.e. 3.3e-8 relative)
    assert 1.0 / C.MOON_EARTH_MASS_RATIO == pytest.approx(81.30056907, rel=3.3e-8)
    # ε₀ = 23°26′21.406″
    assert math.degrees(C.OBLIQUITY_J2000_RAD) == pytest.approx(23 + 26 / 60 + 21.406 / 3600, abs=1e-12)
    # Astronomical Almanac: sidereal month 27.321 661 6 d, tropical 27.321 582 d, anomalistic
    # 27.554 550 d, anomalistic year 365.259 636 d; node 6798.38 d from the equinox of date;
    # perigee 3232.6 d against the stars
    assert C.SIDEREAL_MONTH_DAYS == pytest.approx(27.3216616, abs=2e-7)
    assert C.TROPICAL_MONTH_DAYS == pytest.approx(27.321582, abs=1e-6)
    assert C.ANOMALISTIC_MONTH_DAYS == pytest.approx(27.554550, abs=1e-6)
    assert C.ANOMALISTIC_YEAR_DAYS == pytest.approx(365.259636, abs=1e-6)
    assert C.NODE_PERIOD_OF_DATE_DAYS == pytest.approx(6798.38, abs=0.01)
    assert C.APSE_PERIOD_SIDEREAL_DAYS == pytest.approx(3232.6, abs=0.05)
    # Meeus eq. 47.1 and 47.4: the perigee's rate is L′ − M′
    assert C.MOON_PERIGEE_RATE_DEG_PER_CY == pytest.approx(4069.0137287, abs=1e-7)
