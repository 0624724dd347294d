"""Scene drawings of Euler's three-body papers (seed 003; issue 6 item 5).

Everything drawn is read from the Result: body positions (Trajectory.bodies), the angle of the
co-rotating frame (`series["frame_angle_rad"]`), the co-rotating/element series, the
zero-velocity grid and Lagrange points (`Result.extras`). The only computations here are
drawing geometry: a rotation of the positions into the co-rotating frame, contour lines of the
physics' grid (marching squares), scaling to scene units.

- `collinear` (1767): the line through the three bodies with a BC/AB read-out; restricted mode:
  L1–L5 markers (labelled) and the zero-velocity curves through L1, L2, L3 (levels of
  2Ω = C_J), turning with the primaries in the inertial view, fixed in the co-rotating view.
- `syzygy` (1766): the Sun–Earth line and the syzygy point (Sun–Earth L1 or L2); in the
  co-rotating frame (default) the Moon swings about the line and then leaves; η and v/b read-out.
- `lunar-perturbation` (1768): the Moon's orbit plane (translucent disc) with its line of nodes
  and normal, the trace of the normal (the plane turning once in 18.6 yr), the ecliptic and the
  equinox direction for reference, the Moon's last month of orbit as a short trail and an
  inclination/node read-out following playback.
"""
from __future__ import annotations

import numpy as np
import trimesh

from ..scene import ORBIT_RADIUS, SceneExtra, register_extra

LEVEL_COLORS = {"L1": (230, 70, 70), "L2": (240, 160, 40), "L3": (70, 140, 240)}
MARKER_COLOR = (250, 250, 255)
LINE_COLOR = (150, 150, 165)


def rot_z(theta: float) -> tuple[float, float, float, float]:
    """wxyz quaternion of a rotation by theta about z."""
    return (float(np.cos(theta / 2)), 0.0, 0.0, float(np.sin(theta / 2)))


def rot_zx(psi: float, inc: float) -> tuple[float, float, float, float]:
    """wxyz of R_z(psi)·R_x(inc): takes z to the normal (sin i sin ψ, −sin i cos ψ, cos i) of a
    plane with ascending node at longitude ψ and inclination i, and x to the node direction."""
    cz, sz = np.cos(psi / 2), np.sin(psi / 2)
    cx, sx = np.cos(inc / 2), np.sin(inc / 2)
    return (float(cz * cx), float(cz * sx), float(sz * sx), float(sz * cx))


