"""What the chapter 16 scenes draw besides the body (shared by their `draw` functions).

Everything is read from the Run: the attitudes and derived paths of the trajectory (figure axis,
L, ω on the body), `trajectory.bodies` (the centre of force, the Sun, the Moon), the series (ζ,
dζ/dt, the separatrix, the surface of section) and the metrics (Goldreich–Peale half-widths).
A drawing only changes coordinates (unit vectors → angles on a sphere, scaling into a flat panel)
and never integrates or re-derives a physical quantity. Per-frame data are arrays over the
drawing's frames, computed once.

- F and ζ (§820–838): the line to F, the A axis drawn long, the arc ζ from A to F (§825: ζ is
  the arc AF, measured about C in the plane problems) with its value, F's orbit in true shape.
- a flat `Panel` facing the camera for the charts (phase portrait, surface of section).
- the precession cone (§844–849): the figure axis's path on the celestial sphere, the mean cone
  about the orbit pole, and the nutation magnified (`magnified_wiggle`).
- the Moon's near side (maria) and the bright stars in the J2000 ecliptic frame.
"""
from __future__ import annotations

import dataclasses
import functools

import numpy as np

from ..physics import quaternion as quat
from ..physics.precession import pole_angles
from .drawing import (CELESTIAL_RADIUS, ORBIT_RADIUS, Camera, Drawing, Follow, Label, Option, Path, Points, Segments,
                      Sphere, View, _project, frame_indices, mesh_parts, new_drawing, other_bodies, rigid_body, segments,
                      sphere_grid, unit)

F_COLOR = (200, 40, 160)
ZETA_COLOR = (230, 120, 0)
A_COLOR = (220, 50, 47)
ORBIT_COLOR = (150, 110, 170)
PANEL_COLOR = (90, 90, 100)
PANEL_AXES_COLOR = (170, 170, 180)
POINT_COLOR = (40, 90, 200)
SEPARATRIX_COLOR = (200, 40, 40)
STAR_COLOR = (25, 30, 80)
CONE_COLOR = (38, 110, 220)
CONE_LIGHT = (120, 160, 230)
WIGGLE_COLOR = (200, 30, 60)
PANEL_SIZE = 2.6
A_LENGTH = 1.5  # the A axis drawn long, beyond the body (largest semi-axis 1)
ZETA_RADIUS = 0.9 * A_LENGTH
ARC_POINTS = 24
READOUT_DOWN = 2.75  # a read-out label this far below the look-at point on the screen (outside the sphere of 2.4)
MAX_PATH_SAMPLES = 10000  # samples of a pole path: the renderers thin it further


def body_scene(run, spec, view: View, bodies=None, trails=lambda name: True) -> tuple[Drawing, np.ndarray]:
    """The standard rotation scene (the body and Poinsot's construction, other bodies) with the
    bodies a ch. 16 scene chooses; returns the drawing and the body's drawn semi-axes."""
    d = new_drawing(run, spec)
    semi = rigid_body(d, run, view)
    other_bodies(d, run, bodies=bodies, trails=trails)
    return d, semi


def centre_of_force(run) -> np.ndarray:
    """Positions (N, 3) of the centre of force: the first of the run's bodies."""
    return np.asarray(next(iter(run.trajectory.bodies.values())), float)


