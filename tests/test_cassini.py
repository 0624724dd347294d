"""The Moon's Cassini state: Peale's equation, and the rigid Moon integrated with every monthly
term, against the observed mean obliquity of the lunar equator (1.54242°, IAU)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from theoria import ParameterError
from theoria.physics import cassini as CS
from theoria.physics import constants as C
from theoria.scenarios.base import get


def test_peale_equation_small_angles_and_residual():
    """For small angles the equation is linear: |g| I = K β′ (i + I), I = K β′ i/(|g| − K β′)."""
    moments = np.array([0.9994, 0.99963, 1.0])
    beta_c = (moments[2] - moments[0]) / moments[2]
    g, K = -9.2e-4, 0.34
    i = 1e-4
    I = CS.peale_obliquity(i, g, K, 0.0, moments)
    assert I == pytest.approx(K * beta_c * i / (abs(g) - K * beta_c), rel=1e-6)
    assert abs(CS.peale_residual(I, i, g, K, 0.0, moments)) < 1e-18


def test_cassini_frame_has_the_pole_opposite_the_orbit_normal():
    node = np.radians([10.0, 130.0, 250.0])
    q = CS.cassini_frame(node, np.zeros(3), math.radians(1.5))
    from theoria.physics import quaternion as quat

    s = quat.rotate(q, np.array([0.0, 0.0, 1.0]))
    inc = math.radians(5.0)
    n = np.stack([math.sin(inc) * np.sin(node), -math.sin(inc) * np.cos(node), np.full(3, math.cos(inc))], -1)
    k = np.array([0.0, 0.0, 1.0])
    assert np.allclose(np.degrees(np.arccos(s[:, 2])), 1.5)
    assert np.allclose(CS.out_of_plane(s, n, k), 0.0, atol=1e-12)
    assert np.all(CS.side_of_pole(s, n, k) > 0)


@pytest.mark.slow
def test_moon_keeps_its_cassini_state():
    """Four node cycles of the rigid Moon: the figure axis stays on the far side of the ecliptic pole
    from the orbit normal, close to their plane (its monthly nod is ~0.1°), at a mean obliquity
    within 0.02° of the observed 1.543° and of Peale's first-order equation."""
    m = get("cassini").simulate({}).metrics
    assert m["opposite_side_fraction"] == 1.0
    assert m["out_of_plane_max_arcsec"] < 0.15 * 3600
    assert abs(m["obliquity_mean_deg"] - C.MOON_EQUATOR_INCLINATION_DEG) < 0.02
    assert abs(m["obliquity_peale_deg"] - C.MOON_EQUATOR_INCLINATION_DEG) < 0.02
    assert abs(m["obliquity_mean_deg"] - m["obliquity_peale_deg"]) < 0.02


def test_the_default_step_agrees_with_a_run_at_a_quarter_of_it():
    """The default step (2 days) against the same run at 0.5 days, the finer run the reference: the
    mean obliquity within 1e-4° (the E8 check's tolerance is 0.02°), the figure axis's greatest
    distance from the plane of the normals within 0.5 %, the same side of the pole throughout."""
    cassini = get("cassini")
    coarse = cassini.simulate({}).metrics
    fine = cassini.simulate({"step_days": 0.5}).metrics
    assert cassini.resolve({})["step_days"] == 4 * 0.5
    assert abs(coarse["obliquity_mean_deg"] - fine["obliquity_mean_deg"]) < 1e-4
    assert abs(coarse["out_of_plane_max_arcsec"] / fine["out_of_plane_max_arcsec"] - 1) < 5e-3
    assert coarse["opposite_side_fraction"] == fine["opposite_side_fraction"] == 1.0


def test_bad_values_are_refused_naming_the_parameter():
    with pytest.raises(ParameterError) as e:
        get("cassini").simulate({"node_period_yr": 0.5})
    assert e.value.name == "node_period_yr"


def test_a_run_shorter_than_a_node_cycle_says_its_mean_obliquity_is_not_one():
    from theoria.scenarios import get

    short = get("cassini").simulate(years=0.5)
    assert short.metrics["node_cycles_averaged"] == 0
    assert any("shorter than one regression of the node" in w for w in short.warnings)
    assert not any("regression of the node" in w for w in get("cassini").simulate().warnings)
