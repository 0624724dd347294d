"""What a scenario draws, as plain numpy data: one drawing list, three renderers.

A scenario turns a `Run` into a `Drawing` once: bodies with their meshes, frames that move,
paths that grow with time, points, line segments, arrows, labels, the camera and its look-at, the
text a class reads and the series to plot. Three thin adapters render that list and nothing else:
viser (the live app, `theoria.app.scene`), rerun (`theoria.app.record`) and a standalone HTML
replay (`theoria.app.export_html`). None of them re-derives geometry or physics, so the app, the
recording and the replay show the same objects, colours, scale and camera.

Time. A drawing is sampled at `frames` (indices into the run's samples, at most MAX_FRAMES, first
and last included). An attribute is either static or one value per frame: a position is (3,) or
(F, 3), an attitude (4,) or (F, 4), segments (K, 2, 3) or (F, K, 2, 3), arrow vectors (K, 3) or
(F, K, 3), a label's text a string or F strings, `visible` None or (F,) booleans. A `Path` is
drawn whole, but each of its points carries the frame `at` which it appears, so it grows as the
run plays.

Names are paths: an item called "body/polhode" is drawn in the coordinates of the `Frame` called
"body" (it turns with the body), as viser and rerun both compose transforms along entity paths.
Every item belongs to a `group`, an overlay the user can switch on and off.

Scene units: a rotation scene is scaled so that the body's largest semi-axis is 1 (the celestial
sphere has radius 2.4); orbit scenes fit in a radius of 2. +z is up.
"""
from __future__ import annotations

import colorsys
import functools
from dataclasses import dataclass, field
from typing import Any, Callable, ClassVar, Mapping, Sequence

import numpy as np

from ..physics.constants import JULIAN_YEAR_DAYS
from ..physics.inertia import ellipsoid_semi_axes

Vec = tuple[float, float, float]
RGB = tuple[int, int, int]

MAX_FRAMES = 3000  # playback frames of a drawing: 20 s at 60 Hz, and slow motion to speed 0.4
ORBIT_RADIUS = 2.0
CELESTIAL_RADIUS = 2.4
AXIS_TRAIL_RADIUS = 1.6
DRAW_MAX = 1e4  # scene units; beyond this a scale falls back (a spin-up from nearly at rest)


@dataclass(frozen=True)
class Camera:
    """Where the view starts: position and look-at in scene units (+z up unless `up` says)."""

    position: Vec
    look_at: Vec = (0.0, 0.0, 0.0)
    up: Vec = (0.0, 0.0, 1.0)
    fov_deg: float | None = None


# ---- items ------------------------------------------------------------------------------------

@dataclass(kw_only=True)
class Item:
    name: str
    group: str = "scenario"
    visible: np.ndarray | None = None  # (F,) booleans: shown at that frame; None: always

    def animated(self) -> list[str]:
        """The attributes that hold one value per frame."""
        return [k for k, nd in self.STATIC_NDIM.items() if _ndim(getattr(self, k)) > nd] + \
            (["visible"] if self.visible is not None else [])

    STATIC_NDIM: ClassVar[dict] = {}  # attribute → ndim of its static form (more: one value per frame)


def _ndim(v) -> int:
    if isinstance(v, str):
        return 0
    if isinstance(v, (list, tuple)) and v and isinstance(v[0], str):
        return 1
    return np.ndim(v)


@dataclass(kw_only=True)
class Frame(Item):
    """A coordinate frame: its children (items named "<name>/...") move with it."""

    wxyz: np.ndarray = (1.0, 0.0, 0.0, 0.0)
    position: np.ndarray = (0.0, 0.0, 0.0)
    STATIC_NDIM: ClassVar[dict] = {"wxyz": 1, "position": 1}


@dataclass(kw_only=True)
class Mesh(Item):
    """A triangle mesh (unit shape, scaled by `scale` on its own axes)."""

    vertices: np.ndarray
    faces: np.ndarray
    color: RGB
    opacity: float = 1.0
    scale: Vec = (1.0, 1.0, 1.0)
    wxyz: np.ndarray = (1.0, 0.0, 0.0, 0.0)
    position: np.ndarray = (0.0, 0.0, 0.0)
    double_sided: bool = False
    STATIC_NDIM: ClassVar[dict] = {"wxyz": 1, "position": 1}


@dataclass(kw_only=True)
class Sphere(Item):
    """A marker ball (a body far away, a point of interest)."""

    radius: float
    color: RGB
    position: np.ndarray = (0.0, 0.0, 0.0)
    STATIC_NDIM: ClassVar[dict] = {"position": 1}


@dataclass(kw_only=True)
class Path(Item):
    """A curve traced during the run (polhode, trails): point i appears at frame `at[i]`
    (None: the whole curve at once). `thickness` is its width in scene units."""

    points: np.ndarray
    color: RGB
    thickness: float = 0.02
    at: np.ndarray | None = None


@dataclass(kw_only=True)
class Points(Item):
    """Static points: a star field, a surface of section, a phase portrait."""

    points: np.ndarray
    colors: Any  # one RGB, or (M, 3) uint8
    size: float = 0.02


@dataclass(kw_only=True)
class Segments(Item):
    """Line segments (K, 2, 3), or one set per frame (F, K, 2, 3)."""

    points: np.ndarray
    colors: Any  # one RGB, or (K, 2, 3) uint8
    thickness: float = 0.01
    STATIC_NDIM: ClassVar[dict] = {"points": 3}


@dataclass(kw_only=True)
class Arrows(Item):
    """Arrows from `origins` (K, 3) along `vectors` (K, 3), or one set of vectors per frame."""

    origins: np.ndarray
    vectors: np.ndarray
    colors: Any
    shaft_radius: float = 0.02
    head_radius: float = 0.05
    head_length: float = 0.1
    labels: Sequence[str] = ()  # written at the arrow tips
    # the side of its tip each letter sits on (LABEL_ANCHORS; "top-left" when not given), chosen by
    # declutter_labels with the labels
    label_anchors: Sequence[str] = ()
    STATIC_NDIM: ClassVar[dict] = {"vectors": 2}

    def label_anchor(self, j: int) -> str:
        return self.label_anchors[j] if j < len(self.label_anchors) else "top-left"


