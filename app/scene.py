"""The 3D scene of one simulation result, drawn with viser (design.md: app/ reads the one
Trajectory object and re-derives no physics).

`SceneView(scene)` works on any viser scene API: a client's (`client.scene`, each browser its own
state) or the server's (`server.scene`, used by the standalone HTML export). `show(result, spec)`
sends every path ONCE; `set_frame(i)` then only moves poses, short arrows and visibility.

Scene units: a rotation scene is scaled so that the body's largest semi-axis is 1.  Orbit scenes
(kind="orbit", Trajectory.bodies only) are scaled so that the largest distance is `ORBIT_RADIUS`.

What is drawn for a rotation scenario (Poinsot's construction, §805–808):
- the body: homogeneous ellipsoid with the moments (A, B, C) (`ellipsoid_semi_axes`), bands of
  latitude about the C axis and one meridian so rotation is visible; an "exaggerate shape" factor
  multiplies the departures of the semi-axes from their mean for nearly spherical bodies;
- principal axes A, B, C as red / green / blue labelled arrows (children of the body frame);
- ω and L as arrows (ω scaled so that its tip lies on the energy ellipsoid, whose plane of
  contact is the invariable plane);
- the polhode: where the instantaneous axis pierces the body surface, drawn on the body (child of
  the body frame, so it moves with it);
- the herpolhode: the tip of ω in space, on the invariable plane (a disc normal to L);
- the trail of the rotation axis in space (unit vector on a sphere of radius 1.6);
- optional: the energy ellipsoid ω·Iω = 2E (body-fixed) and the momentum sphere |L| with the
  path of L on the body; a celestial sphere with the paths of the rotation and figure axes.
"""
from __future__ import annotations

import colorsys
from dataclasses import dataclass, field

import numpy as np
import trimesh

from physics.inertia import ellipsoid_semi_axes

AXIS_COLORS = ((220, 50, 47), (60, 170, 60), (38, 110, 220))  # A red, B green, C blue
OMEGA_COLOR = (255, 150, 0)
L_COLOR = (170, 60, 200)
TRAIL_COLOR = (240, 120, 30)
POLHODE_COLOR = (250, 210, 40)
HERPOLHODE_COLOR = (0, 190, 200)
FIGURE_COLOR = (38, 110, 220)
ORBIT_RADIUS = 3.0
MAX_DRAW_POINTS = 10000  # points per drawn path (10⁴-point trails)
TRAIL_CHUNKS = 40  # a path is sent once, in chunks whose visibility grows with time
AXIS_TRAIL_RADIUS = 1.6
CELESTIAL_RADIUS = 2.4

OVERLAYS = {
    # name: (label, default for ch. 15 rotation scenes, default elsewhere)
    "axes": ("principal axes A, B, C", True, True),
    "vectors": ("ω and L arrows", True, True),
    "axis_trail": ("trail of the rotation axis", True, True),
    "polhode": ("polhode (on the body)", True, True),
    "herpolhode": ("herpolhode + invariable plane", True, False),
    "energy_ellipsoid": ("energy ellipsoid (Poinsot)", False, False),
    "momentum_sphere": ("momentum sphere (path of L on the body)", False, False),
    "celestial": ("celestial sphere + pole paths", False, True),
    "bodies": ("other bodies + trails", True, True),
}


def palette(k: int) -> tuple[int, int, int]:
    r, g, b = colorsys.hsv_to_rgb((0.13 + 0.31 * k) % 1.0, 0.75, 0.95)
    return int(255 * r), int(255 * g), int(255 * b)


def decimate_index(n: int, max_points: int = MAX_DRAW_POINTS) -> np.ndarray:
    """Indices of at most `max_points` samples out of n, first and last included."""
    if n <= max_points:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, max_points).round().astype(int))


def segments(path: np.ndarray) -> np.ndarray:
    """(N,3) polyline → (N−1,2,3) line segments."""
    path = np.asarray(path, np.float32)
    return np.stack([path[:-1], path[1:]], axis=1)


