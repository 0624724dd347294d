"""The chapter 16 scene extras (app/scene_extras/ch16.py) with the fake viser scene of
tests/test_app_scene.py: what is drawn must be the scenario's own numbers put in the right place
(ζ arc between the drawn A axis and F, phase-portrait dot at (ζ, dζ/dt), section points and
resonance lines at p ± the Goldreich–Peale half-width, the pole's path and the stars), playback
moves things only, and the time plot leaves out the point clouds."""
from __future__ import annotations

import numpy as np
import pytest

from theoria.app.scene import SceneView
from theoria.app.scene_extras import ch16
from theoria.physics import quaternion as quat
from theoria.scenarios import get

from test_app_scene import FakeScene

QUICK = {
    "gravity-start": {},
    "libration-circular": {},
    "libration-eccentric": {"orbits": 4.0},
    "moon": {"years": 0.5},
    "hyperion": {"n_starts": 12, "n_orbits": 40, "probe_orbits": 4.0},
    "pole-near-axis": {},
    "gravity-gradient-accuracy": {},
    "precession-circular": {"orbits": 20.0},
    "earth": {"years": 2.0},
}


@pytest.fixture(scope="module")
def results():
    out = {}
    for name, given in QUICK.items():
        spec = get(name)
        out[name] = (spec, spec.simulate_fn(spec.resolve(given)))
    return out


def _show(spec, res):
    scene = FakeScene()
    view = SceneView(scene)
    view.show(res, spec)
    return scene, view