LABEL_ANCHORS = ("top-left", "top-center", "top-right", "center-left", "center-center", "center-right",
                 "bottom-left", "bottom-center", "bottom-right")


@dataclass(kw_only=True)
class Label(Item):
    """Text at a point: fixed, or a string per frame (a read-out). `anchor` says which point of the
    text box sits on `position` ("top-left": the text runs right of and below the point,
    "center-right": it ends left of the point, ...; LABEL_ANCHORS)."""

    text: Any  # str, or F strings
    position: np.ndarray = (0.0, 0.0, 0.0)
    anchor: str = "top-left"
    # a background name (a star's) that gives way: left out of the drawing where, on every side of
    # its point, it would still cover another text when the scene opens (declutter_labels)
    yields: bool = False
    STATIC_NDIM: ClassVar[dict] = {"text": 0, "position": 1}


@dataclass(kw_only=True)
class Light(Item):
    """A directional light from `position` toward the origin (the Sun on a full Moon)."""

    position: np.ndarray
    intensity: float = 2.0
    STATIC_NDIM: ClassVar[dict] = {"position": 1}


GEOMETRY = (Frame, Mesh, Sphere, Path, Points, Segments, Arrows, Label)  # what every renderer draws


@dataclass(frozen=True)
class Follow:
    """A camera that moves with the run (the Moon seen from the Earth): per-frame position."""

    position: np.ndarray  # (F, 3)
    look_at: Vec = (0.0, 0.0, 0.0)
    up: Vec = (0.0, 0.0, 1.0)
    fov_deg: float | None = None


@dataclass(frozen=True)
class Option:
    """A checkbox of a scenario's own (a different view: a co-rotating frame, the Earth's view)."""

    label: str
    default: bool = True


# The overlays every scene has: key → (label, default in ch. 15, default elsewhere).
OVERLAYS = {
    "axes": ("principal axes A, B, C", True, True),
    "vectors": ("ω and L arrows", True, True),
    "axis_trail": ("trail of the rotation axis", True, True),
    "polhode": ("polhode (on the body)", True, True),
    "herpolhode": ("herpolhode + invariable plane", True, False),
    "energy_ellipsoid": ("energy ellipsoid (Poinsot)", False, False),
    "momentum_sphere": ("momentum sphere (path of L on the body)", False, False),
    "celestial": ("celestial sphere + pole paths", False, True),
    "bodies": ("other bodies + trails", True, True),
    "scenario": ("this scenario's drawings", True, True),
}


@dataclass
class View:
    """What the person looking chose: the scenario's options, the shape exaggeration."""

    options: dict[str, bool] = field(default_factory=dict)
    exaggerate: float = 1.0
    # the labels' size against the scene's, 1 for the app at 1280×800 (presenter mode's larger type
    # on a projector is larger against the scene: the labels are kept apart at that size)
    text_scale: float = 1.0

    def option(self, key: str, spec=None) -> bool:
        if key in self.options:
            return bool(self.options[key])
        opts = getattr(spec, "options", {}) if spec is not None else {}
        return bool(opts[key].default) if key in opts else True


@dataclass(frozen=True)
class Clock:
    """How a run's time is read out to a class: `name` = t × `scale` `words` ("t = 2.5 of 5 orbits")."""

    scale: float = 1.0
    words: str = ""
    name: str = "t"

    def reading(self, now: float, end: float, number: Callable[[float], str]) -> str:
        last = number(end * self.scale)
        words = self.words[:-1] if last == "1" and self.words in ("days", "years", "orbits") else self.words
        return f"{self.name} = {number(now * self.scale)} of {last}{' ' + words if words else ''}"


# the trajectory's time unit → (words, name); a time in the unit of an orbital rate is counted in orbits
_CLOCK_WORDS = {"s": ("s", "t"), "day": ("days", "t"), "d": ("days", "t"), "yr": ("years", "t"),
                "size/distance": ("", "size/distance"), "G=1 units": ("time units (G = 1)", "t")}
DAYS_READ_IN_YEARS = 1000.0  # a run in days longer than this is read out in years
# "unit": a time unit of its own, δ in rad per unit; "orbits/2π": the turning frame's radians (rate 1)
_PER_ORBITAL_RATE = ("1/n·rad", "1/δ·rad", "1/δ", "unit", "orbits/2π")


def clock_of(run) -> Clock:
    """The read-out of `run`'s time: seconds, days or years as they are; a time measured in the unit
    of an orbital rate (n or δ, in rad per time unit: `orbital_rate`, else 1) as orbits, t·n/2π."""
    unit = run.trajectory.time_unit
    if unit in _PER_ORBITAL_RATE:
        return Clock(float(run.params.get("orbital_rate", 1.0)) / (2 * np.pi), "orbits")
    t = np.asarray(run.trajectory.t, float)
    if unit in ("day", "d") and len(t) and t[-1] - t[0] > DAYS_READ_IN_YEARS:  # Cassini's 74 years, not 27,175 days
        return Clock(1.0 / JULIAN_YEAR_DAYS, "years")
    words, name = _CLOCK_WORDS.get(unit, (unit, "t"))
    return Clock(1.0, words, name)


