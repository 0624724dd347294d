"""The chapter 16 drawings (the `draw` of each ch. 16 scenario, helpers in
scenarios/_ch16_drawing.py), checked on the drawing data against the Run they read: the ζ arc
joins the drawn A axis and F and spans the run's ζ, the phase-portrait dot sits at (ζ, dζ/dt), the
section points and resonance lines map back to the run's (θ mod π, θ̇/n) and p ± the
Goldreich–Peale half-widths, the pole's paths and the stars are where the run and the catalogue
put them; rendered through the viser adapter with a fake scene, playback moves things only; the
time plot leaves out the point clouds."""
from __future__ import annotations

import numpy as np
import pytest

from theoria.app.scene import SceneView
from theoria.physics import quaternion as quat
from theoria.scenarios import _ch16_drawing as ch16
from theoria.scenarios import get
from theoria.scenarios.drawing import Follow, Label, Light, Path, View

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
    "earth-long-view": {"years": 3000.0},
}


@pytest.fixture(scope="module")
def runs():
    return {name: get(name).simulate(**given) for name, given in QUICK.items()}


def _drawing(runs, name, **options):
    run = runs[name]
    return run, get(name).drawing(run, View(options=options))


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _own(d):
    return {it.name: it for it in d.items if it.group == "scenario"}


