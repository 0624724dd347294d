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
import functools
from dataclasses import dataclass, field

import numpy as np
import trimesh

from theoria.physics.inertia import ellipsoid_semi_axes

AXIS_COLORS = ((220, 50, 47), (60, 170, 60), (38, 110, 220))  # A red, B green, C blue
OMEGA_COLOR = (255, 150, 0)
L_COLOR = (170, 60, 200)
TRAIL_COLOR = (240, 120, 30)
POLHODE_COLOR = (250, 210, 40)
HERPOLHODE_COLOR = (0, 190, 200)
FIGURE_COLOR = (38, 110, 220)
ORBIT_RADIUS = 2.0
MAX_DRAW_POINTS = 10000  # points per drawn path (10⁴-point trails)
TRAIL_CHUNKS = 24  # a path is sent once, in chunks whose visibility grows with time
# A path point is not drawn again where an earlier point of the same path already is: points are
# quantised to cells of REPEAT_CELL × their size and only the first (in time) of each cell is kept.
# viser draws a point `size` wide on each side of its centre (its gl_PointSize uses tan(fov/2), not
# 2 tan(fov/2)), so a dropped point lies within 0.61 of a drawn point's width of one that is drawn
# already at that time: the picture is the same, but a path that retraces itself (a periodic
# polhode) costs far fewer points, and software WebGL pays per point.
REPEAT_CELL = 0.7
DRAW_MAX = 1e4  # scene units; paths go out as float16 (inf beyond 65504): larger scales fall back (below)
VECTOR_LENGTH_TOL = 0.02  # ω / L arrows: geometry re-sent only when the length changes by 2 %
AXIS_TRAIL_RADIUS = 1.6
# Paths live in scene units of order 1 (body ≈ 1, celestial sphere 2.4, orbits ≤ 3), where
# float16 is good to ~1e-3 of a unit, far below a point's size: half the bytes per update.
PATH_PRECISION = "float16"
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
    "scenario": ("scenario drawings (orbit, markers, arcs)", True, True),
}


class SceneExtra:
    """What one scenario adds to the generic scene (app/scene_extras/*.py).

    Subclass, decorate with `register_extra("scenario-name", ...)`. `build` runs once per result
    (when the "scenario" overlay is on): create nodes with `self.node(...)` / paths with
    `self.path(...)` under `self.name(...)`, so that they are cached, updated in place, pruned
    and shown/hidden with the overlay. `set_frame` moves poses only. `options` are checkboxes the
    app shows in a "Scene options" folder; a change calls `set_option` (and `build` again if it
    returns True).
    """

    options: dict[str, tuple[str, bool]] = {}

    def __init__(self, view: "SceneView"):
        self.view = view
        self.values = {k: v[1] for k, v in self.options.items()}

    # helpers over the view's node cache
    def name(self, *parts: str) -> str:
        return "/".join((self.view.root, "extra") + parts)

    def node(self, name: str, create, **update):
        h = self.view._node(name, create, **update)
        self.view._static.setdefault("scenario", []).append(h)
        return h

    def path(self, name: str, points, color, thickness=0.02, idx=None) -> None:
        self.view._add_path("scenario", name, points, color, thickness, idx=idx)

    @property
    def scene(self):
        return self.view.scene

    def build(self, traj, result) -> None:  # pragma: no cover - interface
        pass

    def set_frame(self, i: int) -> None:
        pass

    # what the generic "bodies" overlay draws for this scenario
    def bodies(self, traj) -> dict | None:
        """name → (N,3) positions to draw as spheres + trails instead of traj.bodies (e.g. in a
        co-rotating frame, or without marker points the extra draws itself); None: traj.bodies."""
        return None

    def span(self, traj) -> float | None:
        """Distance drawn at ORBIT_RADIUS (trajectory units); None: the largest body distance."""
        return None

    def trail(self, name: str) -> bool:
        """Whether the generic overlay draws the trail of body `name`."""
        return True

    def set_option(self, key: str, value: bool) -> bool:
        self.values[key] = bool(value)
        return True

    def plot_series(self, result) -> dict:
        """The time series the app plots against t (override to leave out point clouds such as a
        separatrix or a surface of section, which the extra draws itself)."""
        return result.plot_series

    def follow_camera(self, traj, i: int) -> dict | None:
        """A camera the app applies at every frame i while this returns one (e.g. the Moon seen
        from the Earth): dict(position, look_at, up, fov_deg). None leaves the camera alone."""
        return None