@dataclass
class Drawing:
    """Everything one run draws (see the module docstring)."""

    frames: np.ndarray  # (F,) sample indices into the run's trajectory
    times: np.ndarray  # (F,) the run's times at the frames
    time_unit: str
    camera: Camera
    title: str = ""
    section: str = ""
    summary: str = ""
    formula: str = ""
    items: list[Item] = field(default_factory=list)
    overlays: dict[str, bool] = field(default_factory=dict)  # group → shown by default
    follow: Follow | None = None
    plot: dict[str, np.ndarray] = field(default_factory=dict)  # series on plot_t, for the live plot
    plot_t: np.ndarray | None = None
    rotation: bool = True
    clock: Clock = field(default_factory=Clock)  # the time as the panel reads it out
    # where playback stands at each frame (0 … 1 of the run, rising); None: in proportion to the
    # time. A sweep whose samples are on a log scale (gravity-gradient-accuracy's distances) plays
    # one sample per equal share instead: in proportion to its "time" the first nine of twelve
    # flashed by in a quarter of the run and the last stood still for its last 30 %.
    pace: np.ndarray | None = None

    @property
    def n_frames(self) -> int:
        return len(self.frames)

    def paces(self) -> np.ndarray:
        """Where playback stands at each frame, 0 … 1 (`pace`, or the times in proportion)."""
        if self.pace is not None:
            return np.asarray(self.pace, float)
        t = np.asarray(self.times, float)
        span = (t[-1] - t[0]) or 1.0
        return (t - t[0]) / span

    def pace_at(self, t: float) -> float:
        """Where playback stands at time `t` of the run."""
        times = np.asarray(self.times, float)
        if self.pace is None:
            return float((t - times[0]) / ((times[-1] - times[0]) or 1.0))
        return float(np.interp(t, times, self.paces()))

    def add(self, *items: Item) -> None:
        self.items.extend(items)

    def item(self, name: str) -> Item:
        for it in self.items:
            if it.name == name:
                return it
        raise KeyError(name)

    def names(self) -> list[str]:
        return [it.name for it in self.items]

    def frame_of_sample(self, idx) -> np.ndarray:
        """The (fractional) frame at which trajectory sample `idx` is reached."""
        return np.interp(np.asarray(idx, float), self.frames, np.arange(len(self.frames), dtype=float))

    def shown(self, it: Item) -> bool:
        return self.overlays.get(it.group, True)


# ---- building blocks ---------------------------------------------------------------------------

def frame_indices(n: int, max_frames: int = MAX_FRAMES) -> np.ndarray:
    """At most `max_frames` sample indices out of n, first and last included."""
    if n <= max_frames:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, max_frames).round().astype(int))


# the bodies a class knows, the same in every scene (by their key in Trajectory.bodies): the Sun
# yellow, the Earth blue, the Moon pale grey; any other body takes the palette's colour of its place
BODY_COLOURS: dict[str, RGB] = {"sun": (255, 196, 40), "earth": (70, 130, 230), "moon": (205, 205, 215)}
BODY_NAMES = {"sun": "Sun", "earth": "Earth", "moon": "Moon", "attractor": "attracting body"}


def body_name(key: str) -> str:
    """A body's name as a class reads it: "Sun", "Moon", "Earth" (proper names), others as they are."""
    return BODY_NAMES.get(key, key)


def palette(k: int) -> RGB:
    r, g, b = colorsys.hsv_to_rgb((0.13 + 0.31 * k) % 1.0, 0.75, 0.95)
    return int(255 * r), int(255 * g), int(255 * b)


def unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)


def segments(path) -> np.ndarray:
    """(N, 3) polyline → (N − 1, 2, 3) line segments."""
    path = np.asarray(path, np.float32)
    return np.stack([path[:-1], path[1:]], axis=1)


def quat_from_matrix(m) -> np.ndarray:
    """Unit quaternions (w, x, y, z) of rotation matrices (..., 3, 3) (Shepperd's method: the
    largest of w, x, y, z found first, so no division by a small number)."""
    m = np.asarray(m, float)
    t = np.stack([m[..., 0, 0] + m[..., 1, 1] + m[..., 2, 2], m[..., 0, 0], m[..., 1, 1], m[..., 2, 2]], -1)
    k = np.argmax(np.stack([t[..., 0], t[..., 1] - t[..., 2] - t[..., 3], t[..., 2] - t[..., 1] - t[..., 3],
                            t[..., 3] - t[..., 1] - t[..., 2]], -1), axis=-1)
    q = np.empty(m.shape[:-2] + (4,))
    r01, r10, r02, r20, r12, r21 = (m[..., 0, 1], m[..., 1, 0], m[..., 0, 2], m[..., 2, 0], m[..., 1, 2],
                                    m[..., 2, 1])
    cases = [
        (1 + t[..., 0], (1 + t[..., 0], r21 - r12, r02 - r20, r10 - r01)),
        (1 + t[..., 1] - t[..., 2] - t[..., 3], (r21 - r12, 1 + t[..., 1] - t[..., 2] - t[..., 3], r01 + r10, r02 + r20)),
        (1 + t[..., 2] - t[..., 1] - t[..., 3], (r02 - r20, r01 + r10, 1 + t[..., 2] - t[..., 1] - t[..., 3], r12 + r21)),
        (1 + t[..., 3] - t[..., 1] - t[..., 2], (r10 - r01, r02 + r20, r12 + r21, 1 + t[..., 3] - t[..., 1] - t[..., 2])),
    ]
    for j, (_, comps) in enumerate(cases):
        sel = k == j
        v = np.stack([c[sel] if np.ndim(c) else np.full(sel.sum(), c) for c in comps], -1)
        q[sel] = v
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    return q * np.where(q[..., :1] < 0, -1.0, 1.0)


def z_to_many(v) -> tuple[np.ndarray, np.ndarray]:
    """Unit quaternions (w, x, y, z) turning +z onto each row of v (N, 3) (identity where v is zero
    or not finite) and the lengths: (N, 4), (N,)."""
    v = np.asarray(v, float)
    n = np.linalg.norm(v, axis=1)
    ok = (n > 0) & np.isfinite(n)
    u = np.where(ok[:, None], v / np.where(ok, n, 1.0)[:, None], [0.0, 0.0, 1.0])
    q = np.stack([1.0 + u[:, 2], -u[:, 1], u[:, 0], np.zeros(len(u))], 1)
    down = u[:, 2] < -1 + 1e-12
    q[down] = (0.0, 1.0, 0.0, 0.0)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return q, np.where(ok, n, 0.0)


