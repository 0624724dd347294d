"""Derived paths of the Trajectory: Poinsot's construction holds for a free body."""
import numpy as np

from physics.scenarios import get


def test_free_tumble_paths_obey_poinsot():
    r = get("free-tumble").simulate({"duration": 30})
    tr = r.trajectory
    # L is fixed in space
    assert np.allclose(tr.L_inertial, tr.L_inertial[0], atol=1e-12 * np.linalg.norm(tr.L_inertial[0]))
    # the herpolhode lies on the invariable plane ω·L̂ = 2E/|L|
    Lhat = tr.L_inertial[0] / np.linalg.norm(tr.L_inertial[0])
    height = tr.herpolhode @ Lhat
    assert np.allclose(height, 2 * tr.energy[0] / tr.momentum_norm[0], rtol=1e-12)
    # the polhode lies on the energy ellipsoid and the momentum sphere (in the body)
    I = tr.inertia
    assert np.allclose(np.sum(I * tr.polhode**2, axis=1), 2 * tr.energy[0], rtol=1e-12)
    assert np.allclose(np.linalg.norm(I * tr.polhode, axis=1), tr.momentum_norm[0], rtol=1e-12)
    # unit rotation axis and figure axis
    assert np.allclose(np.linalg.norm(tr.rotation_axis, axis=1), 1)
    assert np.allclose(np.linalg.norm(tr.figure_axis, axis=1), 1)
    assert len(tr) <= 20001