def camera_basis(camera: Camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Right and up unit vectors of the screen and the look-at point of `camera` (+z up): a panel
    spanned by them faces the camera."""
    look = np.asarray(camera.look_at, float)
    view = -unit(np.asarray(camera.position, float) - look)
    right = unit(np.cross(view, [0.0, 0.0, 1.0]))
    up = np.cross(right, view)
    return right, up, look


class Panel:
    """A flat 2-D chart in the scene: data (x, y) in [x0, x1] × [y0, y1] mapped onto a square of
    side `size` centred at `centre`, spanned by the unit vectors `right` and `up`."""

    def __init__(self, centre, right, up, xlim, ylim, size=PANEL_SIZE):
        self.c, self.r, self.u = np.asarray(centre, float), np.asarray(right, float), np.asarray(up, float)
        self.xlim, self.ylim, self.size = tuple(xlim), tuple(ylim), float(size)

    def map(self, x, y) -> np.ndarray:
        x, y = np.asarray(x, float), np.asarray(y, float)
        fx = (x - self.xlim[0]) / (self.xlim[1] - self.xlim[0]) - 0.5
        fy = (y - self.ylim[0]) / (self.ylim[1] - self.ylim[0]) - 0.5
        return self.c + self.size * (fx[..., None] * self.r + fy[..., None] * self.u)

    def unmap(self, p) -> tuple[np.ndarray, np.ndarray]:
        """Data coordinates of scene points on the panel (the inverse of `map`)."""
        q = np.asarray(p, float) - self.c
        fx, fy = q @ self.r / self.size + 0.5, q @ self.u / self.size + 0.5
        return (self.xlim[0] + fx * (self.xlim[1] - self.xlim[0]),
                self.ylim[0] + fy * (self.ylim[1] - self.ylim[0]))

    def frame(self) -> np.ndarray:
        x0, x1 = self.xlim
        y0, y1 = self.ylim
        return segments(self.map(np.array([x0, x1, x1, x0, x0]), np.array([y0, y0, y1, y1, y0])))

    def hline(self, y) -> np.ndarray:
        return self.map(np.array(self.xlim), np.array([y, y]))[None]

    def vline(self, x) -> np.ndarray:
        return self.map(np.array([x, x]), np.array(self.ylim))[None]

    @property
    def normal(self) -> np.ndarray:
        return np.cross(self.r, self.u)


# sideways reach of a body's scene on the screen from its centre: the celestial sphere and F's label
SCENE_REACH = CELESTIAL_RADIUS + 0.3
PANEL_VIEW_BACK = 1.3  # the camera this much farther back when a chart stands beside the body


def frame_with_panel(d: Drawing, panel: Panel) -> None:
    """Aim the view at the middle of the body's scene and a chart beside it (left of it on the
    screen), the camera moved sideways and a little back, still looking the same way. Aimed at
    the body alone, the chart's left half and its title were off a 1280×800 screen."""
    right, _, look = camera_basis(d.camera)
    left = float((panel.c - look) @ right) - 0.5 * panel.size
    shift = 0.5 * (left + SCENE_REACH) * right
    pos = np.asarray(d.camera.position, float)
    d.camera = dataclasses.replace(d.camera, look_at=tuple(look + shift),
                                   position=tuple(look + shift + PANEL_VIEW_BACK * (pos - look)))


def great_arcs(a, b, radius: float, n: int = ARC_POINTS) -> np.ndarray:
    """Points (F, n, 3) of the shorter great-circle arc from each unit vector a[k] to b[k] (F, 3);
    opposite vectors get a half great circle, equal ones a point repeated."""
    a, b = unit(a), unit(b)
    ang = np.arccos(np.clip(np.sum(a * b, axis=1), -1.0, 1.0))
    normal = np.cross(a, b)
    alt = np.cross(a, [0.0, 0.0, 1.0])
    alt = np.where(np.linalg.norm(alt, axis=1, keepdims=True) > 1e-9, alt, np.cross(a, [1.0, 0.0, 0.0]))
    normal = unit(np.where(np.linalg.norm(normal, axis=1, keepdims=True) > 1e-9, normal, alt))
    perp = np.cross(normal, a)
    th = ang[:, None] * np.linspace(0.0, 1.0, n)[None, :]
    return radius * (np.cos(th)[..., None] * a[:, None, :] + np.sin(th)[..., None] * perp[:, None, :])


