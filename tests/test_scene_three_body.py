"""The three-body scene drawings (app/scene_extras/three_body.py) with the fake viser scene of
tests/test_app_scene.py: what is drawn agrees with the Result it reads (L-points, zero-velocity
levels, co-rotating positions, orbit normal), and playback only moves / shows / relabels."""
from __future__ import annotations

import numpy as np
import pytest

from theoria.app.scene import ORBIT_RADIUS, SceneView
from theoria.app.scene_extras.three_body import contour_segments, rot_zx, to_corotating
from theoria.physics import quaternion
from theoria.physics.three_body import collinear as col

from test_app_scene import FakeHandle, FakeScene, _result


class KwFakeScene(FakeScene):
    """FakeScene whose handles also keep the keyword arguments they were created with."""

    def __getattr__(self, method):
        if not method.startswith("add_"):
            raise AttributeError(method)

        def add(name, *args, **kw):
            self.log.append(("add", method, name, None, None))
            pts = kw.pop("points", args[0] if args and isinstance(args[0], np.ndarray) else None)
            kw.pop("visible", None)
            return FakeHandle(self.log, method, name, points=pts, **kw)

        return add


def _show(name, **given):
    scene = KwFakeScene()
    view = SceneView(scene)
    spec, res = _result(name, **given)
    view.show(res, spec)
    return scene, view, res