SCENE_EXTRAS: dict[str, type[SceneExtra]] = {}


def register_extra(*names: str):
    def deco(cls):
        for n in names:
            SCENE_EXTRAS[n] = cls
        return cls

    return deco


def extra_for(name: str) -> type[SceneExtra] | None:
    from . import scene_extras  # noqa: F401  (registers every module)

    return SCENE_EXTRAS.get(name)


def palette(k: int) -> tuple[int, int, int]:
    r, g, b = colorsys.hsv_to_rgb((0.13 + 0.31 * k) % 1.0, 0.75, 0.95)
    return int(255 * r), int(255 * g), int(255 * b)


def decimate_index(n: int, max_points: int = MAX_DRAW_POINTS) -> np.ndarray:
    """Indices of at most `max_points` samples out of n, first and last included."""
    if n <= max_points:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, max_points).round().astype(int))


def densify(path: np.ndarray, idx: np.ndarray, spacing: float, max_points: int):
    """Resample a polyline uniformly in arc length: gaps ≤ spacing where possible, at least the
    original number of points (capped at max_points); `idx` (trajectory index of each point)
    is interpolated alongside."""
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] <= 0:
        return path[: max_points], idx[: max_points]
    n = int(np.clip(s[-1] / spacing, len(path), max_points))
    if n == len(path) and n <= max_points:
        return path, idx
    u = np.linspace(0.0, s[-1], n)
    out = np.stack([np.interp(u, s, path[:, k]) for k in range(3)], axis=1)
    return out, np.interp(u, s, idx)


def drop_repeats(path: np.ndarray, idx: np.ndarray, cell: float):
    """Keep, in order, the first point of `path` in each cubic cell of side `cell` (and its idx)."""
    if len(path) < 2 or cell <= 0:
        return path, idx
    key = np.floor(np.asarray(path, float) / cell).astype(np.int64)
    if np.abs(key).max() < 2**20:  # one int64 per cell: a 1-D unique, ~10× faster than unique(axis=0)
        key = ((key[:, 0] + 2**20) << 42) | ((key[:, 1] + 2**20) << 21) | (key[:, 2] + 2**20)
    _, first = np.unique(key, axis=0, return_index=True)
    keep = np.sort(first)
    return path[keep], idx[keep]


def z_to_many(v) -> tuple[np.ndarray, np.ndarray]:
    """Unit quaternions (w, x, y, z) turning +z onto each row of v (N,3) (identity where v is zero or
    not finite) and the lengths: (N,4), (N,). Computed once per result so that playback only
    indexes arrays: the per-frame arrow poses (numpy calls on 3-vectors) were ~5 % of the server's
    CPU in a py-spy profile under thirty browsers."""
    v = np.asarray(v, float)
    n = np.linalg.norm(v, axis=1)
    ok = (n > 0) & np.isfinite(n)
    u = np.where(ok[:, None], v / np.where(ok, n, 1.0)[:, None], [0.0, 0.0, 1.0])
    q = np.stack([1.0 + u[:, 2], -u[:, 1], u[:, 0], np.zeros(len(u))], 1)
    down = u[:, 2] < -1 + 1e-12
    q[down] = (0.0, 1.0, 0.0, 0.0)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return q, np.where(ok, n, 0.0)


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


BAND_LIGHT, BAND_BLUE = (200, 190, 170), (120, 140, 175)
MERIDIAN_COLOR, EQUATOR_COLOR = (60, 40, 30), (230, 80, 60)
MERIDIAN_HALF_WIDTH, EQUATOR_HALF_WIDTH = 0.12, 0.05  # rad