@pytest.mark.parametrize("name", list(QUICK))
def test_extra_builds_and_playback_only_moves(results, name):
    spec, res = results[name]
    scene, view = _show(spec, res)
    assert view.extra is not None and type(view.extra).__module__ == "theoria.app.scene_extras.ch16", name
    extra_nodes = [n for n in view._h if n.startswith("/world/extra/") or n in ("/world/body/moon_surface",)]
    assert extra_nodes, name
    scene.log.clear()
    for i in range(0, len(res.trajectory.t), max(1, len(res.trajectory.t) // 40)):
        view.set_frame(i)
    assert not [e for e in scene.log if e[0] != "set"], name  # nothing added or removed
    assert {e[3] for e in scene.log} <= {"wxyz", "points", "position", "visible", "text"}, name
    # the time plot: only series on trajectory.t
    for k, v in view.extra.plot_series(res).items():
        assert np.shape(v) == np.shape(res.trajectory.t), (name, k)


def test_zeta_arc_joins_the_drawn_a_axis_and_f(results):
    spec, res = results["libration-circular"]
    _, view = _show(spec, res)
    ex, traj = view.extra, res.trajectory
    for i in (0, len(traj.t) // 3, len(traj.t) - 1):
        view.set_frame(i)
        arc = np.asarray(ex._arc.points, float)
        a = quat.rotate(traj.quat_wxyz[i], np.array([1.0, 0.0, 0.0]))
        f = traj.bodies["attractor"][i] / np.linalg.norm(traj.bodies["attractor"][i])
        start, end = arc[0, 0], arc[-1, 1]
        assert np.allclose(start / np.linalg.norm(start), a, atol=1e-5)
        assert np.allclose(end / np.linalg.norm(end), f, atol=1e-5)
        # the arc spans the angle ζ of the scenario (|ζ| ≤ 180° here: a librating start)
        ang = np.degrees(np.arccos(np.clip(start @ end / np.linalg.norm(start) / np.linalg.norm(end), -1, 1)))
        z = np.degrees(traj.series["zeta_rad"][i])
        assert ang == pytest.approx(abs(z), abs=1e-3)
        assert ex._zlabel.text == f"ζ = {z:+.1f}°"
        # the line to F points at F
        fl = np.asarray(ex._fline.points, float)[0, 1]
        assert np.allclose(fl / np.linalg.norm(fl), f, atol=1e-5)


def test_phase_portrait_dot_follows_the_series_inside_the_separatrix(results):
    spec, res = results["libration-circular"]
    _, view = _show(spec, res)
    ex, s = view.extra, res.trajectory.series
    p = ex._panel
    assert "separatrix_zeta_rad" not in ex.plot_series(res) and "zeta_rad" in ex.plot_series(res)
    lo = np.nanmin(s["separatrix_zeta_rad"])
    for i in (0, 100, 777):
        view.set_frame(i)
        z = lo + np.remainder(s["zeta_rad"][i] - lo, np.pi)
        assert np.allclose(ex._pdot.position, p.map(z, s["zeta_dot"][i]), atol=1e-9)
    # the drawn points lie in the panel's plane and inside its frame
    sep = np.asarray(view._h["/world/extra/portrait/separatrix"].points, float)
    n = np.cross(p.r, p.u)
    assert np.max(np.abs((sep - p.c) @ n)) < 1e-4
    assert np.max(np.abs((sep - p.c) @ p.r)) <= p.size / 2 + 1e-4
    assert np.max(np.abs((sep - p.c) @ p.u)) <= p.size / 2 + 1e-4
    # a librating start (ζ₀ = 20°, locked spin) stays inside the drawn separatrix
    traj = np.asarray(view._h["/world/extra/portrait/trajectory"].points, float)
    assert np.max(np.abs((traj - p.c) @ p.u)) < np.max(np.abs((sep - p.c) @ p.u))


def test_portrait_option_off_removes_its_nodes(results):
    spec, res = results["libration-circular"]
    scene, view = _show(spec, res)
    assert "/world/extra/portrait/frame" in view._h
    view.set_option("portrait", False)
    assert not [n for n in view._h if n.startswith("/world/extra/portrait/")]
    assert ("remove", "add_line_segments", "/world/extra/portrait/frame", None, None) in scene.log
    view.set_option("portrait", True)
    assert "/world/extra/portrait/frame" in view._h


def test_hyperion_section_points_and_resonance_lines(results):
    spec, res = results["hyperion"]
    _, view = _show(spec, res)
    pts = np.asarray(view._h["/world/extra/section/points"].points, float)
    assert len(pts) == QUICK["hyperion"]["n_starts"] * QUICK["hyperion"]["n_orbits"]
    assert not [k for k in view.extra.plot_series(res) if k.startswith("section_")]
    lines = np.asarray(view._h["/world/extra/section/resonance_zones"].points, float)
    # map the drawn lines back to θ̇/n through the panel: they are p ± gp_half_width_p
    p = view.extra._section_panel
    y = p.ylim[0] + ((lines - p.c) @ p.u / p.size + 0.5) * (p.ylim[1] - p.ylim[0])
    assert np.allclose(y[:, 0], y[:, 1])  # horizontal
    m = res.metrics
    want = sorted(q + sgn * m[f"gp_half_width_{q:g}"] for q in (0.5, 1.0, 1.5, 2.0, 2.5) for sgn in (-1, 1))
    assert np.allclose(sorted(y[:, 0]), want, atol=1e-5)
    # and the section points are the scenario's (θ mod π, θ̇/n)
    th, w = res.plot_series["section_theta_mod_pi"], res.plot_series["section_theta_dot"]
    ok = np.isfinite(th)
    assert np.allclose(pts, p.map(th[ok], w[ok]), atol=1e-5)


def test_moon_view_from_the_earth(results):
    spec, res = results["moon"]
    _, view = _show(spec, res)
    ex, traj = view.extra, res.trajectory
    e = traj.bodies["earth"] / np.linalg.norm(traj.bodies["earth"], axis=1, keepdims=True)
    for i in (0, len(traj.t) // 2):
        cam = ex.follow_camera(traj, i)
        pos = np.asarray(cam["position"])
        assert np.allclose(pos / np.linalg.norm(pos), e[i], atol=1e-9)
        assert np.linalg.norm(pos) > 1.0 and cam["look_at"] == (0.0, 0.0, 0.0)
    # seen from the Earth the Earth's own marker would block the view: not drawn
    assert not [n for n in view._h if n.startswith("/world/bodies/")]
    # the time plot: one unit at a time (degrees for the face, arcseconds for the physical libration)
    assert set(ex.plot_series(res)) == {"libration_longitude_deg", "libration_latitude_deg", "ζ, Euler §833 (deg)"}
    view.set_option("plot_physical", True)
    assert set(ex.plot_series(res)) == {"physical_libration_arcsec", "physical_libration_euler_arcsec"}
    view.set_option("earth_view", False)
    assert ex.follow_camera(traj, 0) is None
    assert [n for n in view._h if n.startswith("/world/bodies/")]


def test_moon_maria_on_the_near_side():
    parts = ch16.moon_surface_parts(count=64)
    grey = {k: np.mean(rgb) for k, (_, _, rgb) in enumerate(parts)}
    centres = [(v[f].mean(axis=1), k) for k, (v, f, _) in enumerate(parts)]
    c = np.concatenate([x for x, _ in centres])
    part_of = np.concatenate([np.full(len(x), k) for x, k in centres])

    def at(lat, lon):
        la, lo = np.radians(lat), np.radians(lon)
        d = np.array([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)])
        return grey[int(part_of[np.argmax(c @ d)])]

    assert at(17, 59) < 120 and at(33, -16) < 120  # Mare Crisium (east), Mare Imbrium
    assert at(0, 180) > 160 and at(-60, 120) > 160  # far side, southern highlands
    assert sum(len(f) for _, f, _ in parts) == len(trimesh_sphere_faces(64))  # every face in one part


def trimesh_sphere_faces(count):
    import trimesh

    return trimesh.creation.uv_sphere(radius=1.0, count=[count, count]).faces


def test_magnified_wiggle_scales_the_departure_from_the_mean_cone():
    t = np.linspace(0.0, 10.0, 2001)
    p0, a, rate = np.radians(23.4), np.radians(0.01), -0.05
    p = p0 + a * np.cos(4 * t)
    lam = rate * t
    axis = np.stack([np.sin(p) * np.cos(lam), np.sin(p) * np.sin(lam), np.cos(p)], 1)
    path, k = ch16.magnified_wiggle(t, axis, target_deg=4.0)
    assert k == 200.0  # 4°/0.01° ≈ 400 → rounded down to a factor 1, 2 or 5 × 10ⁿ
    pd = np.arccos(path[:, 2])
    assert np.max(np.abs(pd - p.mean())) == pytest.approx(k * np.max(np.abs(p - p.mean())), rel=1e-6)
    assert np.max(np.abs(pd - p.mean())) > 0.9 * k * a
    path1, k1 = ch16.magnified_wiggle(t, axis, factor=1.0)
    assert k1 == 1.0 and np.allclose(path1, axis, atol=1e-9)


def test_precession_cone_and_wiggle(results):
    spec, res = results["precession-circular"]
    _, view = _show(spec, res)
    ex = view.extra
    assert "/world/extra/cone/mean_circle" in view._h
    view.set_frame(len(res.trajectory.t) // 2)
    now = np.asarray(ex._cone_live.points, float)[0, 1]
    assert np.allclose(now / np.linalg.norm(now), res.trajectory.figure_axis[len(res.trajectory.t) // 2], atol=1e-6)
    assert "/world/extra/wiggle_label" in view._h and ex.wiggle_factor >= 1.0
    # the magnified path on the sphere: the factor applied to the figure axis's own departures
    path, k = ch16.magnified_wiggle(res.trajectory.t, res.trajectory.figure_axis, factor=ex.wiggle_factor)
    assert np.allclose(ex._wig / np.linalg.norm(ex._wig, axis=1, keepdims=True), path, atol=1e-9)


def test_earth_stars_and_frame(results):
    spec, res = results["earth"]
    _, view = _show(spec, res)
    from theoria.app.bright_stars import load_bright_stars

    cat = load_bright_stars()
    labelled = [cat.names[int(n.rsplit("_", 1)[1])] for n in view._h if n.startswith("/world/extra/stars/label_")]
    assert {"Polaris", "Vega", "Thuban", "Deneb", "Sirius"} <= set(labelled) and len(labelled) >= 10
    stars = np.concatenate([np.asarray(view._h[n].points, float) for n in view._h if n.startswith("/world/extra/stars/mag_")])
    assert len(stars) == len(cat.names)
    # Polaris on the sphere within 1° of the J2000 celestial pole, here in ecliptic coordinates
    d = ch16.star_directions(cat)[cat.names.index("Polaris")]
    eps = np.radians(23.4392794)
    assert np.degrees(np.arccos(d @ np.array([0.0, np.sin(eps), np.cos(eps)]))) < 1.0
    # the figure axis starts at that pole too (the run starts at J2000)
    assert np.degrees(np.arccos(res.trajectory.figure_axis[0] @ np.array([0.0, np.sin(eps), np.cos(eps)]))) < 0.01
    names = set(view._h)
    assert {"/world/body/equator", "/world/body/earth_axis", "/world/extra/ecliptic", "/world/extra/sun_moon"} <= names
    view.set_frame(3)
    sm = np.asarray(view.extra._frame_lines.points, float)
    sun = res.trajectory.bodies["sun"][3]
    assert np.allclose(sm[0, 1] / np.linalg.norm(sm[0, 1]), sun / np.linalg.norm(sun), atol=1e-6)
    # the planetarium option: the camera looks at the ecliptic pole and the Earth mesh is hidden
    view.set_option("pole_view", True)
    assert view._h["/world/body/mesh"].visible is False
    cam = view.extra.follow_camera(res.trajectory, 0)
    assert cam is not None and cam["look_at"][2] > 2.0
    view.set_option("pole_view", False)
    assert view._h["/world/body/mesh"].visible is True and view.extra.follow_camera(res.trajectory, 0) is None


def test_session_applies_the_moons_camera_and_gives_the_view_back():
    """app/server.py ClientSession with the fake viser client of tests/test_gallery.py: the
    camera follows the Earth's direction while "view from the Earth" is on."""
    from test_gallery import _session, _wait

    with _session("moon") as (s, client):
        _wait(lambda: s.updates >= 1)
        with s._view_lock:
            s.view.set_frame(17)
            s._follow_camera()
            e = s.result.trajectory.bodies["earth"][17]
            pos = np.asarray(client.camera.position, float)
            assert np.allclose(pos / np.linalg.norm(pos), e / np.linalg.norm(e), atol=1e-9)
            assert client.camera.fov == pytest.approx(np.radians(ch16.MoonExtra.FOV_DEG))
            # the plot shows the extra's choice (degrees of the wobbling face)
            assert "ζ, Euler §833 (deg)" in s._plot_key
            cb = [h for h in s._option_handles if h.label.startswith("view from the Earth")][0]
            cb.value = False  # the checkbox's callback: option off → default camera and fov back
            assert client.camera.fov == pytest.approx(np.radians(75.0))
            assert tuple(client.camera.position) != tuple(pos)


def test_pole_near_axis_path_is_the_body_pole_magnified_about_its_start(results):
    spec, res = results["pole-near-axis"]
    _, view = _show(spec, res)
    ex = view.extra
    assert any(n.startswith("/world/body/pole_path/") for n in view._h)  # drawn on the body frame
    u = res.trajectory.omega_body / np.linalg.norm(res.trajectory.omega_body, axis=1, keepdims=True)
    k = ex.wiggle_factor
    assert k >= 10.0  # in the body the pole moves by a fraction of a degree in a few turns
    drawn = ex._pole / np.linalg.norm(ex._pole, axis=1, keepdims=True)
    # the drawn departure from the start is k times the true one (small angles)
    true = np.degrees(np.arccos(np.clip(u @ u[0], -1, 1)))
    shown = np.degrees(np.arccos(np.clip(drawn @ drawn[0], -1, 1)))
    j = int(np.argmax(true))
    assert shown[j] == pytest.approx(k * true[j], rel=0.02)
    view.set_frame(j)
    assert np.allclose(ex._pdot.position, ex._pole[j])


def test_gravity_accuracy_brings_f_in_at_its_distance_with_the_errors_there(results):
    spec, res = results["gravity-gradient-accuracy"]
    _, view = _show(spec, res)
    ex = view.extra
    traj = res.trajectory
    assert not any(n.startswith("/world/bodies/") for n in view._h)  # no second F on the sphere of directions
    assert view._h["/world/omega"].visible is False and view._h["/world/L"].visible is False  # no motion: no ω, L
    u = np.asarray(traj.bodies["attractor"][-1], float)
    u /= np.linalg.norm(u)
    last = len(traj.t) - 1
    view.set_frame(last)  # nearest: s = 1 / max_ratio body sizes, in view
    assert np.allclose(ex._F.position, u / traj.t[last])
    err = res.plot_series["torque_rel_error"][last]
    assert f"s = {1 / traj.t[last]:.3g} sizes" in ex._label.text and f"{100 * err:.2g} %" in ex._label.text
    view.set_frame(0)  # far away: waits at VIEW on its direction, and says so
    assert np.linalg.norm(ex._F.position) == pytest.approx(ex.VIEW) and "drawn nearer" in ex._label.text