def readout_position(d: Drawing, down: float = READOUT_DOWN, left: float = 1.0) -> np.ndarray:
    """Where a read-out label goes: `down` below the camera's look-at point on the screen (under
    the scene, where no other label is) and `left` to its left (a label starts at its point)."""
    right, up, look = camera_basis(d.camera)
    return look - down * up - left * right


def wrap(x, lo, period):
    return lo + np.remainder(np.asarray(x, float) - lo, period)


def signed_deg(z) -> np.ndarray:
    """An angle in radians as degrees in [−180°, 180°)."""
    return np.degrees(np.remainder(np.asarray(z, float) + np.pi, 2 * np.pi) - np.pi)


def line_from_centre(points) -> np.ndarray:
    """(F, 3) end points → (F, 1, 2, 3) one segment per frame from the origin."""
    p = np.asarray(points, float)
    return np.stack([np.zeros_like(p), p], axis=1)[:, None]


# ---- F and ζ -------------------------------------------------------------------------------------

ZETA_OPTION = {"zeta": Option("angle ζ: arc from the A axis to F")}
ORBIT_OPTION = {"orbit": Option("orbit of F (true shape, scaled)")}


def f_and_zeta(d: Drawing, run, spec, view: View, zeta_key: str = "zeta_rad") -> None:
    """The line to F, the A axis drawn long (on the body), the arc ζ from A to F with its value
    (the run's series `zeta_key`; without it, the arc's angle), F's orbit in true shape with F on it."""
    tr, f = run.trajectory, d.frames
    pos = centre_of_force(run)
    fdir = unit(pos[f])
    d.add(Segments(name="f_direction", points=line_from_centre(ORBIT_RADIUS * fdir), colors=F_COLOR, thickness=0.02),
          Segments(name="body/a_direction", points=np.array([[[0.0, 0.0, 0.0], [A_LENGTH, 0.0, 0.0]]]),
                   colors=A_COLOR, thickness=0.012))
    if view.option("zeta", spec):
        adir = quat.rotate(np.asarray(tr.quat_wxyz, float)[f], np.array([1.0, 0.0, 0.0]))
        arc = great_arcs(adir, fdir, ZETA_RADIUS)
        d.add(Segments(name="zeta_arc", points=np.stack([arc[:, :-1], arc[:, 1:]], axis=2), colors=ZETA_COLOR,
                       thickness=0.025))
        z = tr.series.get(zeta_key)
        if z is not None:
            text = [f"ζ = {x:+.1f}° (orange arc, A to F)" for x in signed_deg(np.asarray(z, float)[f])]
        else:  # the arc AF itself (§815: cos ζ is the cosine of F's angle from A)
            text = [f"ζ = {x:.1f}° (orange arc, A to F)"
                    for x in np.degrees(np.arccos(np.clip(np.sum(adir * fdir, 1), -1, 1)))]
        # a read-out under the scene: on the arc it would sit on the labels of A and F whenever ζ is small
        d.add(Label(name="zeta_label", text=text, position=readout_position(d)))
    if view.option("orbit", spec):
        dist = np.linalg.norm(pos, axis=1)
        if np.ptp(pos, axis=0).max() > 1e-9 * dist.max():  # F moves: its orbit in true shape
            k = ORBIT_RADIUS / dist.mean()
            idx = frame_indices(len(pos))
            d.add(Segments(name="f_orbit", points=segments(k * pos[idx]), colors=ORBIT_COLOR, thickness=0.008),
                  Sphere(name="f_on_orbit", radius=0.07, color=F_COLOR, position=k * pos[f]))


def centre_line(d: Drawing, run, spec, view: View) -> None:
    """The line from the body's centre toward the centre of force."""
    if view.option("centre", spec) and run.trajectory.bodies:
        d.add(Segments(name="centre_direction", points=line_from_centre(ORBIT_RADIUS * unit(centre_of_force(run)[d.frames])),
                       colors=F_COLOR, thickness=0.015))


# ---- the pole's path: the precession cone and the magnified nutation ---------------------------