@functools.lru_cache(maxsize=4)
def banded_sphere_parts(rows_per_band: int = 4, columns: int = 64) -> list[tuple[np.ndarray, np.ndarray, tuple]]:
    """A unit sphere in latitude bands of π/8 about the body z (C) axis, a dark meridian in the
    body x–z half-plane and a red equator, so that spin is visible: one (vertices, faces, colour)
    per colour. The grid's rings and meridians fall on the band edges, so every edge is clean.

    One plain mesh per colour rather than one vertex-coloured GLB: in software WebGL at 1280×800,
    forced redraws, the GLB body cost 9–12 ms a frame and the plain meshes ~5 ms (docs/app.md)."""
    lat = np.unique(np.concatenate([np.linspace(-np.pi / 2, np.pi / 2, 8 * rows_per_band + 1),
                                    [-EQUATOR_HALF_WIDTH, EQUATOR_HALF_WIDTH]]))
    lon = np.unique(np.concatenate([np.linspace(-np.pi, np.pi, columns + 1),
                                    [-MERIDIAN_HALF_WIDTH, MERIDIAN_HALF_WIDTH]]))
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    verts = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], -1).reshape(-1, 3)
    nl = len(lon)
    i, j = np.meshgrid(np.arange(len(lat) - 1), np.arange(nl - 1), indexing="ij")
    a, b, c, d = i * nl + j, i * nl + j + 1, (i + 1) * nl + j + 1, (i + 1) * nl + j  # counter-clockwise seen from outside
    lat_c = 0.5 * (lat[:-1] + lat[1:])[i]
    lon_c = 0.5 * (lon[:-1] + lon[1:])[j]
    band = np.floor((lat_c + np.pi / 2) / (np.pi / 8)).astype(int) % 2
    colour = np.where(band == 1, 0, 1)
    colour = np.where(np.abs(lon_c) < MERIDIAN_HALF_WIDTH, 2, colour)
    colour = np.where(np.abs(lat_c) < EQUATOR_HALF_WIDTH, 3, colour)
    quads = np.stack([a, b, c, d], -1).reshape(-1, 4)
    colour = colour.ravel()
    parts = []
    for k, rgb in enumerate((BAND_LIGHT, BAND_BLUE, MERIDIAN_COLOR, EQUATOR_COLOR)):
        q = quads[colour == k]
        tri = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
        tri = tri[np.ptp(verts[tri], axis=1).max(axis=1) > 1e-12]  # no triangles collapsed at the poles
        used, inv = np.unique(tri, return_inverse=True)
        parts.append((verts[used].astype(np.float32), inv.reshape(-1, 3).astype(np.uint32), rgb))
    return parts