def shape_semi_axes(inertia, exaggerate: float = 1.0) -> np.ndarray:
    """Semi-axes of the body drawn: the homogeneous ellipsoid with the moments, normalised to a
    largest semi-axis of 1, with departures from the mean multiplied by `exaggerate`."""
    ax = ellipsoid_semi_axes(inertia)
    ax = ax / ax.max()
    mean = ax.mean()
    ax = mean + exaggerate * (ax - mean)
    ax = ax / ax.max()
    return np.clip(ax, 0.12, None)  # a flat body (A + B = C) keeps a visible thickness


def box_semi_axes(inertia, exaggerate: float = 1.0) -> np.ndarray:
    """Half-sides of the homogeneous box with the moments (A, B, C), normalised to a largest of 1:
    A = m(b² + c²)/12 and its cyclic versions give a² ∝ B + C − A (full sides a, b, c along body
    x, y, z). Departures from the mean multiplied by `exaggerate`; a plate (A + B = C) keeps a
    visible thickness."""
    I = np.asarray(inertia, float)
    sq = np.clip(np.array([I[1] + I[2] - I[0], I[0] + I[2] - I[1], I[0] + I[1] - I[2]]), 0.0, None)
    ax = np.sqrt(sq)
    ax = ax / ax.max()
    mean = ax.mean()
    ax = mean + exaggerate * (ax - mean)
    ax = ax / ax.max()
    return np.clip(ax, 0.12, None)


BOX_COLORS = ((225, 150, 140), (150, 205, 150), (140, 170, 225))  # faces normal to A, B, C (the axes' hues, lighter)


@functools.lru_cache(maxsize=1)
def box_parts():
    """A cube of half-side 1 as three plain meshes, one colour per pair of opposite faces (normal
    to body x, y, z), so that a turning brick shows which face is which."""
    parts = []
    for axis in range(3):
        v, f = [], []
        for sign in (1.0, -1.0):
            u, w = (axis + 1) % 3, (axis + 2) % 3
            corners = []
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = np.zeros(3)
                p[axis], p[u], p[w] = sign, a, b
                corners.append(p)
            base = len(v)
            v.extend(corners)
            quad = [base, base + 1, base + 2, base + 3] if sign > 0 else [base, base + 3, base + 2, base + 1]
            f.extend([[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]])
        parts.append((np.asarray(v, np.float32), np.asarray(f, np.uint32), BOX_COLORS[axis]))
    return tuple(parts)


def box_edges(semi) -> np.ndarray:
    """The 12 edges of the box with half-sides `semi` as line segments (12, 2, 3)."""
    s = np.asarray(semi, float)
    segs = []
    for axis in range(3):
        u, w = (axis + 1) % 3, (axis + 2) % 3
        for a in (-1, 1):
            for b in (-1, 1):
                p, q = np.zeros(3), np.zeros(3)
                p[axis], q[axis] = -s[axis], s[axis]
                p[u] = q[u] = a * s[u]
                p[w] = q[w] = b * s[w]
                segs.append([p, q])
    return np.asarray(segs, np.float32)


BAND_LIGHT, BAND_BLUE = (200, 190, 170), (120, 140, 175)
MERIDIAN_COLOR, EQUATOR_COLOR = (60, 40, 30), (230, 80, 60)
MERIDIAN_HALF_WIDTH, EQUATOR_HALF_WIDTH = 0.12, 0.05  # rad


def sphere_grid(lat, lon):
    """Vertices of a latitude/longitude grid on the unit sphere and its quads (counter-clockwise
    seen from outside), with each quad's centre latitude and longitude."""
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    verts = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], -1).reshape(-1, 3)
    nl = len(lon)
    i, j = np.meshgrid(np.arange(len(lat) - 1), np.arange(nl - 1), indexing="ij")
    a, b, c, d = i * nl + j, i * nl + j + 1, (i + 1) * nl + j + 1, (i + 1) * nl + j
    quads = np.stack([a, b, c, d], -1).reshape(-1, 4)
    lat_c = (0.5 * (lat[:-1] + lat[1:])[i]).ravel()
    lon_c = (0.5 * (lon[:-1] + lon[1:])[j]).ravel()
    return verts, quads, lat_c, lon_c


def mesh_parts(verts, quads, colour_index, colours) -> list[tuple[np.ndarray, np.ndarray, RGB]]:
    """One (vertices, faces, colour) per colour: plain meshes, not one vertex-coloured mesh (in
    software WebGL at 1280×800 a vertex-coloured GLB body cost 9–12 ms a frame, plain meshes ~5 ms)."""
    parts = []
    for k, rgb in enumerate(colours):
        q = quads[colour_index == k]
        if len(q) == 0:
            continue
        tri = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
        tri = tri[np.ptp(verts[tri], axis=1).max(axis=1) > 1e-12]  # no triangles collapsed at the poles
        used, inv = np.unique(tri, return_inverse=True)
        parts.append((verts[used].astype(np.float32), inv.reshape(-1, 3).astype(np.uint32), rgb))
    return parts


@functools.lru_cache(maxsize=4)
def banded_sphere_parts(rows_per_band: int = 4, columns: int = 64):
    """A unit sphere in latitude bands of π/8 about the body z (C) axis, a dark meridian in the
    body x–z half-plane and a red equator, so that spin is visible. The grid's rings and
    meridians fall on the band edges, so every edge is clean."""
    lat = np.unique(np.concatenate([np.linspace(-np.pi / 2, np.pi / 2, 8 * rows_per_band + 1),
                                    [-EQUATOR_HALF_WIDTH, EQUATOR_HALF_WIDTH]]))
    lon = np.unique(np.concatenate([np.linspace(-np.pi, np.pi, columns + 1),
                                    [-MERIDIAN_HALF_WIDTH, MERIDIAN_HALF_WIDTH]]))
    verts, quads, lat_c, lon_c = sphere_grid(lat, lon)
    band = np.floor((lat_c + np.pi / 2) / (np.pi / 8)).astype(int) % 2
    colour = np.where(band == 1, 0, 1)
    colour = np.where(np.abs(lon_c) < MERIDIAN_HALF_WIDTH, 2, colour)
    colour = np.where(np.abs(lat_c) < EQUATOR_HALF_WIDTH, 3, colour)
    return tuple(mesh_parts(verts, quads, colour, (BAND_LIGHT, BAND_BLUE, MERIDIAN_COLOR, EQUATOR_COLOR)))