def _playback_only_sets(scene, view):
    scene.log.clear()
    for i in range(0, view.n, max(1, view.n // 40)):
        view.set_frame(i)
    assert scene.log and all(e[0] == "set" for e in scene.log)
    assert {e[3] for e in scene.log} <= {"wxyz", "points", "position", "visible", "text"}


def test_contour_of_a_circle():
    """Marching squares on x² + y²: every segment end lies on the circle to the interpolation
    error of a cell (h²/r), and the total length is 2πr to the polygon's deficit."""
    g = np.linspace(-1.5, 1.5, 151)
    X, Y = np.meshgrid(g, g)
    r = 0.77
    segs = contour_segments(g, g, X**2 + Y**2, r * r)
    h = g[1] - g[0]
    rad = np.linalg.norm(segs[:, :, :2], axis=2)
    assert np.max(np.abs(rad - r)) < h * h / r
    length = np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1).sum()
    assert length == pytest.approx(2 * np.pi * r, rel=1e-3)
    assert len(contour_segments(g, g, X**2 + Y**2, 100.0)) == 0  # level outside the grid: nothing


def test_rot_zx_takes_z_to_the_orbit_normal():
    for psi, inc in [(0.3, 0.09), (2.5, 0.5), (-1.0, 1.2)]:
        q = np.array(rot_zx(psi, inc))
        n = quaternion.rotate(q, np.array([0.0, 0.0, 1.0]))
        assert np.allclose(n, [np.sin(inc) * np.sin(psi), -np.sin(inc) * np.cos(psi), np.cos(inc)], atol=1e-14)
        assert np.allclose(quaternion.rotate(q, np.array([1.0, 0, 0])), [np.cos(psi), np.sin(psi), 0], atol=1e-14)


def test_collinear_restricted_points_and_zero_velocity_curves():
    scene, view, res = _show("collinear", motion="restricted", lagrange_point="L1")
    ex = view.extra
    k = ex.k
    added = {e[2] for e in scene.log if e[0] == "add"}
    # L1–L5 drawn as markers (not as bodies with trails) at the physics' points
    pts = col.lagrange_points_rotating(res.params["mass_ratio"])
    for name, (x, y) in pts.items():
        h = view._h[f"/world/extra/rot/L/{name}"]
        assert np.allclose(h.position, (k * x, k * y, 0.0), atol=1e-12)
        assert f"/world/bodies/{name}" not in added
    # the zero-velocity curve through L1 passes through L1 (a saddle of 2Ω), to about a grid cell
    segs = view._h["/world/extra/rot/zvc/L1"].points / k
    zv = res.extras["zero_velocity"]
    cell = zv["x"][1] - zv["x"][0]
    d = np.min(np.linalg.norm(segs[:, :, :2].reshape(-1, 2) - np.array(pts["L1"]), axis=1))
    assert d < 2 * cell
    # and every point of it is on the level 2Ω = C_J(L1) to the interpolation error
    vals = col.jacobi_function(segs[:, :, 0].ravel(), segs[:, :, 1].ravel(), res.params["mass_ratio"])
    assert np.median(np.abs(vals / zv["levels"]["L1"] - 1)) < 1e-3
    _playback_only_sets(scene, view)
    # inertial view: the markers' frame turns with the primaries
    view.set_frame(view.n - 1)
    th = res.trajectory.series["frame_angle_rad"][-1]
    assert np.allclose(view._h["/world/extra/rot"].wxyz, (np.cos(th / 2), 0, 0, np.sin(th / 2)))


def test_corotating_option_redraws_bodies_in_the_turning_frame():
    scene, view, res = _show("collinear", motion="restricted", lagrange_point="L4")
    tr = res.trajectory
    scene.log.clear()
    view.set_option("corotating", True)
    assert not [e for e in scene.log if e[0] == "add" and "/bodies/" in e[2]]  # updated in place
    k = ORBIT_RADIUS / view.extra.span(tr)
    sat = view._markers["satellite"][1]
    assert np.allclose(sat[:, 0], k * tr.series["satellite_corotating_x"], atol=1e-9)
    assert np.allclose(sat[:, 1], k * tr.series["satellite_corotating_y"], atol=1e-9)
    view.set_frame(view.n // 2)
    assert tuple(view._h["/world/extra/rot"].wxyz) == (1.0, 0.0, 0.0, 0.0)
    _playback_only_sets(scene, view)


def test_syzygy_corotating_moon_matches_the_physics_series():
    scene, view, res = _show("syzygy")
    tr = res.trajectory
    assert view.extra.values["corotating"]  # default
    th = tr.series["frame_angle_rad"]
    moon = to_corotating(tr.bodies["moon"], th)
    assert np.allclose(moon[:, 0], tr.series["moon_corotating_x"], rtol=1e-12, atol=1e-9)
    assert np.allclose(moon[:, 1], tr.series["moon_corotating_y"], rtol=1e-12, atol=1e-9)
    sun = to_corotating(tr.bodies["sun"], th)
    assert np.allclose(sun[:, 1], 0, atol=1e-9)  # the Sun stands still on +x
    # syzygy point marker on the Sun line at the physics' distance; the magnified inset exists
    k = view.extra.k
    p = res.extras["syzygy_point_lunar"]
    assert np.allclose(view._h["/world/extra/rot/syzygy_point"].position, (k * p[0], 0, 0))
    assert any(n.startswith("/world/extra/inset/path/") for n in view._h)
    _playback_only_sets(scene, view)
    view.set_frame(0)
    assert "η = " in view.extra.readout.text


def test_lunar_plane_follows_node_and_inclination():
    scene, view, res = _show("lunar-perturbation", duration_yr="3")
    tr, s = res.trajectory, res.trajectory.series
    i = view.n // 2
    view.set_frame(i)
    q = np.array(view._h["/world/extra/plane"].wxyz)
    n = quaternion.rotate(q, np.array([0.0, 0.0, 1.0]))
    assert np.allclose(n, [s["orbit_normal_x"][i], s["orbit_normal_y"][i], s["orbit_normal_z"][i]], atol=1e-9)
    assert f"i = {s['inclination_deg'][i]:.3f}°" in view.extra.readout.text
    # 40 years of the Moon are not drawn as a trail; a one-month trail of constant size moves
    assert not any(n.startswith("/world/body_trails/moon") for n in view._h)
    shape = view._h["/world/extra/moon_trail"].points.shape
    view.set_frame(3)
    assert view._h["/world/extra/moon_trail"].points.shape == shape
    _playback_only_sets(scene, view)


def test_plot_choices_read_the_physics_series():
    _, view, res = _show("syzygy")
    ps = view.extra.plot_series(res)
    A = res.params["amplitude_deg"]
    euler = ps["η/A Euler: sin αζ"]
    assert np.allclose(euler * A, res.plot_series["η Euler A sin αζ (deg)"])
    assert np.max(np.abs(euler)) == pytest.approx(1.0, abs=1e-3)  # Euler's curve at unit amplitude
    sim = next(v for k, v in ps.items() if k.startswith("η/A simulated"))
    assert np.max(np.abs(sim)) <= view.extra.PLOT_CLIP
    view.set_option("plot_per_amplitude", False)
    assert view.extra.plot_series(res) is res.plot_series
    _, view, res = _show("lunar-perturbation", duration_yr="3")
    assert list(view.extra.plot_series(res)) == [k for k in res.plot_series if not k.startswith("inclination")]
    view.set_option("plot_inclination", True)
    assert list(view.extra.plot_series(res)) == ["inclination (deg)"]


def test_orbit_cameras_are_shifted_clear_of_the_panel():
    """Orbit scenes: camera and look-at point moved by the same vector, to the screen's right
    (so the scene sits left of the control panel); rotation scenes keep the gallery's view."""
    from theoria.app import gallery
    from theoria.app.server import PANEL_SHIFT, camera_view
    from theoria.scenarios import get

    for name in ("collinear", "syzygy", "lunar-perturbation"):
        spec = get(name)
        p0, l0 = (np.array(v, float) for v in gallery.camera_for(spec))
        p1, l1 = (np.array(v) for v in camera_view(spec))
        shift = l1 - l0
        assert np.allclose(p1 - p0, shift)
        fwd = l0 - p0
        assert np.linalg.norm(shift) == pytest.approx(PANEL_SHIFT * np.linalg.norm(fwd))
        assert abs(shift @ fwd) < 1e-9 and abs(shift[2]) < 1e-12
        assert np.cross(shift, fwd)[2] > 0  # right × forward = up: to the right of the view
    spec = get("free-tumble")
    assert camera_view(spec) == tuple(tuple(float(x) for x in v) for v in gallery.camera_for(spec))


def test_lunar_height_exaggeration_keeps_moon_and_plane_coplanar():
    scene, view, res = _show("lunar-perturbation", duration_yr="2")
    view.set_option("exaggerate", True)
    f = view.extra.EXAGGERATION
    tr, s = res.trajectory, res.trajectory.series
    for i in (5, view.n // 3, view.n - 1):
        view.set_frame(i)
        q = np.array(view._h["/world/extra/plane"].wxyz)
        n = quaternion.rotate(q, np.array([0.0, 0.0, 1.0]))
        moon = view._markers["moon"][1][i]
        # the Moon lies in the drawn plane to the osculating plane's tolerance (the Moon is in its
        # osculating plane exactly), and the drawn tilt is atan(f tan i)
        assert abs(moon @ n) < 1e-6 * np.linalg.norm(moon)
        assert np.degrees(np.arccos(n[2])) == pytest.approx(np.degrees(np.arctan(f * np.tan(np.radians(
            s["inclination_deg"][i])))), abs=1e-9)
        assert f"i = {s['inclination_deg'][i]:.3f}°" in view.extra.readout.text  # the read-out stays true


def test_rigidly_turning_line_stands_still_in_the_corotating_frame():
    """Euler's rotating collinear solution (1767): in the frame turning at the physics' rate the
    three bodies stay on the x axis, to the size of the unstable drift the physics reports."""
    scene, view, res = _show("collinear")
    view.set_option("corotating", True)
    drift = res.metrics["ratio_max_rel_deviation"]
    xs = np.concatenate([view._markers[n][1] for n in ("A", "B", "C")])
    # (inertial frame: the ratio is ~1; here 1.6e-4 against a 7.7e-4 drift of the spacing ratio)
    assert np.max(np.abs(xs[:, 1])) < 2 * drift * np.max(np.abs(xs[:, 0]))
    _playback_only_sets(scene, view)
