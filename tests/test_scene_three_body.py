"""The three-body scene drawings (scenarios/collinear.py, syzygy.py, lunar_perturbation.py and
scenarios/_three_body_drawing.py): what is drawn agrees with the Run it reads (L-points,
zero-velocity levels, co-rotating positions, the magnified swing, the orbit normal, read-outs),
and, rendered by the viser adapter with the fake scene of tests/test_app_scene.py, playback only
moves, shows and relabels."""
from __future__ import annotations

import numpy as np
import pytest

from theoria.app.format import human_number
from theoria.app.scene import SceneView
from theoria.physics import quaternion
from theoria.physics.three_body import collinear as col
from theoria.scenarios import _three_body_drawing as tbd
from theoria.scenarios import get
from theoria.scenarios.drawing import ORBIT_RADIUS, Label, Path, View

from test_app_scene import FakeScene


def _drawing(name, options=None, **given):
    spec = get(name)
    run = spec.simulate_fn(spec.resolve(given))
    return spec, run, spec.drawing(run, View(options=dict(options or {})))


def _rotate(wxyz, v):
    return np.array([quaternion.rotate(np.asarray(q, float), np.asarray(v, float)) for q in np.atleast_2d(wxyz)])


def _frames_consistent(d):
    """Every per-frame attribute holds one value per frame; a growing path's points appear in frame order."""
    F = d.n_frames
    for it in d.items:
        for attr in it.animated():
            assert len(getattr(it, attr)) == F, (it.name, attr)
        if isinstance(it, Path) and it.at is not None:
            assert len(it.at) == len(it.points) and np.all(np.diff(it.at) >= 0), it.name
            assert it.at[0] >= 0 and it.at[-1] <= F - 1, it.name