def _from_angles(p, lam):
    return np.stack([np.sin(p) * np.cos(lam), np.sin(p) * np.sin(lam), np.cos(p)], -1)


def nice_step(k: float) -> float:
    """Round down to 1, 2 or 5 × 10ⁿ (a magnification, a scale's step: the label shows the value)."""
    e = 10 ** np.floor(np.log10(k))
    return float(max(m for m in (1, 2, 5, 10) if m * e <= k * (1 + 1e-12)) * e)


def magnified_wiggle(t, axis, target_deg=4.0, max_factor=1e6, factor=None):
    """The pole path with its departure from the mean cone magnified: obliquity p about its mean
    and longitude λ about its straight-line fit in time (the mean precession), both scaled by k
    (`factor`, or chosen so that the largest departure is drawn `target_deg`, rounded down to 1,
    2 or 5 × 10ⁿ). Returns (path, k)."""
    p, lam = pole_angles(unit(axis))
    t = np.asarray(t, float)
    c = np.polyfit(t - t[0], lam, 1) if np.ptp(t) > 0 else np.array([0.0, lam[0]])
    lam_m = np.polyval(c, t - t[0])
    pm = float(np.mean(p))
    dev = max(float(np.max(np.abs(p - pm))), float(np.max(np.abs((lam - lam_m) * np.sin(pm)))), 1e-300)
    k = nice_step(float(np.clip(np.radians(target_deg) / dev, 1.0, max_factor))) if factor is None else float(factor)
    return _from_angles(pm + k * (p - pm), lam_m + k * (lam - lam_m)), k


def magnified_about_start(u, target_deg=8.0, max_factor=1e6):
    """Unit vectors u (N, 3) with their departure from u[0] magnified by k (1, 2 or 5 × 10ⁿ,
    chosen so the largest departure is drawn about `target_deg`). Returns (path, k)."""
    u = unit(u)
    dev = max(float(np.max(np.linalg.norm(u - u[0], axis=1))), 1e-300)
    k = nice_step(float(np.clip(np.radians(target_deg) / dev, 1.0, max_factor)))
    return unit(u[0] + k * (u - u[0])), k


