"""Playback cost: paths that retrace themselves send far fewer points with
the picture unchanged, and the ω / L arrows move by pose updates, re-sending geometry rarely."""
from __future__ import annotations

import numpy as np
import pytest

from theoria.app.scene import REPEAT_CELL, TRAIL_CHUNKS, SceneView, drop_repeats
from theoria.physics.quaternion import rotate
from theoria.scenarios import get
from theoria.scenarios.drawing import omega_scale, z_to_many
from tests.test_app_scene import FakeScene


def test_drop_repeats_keeps_the_picture_at_every_time():
    rng = np.random.default_rng(1)
    th = np.linspace(0, 40 * np.pi, 20000)  # a circle traced 20 times, with a little noise
    path = np.stack([np.cos(th), np.sin(th), 0 * th], 1) + 1e-4 * rng.standard_normal((len(th), 3))
    idx = np.arange(len(th), dtype=float)
    cell = 0.01
    kept, kidx = drop_repeats(path, idx, cell)
    assert len(kept) < len(path) / 5  # the retraced laps cost almost nothing
    assert np.all(np.diff(kidx) > 0) and kidx[0] == 0  # time order, first point kept
    # every dropped point lies within one cell diagonal of a point kept no later than itself
    from scipy.spatial import cKDTree

    for t in (500, 3000, 19999):
        shown = kept[kidx <= t]
        d, _ = cKDTree(shown).query(path[: t + 1])
        assert d.max() <= np.sqrt(3) * cell + 1e-12
    # a path that never comes back keeps all its points
    line = np.stack([np.linspace(0, 10, 1000), 0 * th[:1000], 0 * th[:1000]], 1)
    assert len(drop_repeats(line, idx[:1000], cell)[0]) == 1000


def test_drop_repeats_packed_keys_match_the_plain_cell_search():
    """The packed one-int64-per-cell key keeps exactly the points a unique over (i, j, k) rows keeps,
    including negative cells and paths far from the origin (which fall back to the row search)."""
    rng = np.random.default_rng(7)
    for scale, cell in ((1.0, 0.01), (50.0, 0.5), (1.0, 1e-7)):  # the last: cells beyond 2**20, the fallback
        path = scale * rng.standard_normal((5000, 3))
        path = np.concatenate([path, path[::3] + 0.1 * cell * rng.standard_normal((len(path[::3]), 3))])
        idx = np.arange(len(path), dtype=float)
        key = np.floor(path / cell).astype(np.int64)
        keep = np.sort(np.unique(key, axis=0, return_index=True)[1])
        kept, kidx = drop_repeats(path, idx, cell)
        assert np.array_equal(kidx, idx[keep]) and np.array_equal(kept, path[keep])


def test_z_to_many_turns_z_onto_each_vector():
    vs = np.array([[1, 2, 3], [0, 0, -5], [0, 0, 2], [1e-3, 0, -1], [-1, 0, 0], [0, 0, 0], [np.nan, 0, 1]], float)
    q, n = z_to_many(vs)
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)
    for k in range(5):
        assert np.allclose(rotate(q[k], [0, 0, 1.0]), vs[k] / np.linalg.norm(vs[k]), atol=1e-9)
        assert n[k] == pytest.approx(np.linalg.norm(vs[k]))
    assert np.allclose(q[5:], [1, 0, 0, 0]) and np.all(n[5:] == 0)  # nothing to point along: identity, length 0


def test_periodic_polhode_sends_fewer_points_and_arrows_move_by_pose():
    spec = get("middle-axis-flip")
    res = spec.simulate_fn(spec.resolve({"duration": "100", "step": "0.005"}))  # the bench run
    scene = FakeScene()
    view = SceneView(scene)
    d = spec.drawing(res)
    view.show(d)
    sent = {n: len(h.points) for n, h in view._h.items() if h.kind == "add_point_cloud"}
    polhode = sum(v for n, v in sent.items() if n.startswith("/world/body/polhode/"))
    assert polhode < 0.5 * 10000  # 9 flips retrace the same two loops
    assert len([n for n in sent if n.startswith("/world/body/polhode/")]) == TRAIL_CHUNKS  # a growing trail
    # the ω / L arrows: direction by the frame's pose, geometry only when the length changes
    scene.log.clear()
    n = d.n_frames
    frames = range(0, n, 10)
    for i in frames:
        view.set_frame(i)
    pts = [e for e in scene.log if e[3] == "points"]
    poses = [e for e in scene.log if e[3] == "wxyz" and e[2] in ("/world/omega", "/world/L")]
    assert len(poses) == 2 * len(frames)
    assert len(pts) < 0.2 * len(poses)
    # the drawn ω arrow points along ω with the scene's scale (within the length tolerance)
    i = n // 3
    view.set_frame(i)
    fr, arrow = view._h["/world/omega"], view._h["/world/omega/arrow"]
    drawn = rotate(np.asarray(fr.wxyz), arrow.points[0, 1].astype(float))
    want = omega_scale(res.trajectory) * res.trajectory.omega_inertial[d.frames[i]]
    assert np.allclose(drawn, want, rtol=0.03, atol=1e-3 * np.linalg.norm(want))
    assert REPEAT_CELL < 2 / np.sqrt(3)  # a dropped point lies within a drawn point's width (2 × size)