def _playback_only_moves(d):
    """Shown by the viser adapter: playback adds and removes nothing, and sets only poses,
    visibility, read-out text and the per-frame segments."""
    scene = FakeScene()
    view = SceneView(scene)
    view.show(d)
    scene.log.clear()
    for k in range(0, d.n_frames, max(1, d.n_frames // 40)):
        view.set_frame(k)
    assert scene.log and all(e[0] == "set" for e in scene.log)
    assert {e[3] for e in scene.log} <= {"wxyz", "points", "position", "visible", "text"}
    per_frame_segments = {f"/world/{it.name}" for it in d.items if "points" in it.animated()}
    assert {e[2] for e in scene.log if e[3] == "points"} <= per_frame_segments
    return scene, view


def test_contour_of_a_circle():
    """Marching squares on x² + y²: every segment end lies on the circle to the interpolation
    error of a cell (h²/r), and the total length is 2πr to the polygon's deficit."""
    g = np.linspace(-1.5, 1.5, 151)
    X, Y = np.meshgrid(g, g)
    r = 0.77
    segs = tbd.contour_segments(g, g, X**2 + Y**2, r * r)
    h = g[1] - g[0]
    rad = np.linalg.norm(segs[:, :, :2], axis=2)
    assert np.max(np.abs(rad - r)) < h * h / r
    length = np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1).sum()
    assert length == pytest.approx(2 * np.pi * r, rel=1e-3)
    assert len(tbd.contour_segments(g, g, X**2 + Y**2, 100.0)) == 0  # level outside the grid: nothing


def test_rot_zx_takes_z_to_the_orbit_normal():
    psi, inc = np.array([0.3, 2.5, -1.0]), np.array([0.09, 0.5, 1.2])
    q = tbd.rot_zx(psi, inc)
    n = _rotate(q, [0.0, 0.0, 1.0])
    assert np.allclose(n, np.stack([np.sin(inc) * np.sin(psi), -np.sin(inc) * np.cos(psi), np.cos(inc)], 1), atol=1e-14)
    assert np.allclose(_rotate(q, [1.0, 0, 0]), np.stack([np.cos(psi), np.sin(psi), 0 * psi], 1), atol=1e-14)
    th = np.array([0.0, 1.0, 4.0])
    assert np.allclose(_rotate(tbd.rot_z(th), [1.0, 0, 0]), np.stack([np.cos(th), np.sin(th), 0 * th], 1), atol=1e-14)


def test_collinear_restricted_points_and_zero_velocity_curves():
    spec, run, d = _drawing("collinear", motion="restricted", lagrange_point="L1")
    tr, f = run.trajectory, d.frames
    pts = col.lagrange_points_rotating(run.params["mass_ratio"])
    # the scale: the largest body distance or 1.1 × the farthest L-point (L3), drawn at ORBIT_RADIUS
    span = max(max(np.max(np.linalg.norm(tr.bodies[n], axis=1)) for n in ("primary", "secondary", "satellite")),
               1.1 * max(np.hypot(x, y) for x, y in pts.values()))
    k = ORBIT_RADIUS / span
    names = d.names()
    # L1–L5 drawn as markers in the turning frame (not as bodies with trails) at the physics' points
    for name, (x, y) in pts.items():
        assert np.allclose(d.item(f"turning/L/{name}").position, (k * x, k * y, 0.0), atol=1e-12)
        assert d.item(f"turning/L/{name}/label").text == name
        assert f"bodies/{name}" not in names and f"body_trails/{name}" not in names
    # the bodies where the run has them (inertial view by default)
    assert np.allclose(d.item("bodies/satellite").position, k * tr.bodies["satellite"][f], atol=1e-12)
    # the satellite starts on L1's label and the secondary sits between L1 and L2: the bodies are
    # named by their colours in a key instead
    assert not [n for n in names if n.startswith("bodies/") and n.endswith("/label")]
    # (the Moon/Earth mass ratio: the Earth and the Moon, in their colours)
    assert d.item("body_key").text == "blue: Earth · white: Moon · purple: satellite"
    # the zero-velocity curve through L1 passes through L1 (a saddle of 2Ω), to about a grid cell
    segs = d.item("turning/zero_velocity/L1").points / k
    zv = run.extras["zero_velocity"]
    cell = zv["x"][1] - zv["x"][0]
    dist = np.min(np.linalg.norm(segs[:, :, :2].reshape(-1, 2) - np.array(pts["L1"]), axis=1))
    assert dist < 2 * cell
    # and every point of each curve is on its level 2Ω = C_J to the interpolation error
    for name in ("L1", "L2", "L3"):
        s = d.item(f"turning/zero_velocity/{name}").points / k
        vals = col.jacobi_function(s[:, :, 0].ravel(), s[:, :, 1].ravel(), run.params["mass_ratio"])
        assert np.median(np.abs(vals / zv["levels"][name] - 1)) < 1e-3, name
    # inertial view: the turning frame follows the primaries at every frame
    th = tr.series["frame_angle_rad"][f]
    wxyz = d.item("turning").wxyz
    assert wxyz.shape == (d.n_frames, 4)
    assert np.allclose(_rotate(wxyz[::50], [1.0, 0, 0])[:, :2], np.stack([np.cos(th), np.sin(th)], 1)[::50], atol=1e-12)
    # the read-out: the run's drift at each frame
    drift = run.plot_series["satellite drift from the point (distances)"]
    texts = d.item("readout").text
    for j in (0, d.n_frames // 2, d.n_frames - 1):
        # time in the frame's turns, the drift as the panel writes numbers ("5.62 × 10⁻⁹")
        assert texts[j].startswith(f"t = {tr.t[f[j]] / (2 * np.pi):.3g} orbit")
        assert f"satellite {human_number(drift[f[j]], 3)} from L1" in texts[j] and "e-" not in texts[j]
    _frames_consistent(d)
    _playback_only_moves(d)


def test_collinear_corotating_view_draws_the_physics_corotating_satellite():
    spec, run, d = _drawing("collinear", {"corotating": True}, motion="restricted", lagrange_point="L4")
    tr, f = run.trajectory, d.frames
    sat = d.item("bodies/satellite").position
    k = d.item("turning/L/L4").position[0] / run.extras["lagrange_points"]["L4"][0]
    assert np.allclose(sat[:, 0], k * tr.series["satellite_corotating_x"][f], atol=1e-9)
    assert np.allclose(sat[:, 1], k * tr.series["satellite_corotating_y"][f], atol=1e-9)
    # the primaries stand still on the x axis; the turning frame does not turn
    for n in ("earth", "moon"):  # the primary and the secondary, the Earth and the Moon here
        p = d.item(f"bodies/{n}").position
        assert np.allclose(p[:, 1], 0, atol=1e-9) and np.ptp(p[:, 0]) < 1e-9
    assert "wxyz" not in d.item("turning").animated() and tuple(d.item("turning").wxyz) == (1.0, 0.0, 0.0, 0.0)
    _playback_only_moves(d)


def test_rigidly_turning_line_stands_still_in_the_corotating_frame():
    """Euler's rotating collinear solution (1767): in the frame turning at the physics' rate the
    three bodies stay on the x axis, to the size of the unstable drift the physics reports."""
    spec, run, d = _drawing("collinear", {"corotating": True})
    drift = run.metrics["ratio_max_rel_deviation"]
    xs = np.concatenate([d.item(f"bodies/{n}").position for n in ("A", "B", "C")])
    # (inertial frame: |y| reaches |x|; here 1.6e-4 against a 7.7e-4 drift of the spacing ratio)
    assert np.max(np.abs(xs[:, 1])) < 2 * drift * np.max(np.abs(xs[:, 0]))
    tr, f = run.trajectory, d.frames
    alpha = run.metrics["alpha"]
    assert d.item("readout").text[-1].startswith(f"BC/AB = {tr.series['ratio_BC_over_AB'][f[-1]]:.6f}  (α = {alpha:.6f})")
    # the inertial view: the line turns with the bodies (frame angle Ω t); it covers them all
    _, run, d = _drawing("collinear")
    line = d.item("turning/line").points[0]
    assert line[1, 0] >= max(np.max(np.abs(d.item(f"bodies/{n}").position[:, 0])) for n in ("A", "B", "C"))
    assert d.item("turning").wxyz.shape == (d.n_frames, 4)
    _playback_only_moves(d)


def test_collapse_has_no_turning_frame_angle():
    """Case II (collapse from rest): the bodies stay on x; the line does not turn."""
    spec, run, d = _drawing("collinear", motion="collapse")
    assert "wxyz" not in d.item("turning").animated()
    for n in ("A", "B", "C"):
        assert np.allclose(d.item(f"bodies/{n}").position[:, 1:], 0, atol=1e-9)


def test_syzygy_corotating_moon_and_the_magnified_swing():
    spec, run, d = _drawing("syzygy")
    tr, f, s = run.trajectory, d.frames, run.trajectory.series
    # co-rotating by default: the Moon is drawn where the physics' co-rotating series put it
    sun, moon = d.item("bodies/sun").position, d.item("bodies/moon").position
    k = sun[0, 0] / tr.bodies["sun"][0, 0]
    assert np.allclose(sun[:, 1], 0, atol=1e-9)  # the Sun stands still on +x
    assert np.allclose(moon[:, 0], k * s["moon_corotating_x"][f], atol=1e-9)
    assert np.allclose(moon[:, 1], k * s["moon_corotating_y"][f], atol=1e-9)
    # the syzygy point on the Sun line at the physics' distance
    p = np.asarray(run.extras["syzygy_point_lunar"], float)
    assert np.allclose(d.item("turning/syzygy_point").position, k * p)
    assert d.item("turning/syzygy_point/label").text == "syzygy point (L1)"
    # the inset: the Moon's offset from the point magnified so that the first swing is
    # INSET_AMPLITUDE; its first swing is Euler's retrograde ellipse, radial/transverse = the
    # run's amplitude ratio (Euler: 0.3117)
    path = d.item("inset/path")
    n = len(path.points)
    rel = np.stack([s["moon_corotating_x"][:n] - p[0], s["moon_corotating_y"][:n] - p[1]], 1)
    M = float(d.item("inset/label").text.split("×")[1])
    A = np.radians(run.params["amplitude_deg"])
    assert M == pytest.approx(0.18 / (k * abs(p[0]) * A), abs=0.5)
    centre = path.points[0, :2] - k * (0.18 / (k * abs(p[0]) * A)) * rel[0]
    assert np.allclose(path.points[:, :2], centre + k * (0.18 / (k * abs(p[0]) * A)) * rel, atol=1e-9)
    first = tr.t[:n] <= 1 / 2.0708  # one swing: 2π/ω with ω = √(√28 − 1) Sun's mean motions
    ratio = np.ptp(path.points[first, 0]) / np.ptp(path.points[first, 1])
    assert ratio == pytest.approx(run.metrics["amplitude_ratio"], rel=0.01)
    assert ratio == pytest.approx(0.3117, rel=0.02)
    # drawn while inside the ring; the dot follows it there and is hidden after
    assert np.all(np.linalg.norm(path.points[:, :2] - centre, axis=1) <= 0.55 + 1e-12)
    dot = d.item("inset/moon")
    assert np.array_equal(dot.visible, f < n)
    assert np.allclose(dot.position[dot.visible], path.points[f[dot.visible]])
    # the read-out follows the physics' η and v/b
    j = d.n_frames // 3
    assert d.item("readout").text[j] == (f"η = {s['eta_deg'][f[j]]:+.3g}°  v/b = {s['distance_over_b'][f[j]]:.4f}  "
                                         f"t = {tr.t[f[j]]:.3f} yr")
    _frames_consistent(d)
    _playback_only_moves(d)


def test_syzygy_inertial_view_turns_the_sun_line():
    spec, run, d = _drawing("syzygy", {"corotating": False})
    tr, f = run.trajectory, d.frames
    assert not any(n.startswith("inset/") for n in d.names())  # the magnified swing is a co-rotating view
    wxyz = d.item("turning").wxyz
    sun = tr.bodies["sun"][f]
    # the Sun line (along x of the turning frame) points at the Sun at every frame
    x = _rotate(wxyz[::40], [1.0, 0, 0])
    assert np.allclose(x[:, :2], (sun / np.linalg.norm(sun, axis=1, keepdims=True))[::40, :2], atol=1e-9)
    _playback_only_moves(d)


def test_syzygy_plot_choices_read_the_physics_series():
    _, run, d = _drawing("syzygy")
    A = run.params["amplitude_deg"]
    euler = d.plot["η/A Euler: sin αζ"]
    assert np.allclose(euler * A, run.plot_series["η Euler A sin αζ (deg)"])
    assert np.max(np.abs(euler)) == pytest.approx(1.0, abs=1e-3)  # Euler's curve at unit amplitude
    sim = next(v for key, v in d.plot.items() if key.startswith("η/A simulated"))
    assert np.allclose(sim, np.clip(run.plot_series["η simulated (deg)"] / A, -4, 4))
    assert len(sim) == len(d.plot_t) == len(run.trajectory.t)
    d2 = get("syzygy").drawing(run, View(options={"plot_per_amplitude": False}))
    assert list(d2.plot) == list(run.plot_series)


def test_lunar_plane_follows_node_and_inclination():
    spec, run, d = _drawing("lunar-perturbation", duration_yr="3")
    tr, f, s = run.trajectory, d.frames, run.trajectory.series
    # the plane's z axis is the physics' orbit normal at every frame
    n = _rotate(d.item("plane").wxyz, [0.0, 0.0, 1.0])
    assert np.allclose(n, np.stack([s["orbit_normal_x"], s["orbit_normal_y"], s["orbit_normal_z"]], 1)[f], atol=1e-9)
    j = d.n_frames // 2
    assert d.item("readout").text[j].startswith(f"i = {s['inclination_deg'][f[j]]:.3f}°")
    # 3 years of the Moon are not drawn as a trail; a trail of its last month moves with it
    assert "body_trails/moon" not in d.names()
    trail = d.item("moon_trail").points  # (F, K, 2, 3)
    k = d.item("bodies/moon").position[5, 0] / tr.bodies["moon"][f[5], 0]
    assert trail.ndim == 4 and trail.shape[0] == d.n_frames
    assert np.allclose(trail[:, -1, 1], k * tr.bodies["moon"][f], atol=1e-5)  # ends at the Moon
    assert np.allclose(trail[:, 1:, 0], trail[:, :-1, 1])  # one connected strip
    days = (trail.shape[1]) * np.median(np.diff(tr.t)) * 365.25
    assert 27.3 <= days < 27.3 + 365.25 * np.median(np.diff(tr.t)) + 1e-9
    # the Sun's direction
    sun = tr.bodies["sun"][f]
    u = d.item("sun_dir").position
    assert np.allclose(np.cross(u, sun), 0, atol=1e-5) and np.all(np.sum(u * sun, axis=1) > 0)
    _frames_consistent(d)
    _playback_only_moves(d)


def test_lunar_height_exaggeration_keeps_moon_and_plane_coplanar():
    spec, run, d = _drawing("lunar-perturbation", {"exaggerate": True}, duration_yr="2")
    f5 = 5.0
    tr, f, s = run.trajectory, d.frames, run.trajectory.series
    n = _rotate(d.item("plane").wxyz, [0.0, 0.0, 1.0])
    moon = d.item("bodies/moon").position
    # the Moon lies in the drawn plane (it is in its osculating plane exactly), and the drawn tilt
    # is atan(5 tan i)
    assert np.max(np.abs(np.sum(moon * n, axis=1)) / np.linalg.norm(moon, axis=1)) < 1e-6
    tilt = np.degrees(np.arccos(n[:, 2]))
    assert np.allclose(tilt, np.degrees(np.arctan(f5 * np.tan(np.radians(s["inclination_deg"][f])))), atol=1e-9)
    j = d.n_frames - 1
    assert d.item("readout").text[j].startswith(f"i = {s['inclination_deg'][f[j]]:.3f}°")  # the read-out stays true
    # the normal's trace is the drawn plane's normal
    trace = d.item("normal_trace").points
    assert np.allclose(trace / np.linalg.norm(trace, axis=1, keepdims=True), n, atol=1e-9)


def test_lunar_plot_choice():
    _, run, d = _drawing("lunar-perturbation", duration_yr="2")
    assert list(d.plot) == [key for key in run.plot_series if not key.startswith("inclination")]
    d2 = get("lunar-perturbation").drawing(run, View(options={"plot_inclination": True}))
    assert list(d2.plot) == ["inclination (deg)"]


def test_options_are_declared_with_their_defaults():
    assert {k: o.default for k, o in get("collinear").options.items()} == {"corotating": False}
    assert {k: o.default for k, o in get("syzygy").options.items()} == {
        "corotating": True, "inset": True, "plot_per_amplitude": True}
    assert {k: o.default for k, o in get("lunar-perturbation").options.items()} == {
        "plot_inclination": False, "exaggerate": False}


def _world(d, name, j, p):
    """Where a point given in the coordinates of item `name`'s parent is at frame j: composed
    along the name's path, as the renderers do (a Frame turns and moves, a marker moves)."""
    p = np.asarray(p, float)
    names = set(d.names())
    parts = name.split("/")
    for i in range(len(parts) - 1, 0, -1):
        parent = "/".join(parts[:i])
        if parent not in names:
            continue
        it = d.item(parent)
        wxyz = np.asarray(getattr(it, "wxyz", (1.0, 0.0, 0.0, 0.0)), float)
        pos = np.asarray(getattr(it, "position", (0.0, 0.0, 0.0)), float)
        p = quaternion.rotate(wxyz[j] if wxyz.ndim == 2 else wxyz, p)
        p = p + (pos[j] if pos.ndim == 2 else pos)
    return p


def _label_boxes(d, j, width=1280, height=800, px_per_char=6.0, line_px=16.0):
    """Screen boxes (x0, x1, y0, y1 in pixels) of the labels at frame j seen from the scenario's
    camera at 1280×800 (viser's 75° field of view): text of a constant size on the screen, written
    to the right of its point (as viser's labels are)."""
    cam = d.camera
    eye, target, up = (np.asarray(v, float) for v in (cam.position, cam.look_at, cam.up))
    fwd = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    upv = np.cross(right, fwd)
    focal = (height / 2) / np.tan(np.radians(cam.fov_deg or 75.0) / 2)
    boxes = {}
    for it in d.items:
        if not isinstance(it, Label) or (it.visible is not None and not it.visible[j]):
            continue
        pos = np.asarray(it.position, float)
        w = _world(d, it.name, j, pos[j] if pos.ndim == 2 else pos) - eye
        x, y = focal * (w @ right) / (w @ fwd), focal * (w @ upv) / (w @ fwd)
        text = it.text[j] if not isinstance(it.text, str) else it.text
        boxes[it.name] = (x, x + px_per_char * len(text), y - line_px / 2, y + line_px / 2)
    return boxes


@pytest.mark.parametrize("name,given,opts", [
    ("collinear", {"motion": "restricted"}, {}),
    ("collinear", {"motion": "restricted", "lagrange_point": "L4"}, {"corotating": True}),
    ("collinear", {}, {}),
    ("syzygy", {}, {}),
    ("syzygy", {"side": "opposition"}, {}),
    ("syzygy", {}, {"corotating": False}),
    ("lunar-perturbation", {"duration_yr": "2"}, {}),
    ("lunar-perturbation", {"duration_yr": "2"}, {"exaggerate": True}),
], ids=["collinear-L1", "collinear-L4-corotating", "collinear-rotating", "syzygy", "syzygy-opposition", "syzygy-inertial", "lunar",
        "lunar-exaggerated"])
def test_labels_do_not_sit_on_each_other(name, given, opts):
    """No two labels overlap on the screen from the scenario's camera, at any of 200 frames
    through the run (the bodies' names move with them), and every label is on the canvas beside
    the app's control panel: 1280 × 800 less the docked panel's 400 px, the look-at point in its
    middle (app/browser.py `frame` keeps it there when the panel is dragged over the canvas)."""
    spec, run, d = _drawing(name, opts, **given)
    left, right = -(1280 - 400) / 2, (1280 - 400) / 2
    for j in np.unique(np.linspace(0, d.n_frames - 1, 200).round().astype(int)):
        boxes = _label_boxes(d, j)
        for key, (x0, x1, y0, y1) in boxes.items():
            assert left <= x0 and x1 <= right and -400 <= y0 and y1 <= 400, (name, j, key, (x0, x1, y0, y1))
        keys = sorted(boxes)
        for a in range(len(keys)):
            for b in range(a + 1, len(keys)):
                A, B = boxes[keys[a]], boxes[keys[b]]
                overlap = A[0] < B[1] and B[0] < A[1] and A[2] < B[3] and B[2] < A[3]
                assert not overlap, (name, j, keys[a], keys[b], A, B)


def test_option_change_updates_a_real_viser_scene_in_place():
    """The syzygy scene shown on a real viser scene, then drawn again with the inertial view (a
    scene option): the bodies, lines and labels are updated in place (viser takes colours as
    arrays, not tuples, on an update)."""
    import contextlib
    import io

    import viser

    spec, run, d = _drawing("syzygy", duration_yr="0.5")
    with contextlib.redirect_stdout(io.StringIO()):
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        view = SceneView(server.scene)
        view.show(d)
        before = {n: h for n, h in view._h.items()}
        view.show(spec.drawing(run, View(options={"corotating": False})))
        view.set_frame(d.n_frames - 1)
        for n in ("/world/bodies/moon", "/world/turning/sun_line", "/world/readout", "/world/bodies/moon/label"):
            assert view._h[n] is before[n], n
        assert not any(n.startswith("/world/inset") for n in view._h)
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