def path_samples(d: Drawing, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Sample indices of a path drawn from all of a run's n samples (at most MAX_PATH_SAMPLES,
    finer than the frames: a nutation faster than the frames still shows) and the frame at which
    each appears."""
    idx = frame_indices(n, MAX_PATH_SAMPLES)
    return idx, d.frame_of_sample(idx)


def pole_cone(d: Drawing, run, axis, radius: float = CELESTIAL_RADIUS, wiggle: bool = True,
              generators: bool = True) -> float | None:
    """The cone swept by `axis` (N, 3, the pole's path of the run): lines from near the centre to
    the path (24 along the run), the mean cone (the circle at the mean polar angle about the orbit
    pole), the orbit pole, the axis now; with `wiggle`, the path with its departure from the mean
    cone magnified, a dot on it now and the factor. Returns the factor (None without wiggle)."""
    axis = unit(axis)
    n = len(axis)
    if generators:  # (none when the camera sits at the centre: they would fill the view)
        gens = np.linspace(0, n - 1, 24).round().astype(int)
        d.add(Segments(name="cone/generators", points=np.stack([0.45 * radius * axis[gens], radius * axis[gens]], 1),
                       colors=CONE_LIGHT, thickness=0.006))
    p, _ = pole_angles(axis)
    th = np.linspace(0, 2 * np.pi, 181)
    d.add(Segments(name="cone/mean_circle", points=segments(radius * _from_angles(np.full_like(th, p.mean()), th)),
                   colors=CONE_LIGHT, thickness=0.008),
          Segments(name="cone/orbit_pole", points=np.array([[[0.0, 0.0, 0.0], [0.0, 0.0, 1.05 * radius]]]),
                   colors=(90, 90, 90), thickness=0.01),
          Label(name="cone/orbit_pole_label", text="orbit pole", position=(0.0, 0.0, 1.1 * radius)),
          Segments(name="cone/now", points=line_from_centre(radius * axis[d.frames]), colors=CONE_COLOR,
                   thickness=0.02))
    if not wiggle:
        return None
    path, k = magnified_wiggle(run.trajectory.t, axis)
    path = 1.01 * radius * path
    idx, at = path_samples(d, n)
    d.add(Path(name="wiggle", points=path[idx], color=WIGGLE_COLOR, thickness=0.02, at=at),
          Sphere(name="wiggle_now", radius=0.04, color=WIGGLE_COLOR, position=path[d.frames]),
          Label(name="wiggle_label", text=f"nutation ×{k:g}", position=_far_from_the_pole(d, path, radius)))
    return k


def _far_from_the_pole(d: Drawing, path, radius: float) -> np.ndarray:
    """Where the magnified path's factor is written: just outside the path, at the point of its
    first half (drawn by the time the run is half played) that the camera sees farthest from the
    orbit pole's label (at the path's middle it sat on that label when the cone is narrow, e.g. at
    an obliquity of 23°)."""
    cands = 1.08 * path[np.linspace(0, (len(path) - 1) // 2, 7).round().astype(int)]
    pole, _ = _project(np.array([[0.0, 0.0, 1.1 * radius]]), d.camera)
    xy, depth = _project(cands, d.camera)
    away = np.where(depth > 0, np.hypot(*(xy - pole[0]).T), -1.0)
    return cands[int(np.argmax(away))]


# ---- the Moon's near side --------------------------------------------------------------------------

# (selenographic latitude, east longitude, radius) in degrees: the large near-side maria as round
# patches (Procellarum, Imbrium, Serenitatis, Tranquillitatis, Crisium, Fecunditatis, Nectaris,
# Nubium, Humorum, Insularum, Frigoris, Cognitum), approximate centres written from general lunar
# maps, not transcribed from a catalogue: good to several degrees, enough to recognise the face and
# see it wobble, not for measuring.
MARIA = (
    (18, -57, 24), (32, -40, 14), (5, -45, 12),  # Oceanus Procellarum (three overlapping discs)
    (33, -16, 16), (28, 17, 10), (8, 31, 11), (17, 59, 8), (-8, 51, 9), (-15, 35, 7),
    (-21, -17, 9), (-24, -39, 6), (-4, -23, 8), (56, 0, 5), (56, 20, 5), (-13, -14, 6),
)
BRIGHT_CRATERS = ((-43, -11, 3), (10, -20, 2), (24, -47, 2))  # Tycho, Copernicus, Aristarchus
MOON_HIGHLAND, MOON_MARE, MOON_CRATER = (185, 182, 172), (88, 88, 96), (245, 245, 240)


def moon_colour_index(dirs) -> np.ndarray:
    """0 highland, 1 mare, 2 bright crater for unit vectors (N, 3) in the Moon's body frame."""
    dirs = np.asarray(dirs, float)
    out = np.zeros(len(dirs), int)

    def near(lat, lon, rad):
        la, lo = np.radians(lat), np.radians(lon)
        c = np.array([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)])
        return dirs @ c > np.cos(np.radians(rad))

    for lat, lon, rad in MARIA:
        out[near(lat, lon, rad)] = 1
    for lat, lon, rad in BRIGHT_CRATERS:
        out[near(lat, lon, rad)] = 2
    return out