def to_corotating(pos: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Positions (N,3) seen from the frame turned by theta(t) about z."""
    c, s = np.cos(theta), np.sin(theta)
    out = np.array(pos, float, copy=True)
    out[:, 0] = c * pos[:, 0] + s * pos[:, 1]
    out[:, 1] = -s * pos[:, 0] + c * pos[:, 1]
    return out


def contour_segments(x: np.ndarray, y: np.ndarray, Z: np.ndarray, level: float) -> np.ndarray:
    """Line segments (M,2,3) of the level set Z = level on the grid Z[j, i] at (x[i], y[j])
    (marching squares, linear interpolation on the cell edges; a saddle cell gets two segments
    paired by edge order). z = 0."""
    F = np.asarray(Z, float) - level
    f00, f01, f11, f10 = F[:-1, :-1], F[:-1, 1:], F[1:, 1:], F[1:, :-1]
    X0, X1 = np.meshgrid(x[:-1], y[:-1])[0], np.meshgrid(x[1:], y[:-1])[0]
    Y0, Y1 = np.meshgrid(x[:-1], y[:-1])[1], np.meshgrid(x[:-1], y[1:])[1]

    def cut(a, b):
        ok = np.isfinite(a) & np.isfinite(b) & ((a > 0) != (b > 0))
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.where(ok, a / (a - b), 0.5)
        return ok, u

    edges = []  # bottom, right, top, left: (mask, px, py)
    ok, u = cut(f00, f01)
    edges.append((ok, X0 + u * (X1 - X0), Y0))
    ok, u = cut(f01, f11)
    edges.append((ok, X1, Y0 + u * (Y1 - Y0)))
    ok, u = cut(f10, f11)
    edges.append((ok, X0 + u * (X1 - X0), Y1))
    ok, u = cut(f00, f10)
    edges.append((ok, X0, Y0 + u * (Y1 - Y0)))
    M = np.stack([e[0] for e in edges], -1)
    P = np.stack([np.stack([e[1], e[2]], -1) for e in edges], -2)  # (ny-1, nx-1, 4, 2)
    cnt = M.sum(-1)
    segs = []
    two = cnt == 2
    if np.any(two):
        order = np.argsort(~M[two], axis=-1, kind="stable")[:, :2]  # the two cut edges
        p = P[two]
        segs.append(np.stack([p[np.arange(len(p)), order[:, 0]], p[np.arange(len(p)), order[:, 1]]], 1))
    four = cnt == 4
    if np.any(four):
        p = P[four]
        segs += [np.stack([p[:, 0], p[:, 1]], 1), np.stack([p[:, 2], p[:, 3]], 1)]
    if not segs:
        return np.zeros((0, 2, 3), np.float32)
    s2 = np.concatenate(segs)
    return np.concatenate([s2, np.zeros(s2.shape[:2] + (1,))], -1).astype(np.float32)


class _OrbitExtra(SceneExtra):
    """Common parts: the co-rotating option, scaled positions, a frame node turning with the
    co-rotating frame (children drawn in co-rotating coordinates) and a read-out label."""

    skip_bodies: tuple[str, ...] = ()
    uses_rot = True  # draws children of the co-rotating frame node

    def corotating(self, traj) -> bool:
        return bool(self.values.get("corotating", False)) and "frame_angle_rad" in traj.series

    def bodies(self, traj):
        out = {k: np.asarray(v, float) for k, v in traj.bodies.items() if k not in self.skip_bodies}
        if self.corotating(traj):
            th = np.asarray(traj.series["frame_angle_rad"], float)
            out = {k: to_corotating(v, th) for k, v in out.items()}
        return out

    def span(self, traj) -> float:
        return float(max(np.max(np.linalg.norm(v, axis=1)) for v in self.bodies(traj).values())) or 1.0

    def scale(self, traj) -> float:
        return ORBIT_RADIUS / self.span(traj)

    def rot_frame(self):
        n = self.name("rot")
        return self.node(n, lambda: self.scene.add_frame(n, show_axes=False))

    def segments_node(self, name, segs, color, thickness=0.01):
        n = self.name(*name.split("/"))
        segs = np.asarray(segs, np.float32)
        return self.node(n, lambda: self.scene.add_line_segments(n, segs, color, thickness=thickness,
                                                                 thickness_units="world"), points=segs)

    def label(self, name, text, position):
        n = self.name(*name.split("/"))
        pos = tuple(float(v) for v in position)
        return self.node(n, lambda: self.scene.add_label(n, text, position=pos), text=text, position=pos)

    def marker(self, name, position, color, radius=0.05):
        n = self.name(*name.split("/"))
        pos = tuple(float(v) for v in position)
        return self.node(n, lambda: self.scene.add_icosphere(n, radius=radius, color=color, position=pos,
                                                             cast_shadow=False, receive_shadow=False), position=pos)

    def build(self, traj, result) -> None:
        self.traj, self.result = traj, result
        self.k = self.scale(traj)
        self.theta = np.asarray(traj.series.get("frame_angle_rad", np.zeros(len(traj.t))), float)
        self.rot = self.rot_frame() if self.uses_rot else None
        self._rot_wxyz = None
        self.readout = None
        self.build_scene(traj, result)

    def build_scene(self, traj, result) -> None:  # pragma: no cover - interface
        pass

    def readout_text(self, i: int) -> str:
        return ""

    def set_frame(self, i: int) -> None:
        if getattr(self, "traj", None) is None:
            return
        want = (1.0, 0.0, 0.0, 0.0) if self.corotating(self.traj) else rot_z(self.theta[i])
        if self.rot is not None and getattr(self, "_rot_wxyz", None) != want:
            self.rot.wxyz = self._rot_wxyz = want
        if self.readout is not None:
            text = self.readout_text(i)
            if text != getattr(self.readout, "text", None):
                self.readout.text = text


@register_extra("collinear")
class Collinear(_OrbitExtra):
    """The line of the three bodies (rotating/collapse/expansion) or, for the restricted problem,
    L1–L5 with the zero-velocity curves through L1, L2, L3."""

    options = {"corotating": ("co-rotating frame (turning with the bodies)", False)}
    skip_bodies = ("L1", "L2", "L3", "L4", "L5")

    def span(self, traj) -> float:
        s = super().span(traj)
        res = self.view._result  # the result being shown (the bodies overlay is built before `build`)
        pts = res.extras.get("lagrange_points") if res is not None else None
        if pts is None and "L2" in traj.bodies:
            pts = {k: traj.bodies[k][0, :2] for k in self.skip_bodies if k in traj.bodies}
        if pts:
            s = max(s, 1.1 * max(np.hypot(*p) for p in pts.values()))
        return s

    def build_scene(self, traj, result) -> None:
        k = self.k
        zv = result.extras.get("zero_velocity")
        pts = result.extras.get("lagrange_points")
        self.restricted = pts is not None
        if self.restricted:
            # markers L1–L5 and the zero-velocity curves, in co-rotating coordinates under `rot`
            for name, (x, y) in pts.items():
                self.marker(f"rot/L/{name}", (k * x, k * y, 0.0), MARKER_COLOR)
                self.label(f"rot/L/{name}/label", name, (0.0, -0.11, 0.0))  # below: clear of the bodies' labels
            if zv is not None:
                for name, col in LEVEL_COLORS.items():
                    if name in zv["levels"]:
                        segs = k * contour_segments(np.asarray(zv["x"]), np.asarray(zv["y"]),
                                                    np.asarray(zv["two_omega"]), zv["levels"][name])
                        if len(segs):
                            self.segments_node(f"rot/zvc/{name}", segs, col, 0.008)
                self.label("zvc_key", "zero-velocity curves 2Ω = C_J through L1 (red), L2 (orange), L3 (blue)",
                           (-ORBIT_RADIUS, -ORBIT_RADIUS, 0.0))
            self.segments_node("rot/axis", [[[-1.25 * k, 0, 0], [1.25 * k, 0, 0]]], LINE_COLOR, 0.004)
            self.readout = self.label("readout", "", (-ORBIT_RADIUS, ORBIT_RADIUS, 0.0))
        else:
            # the line through the three bodies: the bodies start on x and turn with the frame
            P = [np.asarray(traj.bodies[n], float) for n in ("A", "B", "C") if n in traj.bodies]
            ext = 1.15 * k * max(np.max(np.abs(p[:, 0])) for p in P) if P else ORBIT_RADIUS
            self.segments_node("rot/line", [[[-ext, 0, 0], [ext, 0, 0]]], LINE_COLOR, 0.006)
            self.readout = self.label("readout", "", (-ORBIT_RADIUS, ORBIT_RADIUS, 0.0))

    def readout_text(self, i: int) -> str:
        tr, m = self.traj, self.result.metrics
        if self.restricted:
            drift = self.result.plot_series.get("satellite drift from the point (distances)")
            d = f"  satellite drift {drift[i]:.3g}" if drift is not None else ""
            return f"t = {tr.t[i]:.3g} {tr.time_unit}{d}"
        r = tr.series.get("ratio_BC_over_AB")
        return (f"BC/AB = {r[i]:.6f}  (α = {m['alpha']:.6f})  t = {tr.t[i]:.3g}" if r is not None
                else f"t = {tr.t[i]:.3g}")


@register_extra("syzygy")
class Syzygy(_OrbitExtra):
    """The Sun–Earth line and the syzygy point; the Moon's swing and escape in the co-rotating
    frame (default)."""

    options = {"corotating": ("co-rotating frame (Sun fixed on +x)", True),
               "inset": ("magnified swing about the syzygy point (inset)", True),
               "plot_per_amplitude": ("plot in units of the amplitude A (Euler's curve visible)", True)}
    PLOT_CLIP = 4.0  # |η/A| shown up to this (the escape is read in the scene)
    INSET_OFFSET = (0.0, 0.75, 0.0)  # scene units from the syzygy point
    INSET_AMPLITUDE = 0.18  # the first swing drawn this large (scene units)
    INSET_CLIP = 0.55  # the magnified path is drawn while within this radius

    def build_scene(self, traj, result) -> None:
        k = self.k
        self.inset_dot = None
        sun_d = float(np.linalg.norm(np.asarray(traj.bodies["sun"])[0])) if "sun" in traj.bodies else self.span(traj)
        self.segments_node("rot/sun_line", [[[-0.5 * k * sun_d, 0, 0], [k * sun_d, 0, 0]]], (240, 200, 60), 0.006)
        p = result.extras.get("syzygy_point_lunar")
        if p is not None:
            side = "L1" if p[0] > 0 else "L2"
            self.marker("rot/syzygy_point", (k * p[0], k * p[1], 0.0), MARKER_COLOR, 0.04)
            self.label("rot/syzygy_point/label", f"syzygy point (Sun–Earth {side})", (0.0, -0.18, 0.0))
        self.readout = self.label("readout", "", (-0.4, -0.6, 0.0))
        if p is not None and self.values.get("inset", True) and self.corotating(traj):
            self._build_inset(traj, result, np.asarray(p, float))

    def _build_inset(self, traj, result, p) -> None:
        """The Moon's offset from the syzygy point, magnified M times so that the first swing
        (η amplitude A) is INSET_AMPLITUDE long, drawn beside the point while it stays within
        INSET_CLIP: Euler's small oscillation (a retrograde ellipse, radial/transverse = 0.31) and
        its growth into the escape."""
        k, s = self.k, traj.series
        rel = np.stack([np.asarray(s["moon_corotating_x"]) - p[0], np.asarray(s["moon_corotating_y"]) - p[1],
                        np.zeros(len(traj.t))], 1)
        A = np.radians(float(result.params.get("amplitude_deg", 0.0)))
        amp0 = abs(p[0]) * A if A > 0 else float(np.linalg.norm(rel[min(len(rel) - 1, 5)]))
        if amp0 <= 0:
            return
        M = self.INSET_AMPLITUDE / (k * amp0)
        centre = k * p + np.asarray(self.INSET_OFFSET)
        with np.errstate(over="ignore", invalid="ignore"):
            pts = centre + k * M * rel
        if not np.all(np.isfinite(pts)):  # a swing too small to magnify (amplitude 1e-311°: found by test_fuzz)
            return
        inside = np.linalg.norm(pts - centre, axis=1) <= self.INSET_CLIP
        last = int(np.argmin(inside)) if not inside.all() else len(inside)
        self.inset_pts, self.inset_last = pts, last
        if last >= 2:
            idx = np.arange(last)
            self.path(self.name("inset", "path"), pts[:last], (190, 120, 255), 0.008, idx=idx)
        r = self.INSET_CLIP
        th = np.linspace(0, 2 * np.pi, 65)
        ring = centre + np.stack([r * np.cos(th), r * np.sin(th), 0 * th], 1)
        self.segments_node("inset/frame", np.stack([ring[:-1], ring[1:]], 1), (110, 110, 125), 0.003)
        self.segments_node("inset/line", [[centre - (r, 0, 0), centre + (r, 0, 0)]], (240, 200, 60), 0.004)
        self.label("inset/label", f"swing about the Sun line ×{M:.0f}", centre + (-r, r + 0.05, 0))
        self.inset_dot = self.marker("inset/moon", pts[0], (190, 120, 255), 0.03)

    def set_frame(self, i: int) -> None:
        if getattr(self, "traj", None) is None:
            return
        super().set_frame(i)
        if self.inset_dot is not None:
            on = i < self.inset_last
            if on:
                self.inset_dot.position = tuple(float(x) for x in self.inset_pts[i])
            if getattr(self, "_dot_on", None) != on:
                self.inset_dot.visible = self._dot_on = on

    def plot_series(self, result) -> dict:
        """η/A and (v/b − 1)/A beside Euler's sin αζ and −0.3117 cos αζ (§16), clipped at
        ±PLOT_CLIP: in degrees the escape (tens of degrees) flattens the first swings of 0.05°."""
        ps = result.plot_series
        A = float(result.params.get("amplitude_deg", 0.0))
        keys = ("η simulated (deg)", "η Euler A sin αζ (deg)", "v/b simulated", "v/b Euler 1 − 0.3117 A cos αζ")
        if not self.values.get("plot_per_amplitude", True) or A <= 0 or not all(k in ps for k in keys):
            return ps
        Ar, c = np.radians(A), self.PLOT_CLIP
        return {  # Euler's curve first, the simulation drawn over it
            "η/A Euler: sin αζ": np.asarray(ps[keys[1]]) / A,
            f"η/A simulated (clipped at ±{c:g})": np.clip(np.asarray(ps[keys[0]]) / A, -c, c),
            "(v/b − 1)/A Euler: −0.3117 cos αζ": (np.asarray(ps[keys[3]]) - 1) / Ar,
            f"(v/b − 1)/A simulated (clipped at ±{c:g})": np.clip((np.asarray(ps[keys[2]]) - 1) / Ar, -c, c),
        }

    def readout_text(self, i: int) -> str:
        tr = self.traj
        eta, v = tr.series.get("eta_deg"), tr.series.get("distance_over_b")
        if eta is None or v is None:
            return f"t = {tr.t[i]:.3g} {tr.time_unit}"
        return f"η = {eta[i]:+.3g}°  v/b = {v[i]:.4f}  t = {tr.t[i]:.3f} {tr.time_unit}"


@register_extra("lunar-perturbation")
class LunarPerturbation(_OrbitExtra):
    """The Moon's orbit plane turning: disc, node line, normal and the trace of the normal."""

    options = {"plot_inclination": ("plot the inclination (else node and perigee longitudes)", False),
               "exaggerate": ("heights ×5 (tilt drawn as atan(5 tan i); read-out true)", False)}
    EXAGGERATION = 5.0
    TRAIL_DAYS = 27.3
    NORMAL_LENGTH = 1.7  # lunar distances: the tip traces a circle of radius 1.7 sin i

    uses_rot = False
    skip_bodies = ("sun",)  # drawn as a direction from the Earth (its distance is 389 lunar distances)

    def trail(self, name: str) -> bool:
        return name != "moon"  # 40 years of the Moon fill a disc: a one-month trail is drawn instead

    def factor(self) -> float:
        """Vertical exaggeration: heights above the ecliptic multiplied by f, an affine map that
        takes a plane of tilt i to one of tilt atan(f tan i), so Moon, trail and disc stay coplanar."""
        return self.EXAGGERATION if self.values.get("exaggerate", False) else 1.0

    def bodies(self, traj):
        b = super().bodies(traj)  # Moon first: the palette's pale yellow, the Earth its green
        if "moon" in b and self.factor() != 1.0:
            b["moon"] = b["moon"] * np.array([1.0, 1.0, self.factor()])
        return {k: b[k] for k in sorted(b, key=lambda n: n != "moon")}

    def span(self, traj) -> float:
        moon = np.asarray(traj.bodies["moon"], float) if "moon" in traj.bodies else None
        return 2.0 * float(np.max(np.linalg.norm(moon, axis=1))) if moon is not None else super().span(traj)

    def build_scene(self, traj, result) -> None:
        k, s = self.k, traj.series
        self.inc = np.radians(np.asarray(s["inclination_deg"], float))
        self.node_lon = np.radians(np.asarray(s["node_longitude_deg"], float))
        moon = np.asarray(traj.bodies["moon"], float)
        f = self.factor()
        self.moon = (k * moon * np.array([1.0, 1.0, f])).astype(np.float32)
        self.inc_drawn = np.arctan(f * np.tan(self.inc)) if f != 1.0 else self.inc
        R = 1.2 * k * float(np.max(np.linalg.norm(moon, axis=1)))
        # fixed references: the ecliptic circle and the equinox direction
        th = np.linspace(0, 2 * np.pi, 97)
        circle = np.stack([R * np.cos(th), R * np.sin(th), 0 * th], 1)
        self.segments_node("ecliptic", np.stack([circle[:-1], circle[1:]], 1), (120, 120, 130), 0.004)
        self.segments_node("equinox", [[[0, 0, 0], [1.1 * R, 0, 0]]], (120, 120, 130), 0.004)
        self.label("equinox_label", "♈ equinox (x)", (1.15 * R, 0.0, 0.0))
        # the plane: a frame turned by R_z(node)·R_x(inclination); its children lie in the plane
        n = self.name("plane")
        self.plane = self.node(n, lambda: self.scene.add_frame(n, show_axes=False))
        disc = trimesh.creation.cylinder(radius=1.0, height=0.002, sections=72)
        dn = self.name("plane", "disc")
        sc = (R, R, 1.0)
        self.node(dn, lambda: self.scene.add_mesh_simple(dn, disc.vertices, disc.faces, color=(150, 110, 230),
                                                         opacity=0.22, side="double", scale=sc, cast_shadow=False,
                                                         receive_shadow=False), scale=sc)
        self.segments_node("plane/node_line", [[[0, 0, 0], [1.15 * R, 0, 0]], [[0, 0, 0], [-1.15 * R, 0, 0]]],
                           np.array([[[230, 60, 60]] * 2, [[110, 110, 120]] * 2], np.uint8), 0.008)
        self.label("plane/node_label", "☊ ascending node", (1.2 * R, 0.0, 0.0))
        L = self.NORMAL_LENGTH * k
        self.segments_node("plane/normal", [[[0, 0, 0], [0, 0, L]]], (150, 110, 230), 0.008)
        self.label("plane/normal_label", "orbit normal", (0.0, 0.0, 1.05 * L))
        nrm = np.stack([s["orbit_normal_x"], s["orbit_normal_y"], s["orbit_normal_z"]], 1)
        if f != 1.0:  # the normal of the stretched plane
            si = np.sin(self.inc_drawn)
            nrm = np.stack([si * np.sin(self.node_lon), -si * np.cos(self.node_lon), np.cos(self.inc_drawn)], 1)
        idx = self.view._idx
        self.path(self.name("normal_trace"), L * nrm[idx], (150, 110, 230), 0.012, idx=idx)
        self.segments_node("pole", [[[0, 0, 0], [0, 0, 1.1 * L]]], (120, 120, 130), 0.004)
        # the last month of the Moon's orbit (points updated each frame)
        dt = float(np.median(np.diff(traj.t))) if len(traj.t) > 1 else 1.0
        days = dt * (365.25 if traj.time_unit == "yr" else 1.0)
        self.nk = int(np.clip(np.ceil(self.TRAIL_DAYS / max(days, 1e-9)), 2, 400))
        self.moon_trail = self.segments_node("moon_trail", self._trail(0), (240, 240, 250), 0.014)
        # the direction of the Sun (turning once a year)
        self.sun_dir = None
        if "sun" in traj.bodies:
            sun = np.asarray(traj.bodies["sun"], float)
            self.sun_dir = (1.35 * R * sun / np.linalg.norm(sun, axis=1, keepdims=True)).astype(np.float32)
            self.sun_line = self.segments_node("sun_line", [[[0, 0, 0], self.sun_dir[0]]], (240, 200, 60), 0.006)
            self.sun_mark = self.marker("sun_dir", self.sun_dir[0], (250, 210, 60), 0.06)
            self.label("sun_dir/label", "to the Sun", (0.0, 0.0, 0.1))
        self.readout = self.label("readout", "", (-1.6 * R, 0.0, 1.3 * R))

    def plot_series(self, result) -> dict:
        """One y-axis: the longitudes (hundreds of degrees over decades) or the inclination
        (5.0°–5.3°), not both."""
        ps = result.plot_series
        inc = {k: v for k, v in ps.items() if k.startswith("inclination")}
        rest = {k: v for k, v in ps.items() if not k.startswith("inclination")}
        return (inc or ps) if self.values.get("plot_inclination", False) else (rest or ps)

    def _trail(self, i: int) -> np.ndarray:
        a = max(0, i - self.nk + 1)
        p = self.moon[a:i + 1]
        if len(p) < self.nk:
            p = np.concatenate([np.repeat(p[:1], self.nk - len(p), 0), p])
        return np.stack([p[:-1], p[1:]], 1)

    def set_frame(self, i: int) -> None:
        if getattr(self, "traj", None) is None:
            return
        super().set_frame(i)
        self.plane.wxyz = rot_zx(self.node_lon[i], self.inc_drawn[i])
        self.moon_trail.points = self._trail(i)
        if self.sun_dir is not None:
            self.sun_line.points = np.array([[[0, 0, 0], self.sun_dir[i]]], np.float32)
            self.sun_mark.position = tuple(float(x) for x in self.sun_dir[i])

    def readout_text(self, i: int) -> str:
        tr = self.traj
        return (f"i = {np.degrees(self.inc[i]):.3f}°   ☊ = {np.degrees(self.node_lon[i]):.1f}°   "
                f"t = {tr.t[i]:.2f} {tr.time_unit}")