@functools.lru_cache(maxsize=2)
def unit_sphere(n: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """A plain unit sphere (vertices, faces) for translucent shells (energy ellipsoid, momentum sphere)."""
    verts, quads, _, _ = sphere_grid(np.linspace(-np.pi / 2, np.pi / 2, n + 1), np.linspace(-np.pi, np.pi, 2 * n + 1))
    (v, f, _), = mesh_parts(verts, quads, np.zeros(len(quads), int), ((0, 0, 0),))
    return v, f


def flat_disc(radius: float, sections: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """A disc in the z = 0 plane (triangle fan): one layer, so a see-through disc is blended once
    per pixel."""
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


def circle(radius: float, n: int = 181, z: float = 0.0) -> np.ndarray:
    th = np.linspace(0, 2 * np.pi, n)
    return np.stack([radius * np.cos(th), radius * np.sin(th), np.full_like(th, z)], 1)


# ---- the drawings every scene shares ----------------------------------------------------------

AXIS_COLORS = ((220, 50, 47), (60, 170, 60), (38, 110, 220))  # A red, B green, C blue
OMEGA_COLOR = (255, 150, 0)
L_COLOR = (170, 60, 200)
TRAIL_COLOR = (240, 120, 30)
POLHODE_COLOR = (250, 210, 40)
HERPOLHODE_COLOR = (0, 190, 200)
FIGURE_COLOR = (38, 110, 220)


def new_drawing(run, spec, max_frames: int = MAX_FRAMES) -> Drawing:
    """An empty drawing of `run`: frames, text, camera, default overlays, and the run's plot."""
    tr = run.trajectory
    frames = frame_indices(len(tr.t), max_frames)
    ch15 = spec.group == "ch. 15"
    overlays = {k: (v[1] if ch15 else v[2]) for k, v in OVERLAYS.items()}
    overlays.update(spec.overlays)
    return Drawing(frames=frames, times=np.asarray(tr.t, float)[frames], time_unit=tr.time_unit,
                   camera=spec.camera or default_camera(spec), title=spec.title, section=spec.section,
                   summary=spec.summary, formula=spec.euler_formula, overlays=overlays,
                   plot=dict(run.plot_series), plot_t=np.asarray(tr.t, float), rotation=spec.kind == "rotation",
                   clock=clock_of(run))


def default_camera(spec) -> Camera:
    """A scenario without a camera of its own: oblique for rotation scenes, from above for orbits."""
    if spec.kind != "rotation":
        return Camera((0.0, -2.6, 4.2))
    if spec.group == "ch. 15":
        return Camera((3.0, 2.3, 1.8))
    return Camera((4.8, 3.7, 2.9))


def omega_scale(traj) -> float:
    """Scene length per rad/s of ω: its tip on the energy ellipsoid (largest semi-axis 1.3), whose
    plane of contact is the invariable plane (Poinsot); a body starting at rest has its largest ω
    drawn 1.3 long, and so does a spin-up from nearly nothing that would overflow the scene."""
    E = float(traj.energy[0])
    wmax = float(np.max(np.linalg.norm(traj.omega_body, axis=1)))
    k = 1.3 / np.sqrt(2 * E / traj.inertia).max() if E > 0 else (1.3 / wmax if wmax > 0 else 1.0)
    if not (np.isfinite(k) and k * wmax <= DRAW_MAX):
        k = 1.3 / wmax if wmax > 0 and np.isfinite(1.3 / wmax) else 1.0
    return float(k)


SAME_DIRECTION_RAD = np.radians(1.0)  # two arrows closer than this are one line on screen


def _one_direction(a: np.ndarray, b: np.ndarray) -> bool:
    """Do the vectors a[k] and b[k] point the same way (within SAME_DIRECTION_RAD) at every frame?"""
    na, nb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
    if not (np.all(na > 0) and np.all(nb > 0)):
        return False
    cos = np.einsum("ij,ij->i", a, b) / (na * nb)
    return bool(np.all(cos > np.cos(SAME_DIRECTION_RAD)))


def rigid_body(d: Drawing, run, view: View, shape: str = "ellipsoid") -> np.ndarray:
    """The body and Poinsot's construction (§805–808) in their overlay groups; returns the
    semi-axes drawn (scene units).

    - the body: the homogeneous ellipsoid of the moments in latitude bands about C with one
      meridian, so that rotation shows ("body", a Frame turning with the attitude);
    - principal axes A, B, C (red, green, blue) with their moments;
    - ω and L as arrows (ω scaled so that its tip lies on the energy ellipsoid);
    - the polhode (where the rotation axis pierces the body's surface, on the body), the
      herpolhode (the tip of ω in space, on the invariable plane), the trail of the rotation axis;
    - optional: the energy ellipsoid with the polhode on it, the momentum sphere with the path of
      L on the body, a celestial sphere with the paths of the figure and rotation axes.
    """
    tr, f = run.trajectory, d.frames
    at = np.arange(len(f), dtype=float)
    box = shape == "box"
    semi = box_semi_axes(tr.inertia, view.exaggerate) if box else shape_semi_axes(tr.inertia, view.exaggerate)
    d.add(Frame(name="body", group="body", wxyz=tr.quat_wxyz[f]))
    for k, (v, fc, rgb) in enumerate(box_parts() if box else banded_sphere_parts()):
        d.add(Mesh(name=f"body/mesh/{k}", group="body", vertices=v, faces=fc, color=rgb, scale=tuple(semi)))
    if box:
        d.add(Segments(name="body/edges", group="body", points=box_edges(semi * 1.002), colors=(60, 60, 70),
                       thickness=0.012))
    ends = np.diag(semi * 1.35)
    d.add(Arrows(name="body/axes", group="axes", origins=np.zeros((3, 3)), vectors=ends, colors=AXIS_COLORS,
                 shaft_radius=0.018, head_radius=0.05, head_length=0.1))
    for k, lab in enumerate("ABC"):
        d.add(Label(name=f"body/axis_labels/{lab}", group="axes", text=f"{lab} = {tr.inertia[k]:.4g}",
                    position=ends[k] * 1.08))
    k_w = omega_scale(tr)
    Lm = np.asarray(tr.momentum_norm, float)[:, None]
    L_drawn = np.where(Lm > 0, 1.3 * tr.L_inertial / np.where(Lm > 0, Lm, 1.0), 0.0)
    # ω and L one line on screen for the whole run (the Earth: 10⁻⁶ rad apart): one letter for both,
    # not "ω" and "L" printed over each other
    together = _one_direction(tr.omega_inertial[f], tr.L_inertial[f])
    for key, vec, color, text in (("omega", k_w * tr.omega_inertial, OMEGA_COLOR, "ω, L" if together else "ω"),
                                  ("L", L_drawn, L_COLOR, None if together else "L")):
        v = np.asarray(vec, float)[f]
        d.add(Arrows(name=key, group="vectors", origins=np.zeros((1, 3)), vectors=v[:, None, :], colors=(color,),
                     shaft_radius=0.025, head_radius=0.06, head_length=0.12, labels=(text,) if text else ()))
    # the polhode: the rotation axis meets the body's surface (ray/ellipsoid), drawn on the body
    w = tr.omega_body[f]
    nw = np.linalg.norm(w, axis=1, keepdims=True)
    ok = nw[:, 0] > 0
    if np.count_nonzero(ok) >= 2:
        u = w[ok] / nw[ok]
        if box:  # where the ray along ω leaves the box
            s = 1.0 / np.max(np.abs(u) / semi, axis=1, keepdims=True)
        else:
            s = 1.0 / np.sqrt(np.sum((u / semi) ** 2, axis=1, keepdims=True))
        d.add(Path(name="body/polhode", group="polhode", points=1.015 * s * u, color=POLHODE_COLOR, thickness=0.02,
                   at=at[ok]))
    E, Lmag = float(tr.energy[0]), float(tr.momentum_norm[0])
    if E > 0:
        e_semi = tuple(float(x) for x in np.sqrt(2 * E / tr.inertia) * k_w)
        v, fc = unit_sphere()
        d.add(Mesh(name="body/energy_ellipsoid", group="energy_ellipsoid", vertices=v, faces=fc, color=(120, 200, 255),
                   opacity=0.25, scale=e_semi, double_sided=True),
              Path(name="body/polhode_on_ellipsoid", group="energy_ellipsoid", points=k_w * w, color=POLHODE_COLOR,
                   thickness=0.012, at=at))
    if Lmag > 0:
        v, fc = unit_sphere()
        k_L = 1.3 / Lmag
        Lmax = float(np.max(np.linalg.norm(tr.L_body, axis=1)))
        if not (np.isfinite(k_L) and k_L * Lmax <= DRAW_MAX):  # |L| grows from nearly nothing (as ω above)
            k_L = 1.3 / Lmax if Lmax > 0 and np.isfinite(1.3 / Lmax) else 1.0
        d.add(Mesh(name="body/momentum_sphere", group="momentum_sphere", vertices=v, faces=fc, color=(200, 150, 255),
                   opacity=0.2, scale=(1.3, 1.3, 1.3), double_sided=True),
              Path(name="body/L_path", group="momentum_sphere", points=k_L * tr.L_body[f], color=L_COLOR,
                   thickness=0.02, at=at))
    if E > 0 and Lmag > 0:
        # the tip of ω in space on the invariable plane ω·L̂ = 2E/|L|, a disc normal to L
        Lhat = tr.L_inertial[0] / Lmag
        dv, df = flat_disc(1.25)
        d.add(Path(name="herpolhode", group="herpolhode", points=k_w * tr.omega_inertial[f], color=HERPOLHODE_COLOR,
                   thickness=0.012, at=at),
              Mesh(name="invariable_plane", group="herpolhode", vertices=dv, faces=df, color=(0, 160, 170),
                   opacity=0.08, double_sided=True, wxyz=z_to_many(Lhat[None])[0][0],
                   position=k_w * 2 * E / Lmag * Lhat))
    d.add(Path(name="axis_trail", group="axis_trail", points=AXIS_TRAIL_RADIUS * tr.rotation_axis[f], color=TRAIL_COLOR,
               thickness=0.012, at=at))
    d.add(Segments(name="celestial/grid", group="celestial", points=wire_sphere(CELESTIAL_RADIUS), colors=(150, 150, 160),
                   thickness=0.004),
          Path(name="celestial/figure_axis", group="celestial", points=CELESTIAL_RADIUS * tr.figure_axis[f],
               color=FIGURE_COLOR, thickness=0.03, at=at),
          Path(name="celestial/rotation_axis", group="celestial", points=CELESTIAL_RADIUS * tr.rotation_axis[f],
               color=TRAIL_COLOR, thickness=0.012, at=at))
    return semi


def other_bodies(d: Drawing, run, bodies: Mapping[str, np.ndarray] | None = None, span: float | None = None,
                 trails: Callable[[str], bool] = lambda name: True, directions: bool | None = None) -> float:
    """Other bodies as coloured balls with their names and trails ("bodies" group). In a rotation
    scene a distant attractor is drawn by its direction at ORBIT_RADIUS; in an orbit scene the
    positions are scaled so that `span` (default: the largest distance) is drawn at ORBIT_RADIUS.
    Returns the scale used (scene units per trajectory unit; 0 for directions)."""
    tr, f = run.trajectory, d.frames
    bodies = tr.bodies if bodies is None else bodies
    if not bodies:
        return 0.0
    directions = d.rotation if directions is None else directions
    k = 0.0
    if not directions:
        allpos = np.concatenate([np.asarray(p, float) for p in bodies.values()])
        span = span or float(np.max(np.linalg.norm(allpos, axis=1))) or 1.0
        k = ORBIT_RADIUS / span
    at = np.arange(len(f), dtype=float)
    for j, (name, pos) in enumerate(bodies.items()):
        pos = np.asarray(pos, float)[f]
        pos = ORBIT_RADIUS * unit(pos) if directions else k * pos
        col = BODY_COLOURS.get(name, palette(j))
        d.add(Sphere(name=f"bodies/{name}", group="bodies", radius=0.12, color=col, position=pos),
              Label(name=f"bodies/{name}/label", group="bodies", text=body_name(name), position=(0.0, 0.0, 0.2)))
        if trails(name):
            d.add(Path(name=f"body_trails/{name}", group="bodies", points=pos, color=col, thickness=0.02, at=at))
    return k


# ---- labels that do not overlap -----------------------------------------------------------------

LABEL_PX_PER_CHAR, LABEL_PX_HEIGHT, LABEL_PAD_PX = 7.2, 18.0, 4.0  # viser's label at 1280×800
SHOWN_WIDTH_PX = 1280 - 384  # the canvas beside the app's docked panel, the look-at in its middle
ANCHOR_TRIES = ("top-left", "bottom-left", "center-left", "top-right", "bottom-right", "center-right",
                "bottom-center", "top-center")


def _project(points, camera: Camera, width: float = 1280.0, height: float = 800.0):
    """Pixel coordinates (x right, y down) and depth of scene points seen from `camera`."""
    P, L = np.asarray(camera.position, float), np.asarray(camera.look_at, float)
    f = unit(L - P)
    r = unit(np.cross(f, np.asarray(camera.up, float)))
    u = np.cross(r, f)
    v = np.atleast_2d(points) - P
    depth = v @ f
    t = np.tan(np.radians(camera.fov_deg if camera.fov_deg is not None else 75.0) / 2)
    x = (v @ r) / np.maximum(depth, 1e-9) / (t * width / height)
    y = (v @ u) / np.maximum(depth, 1e-9) / t
    return np.stack([(x + 1) * width / 2, (1 - y) * height / 2], 1), depth


def _box(xy, text: str, anchor: str, scale: float = 1.0) -> tuple[float, float, float, float]:
    w = scale * (LABEL_PX_PER_CHAR * len(text) + 2 * LABEL_PAD_PX)
    h = scale * LABEL_PX_HEIGHT
    vert, horiz = anchor.split("-")
    x0 = {"left": xy[0], "center": xy[0] - w / 2, "right": xy[0] - w}[horiz]
    y0 = {"top": xy[1], "center": xy[1] - h / 2, "bottom": xy[1] - h}[vert]
    return x0, y0, x0 + w, y0 + h


def _overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _per_frame(v, ks) -> np.ndarray:
    """An attribute's value at frames `ks` (one value per frame, or one for all)."""
    v = np.asarray(v, float)
    return v[ks] if v.ndim == 2 else np.broadcast_to(v, (len(ks),) + v.shape)


def _world(d: Drawing, it: Item, ks, position=None) -> tuple[np.ndarray, np.ndarray]:
    """The scene position of a label at frames `ks` (through the frames it hangs on), and whether
    it is shown there. `position`: a point of the item other than its own `position` (per frame
    or fixed, in the item's frame)."""
    from ..physics import quaternion as quat

    pos = _per_frame(it.position if position is None else position, ks)
    shown = np.ones(len(ks), bool) if it.visible is None else np.asarray(it.visible, bool)[ks]
    parts = it.name.split("/")
    for k in range(len(parts) - 1, 0, -1):
        try:
            fr = d.item("/".join(parts[:k]))
        except KeyError:
            continue
        if not isinstance(fr, Frame):
            continue
        pos = quat.rotate(_per_frame(fr.wxyz, ks), pos) + _per_frame(fr.position, ks)
        if fr.visible is not None:
            shown &= np.asarray(fr.visible, bool)[ks]
    return pos, shown


@dataclass
class _Text:
    """A text the scene writes at a point: a label, or the letter at an arrow's tip."""

    text: str
    pos: np.ndarray  # scene positions at the frames looked at
    shown: np.ndarray
    moves: bool
    anchor: str
    turn: Callable[[str], None]
    shown_first: bool = True  # its overlay is on when the scene opens
    label: Label | None = None  # the label it is (None: an arrow's letter)


def _texts(d: Drawing, ks) -> list[_Text]:
    """Every fixed-text label and arrow letter of the drawing, in the drawing's order, those of
    overlays that are on when the scene opens first."""
    out = []
    for it in d.items:
        if isinstance(it, Label) and isinstance(it.text, str):
            pos, shown = _world(d, it, ks)
            out.append(_Text(it.text, pos, shown, _moves(d, it), it.anchor,
                             lambda a, it=it: setattr(it, "anchor", a), d.overlays.get(it.group, True), it))
        elif isinstance(it, Arrows) and len(it.labels):
            origins = np.asarray(it.origins, float).reshape(-1, 3)
            vectors = np.asarray(it.vectors, float)
            vectors = vectors.reshape(-1, len(origins), 3) if vectors.ndim == 3 else vectors.reshape(len(origins), 3)

            def turn(a, j, it=it):
                anchors = [it.label_anchor(i) for i in range(len(it.labels))]
                anchors[j] = a
                it.label_anchors = tuple(anchors)

            for j, text in enumerate(it.labels):
                # where the scene writes it: just beyond the tip (app/scene.py)
                tip = origins[j] + 1.1 * (vectors[:, j] if vectors.ndim == 3 else vectors[j])
                pos, shown = _world(d, it, ks, position=tip)
                out.append(_Text(str(text), pos, shown, _moves(d, it), it.label_anchor(j),
                                 lambda a, j=j, turn=turn: turn(a, j), d.overlays.get(it.group, True)))
    # what the scene shows when it opens is placed first; an overlay switched on later fits around it
    return sorted(out, key=lambda t: not t.shown_first)


def _moves(d: Drawing, it: Item) -> bool:
    parts = it.name.split("/")
    frames = [d.item(n) for n in ("/".join(parts[:k]) for k in range(1, len(parts))) if _has(d, n)]
    return bool(it.animated()) or any(isinstance(f, Frame) and f.animated() for f in frames)


def _has(d: Drawing, name: str) -> bool:
    return any(x.name == name for x in d.items)


SWEPT_FRAMES = 12  # frames at which a moving label's place is taken as taken


def declutter_labels(d: Drawing, width: float = 1280.0, height: float = 800.0, text_scale: float = 1.0) -> int:
    """Labels and the letters at arrow tips are seen from the drawing's camera at SWEPT_FRAMES
    frames of the run and turned to another side of their point (their `anchor`; the point stays
    where the physics puts it) so that they cover one another in as few of those frames as can be:
    a text that stays put and another that passes over it meet in the frames it passes; two that
    stay put, in all of them. A side where a text runs off the canvas beside the panel counts as
    covering in every frame it does, and the opening frame (what a class sees before Play) weighs
    as many frames as were looked at. Each text in turn takes its best side against those placed
    before it (in the drawing's order, the texts of overlays that are off when the scene opens
    last), then each again against all the others, for at most four rounds (the scenes' own labels
    settle in one or two; a crowd of random ones may not). A label that `yields` (a star's name)
    and still covers another text when the scene opens is left out. `text_scale`: the labels'
    size against viser's at `width`×`height` (View.text_scale). Returns how many were turned."""
    ks = np.unique(np.linspace(0, max(d.n_frames - 1, 0), SWEPT_FRAMES).round().astype(int))
    texts = _texts(d, ks)
    if not texts:
        return 0
    sides = ANCHOR_TRIES + tuple(dict.fromkeys(t.anchor for t in texts if t.anchor not in ANCHOR_TRIES))
    weight = np.ones(len(ks))
    weight[0] = len(ks)
    # every text's box on every side at every frame; NaN where it is not shown (meets nothing)
    boxes = np.full((len(texts), len(sides), len(ks), 4), np.nan)
    for i, t in enumerate(texts):
        xy, depth = _project(t.pos, d.camera, width, height)
        on = np.asarray(t.shown, bool) & (depth > 0)
        for s, a in enumerate(sides):
            if on.any():
                boxes[i, s, on] = [_box(p, t.text, a, text_scale) for p in xy[on]]
    half = SHOWN_WIDTH_PX / 2 * width / 1280.0
    cut = ((boxes[..., 0] < width / 2 - half) | (boxes[..., 2] > width / 2 + half)
           | (boxes[..., 1] < 0) | (boxes[..., 3] > height))
    side = np.array([sides.index(t.anchor) for t in texts])
    first = np.array([t.shown_first for t in texts])

    def best(i: int, others: np.ndarray) -> int:
        """The side of text i that covers the others (on their sides now) least, weighed by frame:
        its own if none covers less, else the first in ANCHOR_TRIES that covers least."""
        mine, theirs = boxes[i][:, None], boxes[others, side[others]][None]  # (sides, 1, K, 4), (1, n, K, 4)
        meets = ((mine[..., 0] < theirs[..., 2]) & (theirs[..., 0] < mine[..., 2])
                 & (mine[..., 1] < theirs[..., 3]) & (theirs[..., 1] < mine[..., 3]))
        cost = (meets.sum(1) + cut[i]) @ weight
        order = [side[i]] + [s for s in range(len(sides)) if s != side[i]]
        return order[int(np.argmin(cost[order]))]

    everyone = np.arange(len(texts))
    for i in everyone:  # each against those placed before it
        side[i] = best(i, everyone[:i])
    for _ in range(4):  # then against all the others (an overlay switched on later never moves the opening ones)
        moved = False
        for i in everyone:
            s = best(i, everyone[(everyone != i) & (first | ~first[i])])
            moved |= s != side[i]
            side[i] = s
        if not moved:
            break
    # a background name that still covers another text when the scene opens, or that another text
    # already says, gives way: the star "Polaris" on the pole's "AD 2000", "Deneb" under "C = 1",
    # "Vega" beside "Vega: AD 13695 (6.6°)"
    kept = np.ones(len(texts), bool)
    for i in everyone:
        t = texts[i]
        if t.label is None or not t.label.yields or not first[i]:
            continue
        mine, theirs = boxes[i, side[i], 0], boxes[everyone, side, 0]
        others = kept & first & (everyone != i)
        said = any(o.text.startswith(t.text + ":") for o, k in zip(texts, others) if k)  # "Vega: AD 13695 (6.6°)"
        if said or np.any(others & (mine[0] < theirs[:, 2]) & (theirs[:, 0] < mine[2])
                          & (mine[1] < theirs[:, 3]) & (theirs[:, 1] < mine[3])):
            kept[i] = False
            d.items.remove(t.label)
    turned = 0
    for t, s, k in zip(texts, side, kept):
        if k and sides[s] != t.anchor:
            t.turn(sides[s])
            turned += 1
    return turned


def standard(run, spec, view: View, shape: str = "ellipsoid") -> Drawing:
    """The drawing of a scenario that declares none of its own: Poinsot's construction for a
    rotation scene (the body an ellipsoid, or a box with `shape="box"`), and the other bodies."""
    d = new_drawing(run, spec)
    if d.rotation:
        rigid_body(d, run, view, shape)
    other_bodies(d, run)
    return d
