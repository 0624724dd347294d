"""Derived paths of the Trajectory: Poinsot's construction holds for a free body."""
import numpy as np

from theoria.scenarios import get


def test_free_tumble_paths_obey_poinsot():
    r = get("free-tumble").simulate({"duration": 30})
    tr = r.trajectory
    # L is fixed in space
    assert np.allclose(tr.L_inertial, tr.L_inertial[0], atol=1e-12 * np.linalg.norm(tr.L_inertial[0]))
    # the herpolhode lies on the invariable plane: ω in space against the normal L̂ of the FIRST
    # sample (this needs the attitude of every sample right, not only ω·L = 2E)
    Lhat = tr.L_inertial[0] / np.linalg.norm(tr.L_inertial[0])
    height = tr.herpolhode @ Lhat
    assert np.allclose(height, 2 * tr.energy[0] / tr.momentum_norm[0], rtol=1e-12)
    # and it is not a point: the tip of ω really moves on that plane
    assert np.ptp(tr.herpolhode - np.outer(height, Lhat), axis=0).max() > 0.1
    # unit rotation axis and figure axis
    assert np.allclose(np.linalg.norm(tr.rotation_axis, axis=1), 1)
    assert np.allclose(np.linalg.norm(tr.figure_axis, axis=1), 1)
    assert len(tr) <= 20001
