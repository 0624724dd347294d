"""Scene drawings of chapter 16 (issue 4 item 4, issue 5 item 3).

Everything here is drawn from the scenario's Result: the trajectory's quaternions and derived
paths (figure axis, L), `Trajectory.bodies` (positions of the centre of force, the Sun, the
Moon), `Trajectory.series` / `Result.plot_series` (ζ, dζ/dt, the separatrix, the surface of
section) and `Result.metrics` (Goldreich–Peale half-widths). The app only changes coordinates
(unit vectors → angles on a sphere, scaling into a panel) and never integrates or re-derives a
physical quantity.

- gravity-start, libration-circular, libration-eccentric (§820–838): the direction to F, the
  angle ζ between the A axis and F drawn as an arc in the orbit plane (§825: ζ is measured from
  A about C), the orbit of F in its true shape scaled around the body; libration-circular adds
  a flat panel with the phase portrait (ζ, dζ/dt), its separatrix (§829–831) and the current
  state as a moving dot.
- moon: maria painted on the body mesh (vertex colours, selenographic positions of the large
  maria rounded to a few degrees) so the wobbling face shows; option "view from the Earth"
  puts the camera on the Earth's direction, looking at the Moon (the `camera` hook).
- hyperion: the surface of section (θ mod π, θ̇/n at each periapse) as a flat panel beside the
  body, points coloured by the Lyapunov exponent, with the Goldreich–Peale resonance zones
  p ± half-width drawn as lines; and the same F / ζ drawings as the libration scenes.
- gravity-gradient-accuracy (§815–818): F coming in from far away as the sweep of its distance
  plays, with the errors of Euler's torque and of the §818 force at that distance in its label.
- pole-near-axis (§840–843): the path of the rotation pole O in the body (direction of ω,
  beyond the A axis), its departure from the start magnified by a factor shown in its label.
- precession-circular (§844–849): the precession cone (lines from the centre to the figure
  axis's path on the celestial sphere, and the mean cone about the orbit pole) and the nutation
  wiggle magnified by a factor shown in its label.
- earth, earth-long-view: the Earth's axis and equator (body-fixed), the ecliptic, the Sun and
  Moon directions, the bright stars on the celestial sphere (assets/bright_stars.csv via
  app.bright_stars; the brightest and the pole stars labelled), the pole's path with year
  marks, the precession cone, and for `earth` the nutation wiggle magnified.
"""
from __future__ import annotations

import functools

import numpy as np
import trimesh

from theoria.physics import quaternion as quat

from ..scene import CELESTIAL_RADIUS, ORBIT_RADIUS, SceneExtra, register_extra, segments

F_COLOR = (200, 40, 160)
ZETA_COLOR = (230, 120, 0)
A_COLOR = (220, 50, 47)
PANEL_COLOR = (90, 90, 100)
POINT_COLOR = (40, 90, 200)
STAR_COLOR = (25, 30, 80)
CONE_COLOR = (38, 110, 220)
WIGGLE_COLOR = (200, 30, 60)
PANEL_SIZE = 2.6
# ch. 16 rotation scenes are seen from app.server.camera_position (an oblique view from +x+y+z).
CAMERA = np.array([4.8, 3.7, 2.9])


def _unit(v):
    v = np.asarray(v, float)
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)


def _f32(x):
    return np.asarray(x, np.float32)


def _tuple(v):
    return tuple(float(x) for x in v)


def camera_basis(camera=CAMERA):
    """Right and up unit vectors of the screen for a camera at `camera` looking at the origin
    with +z up (a panel spanned by them faces the camera)."""
    view = -_unit(camera)
    right = _unit(np.cross(view, [0.0, 0.0, 1.0]))
    up = np.cross(right, view)
    return right, up


class Panel:
    """A flat 2D chart in the 3D scene: data (x, y) in [x0, x1] × [y0, y1] mapped onto a square of
    side `size` centred at `centre`, spanned by the unit vectors `right` and `up`."""

    def __init__(self, centre, right, up, xlim, ylim, size=PANEL_SIZE):
        self.c, self.r, self.u = np.asarray(centre, float), np.asarray(right, float), np.asarray(up, float)
        self.xlim, self.ylim, self.size = xlim, ylim, size

    def map(self, x, y):
        x, y = np.asarray(x, float), np.asarray(y, float)
        fx = (x - self.xlim[0]) / (self.xlim[1] - self.xlim[0]) - 0.5
        fy = (y - self.ylim[0]) / (self.ylim[1] - self.ylim[0]) - 0.5
        return self.c + self.size * (fx[..., None] * self.r + fy[..., None] * self.u)

    def frame(self):
        x0, x1 = self.xlim
        y0, y1 = self.ylim
        corners = self.map(np.array([x0, x1, x1, x0, x0]), np.array([y0, y0, y1, y1, y0]))
        return segments(corners)

    def hline(self, y):
        return self.map(np.array(self.xlim), np.array([y, y]))[None]

    def vline(self, x):
        return self.map(np.array([x, x]), np.array(self.ylim))[None]