@pytest.mark.parametrize("name", list(QUICK))
def test_drawing_is_per_frame_data_and_playback_only_moves(runs, name):
    run, d = _drawing(runs, name)
    spec = get(name)
    assert spec.draw is not None and spec.options, name
    F = d.n_frames
    assert _own(d), name
    for it in d.items:  # every animated attribute holds one value per frame
        for attr in it.animated():
            v = getattr(it, attr)
            assert len(v) == F, (name, it.name, attr)
        if isinstance(it, Path) and it.at is not None:
            assert len(it.at) == len(it.points) and 0 <= np.min(it.at) and np.max(it.at) <= F - 1, (name, it.name)
    for k, v in d.plot.items():  # the time plot: only series on the run's samples
        assert np.shape(v) == np.shape(run.trajectory.t), (name, k)
    assert len(set(d.names())) == len(d.names()), name  # names are unique
    # rendered by the viser adapter: after the first show, playback sends no new node
    scene = FakeScene()
    view = SceneView(scene)
    view.show(d)
    assert "/world/" + next(iter(_own(d))) in view._h, name
    scene.log.clear()
    for k in range(0, F, max(1, F // 40)):
        view.set_frame(k)
    assert not [e for e in scene.log if e[0] != "set"], name  # nothing added or removed
    assert {e[3] for e in scene.log} <= {"wxyz", "points", "position", "visible", "text"}, name


def test_zeta_arc_joins_the_drawn_a_axis_and_f(runs):
    run, d = _drawing(runs, "libration-circular")
    tr, own = run.trajectory, _own(d)
    arcs = np.asarray(own["zeta_arc"].points, float)  # (F, 23, 2, 3)
    fline = np.asarray(own["f_direction"].points, float)  # (F, 1, 2, 3)
    assert arcs.shape == (d.n_frames, ch16.ARC_POINTS - 1, 2, 3)
    assert np.allclose(arcs[:, 1:, 0], arcs[:, :-1, 1])  # one connected arc per frame
    for k in (0, d.n_frames // 3, d.n_frames - 1):
        i = d.frames[k]
        a = quat.rotate(tr.quat_wxyz[i], np.array([1.0, 0.0, 0.0]))
        f = _unit(tr.bodies["attractor"][i])
        start, end = arcs[k, 0, 0], arcs[k, -1, 1]
        assert np.allclose(_unit(start), a, atol=1e-9) and np.allclose(_unit(end), f, atol=1e-9)
        # the arc spans the run's ζ (|ζ| ≤ 180° here: a librating start)
        ang = np.degrees(np.arccos(np.clip(_unit(start) @ _unit(end), -1, 1)))
        z = np.degrees(tr.series["zeta_rad"][i])
        assert ang == pytest.approx(abs(z), abs=1e-6)
        assert own["zeta_label"].text[k].startswith(f"ζ = {z:+.1f}°")
        assert np.allclose(_unit(fline[k, 0, 1]), f, atol=1e-9)  # the line to F points at F
    # the A axis drawn long is fixed on the body (the Frame "body" turns it)
    assert own["body/a_direction"].animated() == [] and np.allclose(own["body/a_direction"].points[0, 1],
                                                                   [ch16.A_LENGTH, 0, 0])
    # F's marker is named F, at F's direction
    ball = d.item("bodies/F")
    assert np.allclose(_unit(ball.position), _unit(tr.bodies["attractor"][d.frames]), atol=1e-9)


def test_zeta_of_gravity_start_is_the_arc_af(runs):
    """gravity-start has no ζ series: the read-out is the angle of F from the drawn A axis (§815)."""
    run, d = _drawing(runs, "gravity-start")
    tr = run.trajectory
    k = d.n_frames - 1
    a = quat.rotate(tr.quat_wxyz[d.frames[k]], np.array([1.0, 0.0, 0.0]))
    f = _unit(tr.bodies["attractor"][d.frames[k]])
    assert _own(d)["zeta_label"].text[k].startswith(f"ζ = {np.degrees(np.arccos(a @ f)):.1f}°")
    assert "orbit" not in get("gravity-start").options and "f_orbit" not in _own(d)  # F does not move


def test_eccentric_orbit_in_true_shape_with_f_on_it(runs):
    run, d = _drawing(runs, "libration-eccentric")
    own = _own(d)
    pos = np.asarray(run.trajectory.bodies["attractor"], float)
    k = ch16.ORBIT_RADIUS / np.linalg.norm(pos, axis=1).mean()
    assert np.allclose(own["f_on_orbit"].position, k * pos[d.frames])
    r = np.linalg.norm(np.asarray(own["f_orbit"].points, float)[:, 0], axis=1)
    e = QUICK["libration-eccentric"].get("eccentricity", get("libration-eccentric").resolve({})["eccentricity"])
    assert r.max() / r.min() == pytest.approx((1 + e) / (1 - e), rel=1e-3)  # apoapse / periapse
    _, d2 = _drawing(runs, "libration-eccentric", orbit=False, zeta=False)
    assert not {"f_orbit", "f_on_orbit", "zeta_arc", "zeta_label"} & set(_own(d2))


def test_phase_portrait_dot_follows_the_series_inside_the_separatrix(runs):
    run, d = _drawing(runs, "libration-circular")
    s, own = run.trajectory.series, _own(d)
    assert "zeta_rad" in d.plot and not [k for k in d.plot if k.startswith("separatrix_")]
    frame = np.asarray(own["portrait/frame"].points, float).reshape(-1, 3)  # float32 segments
    centre = frame.mean(axis=0)
    right, up, _ = ch16.camera_basis(d.camera)
    normal = np.cross(right, up)
    lo = float(np.nanmin(s["separatrix_zeta_rad"]))
    # the panel's data → scene map, read off its frame: x from lo to lo + π, y symmetric
    xs, ys = (frame - centre) @ right, (frame - centre) @ up
    size = np.ptp(xs)
    sep = np.asarray(own["portrait/separatrix"].points, float)
    ymax = np.nanmax(np.abs(s["separatrix_zeta_dot_plus"])) / (np.max((sep - centre) @ up) / (size / 2))
    p = ch16.Panel(centre, right, up, (lo, lo + np.pi), (-ymax, ymax), size=size)
    dots = np.asarray(own["portrait/state"].position, float)
    for k in (0, 100, 777):
        i = d.frames[k]
        z = lo + np.remainder(s["zeta_rad"][i] - lo, np.pi)
        assert np.allclose(dots[k], p.map(z, s["zeta_dot"][i]), atol=1e-6)
    zs, zd = p.unmap(sep)
    plus = np.interp(zs, s["separatrix_zeta_rad"], s["separatrix_zeta_dot_plus"])
    assert np.allclose(np.abs(zd), plus, atol=1e-6 * ymax)  # the run's separatrix ±
    # everything drawn lies in the panel's plane, inside its frame
    for pts in (sep, np.asarray(own["portrait/trajectory"].points, float), dots):
        assert np.max(np.abs((pts - centre) @ normal)) < 1e-6
        assert np.max(np.abs((pts - centre) @ right)) <= size / 2 + 1e-6
        assert np.max(np.abs((pts - centre) @ up)) <= size / 2 + 1e-6
    # a librating start (ζ₀ = 20°, locked spin) stays inside the drawn separatrix
    traj = np.asarray(own["portrait/trajectory"].points, float)
    assert np.max(np.abs((traj - centre) @ up)) < np.max(np.abs((sep - centre) @ up))
    _, off = _drawing(runs, "libration-circular", portrait=False)
    assert not [n for n in _own(off) if n.startswith("portrait/")]


def test_hyperion_section_points_and_resonance_lines(runs):
    run, d = _drawing(runs, "hyperion")
    own = _own(d)
    assert not [k for k in d.plot if k.startswith("section_")] and "zeta_rad" in d.plot
    pts = np.asarray(own["section/points"].points, float)
    assert len(pts) == QUICK["hyperion"]["n_starts"] * QUICK["hyperion"]["n_orbits"]
    # the panel: its frame's corners are (0, y0), (π, y0), (π, y1), (0, y1)
    corners = np.asarray(own["section/frame"].points, float)[:, 0]
    right, up, _ = ch16.camera_basis(d.camera)
    centre = corners.mean(axis=0)
    size = np.ptp((corners - centre) @ right)
    sec = run.extras["section"]
    th, w = sec["theta_mod_pi"].ravel(), sec["theta_dot"].ravel()  # start by start
    ok = np.isfinite(th) & np.isfinite(w)
    # y0, y1 from the points: the lowest and highest drawn point are the run's extreme θ̇/n
    fy = (pts - centre) @ up / size + 0.5
    j0, j1 = np.argmin(fy), np.argmax(fy)
    scale = (w[ok][j1] - w[ok][j0]) / (fy[j1] - fy[j0])
    ylim = (w[ok][j0] - fy[j0] * scale, w[ok][j0] + (1 - fy[j0]) * scale)
    p = ch16.Panel(centre, right, up, (0.0, np.pi), ylim, size=size)
    assert np.allclose(pts, p.map(th[ok], w[ok]), atol=1e-9)  # the run's (θ mod π, θ̇/n)
    # chaotic (λ > 0.05 per orbit) red, regular blue
    red = np.all(np.asarray(own["section/points"].colors) == (215, 60, 40), axis=1)
    per_point = np.repeat(sec["lyapunov_per_orbit"], sec["theta_mod_pi"].shape[1])
    assert np.array_equal(red, per_point[ok] > 0.05)
    # the resonance lines map back to p ± gp_half_width_p
    lines = np.asarray(own["section/resonance_zones"].points, float)
    _, y = p.unmap(lines - 0.03 * p.normal)
    assert np.allclose(y[:, 0], y[:, 1])  # horizontal
    m = run.metrics
    want = sorted(q + sgn * m[f"gp_half_width_{q:g}"] for q in (0.5, 1.0, 1.5, 2.0, 2.5) for sgn in (-1, 1)
                  if ylim[0] <= q + sgn * m[f"gp_half_width_{q:g}"] <= ylim[1])
    assert np.allclose(sorted(y[:, 0]), want, atol=1e-9)
    assert own["section/res_1"].text == f"1:1 ± {m['gp_half_width_1']:.2f}"


def test_moon_view_from_the_earth(runs):
    run, d = _drawing(runs, "moon", earth_view=True)
    tr = run.trajectory
    e = _unit(tr.bodies["earth"][d.frames])
    assert isinstance(d.follow, Follow)
    pos = np.asarray(d.follow.position, float)
    assert np.allclose(_unit(pos), e, atol=1e-12) and np.all(np.linalg.norm(pos, axis=1) > 1.0)
    assert tuple(d.follow.look_at) == (0.0, 0.0, 0.0) and d.follow.fov_deg == pytest.approx(60.0)
    assert np.allclose(d.camera.position, pos[0])  # a recording or replay starts from the Earth too
    light = next(it for it in d.items if isinstance(it, Light))
    assert np.allclose(_unit(light.position), e)  # a full Moon: lit from the Earth's side
    # seen from the Earth the Earth's own marker would block the view: not drawn
    assert not [n for n in d.names() if n.startswith("bodies/")]
    # the body is drawn with the Moon's face (maria), not in bands
    meshes = [it for it in d.items if it.name.startswith("body/mesh/")]
    assert {tuple(m.color) for m in meshes} == {ch16.MOON_HIGHLAND, ch16.MOON_MARE, ch16.MOON_CRATER}
    # the time plot: one unit at a time (degrees for the face, arcseconds for the physical libration)
    assert set(d.plot) == {"libration_longitude_deg", "libration_latitude_deg", "ζ, Euler §833 (deg)"}
    assert np.allclose(d.plot["ζ, Euler §833 (deg)"], np.degrees(run.plot_series["zeta_euler_rad"]))
    _, d2 = _drawing(runs, "moon", plot_physical=True, earth_view=False, maria=False)
    assert set(d2.plot) == {"physical_libration_arcsec", "physical_libration_euler_arcsec"}
    assert d2.follow is None and "bodies/earth" in d2.names() and "bodies/attractor" not in d2.names()
    line = np.asarray(_own(d2)["earth_direction"].points, float)[:, 0, 1]
    assert np.allclose(_unit(line), e, atol=1e-12)
    assert ch16.MOON_MARE not in {tuple(it.color) for it in d2.items if it.name.startswith("body/mesh/")}


def test_moon_maria_on_the_near_side():
    parts = ch16.moon_surface_parts()
    grey = {k: np.mean(rgb) for k, (_, _, rgb) in enumerate(parts)}
    centres = [(_unit(v[f].mean(axis=1)), k) for k, (v, f, _) in enumerate(parts)]
    c = np.concatenate([x for x, _ in centres])
    part_of = np.concatenate([np.full(len(x), k) for x, k in centres])

    def at(lat, lon):
        la, lo = np.radians(lat), np.radians(lon)
        return grey[int(part_of[np.argmax(c @ np.array([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)]))])]

    assert at(17, 59) < 120 and at(33, -16) < 120  # Mare Crisium (east), Mare Imbrium
    assert at(0, 180) > 160 and at(-60, 120) > 160  # far side, southern highlands
    assert at(-43, -11) > 230  # Tycho
    # the parts together cover the sphere once: their area is 4π
    area = sum(0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum()
               for v, f, _ in parts)
    assert area == pytest.approx(4 * np.pi, rel=2e-3)


def test_magnified_wiggle_scales_the_departure_from_the_mean_cone():
    t = np.linspace(0.0, 10.0, 2001)
    p0, a, rate = np.radians(23.4), np.radians(0.01), -0.05
    p = p0 + a * np.cos(4 * t)
    lam = rate * t
    axis = np.stack([np.sin(p) * np.cos(lam), np.sin(p) * np.sin(lam), np.cos(p)], 1)
    path, k = ch16.magnified_wiggle(t, axis, target_deg=4.0)
    assert k == 200.0  # 4°/0.01° = 400 → rounded down to a factor 1, 2 or 5 × 10ⁿ
    pd = np.arccos(path[:, 2])
    assert np.max(np.abs(pd - p.mean())) == pytest.approx(k * np.max(np.abs(p - p.mean())), rel=1e-6)
    path1, k1 = ch16.magnified_wiggle(t, axis, factor=1.0)
    assert k1 == 1.0 and np.allclose(path1, axis, atol=1e-9)


def test_precession_cone_and_wiggle(runs):
    run, d = _drawing(runs, "precession-circular")
    own, tr = _own(d), run.trajectory
    now = np.asarray(own["cone/now"].points, float)[:, 0, 1]
    assert np.allclose(_unit(now), tr.figure_axis[d.frames], atol=1e-12)
    # the mean cone: the circle at the figure axis's mean polar angle about the orbit pole
    circ = np.asarray(own["cone/mean_circle"].points, float)[:, 0]
    assert np.allclose(np.arccos(_unit(circ)[:, 2]), np.arccos(tr.figure_axis[:, 2]).mean())
    # the magnified path: the factor in its label applied to the figure axis's own departures
    k = float(own["wiggle_label"].text.split("×")[1])
    path, _ = ch16.magnified_wiggle(tr.t, tr.figure_axis, factor=k)
    idx = ch16.frame_indices(len(tr.t), ch16.MAX_PATH_SAMPLES)
    assert np.allclose(_unit(own["wiggle"].points), path[idx], atol=1e-12)
    assert np.allclose(_unit(own["wiggle_now"].position), path[d.frames], atol=1e-12)
    assert k >= 1.0 and np.array_equal(own["wiggle"].at, d.frame_of_sample(idx))
    _, off = _drawing(runs, "precession-circular", wiggle=False, centre=False)
    assert "wiggle" not in _own(off) and "cone/now" in _own(off) and "centre_direction" not in _own(off)


def test_the_nutations_factor_is_written_on_its_path_away_from_the_orbit_pole(runs):
    """At an obliquity of 23° the magnified path runs close to the orbit pole on the screen, and its
    factor, written above the path's middle, sat on the "orbit pole" label (24 px apart). It is
    written just outside a point of the path's first half, the one farthest from that label, and
    a camera projection computed here by hand (pinhole, 75° vertical view, 1280×800) puts them more
    than the width of "orbit pole" (~70 px) apart."""
    run = get("precession-circular").simulate(resonance_table="off")  # its 100 orbits: the cone's path half done
    d = get("precession-circular").drawing(run)
    own = _own(d)
    cam = d.camera
    P, L, up = (np.asarray(v, float) for v in (cam.position, cam.look_at, cam.up))
    f = _unit(L - P)
    r = _unit(np.cross(f, up))
    u = np.cross(r, f)
    t = np.tan(np.radians(75.0 / 2))

    def pixel(x):
        v = np.asarray(x, float) - P
        return np.array([640 * (1 + (v @ r) / (v @ f) / (t * 1.6)), 400 * (1 - (v @ u) / (v @ f) / t)])

    apart = np.linalg.norm(pixel(own["wiggle_label"].position) - pixel(own["cone/orbit_pole_label"].position))
    assert apart > 80, apart  # 24 px before; now 94
    path = np.asarray(own["wiggle"].points, float)
    first_half = path[: len(path) // 2 + 1]
    near = np.min(np.linalg.norm(1.08 * first_half - np.asarray(own["wiggle_label"].position), axis=1))
    assert near < 0.05 * np.linalg.norm(path[0]), near  # beside a point of the path drawn by half-way


def test_earth_stars_and_frame(runs):
    from theoria.app.bright_stars import load_bright_stars

    run, d = _drawing(runs, "earth")
    own, tr = _own(d), run.trajectory
    cat = load_bright_stars()
    labelled = {own[n].text for n in own if n.startswith("stars/label_")}
    assert {"Polaris", "Vega", "Thuban", "Deneb", "Sirius"} <= labelled and len(labelled) >= 10
    stars = np.concatenate([own[n].points for n in own if n.startswith("stars/mag_")])
    assert len(stars) == len(cat.names)
    # Polaris on the sphere within 1° of the J2000 celestial pole, here in ecliptic coordinates
    eps = np.radians(23.4392794)  # IAU 2006 obliquity at J2000
    pole = np.array([0.0, np.sin(eps), np.cos(eps)])
    j = cat.names.index("Polaris")
    assert np.degrees(np.arccos(ch16.star_directions(cat)[j] @ pole)) < 1.0
    assert np.allclose(own[f"stars/label_{j}"].position, ch16.CELESTIAL_RADIUS * 1.03 * ch16.star_directions(cat)[j])
    # the figure axis starts at that pole too (the run starts at J2000), and the cone follows it
    assert np.degrees(np.arccos(tr.figure_axis[0] @ pole)) < 0.01
    assert np.allclose(_unit(np.asarray(own["cone/now"].points)[:, 0, 1]), tr.figure_axis[d.frames], atol=1e-12)
    assert {"body/equator", "body/earth_axis", "ecliptic", "sun_moon", "wiggle"} <= set(own)
    sm = np.asarray(own["sun_moon"].points, float)
    assert np.allclose(_unit(sm[:, 0, 1]), _unit(tr.bodies["sun"][d.frames]), atol=1e-12)
    assert np.allclose(_unit(sm[:, 1, 1]), _unit(tr.bodies["moon"][d.frames]), atol=1e-12)
    assert "body_trails/moon" not in d.names() and "body_trails/sun" in d.names()
    # the planetarium option: the camera looks at the ecliptic pole from inside, no Earth mesh
    _, pv = _drawing(runs, "earth", pole_view=True)
    assert not [n for n in pv.names() if n.startswith("body/mesh/")] and "body/equator" not in pv.names()
    assert pv.follow is not None and pv.follow.look_at[2] > 2.0 and len(pv.follow.position) == pv.n_frames
    assert "cone/generators" not in pv.names() and d.follow is None


def test_earth_long_view_pole_among_the_stars_with_year_marks(runs):
    run, d = _drawing(runs, "earth-long-view")
    own, tr = _own(d), run.trajectory
    assert "wiggle" not in get("earth-long-view").options and "wiggle" not in own  # no nutation to magnify
    axis = _unit(tr.L_inertial)  # the scenario's pole path
    assert np.allclose(_unit(np.asarray(own["cone/now"].points)[:, 0, 1]), axis[d.frames], atol=1e-12)
    marks = np.asarray(own["pole_years/points"].points, float)
    years = np.arange(0.0, tr.t[-1] + 1e-9, 1000.0)  # a 3000-year run: every 1000 years
    assert len(marks) == len(years)
    for y, m in zip(years, marks):
        assert np.allclose(_unit(m), axis[np.argmin(np.abs(tr.t - y))], atol=1e-12)
    texts = {it.text for n, it in own.items() if n.startswith("pole_years/") and isinstance(it, Label)}
    assert {"AD 2000", "AD 4000"} <= texts


def test_pole_near_axis_path_is_the_body_pole_magnified_about_its_start(runs):
    run, d = _drawing(runs, "pole-near-axis")
    own = _own(d)
    path = own["body/pole_path"]  # drawn on the body frame: it turns with the body
    assert isinstance(path, Path) and path.name.startswith("body/")
    u = _unit(run.trajectory.omega_body)
    k = float(own["body/pole_label"].text.split("×")[1].split(";")[0])
    assert k >= 10.0  # in the body the pole moves by a fraction of a degree in a few turns
    idx = ch16.frame_indices(len(u), ch16.MAX_PATH_SAMPLES)
    drawn = _unit(path.points)
    true = np.degrees(np.arccos(np.clip(u[idx] @ u[0], -1, 1)))
    shown = np.degrees(np.arccos(np.clip(drawn @ drawn[0], -1, 1)))
    j = int(np.argmax(true))
    assert shown[j] == pytest.approx(k * true[j], rel=0.03)
    assert np.allclose(own["body/pole_now"].position, 1.6 * _unit(u[0] + k * (u[d.frames] - u[0])))
    # the scale's rings: a pole θ from the start (a ring's true angle) is drawn on the ring
    step = float(own["body/pole_label"].text.split("rings ")[1].split("°")[0])
    rings = np.asarray(own["body/pole_scale"].points, float)[:, 0]
    ang = np.degrees(np.arccos(np.clip(_unit(rings) @ u[0], -1, 1)))
    th = np.radians(step)
    tb = _unit(np.array([0.0, 1.0, 0.0]) - u[0, 1] * u[0])
    pole = np.cos(th) * u[0] + np.sin(th) * tb
    want = np.degrees(np.arccos(_unit(u[0] + k * (pole - u[0])) @ u[0]))
    assert np.min(np.abs(ang - want)) < 1e-5  # segments are float32


def test_gravity_accuracy_brings_f_in_at_its_distance_with_the_errors_there(runs):
    run, d = _drawing(runs, "gravity-gradient-accuracy")
    own, tr = _own(d), run.trajectory
    assert not [n for n in d.names() if n.startswith("bodies/")]  # no second F on the sphere of directions
    assert d.overlays["vectors"] is False  # nothing moves: no ω, L
    u = _unit(tr.bodies["attractor"][-1])
    last = d.n_frames - 1  # nearest: s = 1 / max_ratio body sizes, in view
    assert np.allclose(own["F"].position[last], u / tr.t[d.frames[last]])
    err = run.plot_series["torque_rel_error"][d.frames[last]]
    text = own["F_readout"].text[last]
    assert f"s = {1 / tr.t[d.frames[last]]:.3g} sizes" in text and f"{100 * err:.2g} %" in text
    # far away: F at F_VIEW on its direction, and says so; between, nearer at every frame (it waited
    # at F_VIEW for all but the last frames while only the caption changed)
    from theoria.scenarios.gravity_gradient_accuracy import F_VIEW

    assert np.linalg.norm(own["F"].position[0]) == pytest.approx(F_VIEW) and "drawn nearer" in own["F_readout"].text[0]
    r = np.linalg.norm(np.asarray(own["F"].position, float), axis=1)
    assert np.all(np.diff(r) < 0) and d.n_frames >= 10, r


def test_session_applies_the_moons_camera_and_gives_the_view_back():
    """app/server.py ClientSession with the fake viser client of tests/test_gallery.py: the
    camera follows the Earth's direction while "view from the Earth" is on."""
    from test_gallery import _session, _wait

    with _session("moon") as (s, client):
        _wait(lambda: s.updates >= 1)
        assert s.drawing.follow is None and "face" in s.drawing.names()  # by default: space, the face beside
        on = [h for h in s._option_handles if "view from the earth" in h.label.lower()][0]
        on.value = True
        with s._view_lock:
            s.view.set_frame(17)
            s._follow_camera()
            e = s.result.trajectory.bodies["earth"][s.drawing.frames[17]]
            pos = np.asarray(client.camera.position, float)
            assert np.allclose(pos / np.linalg.norm(pos), e / np.linalg.norm(e), atol=1e-9)
            assert client.camera.fov == pytest.approx(np.radians(60.0))
            assert "ζ, Euler §833 (°)" in s._plot_key  # the plot shows the drawing's choice
        cb = on
        cb.value = False  # the checkbox's callback: option off → the scenario's camera and fov back
        assert client.camera.fov == pytest.approx(np.radians(75.0))
        assert tuple(client.camera.position) != tuple(pos)


def test_a_new_run_updates_the_live_viser_nodes_in_place(runs):
    """On viser's own scene API (a server, no browser): a second run of a ch. 16 scene (the app
    after a parameter change) updates the existing nodes, one-colour segments and points included
    (an existing handle takes colours only as an array), and an option's redraw prunes its items."""
    import contextlib
    import io

    import viser

    with contextlib.redirect_stdout(io.StringIO()):
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        spec = get("libration-circular")
        view = SceneView(server.scene)
        view.show(spec.drawing(runs["libration-circular"]))
        frame = view._h["/world/portrait/frame"]
        view.show(spec.drawing(spec.simulate(zeta0_deg=40.0, periods=2.0)))
        assert view._h["/world/portrait/frame"] is frame  # the same node, new data
        assert np.array_equal(np.asarray(frame.colors).reshape(-1, 3)[0], ch16.PANEL_COLOR)
        view.set_frame(view.n - 1)
        view.show(spec.drawing(runs["libration-circular"], View(options={"portrait": False})))
        assert not [n for n in view._h if n.startswith("/world/portrait")]
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()


# A 1280×800 browser with the control panel at its right side: docked (the canvas is the rest, the
# look-at point in its middle) or dragged over the canvas (app/browser.py `frame` draws the look-at
# point in the middle of the part left free), the same picture. The panel takes 387 px, 561 px in
# presenter mode (measured on screenshots); the test leaves a little more.
PANEL_COVERS_PX = (400.0, 572.0)


@pytest.mark.parametrize("name,chart", [("hyperion", "section/frame"), ("libration-circular", "portrait/frame")])
def test_a_chart_beside_the_body_is_on_the_screen_with_the_body(runs, name, chart):
    """The surface of section and the phase portrait stand left of the body: with the view aimed at
    the body, their left half and their titles were off a 1280×800 screen. Projected as the
    browser draws them (drawing.py's `_project` matches the screenshots' scale), the chart and the
    body's celestial sphere both fit in the part of the canvas the panel leaves free."""
    from theoria.scenarios.drawing import CELESTIAL_RADIUS, _project

    _, d = _drawing(runs, name)
    right = ch16.camera_basis(d.camera)[0]
    points = np.concatenate([np.asarray(d.item(chart).points, float).reshape(-1, 3),
                             [CELESTIAL_RADIUS * right, -CELESTIAL_RADIUS * right]])  # the sphere about the body
    x = _project(points, d.camera)[0][:, 0]
    for covered in PANEL_COVERS_PX:
        shown = x - covered / 2  # the look-at point drawn in the middle of the free part
        assert shown.min() >= 0 and shown.max() <= 1280 - covered, (covered, shown.min(), shown.max())
    # with the chart switched off the view is the body's own again
    _, alone = _drawing(runs, name, **{name == "hyperion" and "section" or "portrait": False})
    assert alone.camera == get(name).camera