@functools.lru_cache(maxsize=2)
def moon_surface_parts(cell_deg: float = 1.0) -> tuple:
    """A unit sphere with the near side's maria, one (vertices, faces, colour) per colour (each
    grid cell coloured at its centre); body x toward the Earth (selenographic longitude 0), y
    east, z north (as physics.moon.mean_frame). Plain meshes per colour, as the banded body. Cells
    of `cell_deg` where the maria are (longitude ±100°: the near side and its limb as the libration
    shows it; latitude −60°…70°), four times coarser on the far side and near the poles."""
    def axis(lo, a, b, hi):
        fine = np.arange(a, b + 1e-9, cell_deg)
        return np.radians(np.unique(np.concatenate([np.linspace(lo, a, int(round((a - lo) / (4 * cell_deg))) + 1), fine,
                                                    np.linspace(b, hi, int(round((hi - b) / (4 * cell_deg))) + 1)])))

    verts, quads, lat_c, lon_c = sphere_grid(axis(-90.0, -60.0, 70.0, 90.0), axis(-180.0, -100.0, 100.0, 180.0))
    centre = np.stack([np.cos(lat_c) * np.cos(lon_c), np.cos(lat_c) * np.sin(lon_c), np.sin(lat_c)], -1)
    return tuple(mesh_parts(verts, quads, moon_colour_index(centre), (MOON_HIGHLAND, MOON_MARE, MOON_CRATER)))


# ---- the stars -------------------------------------------------------------------------------------

LABELLED_STARS = ("Polaris", "Vega", "Thuban", "Deneb")


def star_directions(catalogue) -> np.ndarray:
    """Unit vectors in the J2000 ecliptic frame (the frame of the Earth scenarios)."""
    from ..physics.earth_precession import equatorial_to_ecliptic

    return equatorial_to_ecliptic(catalogue.ra_deg, catalogue.dec_deg)


def stars_to_label(catalogue, n_brightest: int = 10) -> list[int]:
    order = [int(j) for j in np.argsort(catalogue.vmag)[:n_brightest]]
    for name in LABELLED_STARS:
        if name in catalogue.names:
            j = catalogue.names.index(name)
            if j not in order:
                order.append(j)
    return order


def bright_stars():
    from ..app.bright_stars import load_bright_stars  # the asset reader (physics reads no files)

    return load_bright_stars()


# ---- the Earth: axis, equator, ecliptic, Sun, Moon, the pole among the stars ------------------------

EARTH_OPTIONS = {
    "stars": Option("bright stars on the celestial sphere"),
    "cone": Option("pole's path, precession cone"),
    "wiggle": Option("nutation wiggle, magnified"),
    "frame": Option("axis, equator, ecliptic, Sun and Moon directions"),
    "pole_view": Option("look at the pole among the stars", False),
}
# the planetarium view: toward the north ecliptic pole from just below the (hidden) Earth, so the
# pole's circle of 23.4° and its stars fill the view; shifted along the screen's right (−x here) so
# the circle sits left of the control panel
POLE_VIEW = dict(position=(-0.45, 0.0, -1.2), look_at=(-0.45, 0.0, CELESTIAL_RADIUS), up=(0.0, 1.0, 0.0), fov_deg=60.0)
SUN_COLOR, MOON_COLOR = (230, 170, 0), (110, 110, 130)