def _slerp_arc(a, b, radius, n=24):
    """Points of the shorter great-circle arc from unit vector a to unit vector b."""
    a, b = _unit(a), _unit(b)
    ang = np.arccos(np.clip(a @ b, -1.0, 1.0))
    if ang < 1e-9 or not np.isfinite(ang):
        return np.stack([a, b]) * radius
    if np.pi - ang < 1e-6:  # opposite: any half great circle; take one through the z axis side
        c = np.cross(a, [0.0, 0.0, 1.0])
        c = c if np.linalg.norm(c) > 1e-9 else np.cross(a, [1.0, 0.0, 0.0])
        c = _unit(c)
        return np.concatenate([_slerp_arc(a, c, radius, n // 2), _slerp_arc(c, b, radius, n - n // 2)])
    s = np.linspace(0.0, 1.0, n)
    pts = (np.sin((1 - s) * ang)[:, None] * a + np.sin(s * ang)[:, None] * b) / np.sin(ang)
    return radius * pts


def _wrap(x, lo, period):
    return lo + np.remainder(np.asarray(x, float) - lo, period)


class _Ch16(SceneExtra):
    """Shared drawing helpers."""

    def _segs(self, key, segs, color, thickness=0.012):
        name = self.name(key)
        segs = _f32(segs)
        return self.node(name, lambda: self.scene.add_line_segments(name, segs, color, thickness=thickness),
                         points=segs)

    def _points(self, key, pts, color, size=0.02):
        name = self.name(key)
        pts = _f32(pts)
        col = np.asarray(color, np.uint8) if np.ndim(color) == 2 else color  # per point: uint8 0–255
        return self.node(name, lambda: self.scene.add_point_cloud(name, pts, col, point_size=size,
                                                                  point_shape="circle"), points=pts)

    def _label(self, key, text, pos):
        name = self.name(key)
        pos = _tuple(pos)
        return self.node(name, lambda: self.scene.add_label(name, text, position=pos), text=text, position=pos)

    def _screen(self):
        """(right, up, look_at) of the scenario's camera (app.gallery), for panels facing it."""
        pos, look = CAMERA, np.zeros(3)
        try:
            from ..gallery import camera_for

            pos, look = (np.asarray(v, float) for v in camera_for(self.view._spec))
        except Exception:  # noqa: BLE001 - no curated camera: the default oblique view
            pass
        right, up = camera_basis(pos - look)
        return right, up, look

    def _dot(self, key, color, radius=0.05):
        name = self.name(key)
        return self.node(name, lambda: self.scene.add_icosphere(name, radius=radius, color=color,
                                                                cast_shadow=False, receive_shadow=False))

    def _build_centre_line(self, traj) -> None:
        """The line from the body's centre toward the centre of force (the first of traj.bodies)."""
        self._cline = None
        if self.values.get("centre", True) and traj.bodies:
            self._cdir = _unit(np.asarray(next(iter(traj.bodies.values())), float))
            self._cline = self._segs("centre_direction", np.zeros((1, 2, 3)), F_COLOR, 0.015)

    def _frame_centre_line(self, i: int) -> None:
        if self._cline is not None:
            self._cline.points = _f32([[[0, 0, 0], ORBIT_RADIUS * self._cdir[i]]])


# ---- libration: F, ζ, the orbit, the phase portrait ------------------------------------------

class _FAndZeta(_Ch16):
    """The direction to F, the A axis in space, the arc ζ from A to F and the orbit of F."""

    zeta_key = "zeta_rad"

    def _build_f_zeta(self, traj):
        pos = np.asarray(next(iter(traj.bodies.values())), float)
        self._fdir = _unit(pos)
        self._adir = quat.rotate(traj.quat_wxyz, np.array([1.0, 0.0, 0.0]))
        z = traj.series.get(self.zeta_key)
        self._zeta = None if z is None else np.asarray(z, float)
        zero = np.zeros((1, 2, 3), np.float32)
        self._fline = self._segs("f_direction", zero, F_COLOR, 0.02)
        self._aline = self._segs("a_direction", zero, A_COLOR, 0.012)
        self._flabel = self._label("f_label", "to F", (0, 0, 0))
        self._arc = self._segs("zeta_arc", np.zeros((23, 2, 3)), ZETA_COLOR, 0.025) if self.values.get("zeta", True) else None
        self._zlabel = self._label("zeta_label", "ζ", (0, 0, 0)) if self._arc is not None else None
        self._fdot = None
        if self.values.get("orbit", True):
            d = np.linalg.norm(pos, axis=1)
            if np.ptp(pos, axis=0).max() > 1e-9 * d.max():  # F moves: its orbit in true shape
                k = ORBIT_RADIUS / d.mean()
                idx = np.unique(np.linspace(0, len(pos) - 1, min(len(pos), 3000)).round().astype(int))
                self._orbit_pts = k * pos
                self._segs("f_orbit", segments(k * pos[idx]), (150, 110, 170), 0.008)
                self._fdot = self._dot("f_on_orbit", F_COLOR, 0.07)

    def _frame_f_zeta(self, i):
        f, a = self._fdir[i], self._adir[i]
        self._fline.points = _f32([[[0, 0, 0], ORBIT_RADIUS * f]])
        self._aline.points = _f32([[[0, 0, 0], 1.5 * a]])
        self._flabel.position = _tuple(ORBIT_RADIUS * 0.75 * f + [0, 0, 0.12])
        if self._fdot is not None:
            self._fdot.position = _tuple(self._orbit_pts[i])
        if self._arc is not None:
            arc = _slerp_arc(a, f, 0.9 * 1.5)
            if len(arc) < 24:
                arc = np.concatenate([arc, np.repeat(arc[-1:], 24 - len(arc), 0)])
            self._arc.points = _f32(segments(arc))
            z = self._zeta[i] if self._zeta is not None else None
            text = "ζ" if z is None else f"ζ = {np.degrees(np.remainder(z + np.pi, 2 * np.pi) - np.pi):+.1f}°"
            self._zlabel.text = text
            self._zlabel.position = _tuple(arc[len(arc) // 2] * 1.12)


@register_extra("gravity-start", "libration-eccentric")
class LibrationExtra(_FAndZeta):
    options = {"zeta": ("angle ζ: arc from the A axis to F", True),
               "orbit": ("orbit of F (true shape, scaled)", True)}

    def build(self, traj, result):
        self._build_f_zeta(traj)

    def set_frame(self, i):
        self._frame_f_zeta(i)

    def plot_series(self, result):
        return result.plot_series


@register_extra("libration-circular")
class LibrationCircularExtra(_FAndZeta):
    """§825–831: ζ̈ + N sin 2ζ = 0; the phase portrait with the separatrix (point clouds in
    plot_series, not time series: drawn here, left out of the time plot)."""

    options = {"zeta": ("angle ζ: arc from the A axis to F", True),
               "orbit": ("orbit of F (true shape, scaled)", True),
               "portrait": ("phase portrait (ζ, dζ/dt) with the separatrix", True)}

    def build(self, traj, result):
        self._build_f_zeta(traj)
        self._pdot = None
        s = traj.series
        if not self.values.get("portrait", True) or "zeta_dot" not in s:
            return
        sz = np.asarray(s["separatrix_zeta_rad"], float)
        lo = float(np.nanmin(sz))  # the separatrix spans one period π of the pendulum in 2ζ
        zw = _wrap(s["zeta_rad"], lo, np.pi)
        zd = np.asarray(s["zeta_dot"], float)
        ymax = 1.15 * max(np.nanmax(np.abs(zd)), np.nanmax(np.abs(s["separatrix_zeta_dot_plus"])), 1e-12)
        right, up, look = self._screen()
        p = Panel(look - 3.9 * right + 0.2 * up, right, up, (lo, lo + np.pi), (-ymax, ymax))
        self._panel, self._zw, self._zd = p, zw, zd
        self._segs("portrait/frame", p.frame(), PANEL_COLOR, 0.01)
        mid = lo + np.pi / 2
        self._segs("portrait/axes", np.concatenate([p.hline(0.0), p.vline(mid)]), (170, 170, 180), 0.006)
        sep = np.concatenate([p.map(sz, s["separatrix_zeta_dot_plus"]), p.map(sz, s["separatrix_zeta_dot_minus"])])
        self._points("portrait/separatrix", sep[np.all(np.isfinite(sep), axis=1)], (200, 40, 40), 0.02)
        self._points("portrait/trajectory", p.map(zw, zd), POINT_COLOR, 0.02)
        self._pdot = self._dot("portrait/state", ZETA_COLOR, 0.06)
        x0, x1 = lo, lo + np.pi
        self._label("portrait/title", "phase portrait (ζ, dζ/dt); red: separatrix", p.map(mid, ymax * 1.12))
        self._label("portrait/xlabel", f"ζ from {np.degrees(x0):.0f}° to {np.degrees(x1):.0f}°",
                    p.map(mid, -ymax * 1.12))
        self._label("portrait/ylabel", f"dζ/dt (±{ymax:.3g})", p.map(x0, ymax * 0.9) - 0.15 * right)

    def set_frame(self, i):
        self._frame_f_zeta(i)
        if self._pdot is not None:
            self._pdot.position = _tuple(self._panel.map(self._zw[i], self._zd[i]))

    def plot_series(self, result):
        return {k: v for k, v in result.plot_series.items() if not k.startswith("separatrix_")}


# ---- hyperion: the surface of section ----------------------------------------------------------

@register_extra("hyperion")
class HyperionExtra(_FAndZeta):
    """Wisdom, Peale & Mignard 1984: θ mod π against θ̇/n at each periapse for the ensemble
    (plot_series section_*, a point cloud), the Goldreich–Peale zones p ± half-width (metrics
    gp_half_width_p), the drawn body (the probe start) with F and ζ."""

    options = {"zeta": ("angle ζ: arc from the A axis to F", True),
               "orbit": ("orbit of F (true shape, scaled)", True),
               "section": ("surface of section + resonance zones", True)}

    def build(self, traj, result):
        self._build_f_zeta(traj)
        ps = result.plot_series
        if not self.values.get("section", True) or "section_theta_mod_pi" not in ps:
            return
        th = np.asarray(ps["section_theta_mod_pi"], float)
        w = np.asarray(ps["section_theta_dot"], float)
        ly = np.asarray(ps.get("section_lyapunov_per_orbit", np.zeros_like(th)), float)
        ok = np.isfinite(th) & np.isfinite(w)
        th, w, ly = th[ok], w[ok], ly[ok]
        widths = {}
        for k, v in result.metrics.items():
            if k.startswith("gp_half_width_") and np.isfinite(v):
                widths[float(k[len("gp_half_width_"):])] = float(v)
        y0 = min(float(np.min(w)) if len(w) else 0.0, 0.0)
        y1 = max(float(np.max(w)) if len(w) else 3.0, max((p + h for p, h in widths.items()), default=0.0))
        pad = 0.05 * (y1 - y0)
        right, up, look = self._screen()
        p = Panel(look - 4.5 * right + 0.1 * up, right, up, (0.0, np.pi), (y0 - pad, y1 + pad), size=3.2)
        self._section_panel = p
        self._segs("section/frame", p.frame(), PANEL_COLOR, 0.01)
        # chaotic (λ > 0.05 per orbit, the scenario's own threshold for chaotic_fraction) red, regular blue
        chaotic = ly > 0.05
        col = np.where(chaotic[:, None], np.array([215, 60, 40]), np.array([40, 90, 200])).astype(np.uint8)
        self._points("section/points", p.map(th, w), col, 0.028)
        lines, labels = [], []
        for q, h in sorted(widths.items()):
            for y in (q - h, q + h):
                if y0 - pad <= y <= y1 + pad:
                    lines.append(p.hline(y))
            if y0 - pad <= q <= y1 + pad:
                labels.append((q, h))
        if lines:  # a little toward the camera, so the zones are drawn over the points
            lift = 0.03 * np.cross(right, up)
            self._segs("section/resonance_zones", np.concatenate(lines) + lift, (20, 150, 60), 0.016)
        names = {0.5: "1:2", 1.0: "1:1", 1.5: "3:2", 2.0: "2:1", 2.5: "5:2"}
        for q, h in labels:
            self._label(f"section/res_{q:g}", f"{names.get(q, f'{q:g}')} ± {h:.2f}", p.map(np.pi, q) + 0.25 * right)
        self._label("section/title", "surface of section: θ mod π vs θ̇/n at periapse (red chaotic, blue regular; "
                    "green: Goldreich–Peale zones)", p.map(np.pi / 2, y1 + 2.5 * pad))
        self._label("section/xlabel", "θ mod π: 0 … π", p.map(np.pi / 2, y0 - 2.5 * pad))
        self._label("section/ylabel", f"θ̇/n {y0:.1f} … {y1:.1f}", p.map(0.0, y1) - 0.35 * right)

    def set_frame(self, i):
        self._frame_f_zeta(i)

    def plot_series(self, result):
        return {k: v for k, v in result.plot_series.items() if not k.startswith("section_")}


# ---- the Moon: maria and the view from the Earth ----------------------------------------------

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


@functools.lru_cache(maxsize=1)
def _moon_parts():
    return moon_surface_parts()


MOON_HIGHLAND, MOON_MARE, MOON_CRATER = (185, 182, 172), (88, 88, 96), (245, 245, 240)


def moon_colour_index(d) -> np.ndarray:
    """0 highland, 1 mare, 2 bright crater for unit vectors d (N,3) in the Moon's body frame."""
    d = np.asarray(d, float)
    out = np.zeros(len(d), int)

    def near(lat, lon, rad):
        la, lo = np.radians(lat), np.radians(lon)
        c = np.array([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)])
        return d @ c > np.cos(np.radians(rad))

    for lat, lon, rad in MARIA:
        out[near(lat, lon, rad)] = 1
    for lat, lon, rad in BRIGHT_CRATERS:
        out[near(lat, lon, rad)] = 2
    return out


def moon_surface_parts(count: int = 160) -> list[tuple[np.ndarray, np.ndarray, tuple]]:
    """A unit UV sphere with the near side's maria, one (vertices, faces, colour) per colour (each
    face coloured at its centre); body x toward the Earth (selenographic longitude 0), y east, z
    north (as physics.moon.mean_frame). Plain meshes, not one vertex-coloured GLB, as for the body
    (app.scene.banded_sphere_parts: 9–12 against ~5 ms a frame there; the Moon fills the view)."""
    m = trimesh.creation.uv_sphere(radius=1.0, count=[count, count])
    centre = m.vertices[m.faces].mean(axis=1)
    idx = moon_colour_index(centre / np.linalg.norm(centre, axis=1, keepdims=True))
    parts = []
    for k, rgb in enumerate((MOON_HIGHLAND, MOON_MARE, MOON_CRATER)):
        f = m.faces[idx == k]
        if len(f) == 0:
            continue
        used, inv = np.unique(f, return_inverse=True)
        parts.append((m.vertices[used].astype(np.float32), inv.reshape(-1, 3).astype(np.uint32), rgb))
    return parts


@register_extra("moon")
class MoonExtra(_Ch16):
    options = {"earth_view": ("view from the Earth (camera follows)", True),
               "maria": ("maria on the Moon", True),
               "earth_line": ("direction to the Earth + sub-Earth meridian", True),
               "plot_physical": ("time plot: physical libration (″) instead of the face's wobble (°)", False)}
    FOV_DEG = 60.0
    EYE = 2.3  # camera distance in Moon radii (drawn 1): the disc spans ~52° of the 60° view

    def build(self, traj, result):
        b = traj.bodies
        self._earth = _unit(np.asarray(b.get("earth", next(iter(b.values()))), float))
        r = self.view.root
        semi = tuple(float(x) * 1.004 for x in getattr(self.view, "_semi", (1.0, 1.0, 1.0)))
        if self.values.get("maria", True):
            name = f"{r}/body/moon_surface"
            self.node(name, lambda: self.scene.add_frame(name, show_axes=False))
            for k, (v, f, rgb) in enumerate(_moon_parts()):
                part = f"{name}/{k}"
                self.node(part, lambda part=part, v=v, f=f, rgb=rgb: self.scene.add_mesh_simple(
                    part, v, f, color=rgb, scale=semi, cast_shadow=False, receive_shadow=False), scale=semi)
        self._eline = self._light = None
        if self.values.get("earth_line", True):
            if not self.values.get("earth_view", True):
                self._eline = self._segs("earth_direction", np.zeros((1, 2, 3)), (40, 120, 220), 0.015)
            # the prime meridian and the equator on the body: their crossing (longitude 0, the
            # mean sub-Earth point) wanders about the disc centre by the libration
            th = np.linspace(-np.pi / 2, np.pi / 2, 61)
            mer = np.stack([np.cos(th), np.zeros_like(th), np.sin(th)], 1)
            equ = np.stack([np.cos(th), np.sin(th), np.zeros_like(th)], 1)
            segs = _f32(1.01 * np.concatenate([segments(mer), segments(equ)]) * np.asarray(semi))
            name = f"{r}/body/prime_meridian"
            self.node(name, lambda: self.scene.add_line_segments(name, segs, (230, 60, 40), thickness=0.01),
                      points=segs)
        if self.values.get("earth_view", True):  # a full Moon: lit from the Earth's side
            name = self.name("earth_light")
            self._light = self.node(name, lambda: self.scene.add_light_directional(name, intensity=2.0))

    def set_frame(self, i):
        if self._eline is not None:
            self._eline.points = _f32([[[0, 0, 0], 1.9 * self._earth[i]]])
        if self._light is not None:
            self._light.position = _tuple(5.0 * self._earth[i])

    def plot_series(self, result):
        """One y axis: either the wobbling face in degrees (sub-Earth longitude = the scenario's ζ,
        latitude, and Euler's ζ converted to degrees) or the physical libration in arcseconds
        with Euler's formula (§833, §836)."""
        ps = result.plot_series
        if self.values.get("plot_physical", False):
            keys = ("physical_libration_arcsec", "physical_libration_euler_arcsec")
            return {k: ps[k] for k in keys if k in ps}
        # (the uniform-rotation curves differ from these by < 0.04°: drawn they would hide each other)
        out = {k: ps[k] for k in ("libration_longitude_deg", "libration_latitude_deg") if k in ps}
        if "zeta_euler_rad" in ps:
            out["ζ, Euler §833 (deg)"] = np.degrees(ps["zeta_euler_rad"])
        return out or dict(ps)

    def bodies(self, traj):
        """Seen from the Earth, the Earth's marker would stand in front of the camera: none."""
        return {} if self.values.get("earth_view", True) else None

    def follow_camera(self, traj, i):
        """Camera on the Earth's direction (inside the celestial sphere, so no grid in front),
        looking at the Moon's centre with the ecliptic north up."""
        if not self.values.get("earth_view", True):
            return None
        e = self._earth[min(i, len(self._earth) - 1)]
        return dict(position=_tuple(self.EYE * e), look_at=(0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), fov_deg=self.FOV_DEG)


# ---- precession: the cone and the nutation wiggle ---------------------------------------------

def _pole_angles(u):
    """Polar angle from +z and unwrapped longitude of unit vectors (coordinates only)."""
    u = _unit(u)
    return np.arccos(np.clip(u[:, 2], -1, 1)), np.unwrap(np.arctan2(u[:, 1], u[:, 0]))


def _from_angles(p, lam):
    return np.stack([np.sin(p) * np.cos(lam), np.sin(p) * np.sin(lam), np.cos(p)], -1)


def magnified_wiggle(t, axis, target_deg=4.0, max_factor=1e6, factor=None):
    """The pole path with its departure from the mean cone magnified: obliquity p about its
    mean and longitude λ about its straight-line fit in time (the mean precession), both scaled
    by k (`factor`, or chosen so that the largest departure is drawn `target_deg`, rounded down
    to 1, 2 or 5 × 10ⁿ). Returns (path, k)."""
    p, lam = _pole_angles(axis)
    t = np.asarray(t, float)
    c = np.polyfit(t - t[0], lam, 1) if np.ptp(t) > 0 else np.array([0.0, lam[0]])
    lam_m = np.polyval(c, t - t[0])
    pm = float(np.mean(p))
    dev = max(float(np.max(np.abs(p - pm))), float(np.max(np.abs((lam - lam_m) * np.sin(pm)))), 1e-300)
    k = _nice(float(np.clip(np.radians(target_deg) / dev, 1.0, max_factor))) if factor is None else float(factor)
    return _from_angles(pm + k * (p - pm), lam_m + k * (lam - lam_m)), k


def _nice(k):
    """Round a magnification to 1, 2 or 5 × 10^n (the label shows the factor used)."""
    e = 10 ** np.floor(np.log10(k))
    return float(max(m for m in (1, 2, 5, 10) if m * e <= k * (1 + 1e-12)) * e)


class _PoleExtra(_Ch16):
    """The cone swept by the figure axis and its magnified nutation."""

    def _pole_axis(self, traj):
        return traj.figure_axis

    def _build_cone(self, traj, radius=CELESTIAL_RADIUS, wiggle=True):
        axis = _unit(self._pole_axis(traj))
        n = len(axis)
        idx = np.unique(np.linspace(0, n - 1, min(n, 4000)).round().astype(int))
        # generators of the cone: lines from near the centre to the pole path, 24 along the run
        # (none when the camera sits at the centre: they would fill the view)
        if not self.values.get("pole_view", False):
            gens = np.linspace(0, n - 1, 24).round().astype(int)
            segs = np.stack([0.45 * radius * axis[gens], radius * axis[gens]], 1)
            self._segs("cone/generators", segs, (120, 160, 230), 0.006)
        # the mean cone: the circle at the mean polar angle about the orbit pole
        p, _ = _pole_angles(axis)
        th = np.linspace(0, 2 * np.pi, 181)
        circ = radius * _from_angles(np.full_like(th, p.mean()), th)
        self._segs("cone/mean_circle", segments(circ), (120, 160, 230), 0.008)
        self._segs("cone/orbit_pole", [[[0, 0, 0], [0, 0, radius * 1.05]]], (90, 90, 90), 0.01)
        self._label("cone/orbit_pole_label", "orbit pole", (0, 0, radius * 1.1))
        self._cone_live = self._segs("cone/now", np.zeros((1, 2, 3)), CONE_COLOR, 0.02)
        self._axis_u, self._cone_r = axis, radius
        self._wig = None
        if wiggle and self.values.get("wiggle", True):
            path, k = magnified_wiggle(traj.t, axis)
            self.wiggle_factor = k
            self.path(self.name("wiggle"), 1.01 * radius * path[idx], WIGGLE_COLOR, 0.02, idx=idx)
            self._wig = 1.01 * radius * path
            self._wdot = self._dot("wiggle_now", WIGGLE_COLOR, 0.04)
            mid = self._wig[len(self._wig) // 2]
            self._label("wiggle_label", f"nutation ×{k:g}",
                        mid * 1.08 + np.array([0, 0, 0.15]))

    def _frame_cone(self, i):
        self._cone_live.points = _f32([[[0, 0, 0], self._cone_r * self._axis_u[i]]])
        if self._wig is not None:
            self._wdot.position = _tuple(self._wig[i])


def magnified_about_start(u, target_deg=8.0, max_factor=1e6):
    """Unit vectors u (N,3) with their departure from u[0] magnified by k (1, 2 or 5 × 10ⁿ,
    chosen so the largest departure is drawn about `target_deg`). Returns (path, k)."""
    u = _unit(u)
    d = u - u[0]
    dev = max(float(np.max(np.linalg.norm(d, axis=1))), 1e-300)
    k = _nice(float(np.clip(np.radians(target_deg) / dev, 1.0, max_factor)))
    return _unit(u[0] + k * d), k


@register_extra("pole-near-axis")
class PoleNearAxisExtra(_Ch16):
    """§840–843: the momentary motion of the pole of rotation O near the principal axis A: the
    direction of ω in the body (Trajectory.omega_body) drawn on the body frame beyond the A axis,
    its departure from the start magnified (in a few turns O moves by a fraction of a degree;
    Euler: at right angles to the arc AF), with the direction to the centre of force."""

    options = {"pole_path": ("path of the rotation pole O in the body, magnified", True),
               "centre": ("direction to the centre of force", True)}
    RADIUS = 1.6

    def build(self, traj, result):
        r = self.view.root
        self._pole = None
        if self.values.get("pole_path", True):
            n = len(traj.t)
            idx = np.unique(np.linspace(0, n - 1, min(n, 4000)).round().astype(int))
            path, k = magnified_about_start(traj.omega_body, target_deg=10.0)
            self.wiggle_factor = k
            self._pole = self.RADIUS * path
            self.path(f"{r}/body/pole_path", self._pole[idx], WIGGLE_COLOR, 0.02, idx=idx)
            name = f"{r}/body/pole_now"
            self._pdot = self.node(name, lambda: self.scene.add_icosphere(
                name, radius=0.04, color=WIGGLE_COLOR, cast_shadow=False, receive_shadow=False))
            name = f"{r}/body/pole_label"
            text = f"pole O ×{k:g} (its departure from the start)"
            pos = _tuple(self.RADIUS * 1.1 * _unit(traj.omega_body[0]))
            self.node(name, lambda: self.scene.add_label(name, text, position=pos), text=text, position=pos)
        self._build_centre_line(traj)

    def set_frame(self, i):
        if self._pole is not None:
            self._pdot.position = _tuple(self._pole[i])
        self._frame_centre_line(i)


@register_extra("gravity-gradient-accuracy")
class GravityAccuracyExtra(_Ch16):
    """§815–818: the run is a sweep of the distance s of F (trajectory.t = size/s), so playback
    brings F in from far away: F drawn at its true distance once it is in view (beyond VIEW it
    waits at VIEW on its direction), with the relative errors of Euler's torque and of the §818
    force at that distance in its label (Result.plot_series, computed by the scenario)."""

    options = {"attractor": ("F at its distance, with the errors there", True)}
    VIEW = 2.8  # scene units (the body's largest semi-axis is 1): farther F is drawn here

    def bodies(self, traj):
        return {}  # F is drawn here, at its distance, not on the generic sphere of directions

    def build(self, traj, result):
        self._F = None
        if not self.values.get("attractor", True) or "attractor" not in traj.bodies:
            return
        ratio = np.asarray(traj.t, float)
        self._dist = 1.0 / ratio  # sizes (largest semi-axis) from the centre
        self._dir = _unit(np.asarray(traj.bodies["attractor"], float))
        s = result.plot_series
        self._err = (np.asarray(s.get("torque_rel_error", np.full(len(ratio), np.nan)), float),
                     np.asarray(s.get("force_rel_error", np.full(len(ratio), np.nan)), float))
        name = self.name("F")
        self._F = self.node(name, lambda: self.scene.add_icosphere(
            name, radius=0.1, color=F_COLOR, cast_shadow=False, receive_shadow=False))
        name = self.name("F", "label")
        self._label = self.node(name, lambda: self.scene.add_label(name, "F", position=(0.0, 0.0, 0.22)))
        self._line = self._segs("F_direction", np.zeros((1, 2, 3)), F_COLOR, 0.012)
        self._shown = -1

    def set_frame(self, i):
        if self._F is None or i == self._shown:
            return
        self._shown = i
        d = float(self._dist[i])
        pos = self._dir[i] * min(d, self.VIEW)
        self._F.position = _tuple(pos)
        self._line.points = _f32([[[0, 0, 0], pos]])
        et, ef = self._err[0][i], self._err[1][i]
        where = f"s = {d:.3g} sizes" + ("" if d <= self.VIEW else " (drawn nearer)")
        self._label.text = f"F at {where}: torque error {100 * et:.2g} %, force error {100 * ef:.2g} %"


@register_extra("precession-circular")
class PrecessionExtra(_PoleExtra):
    options = {"cone": ("precession cone (figure axis on the celestial sphere)", True),
               "wiggle": ("nutation wiggle, magnified", True),
               "centre": ("direction to the centre of force", True)}

    def build(self, traj, result):
        self._cone_r = None
        if self.values.get("cone", True):
            self._build_cone(traj)
        self._build_centre_line(traj)

    def set_frame(self, i):
        if self._cone_r is not None:
            self._frame_cone(i)
        self._frame_centre_line(i)


# ---- the Earth: axis, equator, ecliptic, Sun, Moon, stars, the pole among the stars ------------

LABELLED_STARS = ("Polaris", "Vega", "Thuban", "Deneb")


def star_directions(catalogue):
    """Unit vectors in the J2000 ecliptic frame (the frame of the earth scenarios)."""
    from theoria.physics.earth_precession import equatorial_to_ecliptic

    return equatorial_to_ecliptic(catalogue.ra_deg, catalogue.dec_deg)


def stars_to_label(catalogue, n_brightest=10):
    order = list(np.argsort(catalogue.vmag)[:n_brightest])
    for name in LABELLED_STARS:
        if name in catalogue.names:
            j = catalogue.names.index(name)
            if j not in order:
                order.append(j)
    return order


@register_extra("earth", "earth-long-view")
class EarthExtra(_PoleExtra):
    options = {"stars": ("bright stars on the celestial sphere", True),
               "cone": ("pole's path, precession cone", True),
               "wiggle": ("nutation wiggle, magnified (earth)", True),
               "frame": ("axis, equator, ecliptic, Sun and Moon directions", True),
               "pole_view": ("look at the pole among the stars", False)}

    def _pole_axis(self, traj):
        # earth-long-view: the angular-momentum axis (the scenario's pole path); earth: the figure axis
        return traj.L_inertial if self.view._spec is not None and self.view._spec.name == "earth-long-view" \
            else traj.figure_axis

    def build(self, traj, result):
        r = self.view.root
        long_view = result.scenario == "earth-long-view"
        mesh = self.view._h.get(f"{r}/body/mesh")
        if mesh is not None:  # the planetarium view looks out through the Earth: hide its mesh
            want = not self.values.get("pole_view", False)
            if mesh.visible != want:
                mesh.visible = want
        R = CELESTIAL_RADIUS
        if self.values.get("stars", True):
            from ..bright_stars import load_bright_stars

            cat = load_bright_stars()
            d = star_directions(cat)
            for lo, hi, size in ((-2.0, 1.0, 0.07), (1.0, 2.2, 0.05), (2.2, 9.0, 0.035)):
                sel = (cat.vmag >= lo) & (cat.vmag < hi)
                if np.any(sel):
                    self._points(f"stars/mag_{lo:g}", R * d[sel], STAR_COLOR, size)
            for j in stars_to_label(cat):
                self._label(f"stars/label_{j}", cat.names[j], R * 1.03 * d[j])
        self._cone_r = None
        if self.values.get("cone", True):
            # the long view samples every few years: no nutation to magnify
            self._build_cone(traj, wiggle=not long_view)
            self._year_marks(traj, R)
        self._frame_lines = None
        if self.values.get("frame", True) and not self.values.get("pole_view", False):
            th = np.linspace(0, 2 * np.pi, 181)
            eq = 1.08 * np.stack([np.cos(th), np.sin(th), np.zeros_like(th)], 1) * np.asarray(self.view._semi)
            name = f"{r}/body/equator"
            segs = _f32(segments(eq))
            self.node(name, lambda: self.scene.add_line_segments(name, segs, (220, 60, 50), thickness=0.02),
                      points=segs)
            name = f"{r}/body/earth_axis"
            ax = _f32([[[0, 0, -1.5], [0, 0, 1.5]]])
            self.node(name, lambda: self.scene.add_line_segments(name, ax, (30, 30, 30), thickness=0.025), points=ax)
            name = f"{r}/body/north_label"
            self.node(name, lambda: self.scene.add_label(name, "N (axis)", position=(0, 0, 1.6)))
            ecl = 1.7 * np.stack([np.cos(th), np.sin(th), np.zeros_like(th)], 1)
            self._segs("ecliptic", segments(ecl), (200, 160, 0), 0.015)
            self._label("ecliptic_label", "ecliptic", (1.7 * 0.7, -1.7 * 0.7, 0.05))
            self._sun = _unit(traj.bodies["sun"]) if "sun" in traj.bodies else None
            self._moon = _unit(traj.bodies["moon"]) if "moon" in traj.bodies else None
            self._frame_lines = self._segs("sun_moon", np.zeros((2, 2, 3)), np.array(
                [[[230, 170, 0]] * 2, [[110, 110, 130]] * 2], np.uint8), 0.015)

    def _year_marks(self, traj, R):
        t = np.asarray(traj.t, float)
        span = t[-1] - t[0]
        if span < 1000:
            return
        axis = _unit(self._pole_axis(traj))
        step = 2000.0 if span > 6000 else 1000.0
        marks = np.arange(0.0, t[-1] + 1e-9, step)
        pts, keys = [], []
        for y in marks:
            i = int(np.argmin(np.abs(t - y)))
            pts.append(R * 1.005 * axis[i])
            out = np.array([axis[i, 0], axis[i, 1], 0.0])  # away from the ecliptic pole
            keys.append((int(round(2000 + y)), R * axis[i] + 0.1 * _unit(out)))
        self._points("pole_years/points", np.array(pts), (200, 30, 60), 0.05)
        every = 1 if self.values.get("pole_view", False) else 2  # the oblique view has less room
        for k, (yr, pos) in enumerate(keys):
            if k % every == 0 and k < len(keys) - 1 or k == 0:
                self._label(f"pole_years/{k}", f"AD {yr}", pos)

    def set_frame(self, i):
        if self._cone_r is not None:
            self._frame_cone(i)
        if self._frame_lines is not None:
            segs = np.zeros((2, 2, 3), np.float32)
            if self._sun is not None:
                segs[0, 1] = ORBIT_RADIUS * self._sun[i]
            if self._moon is not None:
                segs[1, 1] = ORBIT_RADIUS * self._moon[i]
            self._frame_lines.points = segs

    def follow_camera(self, traj, i):
        """Planetarium view toward the north ecliptic pole from just below the (hidden) Earth, so
        the pole's circle of 23.4° and its stars fill the view."""
        if not self.values.get("pole_view", False):
            return None
        # shifted along the screen's right (−x here) so the circle sits left of the control panel
        return dict(position=(-0.45, 0.0, -1.2), look_at=(-0.45, 0.0, CELESTIAL_RADIUS), up=(0.0, 1.0, 0.0),
                    fov_deg=60.0)

    def trail(self, name):
        """No trail for the Moon: sampled every few years (earth-long-view) its direction is a
        scatter, and over a century (earth) a solid band 2 × 5.1° wide that hides the Earth."""
        return name != "moon"