def shape_semi_axes(inertia, exaggerate: float = 1.0) -> np.ndarray:
    """Semi-axes of the body drawn: the true ellipsoid of the moments, normalised to a largest
    semi-axis of 1, with departures from the mean multiplied by `exaggerate`."""
    ax = ellipsoid_semi_axes(inertia)
    ax = ax / ax.max()
    mean = ax.mean()
    ax = mean + exaggerate * (ax - mean)
    ax = ax / ax.max()
    return np.clip(ax, 0.12, None)  # a flat body (A + B = C) keeps a visible thickness


def banded_ellipsoid(semi_axes, base=(200, 190, 170)) -> trimesh.Trimesh:
    """A UV-sphere scaled to the semi-axes, coloured in latitude bands about the body z (C)
    axis with one dark meridian (body x–z half-plane) so that spin is visible."""
    m = trimesh.creation.uv_sphere(radius=1.0, count=[48, 48])
    v = m.vertices
    lat = np.arcsin(np.clip(v[:, 2], -1, 1))
    lon = np.arctan2(v[:, 1], v[:, 0])
    band = (np.floor((lat + np.pi / 2) / (np.pi / 8)).astype(int)) % 2
    col = np.where(band[:, None] == 1, np.array(base), np.array([120, 140, 175]))
    col = np.where((np.abs(lon) < 0.12)[:, None], np.array([60, 40, 30]), col)
    col = np.where((np.abs(lat) < 0.05)[:, None], np.array([230, 80, 60]), col)
    m.vertices = v * np.asarray(semi_axes)[None, :]
    m.visual = trimesh.visual.ColorVisuals(m, vertex_colors=np.hstack([col, 255 * np.ones((len(col), 1))]).astype(np.uint8))
    return m