def flat_disc(radius: float, sections: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """A disc in the z = 0 plane (triangle fan): one layer, so a see-through disc is blended once
    per pixel (a thin cylinder blends its top and its bottom)."""
    th = np.linspace(0, 2 * np.pi, sections, endpoint=False)
    v = np.vstack([[0.0, 0.0, 0.0], np.stack([radius * np.cos(th), radius * np.sin(th), 0 * th], 1)])
    k = np.arange(sections)
    return v.astype(np.float32), np.stack([np.zeros(sections, int), 1 + k, 1 + (k + 1) % sections], 1).astype(np.uint32)


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


class SceneView:
    """All nodes of one result under `root` (e.g. "/world") on a viser scene API.

    Nodes are kept in a cache by name: a new result of the same scenario updates the existing
    handles in place (points, scale, pose: no node is re-created, meshes are sent once as unit
    shapes and scaled), nodes no longer needed are removed, and the paths of an overlay that is
    switched off are not sent at all until it is switched on.
    """

    def __init__(self, scene, root: str = "/world", grow_trails: bool = True):
        self.scene = scene
        self.root = root
        self.grow_trails = grow_trails
        self.overlays: dict[str, bool] = {}
        self.exaggerate = 1.0
        self.frame = 0
        self.n = 0
        self._result = None
        self._spec = None
        self._h: dict[str, object] = {}  # name → handle (alive)
        self._auto: set[str] = set()  # group nodes created by _ensure_parents
        self._touched: set[str] = set()
        self._paths: dict[str, list[_Path]] = {}  # overlay → paths
        self._static: dict[str, list] = {}  # overlay → handles shown/hidden with it
        self._built: set[str] = set()  # overlays built for the current result
        self._markers: dict[str, tuple] = {}  # name → (handle, (N,3) positions)
        self._labels = []
        self.body_frame = self.omega_arrow = self.L_arrow = None
        self.k_omega = 1.0
        self.extra: SceneExtra | None = None

    # ---- node cache --------------------------------------------------------------------------
    def _node(self, name: str, create, **update):
        """The handle called `name`: created by `create()` the first time, else updated."""
        self._ensure_parents(name)
        h = self._h.get(name)
        if h is None or name in self._auto:
            self._auto.discard(name)  # a group made for a child before its parent: the real node replaces it
            h = create()
            self._h[name] = h
        else:
            for k, v in update.items():
                setattr(h, k, v)
        self._touched.add(name)
        return h

    def _segments(self, name, segs, color, thickness):
        segs = np.asarray(segs, np.float32)
        return self._node(name, lambda: self.scene.add_line_segments(name, segs, color, thickness=thickness,
                                                                       thickness_units="world"), points=segs)

    def _ensure_parents(self, name: str) -> None:
        """Explicit (empty frame) nodes for the groups between the root and `name`: viser keeps a
        parent it created implicitly as an empty group after its children are removed, so every
        group is a cached node, pruned with its last child and removed by `clear`."""
        if not name.startswith(self.root + "/"):
            return
        parts = name.split("/")
        for k in range(self.root.count("/") + 2, len(parts)):
            prefix = "/".join(parts[:k])
            if prefix not in self._h:
                self._h[prefix] = self.scene.add_frame(prefix, show_axes=False)
                self._auto.add(prefix)
            self._touched.add(prefix)

    def _prune(self, keep_prefixes=()):
        for name in sorted(self._h, key=lambda n: -n.count("/")):  # children first
            if name not in self._touched and not name.startswith(keep_prefixes):
                self._auto.discard(name)
                try:
                    self._h.pop(name).remove()
                except Exception:
                    pass

    def clear(self) -> None:
        for name in sorted(self._h, key=lambda n: -n.count("/")):  # children first
            try:
                self._h.pop(name).remove()
            except Exception:
                pass
        self._paths, self._static, self._built, self._markers = {}, {}, set(), {}
        self._auto = set()
        self.body_frame = self.omega_arrow = self.L_arrow = None
        self.extra = None
        self.n = 0

    # ---- building --------------------------------------------------------------------------
    def default_overlays(self, spec) -> dict[str, bool]:
        ch15 = spec is not None and spec.group == "ch. 15"
        out = {k: (v[1] if ch15 else v[2]) for k, v in OVERLAYS.items()}
        out.update(spec.overlays if spec is not None else {})
        return out

    def show(self, result, spec, overlays: dict[str, bool] | None = None, exaggerate: float | None = None) -> None:
        """Show `result` (a physics.scenarios.Result) of scenario `spec`, updating in place."""
        if overlays is not None:
            self.overlays = dict(overlays)
        if not self.overlays:
            self.overlays = self.default_overlays(spec)
        if exaggerate is not None:
            self.exaggerate = float(exaggerate)
        if self._spec is not None and (spec.name != self._spec.name or spec.kind != self._spec.kind):
            self.clear()
        self._result, self._spec = result, spec
        traj = result.trajectory
        self.n = len(traj.t)
        self._idx = decimate_index(self.n)
        self._touched = set()
        self._paths, self._static, self._built = {}, {}, set()
        self._rotation = spec.kind == "rotation"
        cls = extra_for(spec.name)
        if cls is None:
            self.extra = None
        elif type(self.extra) is not cls:
            self.extra = cls(self)
        if self._rotation:
            self._build_body(traj)
        for name, on in self.overlays.items():
            if on:
                self._build(name)
        self._prune()
        for name, on in self.overlays.items():
            self._apply_visibility(name, on)
        self.frame = min(self.frame, self.n - 1)
        self.set_frame(self.frame)

    def _build(self, overlay: str) -> None:
        if overlay in self._built or self._result is None:
            return
        self._built.add(overlay)
        traj = self._result.trajectory
        fn = getattr(self, f"_build_{overlay}", None)
        if fn is not None and (self._rotation or overlay in ("bodies", "scenario")):
            fn(traj)

    def _build_scenario(self, traj) -> None:
        if self.extra is not None:
            self.extra.build(traj, self._result)

    def set_option(self, key: str, value: bool) -> None:
        """A scene option of the scenario's extra changed: rebuild its drawings if it asks."""
        if self.extra is not None and self.extra.set_option(key, value) and self._result is not None:
            self.show(self._result, self._spec)

    def _cloud(self, name, pts, color, size):
        pts = np.asarray(pts, np.float32)
        return self._node(name, lambda: self.scene.add_point_cloud(
            name, pts, color, point_size=size, point_shape="square", precision=PATH_PRECISION, point_shading="flat"),
            points=pts)

    def _add_path(self, overlay: str, name: str, path: np.ndarray, color, thickness=0.02,
                  idx: np.ndarray | None = None) -> None:
        """Send `path` (samples at trajectory indices `idx`) once, as TRAIL_CHUNKS chunks whose
        visibility follows the playback time.

        Paths are drawn as dense clouds of square points (resampled along the arc so that the
        gaps are under the point size, at most MAX_DRAW_POINTS; points that would land on an
        earlier point of the path are dropped, see REPEAT_CELL): in software WebGL a 10⁴-point
        fat line (three's Line2) renders at a few frames per second, a 10⁴-point cloud at ~30.
        """
        path = np.asarray(path, float)
        if len(path) < 2:
            return
        idx = np.arange(len(path)) if idx is None else np.asarray(idx, float)
        path, idx = densify(path, idx, 0.6 * thickness, MAX_DRAW_POINTS)
        path, idx = drop_repeats(path, idx, REPEAT_CELL * thickness)
        k = TRAIL_CHUNKS if self.grow_trails else 1
        # TRAIL_CHUNKS chunks of equal time span (after drop_repeats the points are not uniform in
        # time); always the same number of chunks, so a new result updates the same nodes in place
        # (a chunk left without a new point repeats the previous point)
        grid = np.linspace(idx[0], idx[-1], k + 1)
        bounds = np.concatenate([[0], np.searchsorted(idx, grid[1:-1], side="left"), [len(path)]]).astype(int)
        handles, starts = [], []
        for j in range(k):
            a, b = bounds[j], bounds[j + 1]
            pts = path[a:b] if b > a else path[max(a - 1, 0):max(a - 1, 0) + 1]
            handles.append(self._cloud(f"{name}/{j}", pts, color, thickness))
            starts.append(int(np.ceil(grid[j])) if self.grow_trails else 0)
        self._paths.setdefault(overlay, []).append(_Path(handles, np.asarray(starts)))

    def _build_body(self, traj) -> None:
        sc, r = self.scene, self.root
        semi = shape_semi_axes(traj.inertia, self.exaggerate)
        self.body_frame = self._node(f"{r}/body", lambda: sc.add_frame(f"{r}/body", show_axes=False))
        self._node(f"{r}/body/mesh", lambda: sc.add_frame(f"{r}/body/mesh", show_axes=False))
        for k, (v, f, rgb) in enumerate(banded_sphere_parts()):  # unit sphere parts, scaled to the semi-axes
            self._node(f"{r}/body/mesh/{k}", lambda v=v, f=f, rgb=rgb, k=k: sc.add_mesh_simple(
                f"{r}/body/mesh/{k}", v, f, color=rgb, scale=tuple(semi), cast_shadow=False, receive_shadow=False),
                scale=tuple(semi))
        self._semi = semi
        E = float(traj.energy[0])
        Lmag = float(traj.momentum_norm[0])
        self._E, self._Lmag = E, Lmag
        if E > 0:  # ω drawn in the scale of the energy ellipsoid: its tip touches the invariable plane
            self.k_omega = 1.3 / np.sqrt(2 * E / traj.inertia).max()
        else:  # starts at rest (e.g. initial-axis): the largest ω of the run is drawn 1.3 long
            wmax = float(np.max(np.linalg.norm(traj.omega_body, axis=1)))
            self.k_omega = 1.3 / wmax if wmax > 0 else 1.0
        # a spin-up from nearly at rest (found by tests/test_fuzz.py: hyperion with probe_rate 1e-66 drew
        # ω ~1e66 long, inf in float16): beyond DRAW_MAX the largest ω of the run is drawn 1.3 long
        wmax = float(np.max(np.linalg.norm(traj.omega_body, axis=1)))
        if not (np.isfinite(self.k_omega) and self.k_omega * wmax <= DRAW_MAX):
            self.k_omega = 1.3 / wmax if wmax > 0 and np.isfinite(1.3 / wmax) else 1.0
        # ω and L: an arrow along +z of its own frame, with its label; playback turns the frame
        # (a pose update, no geometry) and re-sends the arrow only when its length changes by
        # more than VECTOR_LENGTH_TOL
        self._vectors = {}
        for key, color, text in (("omega", OMEGA_COLOR, "ω"), ("L", L_COLOR, "L")):
            frame = self._node(f"{r}/{key}", lambda key=key: sc.add_frame(f"{r}/{key}", show_axes=False))
            arrow = self._node(f"{r}/{key}/arrow", lambda key=key, color=color: sc.add_arrows(
                f"{r}/{key}/arrow", np.zeros((1, 2, 3), np.float32), color, shaft_radius=0.025, head_radius=0.06,
                head_length=0.12))
            label = self._node(f"{r}/{key}/label", lambda key=key, text=text: sc.add_label(f"{r}/{key}/label", text))
            self._vectors[key] = [frame, arrow, label, -1.0]
        self.omega_arrow, self.L_arrow = self._vectors["omega"][0], self._vectors["L"][0]
        # their poses at every sample: ω in the energy ellipsoid's scale, L drawn 1.3 long
        Lm = np.asarray(traj.momentum_norm, float)[:, None]
        L_drawn = np.where(Lm > 0, 1.3 * traj.L_inertial / np.where(Lm > 0, Lm, 1.0), 0.0)
        self._vector_poses = {"omega": z_to_many(self.k_omega * traj.omega_inertial), "L": z_to_many(L_drawn)}
        self._labels = [self._vectors["omega"][2], self._vectors["L"][2]]
        # shown and hidden with the "vectors" overlay even when it starts off (nothing to build)
        self._static["vectors"] = [self.omega_arrow, self.L_arrow]

    def _set_vector(self, key: str, i: int) -> None:
        frame, arrow, label, drawn = self._vectors[key]
        wxyz, lengths = self._vector_poses[key]
        length = float(lengths[i])
        frame.wxyz = wxyz[i]
        if drawn < 0 or abs(length - drawn) > VECTOR_LENGTH_TOL * max(drawn, 1e-9):
            arrow.points = np.array([[[0, 0, 0], [0, 0, length]]], np.float32)
            label.position = (0.0, 0.0, 1.1 * length)
            self._vectors[key][3] = length

    def _build_axes(self, traj) -> None:
        sc, r, semi, I = self.scene, self.root, self._semi, traj.inertia
        ends = np.diag(semi * 1.35).astype(np.float32)
        arrows = np.stack([np.zeros((3, 3), np.float32), ends], 1)
        cols = np.array(AXIS_COLORS, np.uint8)
        hs = [self._node(f"{r}/body/axes", lambda: sc.add_arrows(f"{r}/body/axes", arrows, cols, shaft_radius=0.018,
                                                                 head_radius=0.05, head_length=0.1), points=arrows)]
        for k, lab in enumerate("ABC"):
            text = f"{lab} = {I[k]:.4g}"
            pos = tuple(float(x) for x in ends[k] * 1.08)
            hs.append(self._node(f"{r}/body/axis_labels/{lab}",
                                 lambda text=text, pos=pos, lab=lab: sc.add_label(f"{r}/body/axis_labels/{lab}", text,
                                                                                  position=pos),
                                 text=text, position=pos))
        self._static["axes"] = hs

    def _build_polhode(self, traj) -> None:
        """Where the rotation axis pierces the body surface (ray/ellipsoid), on the body frame."""
        idx, semi = self._idx, self._semi
        w = traj.omega_body[idx]
        nw = np.linalg.norm(w, axis=1, keepdims=True)
        ok = nw[:, 0] > 0
        if np.count_nonzero(ok) >= 2:
            u = w[ok] / nw[ok]
            s = 1.0 / np.sqrt(np.sum((u / semi) ** 2, axis=1, keepdims=True))
            self._add_path("polhode", f"{self.root}/body/polhode", 1.015 * s * u, POLHODE_COLOR, 0.02, idx=idx[ok])

    def _build_energy_ellipsoid(self, traj) -> None:
        """Poinsot: the energy ellipsoid ω·Iω = 2E in ω-space (largest semi-axis drawn 1.3),
        fixed in the body, with the polhode (tip of ω) on it."""
        if self._E <= 0:
            return
        sc, r = self.scene, self.root
        e_semi = tuple(float(x) for x in np.sqrt(2 * self._E / traj.inertia) * self.k_omega)
        ico = trimesh.creation.icosphere(subdivisions=3)
        h = self._node(f"{r}/body/energy_ellipsoid", lambda: sc.add_mesh_simple(
            f"{r}/body/energy_ellipsoid", ico.vertices, ico.faces, color=(120, 200, 255), opacity=0.25,
            side="double", scale=e_semi, cast_shadow=False, receive_shadow=False), scale=e_semi)
        self._static["energy_ellipsoid"] = [h]
        self._add_path("energy_ellipsoid", f"{r}/body/polhode_on_ellipsoid", self.k_omega * traj.omega_body[self._idx],
                       POLHODE_COLOR, 0.012, idx=self._idx)

    def _build_momentum_sphere(self, traj) -> None:
        """The sphere |L| = const in the body frame, with the path of L on it."""
        if self._Lmag <= 0:
            return
        sc, r = self.scene, self.root
        sph = trimesh.creation.icosphere(subdivisions=3, radius=1.3)
        h = self._node(f"{r}/body/momentum_sphere", lambda: sc.add_mesh_simple(
            f"{r}/body/momentum_sphere", sph.vertices, sph.faces, color=(200, 150, 255), opacity=0.2, side="double",
            cast_shadow=False, receive_shadow=False))
        self._static["momentum_sphere"] = [h]
        k_L = 1.3 / self._Lmag
        Lmax = float(np.max(np.linalg.norm(traj.L_body, axis=1)))
        if not (np.isfinite(k_L) and k_L * Lmax <= DRAW_MAX):  # |L| grows from nearly nothing (as ω above)
            k_L = 1.3 / Lmax if Lmax > 0 and np.isfinite(1.3 / Lmax) else 1.0
        self._add_path("momentum_sphere", f"{r}/body/L_path", k_L * traj.L_body[self._idx], L_COLOR,
                       0.02, idx=self._idx)

    def _build_herpolhode(self, traj) -> None:
        """Tip of ω in space, on the invariable plane ω·L̂ = 2E/|L| (a disc normal to L₀)."""
        if self._E <= 0 or self._Lmag <= 0:
            return
        sc, r = self.scene, self.root
        self._add_path("herpolhode", f"{r}/herpolhode", self.k_omega * traj.omega_inertial[self._idx],
                       HERPOLHODE_COLOR, 0.012, idx=self._idx)
        Lhat = traj.L_inertial[0] / self._Lmag
        d = self.k_omega * 2 * self._E / self._Lmag
        wxyz = tuple(float(c) for c in z_to_many(Lhat[None])[0][0])  # the disc's normal (z) onto L
        pos = tuple(float(x) for x in d * Lhat)
        dv, df = flat_disc(1.25)
        self._static["herpolhode"] = [self._node(f"{r}/invariable_plane", lambda: sc.add_mesh_simple(
            f"{r}/invariable_plane", dv, df, color=(0, 160, 170), opacity=0.08, side="double",
            position=pos, wxyz=wxyz, cast_shadow=False, receive_shadow=False), position=pos, wxyz=wxyz)]

    def _build_axis_trail(self, traj) -> None:
        self._add_path("axis_trail", f"{self.root}/axis_trail", AXIS_TRAIL_RADIUS * traj.rotation_axis[self._idx],
                       TRAIL_COLOR, 0.012, idx=self._idx)

    def _build_celestial(self, traj) -> None:
        """A celestial sphere with the paths of the figure axis and of the rotation axis."""
        sc, r = self.scene, self.root
        self._static["celestial"] = [self._node(f"{r}/celestial/grid", lambda: sc.add_line_segments(
            f"{r}/celestial/grid", wire_sphere(CELESTIAL_RADIUS), (150, 150, 160), thickness=0.004))]
        self._add_path("celestial", f"{r}/celestial/figure_axis", CELESTIAL_RADIUS * traj.figure_axis[self._idx],
                       FIGURE_COLOR, 0.03, idx=self._idx)
        self._add_path("celestial", f"{r}/celestial/rotation_axis", CELESTIAL_RADIUS * traj.rotation_axis[self._idx],
                       TRAIL_COLOR, 0.012, idx=self._idx)

    def _build_bodies(self, traj) -> None:
        bodies = self.extra.bodies(traj) if self.extra is not None else None
        bodies = traj.bodies if bodies is None else bodies
        if not bodies:
            return
        sc, r, idx = self.scene, self.root, self._idx
        allpos = np.concatenate([np.asarray(p, float) for p in bodies.values()])
        if self._rotation:  # a distant attractor is drawn by its direction, not its distance
            def scale_fn(p):
                return ORBIT_RADIUS * p / np.maximum(np.linalg.norm(p, axis=1, keepdims=True), 1e-300)
        else:
            span = (self.extra.span(traj) if self.extra is not None else None) or \
                float(np.max(np.linalg.norm(allpos, axis=1))) or 1.0

            def scale_fn(p):
                return ORBIT_RADIUS * p / span
        hs = []
        self._markers = {}
        for k, (name, pos) in enumerate(bodies.items()):
            pos = scale_fn(np.asarray(pos, float))
            col = palette(k)
            h = self._node(f"{r}/bodies/{name}", lambda col=col, name=name: sc.add_icosphere(
                f"{r}/bodies/{name}", radius=0.12, color=col, cast_shadow=False, receive_shadow=False))
            lab = self._node(f"{r}/bodies/{name}/label", lambda name=name: sc.add_label(
                f"{r}/bodies/{name}/label", name, position=(0, 0, 0.2)))
            self._markers[name] = (h, pos)
            hs += [h, lab]
            if self.extra is None or self.extra.trail(name):
                self._add_path("bodies", f"{r}/body_trails/{name}", pos[idx], col, 0.02, idx=idx)
        self._static["bodies"] = hs

    # ---- animating -------------------------------------------------------------------------
    def _apply_visibility(self, name: str, on: bool) -> None:
        for h in self._static.get(name, []):
            if h.visible != on:
                h.visible = on
        for p in self._paths.get(name, []):
            p.set_visible(on, self.frame)

    def set_overlay(self, name: str, on: bool) -> None:
        self.overlays[name] = bool(on)
        if on and name not in self._built:
            self._build(name)  # first time on for this result: send its paths now
        self._apply_visibility(name, bool(on))

    def set_exaggerate(self, factor: float) -> None:
        """New proportions: rescale the body mesh, move the axes and redraw the polhode."""
        self.exaggerate = float(factor)
        if self._result is not None:
            self.show(self._result, self._spec)

    def set_frame(self, i: int) -> None:
        if self.n == 0:
            return
        i = int(np.clip(i, 0, self.n - 1))
        self.frame = i
        traj = self._result.trajectory
        if self._rotation and self.body_frame is not None:
            self.body_frame.wxyz = traj.quat_wxyz[i]
            if self.overlays.get("vectors", True):
                self._set_vector("omega", i)
                self._set_vector("L", i)
        for h, pos in self._markers.values():
            h.position = pos[i]
        if self.extra is not None and self.overlays.get("scenario", True):
            self.extra.set_frame(i)
        for paths in self._paths.values():
            for p in paths:
                p.set_time_index(i)