def earth_scene(run, spec, view: View, long_view: bool) -> Drawing:
    """The Earth (axis and equator on the body), the ecliptic, the Sun and Moon directions, the
    bright stars on the celestial sphere (the brightest and the pole stars named), the pole's path
    with the precession cone and, over millennia, year marks; for `earth` the nutation magnified.
    The pole's path is the figure axis (`earth`) or the angular-momentum axis (`earth-long-view`,
    the scenario's pole path). No trail for the Moon: sampled every few years its direction is a
    scatter, and over a century a solid band 2 × 5.1° wide that hides the Earth."""
    tr = run.trajectory
    pole_view = view.option("pole_view", spec)
    d, semi = body_scene(run, spec, view, trails=lambda name: name != "moon")
    R = CELESTIAL_RADIUS
    if pole_view:  # the planetarium looks out through the Earth: no Earth
        d.items = [it for it in d.items if not it.name.startswith("body/mesh/")]
        F = d.n_frames
        d.follow = Follow(position=np.tile(POLE_VIEW["position"], (F, 1)), look_at=POLE_VIEW["look_at"],
                          up=POLE_VIEW["up"], fov_deg=POLE_VIEW["fov_deg"])
        d.camera = Camera(**POLE_VIEW)
    if view.option("stars", spec):
        cat = bright_stars()
        sd = star_directions(cat)
        for lo, hi, size in ((-2.0, 1.0, 0.07), (1.0, 2.2, 0.05), (2.2, 9.0, 0.035)):
            sel = (cat.vmag >= lo) & (cat.vmag < hi)
            if np.any(sel):
                d.add(Points(name=f"stars/mag_{lo:g}", points=R * sd[sel], colors=STAR_COLOR, size=size))
        for j in stars_to_label(cat):
            d.add(Label(name=f"stars/label_{j}", text=cat.names[j], position=R * 1.03 * sd[j], yields=True))
    if view.option("cone", spec):
        axis = unit(tr.L_inertial if long_view else tr.figure_axis)
        # the long view samples every few years: no nutation to magnify
        pole_cone(d, run, axis, R, wiggle=not long_view and view.option("wiggle", spec), generators=not pole_view)
        year_marks(d, run, axis, R, every=1 if pole_view else 2)
    if view.option("frame", spec) and not pole_view:
        th = np.linspace(0, 2 * np.pi, 181)
        ring = np.stack([np.cos(th), np.sin(th), np.zeros_like(th)], 1)
        d.add(Segments(name="body/equator", points=segments(1.08 * ring * semi), colors=(220, 60, 50), thickness=0.02),
              Segments(name="body/earth_axis", points=np.array([[[0.0, 0.0, -1.6], [0.0, 0.0, 1.6]]]),
                       colors=(30, 30, 30), thickness=0.025),
              Label(name="body/north_label", text="N", position=(0.0, 0.0, 1.75)),
              Segments(name="ecliptic", points=segments(1.7 * ring), colors=(200, 160, 0), thickness=0.015),
              Label(name="ecliptic_label", text="ecliptic", position=(1.7 * 0.7, -1.7 * 0.7, 0.05)))
        lines = np.zeros((d.n_frames, 2, 2, 3))
        for k, key in enumerate(("sun", "moon")):
            if key in tr.bodies:
                lines[:, k, 1] = ORBIT_RADIUS * unit(np.asarray(tr.bodies[key], float)[d.frames])
        colors = np.array([[SUN_COLOR] * 2, [MOON_COLOR] * 2], np.uint8)
        d.add(Segments(name="sun_moon", points=lines, colors=colors, thickness=0.015))
    return d


def year_marks(d: Drawing, run, axis, radius: float, every: int = 2) -> None:
    """Marks on the pole's path every 1000 years (2000 over more than 6000), labelled "AD year"
    (every `every`-th label, the first always: the oblique view has less room)."""
    t = np.asarray(run.trajectory.t, float)  # years from J2000 (a run may start before it)
    span = t[-1] - t[0]
    if run.trajectory.time_unit != "yr" or span < 1000:
        return
    step = 2000.0 if span > 6000 else 1000.0
    years = np.arange(np.ceil(t[0] / step - 1e-9) * step, t[-1] + 1e-9, step)
    idx = [int(np.argmin(np.abs(t - y))) for y in years]
    a = axis[idx]
    d.add(Points(name="pole_years/points", points=radius * 1.005 * a, colors=WIGGLE_COLOR, size=0.05))
    out = unit(np.stack([a[:, 0], a[:, 1], np.zeros(len(a))], 1))  # away from the ecliptic pole
    for k in range(len(idx)):
        if (k % every == 0 and k < len(idx) - 1) or k == 0:
            y = int(round(2000 + years[k]))
            d.add(Label(name=f"pole_years/{k}", text=f"AD {y}" if y > 0 else f"{1 - y} BC",
                        position=radius * a[k] + 0.1 * out[k]))