def wire_sphere(radius: float, n_lat: int = 5, n_lon: int = 8, n: int = 72) -> np.ndarray:
    """Line segments of a latitude/longitude wire sphere."""
    segs = []
    th = np.linspace(0, 2 * np.pi, n)
    for lat in np.linspace(-np.pi / 2, np.pi / 2, n_lat + 2)[1:-1]:
        c = np.stack([np.cos(lat) * np.cos(th), np.cos(lat) * np.sin(th), np.full_like(th, np.sin(lat))], 1)
        segs.append(segments(radius * c))
    ph = np.linspace(-np.pi / 2, np.pi / 2, n // 2)
    for lon in np.linspace(0, np.pi, n_lon, endpoint=False):
        for s in (1, -1):
            c = np.stack([s * np.cos(ph) * np.cos(lon), s * np.cos(ph) * np.sin(lon), np.sin(ph)], 1)
            segs.append(segments(radius * c))
    return np.concatenate(segs)


@dataclass
class _Path:
    """A path sent once as chunks; chunk k holds samples [starts[k], starts[k+1]]."""

    handles: list
    starts: np.ndarray  # trajectory sample index where each chunk begins
    shown: int = -1
    visible: bool = True

    def set_time_index(self, i: int) -> None:
        n = int(np.searchsorted(self.starts, i, side="right"))
        if n == self.shown:
            return
        for k, h in enumerate(self.handles):
            want = self.visible and k < n
            if h.visible != want:
                h.visible = want
        self.shown = n

    def set_visible(self, on: bool, i: int) -> None:
        self.visible = on
        self.shown = -1
        self.set_time_index(i)


@dataclass
class SceneState:
    n: int = 0
    t: np.ndarray | None = None
    paths: dict = field(default_factory=dict)  # overlay → list of _Path
    static: dict = field(default_factory=dict)  # overlay → list of handles (shown/hidden, never animated)
    body_frame: object = None
    omega_arrow: object = None
    L_arrow: object = None
    markers: dict = field(default_factory=dict)  # name → (handle, (N,3) positions)


class SceneView:
    """All nodes of one result under `root` (e.g. "/world") on a viser scene API."""

    def __init__(self, scene, root: str = "/world", grow_trails: bool = True):
        self.scene = scene
        self.root = root
        self.grow_trails = grow_trails
        self.state = SceneState()
        self.overlays: dict[str, bool] = {}
        self.exaggerate = 1.0
        self.frame = 0
        self._result = None
        self._spec = None

    # ---- building --------------------------------------------------------------------------
    def default_overlays(self, spec) -> dict[str, bool]:
        ch15 = spec is not None and spec.group == "ch. 15"
        return {k: (v[1] if ch15 else v[2]) for k, v in OVERLAYS.items()}

    def clear(self) -> None:
        for h in self._all_handles():
            try:
                h.remove()
            except Exception:
                pass
        self.state = SceneState()

    def _all_handles(self):
        seen = set()
        for h in self._handles():
            if id(h) not in seen:
                seen.add(id(h))
                yield h

    def _handles(self):
        s = self.state
        for paths in s.paths.values():
            for p in paths:
                yield from p.handles
        for hs in s.static.values():
            yield from hs
        for h, _ in s.markers.values():
            yield h
        for h in (s.omega_arrow, s.L_arrow, s.body_frame):
            if h is not None:
                yield h

    def show(self, result, spec, overlays: dict[str, bool] | None = None, exaggerate: float | None = None) -> None:
        """Replace the scene by `result` (a physics.scenarios.Result) of scenario `spec`."""
        if overlays is not None:
            self.overlays = dict(overlays)
        if not self.overlays:
            self.overlays = self.default_overlays(spec)
        if exaggerate is not None:
            self.exaggerate = float(exaggerate)
        self.clear()
        self._result, self._spec = result, spec
        traj = result.trajectory
        st = self.state
        st.n = len(traj.t)
        st.t = traj.t
        self.frame = 0
        rotation = spec.kind == "rotation"
        if rotation:
            self._build_rotation(traj)
        self._build_bodies(traj, rotation)
        for name, on in self.overlays.items():
            self.set_overlay(name, on)
        self.set_frame(0)

    def _add_path(self, overlay: str, name: str, path: np.ndarray, color, thickness=0.012,
                  grow: bool | None = None, idx: np.ndarray | None = None) -> None:
        """Send `path` (samples at trajectory indices `idx`) once, as TRAIL_CHUNKS chunks."""
        path = np.asarray(path, np.float32)
        if len(path) < 2:
            return
        if idx is None:
            idx = np.arange(len(path))
        grow = self.grow_trails if grow is None else grow
        k = TRAIL_CHUNKS if grow else 1
        bounds = np.unique(np.linspace(0, len(path) - 1, k + 1).round().astype(int))
        handles, starts = [], []
        for j in range(len(bounds) - 1):
            a, b = bounds[j], bounds[j + 1]
            h = self.scene.add_line_segments(f"{name}/{j}", segments(path[a:b + 1]), color,
                                             thickness=thickness, thickness_units="world")
            handles.append(h)
            starts.append(idx[a] if grow else 0)
        self.state.paths.setdefault(overlay, []).append(_Path(handles, np.asarray(starts)))

    def _build_rotation(self, traj) -> None:
        sc, r, st = self.scene, self.root, self.state
        I = traj.inertia
        semi = shape_semi_axes(I, self.exaggerate)
        idx = decimate_index(len(traj.t))
        st.body_frame = sc.add_frame(f"{r}/body", show_axes=False)
        st.static["body"] = [sc.add_mesh_trimesh(f"{r}/body/mesh", banded_ellipsoid(semi))]
        # principal axes A, B, C with labels
        ends = np.diag(semi * 1.35)
        arrows = np.stack([np.zeros((3, 3)), ends], 1)
        cols = np.array(AXIS_COLORS, np.uint8)
        axes = [sc.add_arrows(f"{r}/body/axes", arrows, cols, shaft_radius=0.018, head_radius=0.05, head_length=0.1)]
        for k, lab in enumerate("ABC"):
            axes.append(sc.add_label(f"{r}/body/axis_labels/{lab}", f"{lab} = {I[k]:.4g}",
                                     position=tuple(ends[k] * 1.08)))
        st.static["axes"] = axes
        # polhode on the body: where the rotation axis pierces the surface (ray / ellipsoid)
        w = traj.omega_body[idx]
        nw = np.linalg.norm(w, axis=1, keepdims=True)
        ok = nw[:, 0] > 0
        if np.count_nonzero(ok) >= 2:
            u = w[ok] / nw[ok]
            s = 1.0 / np.sqrt(np.sum((u / semi) ** 2, axis=1, keepdims=True))
            self._add_path("polhode", f"{r}/body/polhode", 1.015 * s * u, POLHODE_COLOR, 0.02, idx=idx[ok])
        # Poinsot: energy ellipsoid ω·Iω = 2E in ω-space, scaled so its largest semi-axis is 1.3
        E = float(traj.energy[0])
        Lmag = float(traj.momentum_norm[0])
        if E > 0 and Lmag > 0:
            e_semi = np.sqrt(2 * E / I)
            k_w = 1.3 / e_semi.max()
            self.k_omega = k_w
            ell = trimesh.creation.icosphere(subdivisions=3)
            ell.vertices = ell.vertices * (e_semi * k_w)[None, :]
            st.static["energy_ellipsoid"] = [
                sc.add_mesh_simple(f"{r}/body/energy_ellipsoid", ell.vertices, ell.faces, color=(120, 200, 255),
                                   opacity=0.25, side="double")]
            self._add_path("energy_ellipsoid", f"{r}/body/polhode_on_ellipsoid", k_w * traj.omega_body[idx],
                           POLHODE_COLOR, 0.012, idx=idx)
            # momentum sphere |L| (body frame) and the path of L on the body
            k_L = 1.3 / Lmag
            sph = trimesh.creation.icosphere(subdivisions=3, radius=1.3)
            st.static["momentum_sphere"] = [
                sc.add_mesh_simple(f"{r}/body/momentum_sphere", sph.vertices, sph.faces, color=(200, 150, 255),
                                   opacity=0.2, side="double")]
            self._add_path("momentum_sphere", f"{r}/body/L_path", k_L * traj.L_body[idx], L_COLOR, 0.012, idx=idx)
            # herpolhode: ω tip in space, and the invariable plane through it (normal to L₀)
            Lhat = traj.L_inertial[0] / Lmag
            self._add_path("herpolhode", f"{r}/herpolhode", k_w * traj.omega_inertial[idx], HERPOLHODE_COLOR,
                           0.012, idx=idx)
            d = k_w * 2 * E / Lmag  # distance of the plane from the centre: ω·L̂ = 2E/|L|
            disc = trimesh.creation.cylinder(radius=1.5, height=0.002, sections=64)
            z = np.array([0, 0, 1.0])
            ax = np.cross(z, Lhat)
            ang = np.arctan2(np.linalg.norm(ax), z @ Lhat)
            wxyz = (1.0, 0.0, 0.0, 0.0)
            if np.linalg.norm(ax) > 1e-12:
                ax = ax / np.linalg.norm(ax)
                wxyz = (np.cos(ang / 2), *(np.sin(ang / 2) * ax))
            st.static["herpolhode"] = [
                sc.add_mesh_simple(f"{r}/invariable_plane", disc.vertices, disc.faces, color=(0, 160, 170),
                                   opacity=0.1, side="double", position=tuple(d * Lhat), wxyz=wxyz)]
        else:
            self.k_omega = 1.0
        # vectors ω and L (updated per frame: one arrow each, tiny messages)
        st.omega_arrow = sc.add_arrows(f"{r}/omega", np.zeros((1, 2, 3)), OMEGA_COLOR, shaft_radius=0.025,
                                       head_radius=0.06, head_length=0.12)
        st.L_arrow = sc.add_arrows(f"{r}/L", np.zeros((1, 2, 3)), L_COLOR, shaft_radius=0.025,
                                   head_radius=0.06, head_length=0.12)
        st.static["vectors"] = [st.omega_arrow, st.L_arrow,
                                sc.add_label(f"{r}/omega_label", "ω"), sc.add_label(f"{r}/L_label", "L")]
        self._labels = st.static["vectors"][2:]
        # trail of the rotation axis in space
        self._add_path("axis_trail", f"{r}/axis_trail", AXIS_TRAIL_RADIUS * traj.rotation_axis[idx], TRAIL_COLOR,
                       0.012, idx=idx)
        # celestial sphere with the paths of the rotation axis and of the figure axis
        st.static["celestial"] = [sc.add_line_segments(f"{r}/celestial/grid", wire_sphere(CELESTIAL_RADIUS),
                                                       (150, 150, 160), thickness=0.004)]
        self._add_path("celestial", f"{r}/celestial/figure_axis", CELESTIAL_RADIUS * traj.figure_axis[idx],
                       FIGURE_COLOR, 0.02, idx=idx)
        self._add_path("celestial", f"{r}/celestial/rotation_axis", CELESTIAL_RADIUS * traj.rotation_axis[idx],
                       TRAIL_COLOR, 0.012, idx=idx)

    def _build_bodies(self, traj, rotation: bool) -> None:
        if not traj.bodies:
            return
        sc, r, st = self.scene, self.root, self.state
        idx = decimate_index(len(traj.t))
        allpos = np.concatenate([np.asarray(p, float) for p in traj.bodies.values()])
        if rotation:
            # a distant attractor is drawn by its direction, not its distance
            scale_fn = lambda p: ORBIT_RADIUS * p / np.maximum(np.linalg.norm(p, axis=1, keepdims=True), 1e-300)  # noqa: E731
        else:
            span = float(np.max(np.linalg.norm(allpos, axis=1))) or 1.0
            scale_fn = lambda p: ORBIT_RADIUS * p / span  # noqa: E731
        hs = []
        for k, (name, pos) in enumerate(traj.bodies.items()):
            pos = scale_fn(np.asarray(pos, float))
            col = palette(k)
            h = sc.add_icosphere(f"{r}/bodies/{name}", radius=0.12, color=col)
            lab = sc.add_label(f"{r}/bodies/{name}/label", name, position=(0, 0, 0.2))
            st.markers[name] = (h, pos)
            hs += [h, lab]
            self._add_path("bodies", f"{r}/body_trails/{name}", pos[idx], col, 0.015, idx=idx)
        st.static["bodies"] = hs

    # ---- animating -------------------------------------------------------------------------
    def set_overlay(self, name: str, on: bool) -> None:
        self.overlays[name] = bool(on)
        for h in self.state.static.get(name, []):
            h.visible = bool(on)
        for p in self.state.paths.get(name, []):
            p.set_visible(bool(on), self.frame)

    def set_exaggerate(self, factor: float) -> None:
        """Re-send only the body mesh and its axes with the new proportions."""
        self.exaggerate = float(factor)
        if self._result is not None:
            self.show(self._result, self._spec)

    def set_frame(self, i: int) -> None:
        st = self.state
        if st.n == 0:
            return
        i = int(np.clip(i, 0, st.n - 1))
        self.frame = i
        traj = self._result.trajectory
        if st.body_frame is not None:
            st.body_frame.wxyz = traj.quat_wxyz[i]
            if self.overlays.get("vectors", True):
                w = self.k_omega * traj.omega_inertial[i]
                Lm = traj.momentum_norm[i]
                Lv = 1.3 * traj.L_inertial[i] / Lm if Lm > 0 else np.zeros(3)
                st.omega_arrow.points = np.array([[[0, 0, 0], w]], np.float32)
                st.L_arrow.points = np.array([[[0, 0, 0], Lv]], np.float32)
                self._labels[0].position = tuple(w * 1.1)
                self._labels[1].position = tuple(Lv * 1.1)
        for h, pos in st.markers.values():
            h.position = pos[i]
        for paths in st.paths.values():
            for p in paths:
                p.set_time_index(i)
