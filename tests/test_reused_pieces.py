"""A slider moved in class usually changes one number. Pieces of a run that depend on other numbers
only (Hyperion's section and resonance branches, the Sun's and Moon's orbits of the Earth's
precession, the forced libration on an eccentric orbit and its stability,
the precession's resonance table, the ellipsoid's quadrature rule, the syzygy's measured swing,
the Moon's calibrated elements)
are kept and reused by the next run that shares those numbers. Reused or made afresh, a run's numbers must be the same, bit for
bit, and a changed number must not reuse a piece made for another."""
from __future__ import annotations

import numba as nb
import numpy as np
import pytest

from theoria.physics import libration as lib
from theoria.physics.kept import forget
from theoria.scenarios.base import get

# (scenario, quick values, a slider that leaves the kept piece as it is, one that changes it)
CASES = [
    ("hyperion", {"n_starts": 6, "n_orbits": 20, "probe_orbits": 3.0}, ("probe_rate", 1.1), ("eccentricity", 0.12)),
    ("libration-eccentric", {"orbits": 3.0}, ("free_zeta0_deg", 5.0), ("asymmetry", 0.07)),
    ("precession-circular", {"orbits": 3.0}, ("h", 0.01), ("flattening", 0.12)),
    ("gravity-gradient-accuracy", {"n_points": 4}, ("max_ratio", 0.4), ("semi_axes", (1.0, 0.7, 0.5))),
    ("syzygy", {}, ("duration_yr", 2.5), ("mass_ratio", 1e-4)),
    # the Moon's calibrated initial elements (three two-year element runs)
    ("lunar-perturbation", {"duration_yr": 1.0, "step_days": 0.1}, ("duration_yr", 1.5), ("inclination_deg", 5.5)),
    # the Sun's and Moon's orbits: a longer span goes on from the kept run, a shorter one is its start
    ("earth", {"years": 2.0, "step_days": 2.0}, ("H", 0.0033), ("years", 3.0)),
    ("earth", {"years": 3.0, "step_days": 2.0}, ("obliquity_deg", 23.0), ("years", 2.0)),
]


def _same(a, b) -> None:
    assert a.metrics.keys() == b.metrics.keys()
    for k in a.metrics:
        np.testing.assert_array_equal(np.asarray(a.metrics[k]), np.asarray(b.metrics[k]), err_msg=k)
    np.testing.assert_array_equal(a.trajectory.quat_wxyz, b.trajectory.quat_wxyz)
    assert [repr(c) for c in a.comparisons] == [repr(c) for c in b.comparisons]
    assert a.notes == b.notes


@pytest.mark.parametrize("name,base,keeps,changes", CASES, ids=[f"{c[0]}:{c[3][0]}={c[3][1]}" for c in CASES])
def test_a_run_with_kept_pieces_is_the_run_made_afresh(name, base, keeps, changes):
    spec = get(name)
    after_keep = {**base, keeps[0]: keeps[1]}
    after_change = {**base, changes[0]: changes[1]}
    forget()
    fresh_keep = spec.simulate(after_keep)
    forget()
    fresh_change = spec.simulate(after_change)
    forget()
    spec.simulate(base)  # makes the pieces of `base`
    _same(spec.simulate(after_keep), fresh_keep)  # reuses them
    _same(spec.simulate(after_change), fresh_change)  # must not
    assert any(not np.array_equal(np.asarray(fresh_keep.metrics[k]), np.asarray(fresh_change.metrics[k]))
               for k in fresh_keep.metrics if k in fresh_change.metrics)  # the changed number shows


def test_the_section_kernel_is_never_called_through_numbas_slow_path():
    """numba's dispatcher takes a slow path (types worked out in Python, ~0.4 ms a call) when a
    compiled function is called with a default argument left out. Hyperion's resonance search maps
    one orbit ~1,600 times, and that path made each Hyperion run four times slower."""
    th0, wd0 = np.zeros(3), np.linspace(0.5, 2.0, 3)
    lib.spin_orbit_section(th0, wd0, 0.1, 0.89, 4, steps_per_orbit=32)
    lib.spin_orbit_section(th0, wd0, 0.1, 0.89, 4, steps_per_orbit=32, progress=lambda f: None)
    sigs = lib._section_run.signatures
    assert sigs
    assert not [s for s in sigs if any(isinstance(t, nb.types.Omitted) for t in s)], sigs
