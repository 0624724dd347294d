"""Every number a run returns has a unit, and the unit is the right one.

The right one is checked by dimensional analysis, which owes nothing to the code under test: make
every rate of a scenario k times faster (every time k times shorter) and a metric measured in
time^p must change by k^-p, a pure number or an angle not at all. A period declared in seconds
that was in fact in turns, or a rate in "n" that was per orbit, fails here.
"""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

import theoria as th

K = 2.0  # every rate ×2, every time ÷2

# each unit's power of time (a unit not listed here makes the test fail: add it with its power)
TIME_POWER = {"": 0, "1": 0, "rad": 0, "deg": 0, "s": 1, "unit": 1, "1/s": -1, "rad/s": -1, "rad/s^2": -2,
              "1/unit^2": -2, "J": -2, "kg m^2/s": -1,
              "rad/unit": -1, "C/unit": -1, "C/unit^2": -2}  # a run's columns in the scenario's own unit of time

# scenario → how to make it K times faster: parameter → factor (rates ×K, rates squared ×K², times ÷K)
FASTER = {
    "free-tumble": {"omega0": K, "duration": 1 / K, "step": 1 / K},
    "middle-axis-flip": {"spin": K, "duration": 1 / K, "step": 1 / K},
    "initial-axis": {"torque": K * K, "probe_time": 1 / K, "duration": 1 / K, "step": 1 / K},  # N m = kg m²/s²
    "gravity-start": {"gm": K * K},  # m³/s²
    "pole-near-axis": {"spin": K, "tidal": K * K},
    "libration-circular": {"orbital_rate": K},
    "libration-eccentric": {"orbital_rate": K},
}


def _scaled(values, factors):
    out = dict(values)
    for name, f in factors.items():
        v = values[name]
        out[name] = tuple(x * f for x in v) if isinstance(v, tuple) else v * f
    return out


@pytest.mark.parametrize("name", sorted(FASTER))
def test_metrics_change_with_the_time_scale_as_their_units_say(name):
    sc = th.scenario(name)
    base = {p: sc.parameters[p].default for p in sc.parameters}
    slow = sc.simulate(**base)
    fast = sc.simulate(**_scaled(base, FASTER[name]))
    units = slow.metric_units
    checked = 0
    for key, v in slow.metrics.items():
        w = fast.metrics[key]
        # rounding-level numbers (a drift of 1e-15) and missing values carry no scale
        if not (math.isfinite(v) and math.isfinite(w)) or abs(v) < 1e-8:
            continue
        want = K ** -TIME_POWER[units[key]]
        assert w / v == pytest.approx(want, rel=1e-6), f"{name}: {key} in {units[key]!r}: ×{w / v:.6g}, not ×{want:g}"
        checked += 1
    assert checked >= 3, f"{name}: only {checked} metrics to check"


@pytest.mark.parametrize("name", sorted(FASTER))
def test_columns_change_with_the_time_scale_as_their_units_say(name):
    """`Run.column_units` (`to_dataframe().attrs["units"]`): ω, L, the energy and the time of each
    sample scale with the rates as their units say. (libration-eccentric's time was labelled in the
    orbit's radians, 1/n·rad, which holds only at its default n = 1: ω doubled with n.)"""
    sc = th.scenario(name)
    base = {p: sc.parameters[p].default for p in sc.parameters}
    slow, fast = sc.simulate(**base), sc.simulate(**_scaled(base, FASTER[name]))
    units, a, b = slow.column_units(), slow.columns(), fast.columns()
    assert fast.column_units() == units
    checked = []
    for key in ("omega_body_x", "omega_body_y", "omega_body_z", "L_body_z", "energy", *[k for k in a if k.startswith("t_")]):
        if key not in a:
            continue
        v, w = a[key][-1], b[key][-1]
        if abs(v) < 1e-8 * max(1.0, float(np.max(np.abs(a[key])))):
            continue
        want = K ** -TIME_POWER[units[key]]
        assert w / v == pytest.approx(want, rel=1e-6), f"{name}: {key} in {units[key]!r}: ×{w / v:.6g}, not ×{want:g}"
        checked.append(key)
    assert "energy" in checked and any(k.startswith("t_") for k in checked), checked


def test_every_column_of_a_rotating_body_has_a_unit_in_the_dataframe():
    run = th.scenario("free-tumble").simulate(duration=5)
    df = run.to_dataframe()
    assert df.attrs["units"] == run.column_units()
    assert {c: df.attrs["units"][c] for c in ("t_s", "q_w", "omega_body_x", "L_body_y", "energy")} == {
        "t_s": "s", "q_w": "1", "omega_body_x": "rad/s", "L_body_y": "kg m^2/s", "energy": "J"}
    earth = th.scenario("earth").simulate(years=1)  # moments as fractions of C, time in years
    assert {k: v for k, v in earth.column_units().items() if k in ("L_body_z", "obliquity − ε₀ (arcsec)")} == {
        "L_body_z": "C/yr", "obliquity − ε₀ (arcsec)": "arcsec"}


@pytest.mark.parametrize("name", th.scenarios())
def test_every_metric_has_a_unit_and_every_declared_unit_a_metric(name):
    sc = th.scenario(name)
    # the preview's sizes, not its switches: a preview leaves out whole parts (Hyperion's islands)
    run = sc.simulate(**{k: v for k, v in sc.preview.items() if not isinstance(v, str)})
    unknown = [k for k, u in run.metric_units.items() if u is None]
    assert not unknown, f"{name}: no unit in the name or in metric_units for {unknown}"
    stale = [p for p in sc.metric_units if not any(k == p or re.fullmatch(p, k) for k in run.metrics)]
    for preset in sc.presets if stale else ():  # a metric of some choices only (the restricted problem's)
        got = sc.simulate(preset=preset, **{k: v for k, v in sc.preview.items() if not isinstance(v, str)})
        assert not [k for k, u in got.metric_units.items() if u is None], (name, preset)
        stale = [p for p in stale if not any(k == p or re.fullmatch(p, k) for k in got.metrics)]
    assert not stale, f"{name}: metric_units names metrics the scenario does not return: {stale}"
    assert run.to_dict()["metric_units"] == run.metric_units
    # and every column of its table: t, the attitude, the rates, the other bodies and the series
    missing = [c for c in run.columns() if c not in run.column_units()]
    assert not missing, f"{name}: no unit in the name, the label or series_units for {missing}"
    assert run.to_dataframe().attrs["units"] == run.column_units()


def test_the_restricted_problems_columns_have_units_too():
    """collinear's satellite at a Lagrange point adds columns of its own (in the turning frame)."""
    run = th.scenario("collinear").simulate(preset="L2")
    units = run.column_units()
    assert [c for c in run.columns() if c not in units] == []
    assert units["satellite_corotating_x"] == "G=1 units" and units["L2_x"] == "G=1 units"
