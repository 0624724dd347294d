"""The viser renderer of a scenario's `Drawing` (theoria.scenarios.drawing): the live app's scene.

`SceneView(scene)` works on any viser scene API: a client's (`client.scene`, each browser its own
state) or a server's (`server.scene`, used by the standalone HTML export). It draws what the
drawing lists and nothing else.

- `show(drawing)` sends every item once. Nodes are cached by name: a new drawing of the same
  scenario updates the existing handles in place (points, scale, pose), removes what is no longer
  drawn, and the items of an overlay that is off are not sent at all until it is switched on.
- `set_frame(k)` then only moves what changes with time: frame poses, marker positions, per-frame
  segments and label text, the visibility of path chunks. Nothing else goes over the wire.

Paths are drawn as dense clouds of square points (resampled along the arc so that the gaps are
under the point size, at most MAX_DRAW_POINTS; points that land on an earlier point of the same
path are dropped, see REPEAT_CELL): in software WebGL a 10⁴-point fat line renders at a few
frames per second, a 10⁴-point cloud at ~30. A path is sent once, in TRAIL_CHUNKS chunks of equal
time span whose visibility follows playback, so a trail grows without being re-sent.

A single arrow that turns with time (ω, L) is drawn along +z of a frame of its own: playback
turns the frame (a pose update) and re-sends the arrow only when its length changes by more than
VECTOR_LENGTH_TOL.

**A page that plays by itself.** `tracks()` hands the page (app/browser.py's player) everything
that changes with time: frame and marker poses, label positions, visibility, the growing paths'
chunks, the length of each turning arrow (as a scale of the arrow drawn once), and the per-frame
props the page gives viser's own update path: label text (each distinct string once, then an index
per frame), per-frame segments and arrays of arrows (float16 points; a long run's are kept for
every s-th frame, within TRACK_POINTS_BYTES and TRACK_TEXT_CHARS). With `page_plays` set,
`set_frame(k, moving=True)` sends nothing at all: during playback a browser draws every frame it
can without a message from the server, and a hundred browsers playing cost the server only the
time read-out. Paused, stepped or scrubbed, `set_frame(k)` sets everything exactly as before (the
server's values, not the page's every s-th frame), so the server's state and the page's agree
whenever the clock stands still.
"""
from __future__ import annotations

import base64
import hashlib
import json
import threading
import weakref
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from theoria.scenarios.drawing import (Arrows, Drawing, Frame, Item, Label, Light, Mesh, Path, Points, Segments,
                                       Sphere, z_to_many)

def _hints_per_class() -> None:
    """viser looks up the type hints of a node's properties (typing.get_type_hints, ~3 ms: it
    evaluates every annotation of the props class) once per node it creates; a scene of 200
    nodes sent to each of 100 browsers spent most of its time there. The hints depend on the
    class only, so they are computed once per class. (viser 1.1: `AssignablePropsBase._prop_hints`,
    a cached_property per handle.)"""
    import functools
    import typing

    try:
        from viser import _assignable_props_api as apa
    except ImportError:
        return
    base = getattr(apa, "AssignablePropsBase", None)
    if base is None or not isinstance(base.__dict__.get("_prop_hints"), functools.cached_property):
        return

    @functools.lru_cache(maxsize=None)
    def hints(cls):
        return typing.get_type_hints(cls)

    base._prop_hints = property(lambda self: hints(type(self._impl.props)))


def _pose_check_without_numpy() -> None:
    """viser sets a node's orientation or position only when it changed, judged by np.allclose on
    four numbers: ~15 µs of numpy's machinery per assignment, and a scene shown to a browser sets
    a hundred poses (the frames, the bodies, the labels), under the one interpreter lock that draws
    every browser's scenes. The same test (|new - old| ≤ 1e-8 + 1e-5 |old| for every component; a
    NaN is never close) in plain Python. (viser 1.1: `_scene_handles._set_pose_vector`.)"""
    import inspect

    try:
        from viser import _scene_handles as sh
        from viser._scene_api import cast_vector
    except ImportError:
        return
    f = getattr(sh, "_set_pose_vector", None)
    if f is None or list(inspect.signature(f).parameters) != ["current", "value", "length", "queue", "make_message"]:
        return

    def set_pose_vector(current, value, length, queue, make_message):
        value_cast = cast_vector(value, length)
        new = [float(x) for x in value_cast]
        if all(abs(a - b) <= 1e-8 + 1e-5 * abs(b) for a, b in zip(new, current.tolist())):
            return
        current[:] = new
        queue(make_message(value_cast))

    set_pose_vector.__wrapped__ = f
    sh._set_pose_vector = set_pose_vector


def _array_hints_built_once() -> None:
    """viser casts each property value it is given by comparing the property's type hint with
    npt.NDArray[np.float16], [np.float32], [np.float64] and [np.uint8], each built anew on every
    assignment (a typing subscription: ~200 of typing's argument checks for one update of the
    flip's scene, 1.4 of its 13 ms under the one interpreter lock). The same comparisons, in the
    same order, against the four built once. (viser 1.1:
    `AssignablePropsBase._cast_value_recursive`.)"""
    import inspect

    try:
        import numpy.typing as npt
        from viser import _assignable_props_api as apa

        f = apa.AssignablePropsBase._cast_value_recursive
        src = inspect.getsource(f)
        to_uint8 = apa.colors_to_uint8
    except (ImportError, AttributeError, OSError, TypeError):
        return
    if not all(s in src for s in ("hint == npt.NDArray[np.float16]", "hint == npt.NDArray[np.float32]",
                                  "hint == npt.NDArray[np.float64]",
                                  'hint == npt.NDArray[np.uint8] and "color" in prop_name')):
        return  # another viser: its own casting stays
    f16, f32, f64, u8 = (npt.NDArray[t] for t in (np.float16, np.float32, np.float64, np.uint8))

    def cast(self, hint, value, prop_name):
        if hint == f16:
            return np.asarray(value).astype(np.float16)
        elif hint == f32:
            return np.asarray(value).astype(np.float32)
        elif hint == f64:
            return np.asarray(value).astype(np.float64)
        elif hint == u8 and "color" in prop_name:
            return to_uint8(value)
        if isinstance(value, np.ndarray):
            return value
        args = getattr(hint, "__args__", None)
        if isinstance(value, tuple) and getattr(hint, "__origin__", None) is tuple and args is not None \
                and len(args) == 2 and args[1] is ...:
            return tuple(cast(self, args[0], item, prop_name) for item in value)
        return value

    cast.__wrapped__ = f
    apa.AssignablePropsBase._cast_value_recursive = cast


_hints_per_class()
_pose_check_without_numpy()
_array_hints_built_once()

MAX_DRAW_POINTS = 10000  # points per drawn path (10⁴-point trails)
# A growing trail is sent once as this many point clouds shown one after another: fewer nodes to
# send per browser and scene (the frame rate does not depend on it, docs/app.md), a trail that
# grows in 1/12 steps of the run.
TRAIL_CHUNKS = 12
# A path point is not drawn again where an earlier point of the same path already is: points are
# quantised to cells of REPEAT_CELL × their size and only the first (in time) of each cell is kept.
# viser draws a point `size` wide on each side of its centre, so a dropped point lies within 0.61 of
# a drawn point's width of one that is drawn already at that time: the picture is the same, but a
# path that retraces itself (a periodic polhode) costs far fewer points.
REPEAT_CELL = 0.7
VECTOR_LENGTH_TOL = 0.02
# Paths and points live in scene units of order 1, where float16 is good to ~1e-3 of a unit, far
# below a point's size: half the bytes per update.
PATH_PRECISION = "float16"
FLOAT16_MAX = 6.5e4
PAGE_ATTRS = {"wxyz", "position", "visible"}  # the poses a page moves by itself during playback
# A page is sent the per-frame props (label text, segment and arrow points) of one scene within
# these sizes: a run whose props would exceed them gives the page every s-th frame's (the smallest
# s that fits). A lunar orbit's 28-segment trail over 3,000 frames is 1 MB in float16: s = 8, still
# 19 updates a second while the run plays in 20 s (app/session.py RUN_SECONDS).
TRACK_POINTS_BYTES = 128_000
TRACK_TEXT_CHARS = 64_000
# The tracks of recently shown drawings, as JSON: a class shown the same cached scene (a preset, a
# scenario's defaults) shares one Drawing, and each browser's tracks differ from another's only by
# the node owner and the overlays' checkboxes. 3-400 kB a scene.
TRACKS_CACHE_BYTES = 32_000_000


class _TracksCache:
    """JSON of `SceneView._tracks_body` by (drawing, what the view drew of it), within a byte
    budget, least recently used first out. A drawing is held weakly: a run dropped from the run
    cache takes its entries' meaning with it (an id reused later does not match)."""

    def __init__(self, max_bytes: int = TRACKS_CACHE_BYTES):
        self.max_bytes = max_bytes
        self._items: OrderedDict = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()

    def get(self, drawing, signature):
        with self._lock:
            hit = self._items.get((id(drawing), signature))
            if hit is None or hit[0]() is not drawing:
                return None
            self._items.move_to_end((id(drawing), signature))
            return hit[1]

    def put(self, drawing, signature, text: str) -> None:
        with self._lock:
            key = (id(drawing), signature)
            old = self._items.pop(key, None)
            if old is not None:
                self._bytes -= len(old[1])
            self._items[key] = (weakref.ref(drawing), text)
            self._bytes += len(text)
            while self._bytes > self.max_bytes and self._items:
                self._bytes -= len(self._items.popitem(last=False)[1][1])


_tracks_cache = _TracksCache()


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def densify(path: np.ndarray, idx: np.ndarray, spacing: float, max_points: int):
    """Resample a polyline uniformly in arc length: gaps ≤ spacing where possible, at least the
    original number of points (capped at max_points); `idx` (the frame of each point) is
    interpolated alongside."""
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if not np.isfinite(s[-1]) or s[-1] <= 0:
        return path[:max_points], idx[:max_points]
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


def path_chunks(it: Path, grow_trails: bool = True):
    """The points a path is drawn with, as (chunks of float32 points, first frame of each chunk,
    precision, the frame at which each chunk's each point appears), or None for a path of fewer
    than two points. Computed once per Path item and kept
    on it: a drawing shared by many browsers (the server caches runs and their drawings) is
    densified and thinned once, not once per browser (17 ms a path)."""
    key = (grow_trails, MAX_DRAW_POINTS, TRAIL_CHUNKS, REPEAT_CELL, float(it.thickness))
    cached = it.__dict__.get("_theoria_chunks")
    if cached is not None and cached[0] == key:
        return cached[1]
    path = np.asarray(it.points, float)
    if len(path) < 2:
        out = None
    else:
        at = np.zeros(len(path)) if it.at is None else np.asarray(it.at, float)
        path, at = densify(path, at, 0.6 * it.thickness, MAX_DRAW_POINTS)
        path, at = drop_repeats(path, at, REPEAT_CELL * it.thickness)
        grow = grow_trails and it.at is not None
        k = TRAIL_CHUNKS if grow else 1
        # chunks of equal time span (after drop_repeats the points are not uniform in time); always
        # the same number, so a new drawing updates the same nodes in place (a chunk left without a
        # point of its own repeats the previous point)
        grid = np.linspace(at[0], at[-1], k + 1)
        bounds = np.concatenate([[0], np.searchsorted(at, grid[1:-1], side="left"), [len(path)]]).astype(int)
        prec = PATH_PRECISION if np.all(np.abs(path) < FLOAT16_MAX / 8) else "float32"
        pieces, starts, ats = [], [], []
        for j in range(k):
            a, b = bounds[j], bounds[j + 1]
            pieces.append(_f32(path[a:b] if b > a else path[max(a - 1, 0):max(a - 1, 0) + 1]))
            starts.append(int(np.ceil(grid[j])) if grow else 0)
            ats.append(np.maximum(at[a:b], starts[-1]) if (grow and b > a) else np.full(len(pieces[-1]), starts[-1]))
        out = (pieces, np.asarray(starts), prec, ats)
    it.__dict__["_theoria_chunks"] = (key, out)
    return out


def flat_faced(vertices, faces) -> bool:
    """Whether every vertex of the mesh lies in faces of one plane only (a brick drawn with a vertex
    per corner of each face): its shading is one tone per face under directional light, which the
    diffuse toon material gives as the physically based one does, at a fraction of the per-pixel
    work in software WebGL (the flip's brick: 40.9 → 43.3 frames a second at 1280×800)."""
    v = np.asarray(vertices, float).reshape(-1, 3)
    f = np.asarray(faces, np.int64).reshape(-1, 3)
    if not len(f):
        return False
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    ids = f.ravel()
    order = np.argsort(ids, kind="stable")
    ids, normals = ids[order], np.repeat(n, 3, axis=0)[order]
    start = np.r_[True, ids[1:] != ids[:-1]]
    first = np.maximum.accumulate(np.where(start, np.arange(len(ids)), 0))  # each vertex's first face
    return bool(np.all(np.einsum("ij,ij->i", normals, normals[first]) > 1 - 1e-9))


def _content_key(*arrays) -> str:
    """A short digest of arrays' contents: a mesh whose geometry is unchanged is not sent again."""
    h = hashlib.blake2b(digest_size=12)
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _f32(x) -> np.ndarray:
    return np.asarray(x, np.float32)


def _tuple(v) -> tuple:
    return tuple(float(x) for x in np.asarray(v, float).ravel())


def _rgb(c):
    a = np.asarray(c)
    return tuple(int(x) for x in a) if a.ndim == 1 else np.asarray(a, np.uint8)


def _stride(n: int, size_at) -> int:
    """The smallest s (1, 2, 3, ...) for which every s-th of n frames fits: size_at(s) ≤ 1."""
    s = 1
    while s < n and size_at(s) > 1.0:
        s += 1
    return s


def _points_track(pts: np.ndarray) -> dict:
    """Per-frame points (F, ...) as the page takes them: flat, float16 when every value fits."""
    pts = np.asarray(pts, float)
    n = len(pts)
    flat = pts.reshape(n, -1)
    f16 = bool(np.isfinite(flat).all() and np.abs(flat).max(initial=0.0) < FLOAT16_MAX)
    per_bytes = flat.shape[1] * (2 if f16 else 4)
    s = _stride(n, lambda s: -(-n // s) * per_bytes / TRACK_POINTS_BYTES)
    data = flat[::s].astype("<f2" if f16 else "<f4")
    return {"data": _b64(data), "dtype": "f2" if f16 else "f4", "per": int(flat.shape[1]), "stride": int(s)}


def _text_track(texts) -> dict:
    """Per-frame text: each distinct string once (in order of first use) and an index per frame."""
    texts = [str(t) for t in texts]
    n = len(texts)

    def table(s):
        seen: dict[str, int] = {}
        idx = [seen.setdefault(t, len(seen)) for t in texts[::s]]
        return list(seen), idx

    s = _stride(n, lambda s: sum(map(len, table(s)[0])) / TRACK_TEXT_CHARS)
    strings, idx = table(s)
    return {"strings": strings, "data": _b64(np.asarray(idx, "<u4")), "stride": int(s)}


def _arrow_points(it: Arrows) -> np.ndarray:
    """(F, K, 2, 3): each frame's arrows from their origins (what viser's arrows take as points)."""
    o = np.asarray(it.origins, float).reshape(1, -1, 3)
    v = np.asarray(it.vectors, float)
    return np.stack([np.broadcast_to(o, v.shape), o + v], axis=2)


@dataclass
class _Chunks:
    """A path sent once as chunks; chunk j appears at frame starts[j]."""

    handles: list
    starts: np.ndarray
    ats: list = field(default_factory=list)  # the frame at which each point of each chunk appears
    shown: int = -1
    visible: bool = True

    def growth(self, n_frames: int) -> list[str]:
        """For a page that plays by itself: for each chunk, how many of its points are drawn at
        each frame from its first to the next chunk's (uint16, base64): the trail ends at the
        body at every frame, where the chunks alone drew up to 1/TRAIL_CHUNKS of the run ahead."""
        out = []
        for j, at in enumerate(self.ats):
            end = int(self.starts[j + 1]) if j + 1 < len(self.starts) else n_frames
            frames = np.arange(int(self.starts[j]), max(end, int(self.starts[j]) + 1))
            counts = np.searchsorted(np.asarray(at, float), frames, side="right")
            out.append(_b64(np.minimum(counts, 65535).astype("<u2")))
        return out

    def set_frame(self, k: int) -> None:
        n = int(np.searchsorted(self.starts, k, side="right"))
        if n == self.shown:
            return
        for j, h in enumerate(self.handles):
            want = self.visible and j < n
            if h.visible != want:
                h.visible = want
        self.shown = n

    def set_visible(self, on: bool, k: int) -> None:
        self.visible = on
        self.shown = -1
        self.set_frame(k)


class SceneView:
    """The nodes of one drawing under `root` (e.g. "/world") on a viser scene API."""

    def __init__(self, scene, root: str = "/world", grow_trails: bool = True):
        self.scene = scene
        self.root = root
        self.grow_trails = grow_trails
        self.label_scale = 1.0  # text size of labels (presenter mode: larger)
        self.drawing: Drawing | None = None
        self.overlays: dict[str, bool] = {}
        self.frame = 0
        self._h: dict[str, object] = {}  # node name → handle (alive)
        self._sig: dict[str, tuple] = {}  # node name → what it was created with (a change re-creates it)
        self._auto: set[str] = set()  # group nodes made for children before their parent
        self._touched: set[str] = set()
        self._built: dict[str, list[Item]] = {}  # group → its items, sent
        self._animated: list[tuple[Item, list]] = []  # (item, handles) moved by set_frame
        self._chunks: dict[str, list[_Chunks]] = {}  # group → paths
        self._static: dict[str, list] = {}  # group → handles shown/hidden with it
        self._vectors: dict[str, list] = {}  # arrow name → [frame, arrow, label, drawn length, (wxyz, lengths)]
        self._state: dict[str, object] = {}  # node name → the value last sent per animated attribute
        self.page_plays = False  # the page moves poses itself during playback (tracks())

    @property
    def n(self) -> int:
        return self.drawing.n_frames if self.drawing is not None else 0

    # ---- node cache --------------------------------------------------------------------------
    def _node(self, name: str, create, sig=(), **update):
        """The handle called `name`: created by `create()` the first time (or when `sig`, what it was
        created with, changes), else updated with `update`."""
        self._ensure_parents(name)
        h = self._h.get(name)
        if h is not None and name not in self._auto and self._sig.get(name) != sig:
            self._remove(name)
            h = None
        if h is None or name in self._auto:
            if name in self._auto:
                self._remove(name)
            h = create()
            self._h[name] = h
            self._sig[name] = sig
        else:
            for k, v in update.items():
                setattr(h, k, v)
        self._touched.add(name)
        return h

    def _remove(self, name: str) -> None:
        # viser removes a node's descendants with it: forget their handles too, or a later drawing
        # would update a removed handle (a scenario whose node was a frame and is now a mesh)
        prefix = name + "/"
        for child in [n for n in self._h if n.startswith(prefix)]:
            self._auto.discard(child)
            self._sig.pop(child, None)
            self._h.pop(child, None)
        self._auto.discard(name)
        self._sig.pop(name, None)
        h = self._h.pop(name, None)
        if h is not None:
            try:
                h.remove()
            except Exception:  # a node already gone with its parent
                pass

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

    def _prune(self) -> None:
        for name in sorted(self._h, key=lambda n: -n.count("/")):  # children first
            if name not in self._touched:
                self._remove(name)

    def clear(self) -> None:
        for name in sorted(self._h, key=lambda n: -n.count("/")):
            self._remove(name)
        self._h, self._sig, self._auto = {}, {}, set()
        self._built, self._animated, self._chunks, self._static, self._vectors = {}, [], {}, {}, {}
        self.drawing = None

    # ---- showing a drawing -------------------------------------------------------------------
    def show(self, drawing: Drawing, overlays: dict[str, bool] | None = None) -> None:
        """Show `drawing`, updating the nodes of the previous one in place. `overlays` (group → on)
        defaults to the drawing's own defaults."""
        self.overlays = dict(drawing.overlays if overlays is None else overlays)
        self.drawing = drawing
        self._touched = set()
        self._built, self._animated, self._chunks, self._static, self._vectors = {}, [], {}, {}, {}
        self._state = {}
        for it in drawing.items:  # frames first and always: other items are placed in them
            if isinstance(it, Frame):
                self._draw(it)
        groups = []
        for it in drawing.items:
            if it.group not in groups and not isinstance(it, Frame):
                groups.append(it.group)
        for g in groups:
            if self._on(g):
                self._build(g)
        self._prune()
        for g in groups:
            self._apply_visibility(g, self._on(g))
        self.frame = min(self.frame, max(self.n - 1, 0))
        self.set_frame(self.frame, force=True)

    def _on(self, group: str) -> bool:
        return self.overlays.get(group, True)

    def _build(self, group: str) -> None:
        if group in self._built or self.drawing is None:
            return
        items = [it for it in self.drawing.items if it.group == group and not isinstance(it, Frame)]
        items.sort(key=lambda it: it.name.count("/"))  # parents before children
        self._built[group] = items
        for it in items:
            self._draw(it)

    def _draw(self, it: Item) -> None:
        name = f"{self.root}/{it.name}"
        anim = it.animated()
        handles = getattr(self, f"_draw_{type(it).__name__.lower()}")(it, name, anim)
        handles = [h for h in handles if h is not None]
        if not isinstance(it, Frame):  # frames are never hidden with a group: they carry other items
            self._static.setdefault(it.group, []).extend(handles)
        if anim:
            self._animated.append((it, handles))

    @staticmethod
    def _static_value(v, anim: bool, k: int = 0):
        return np.asarray(v)[k] if anim else v

    def _draw_frame(self, it: Frame, name, anim):
        wxyz = _tuple(self._static_value(it.wxyz, "wxyz" in anim))
        pos = _tuple(self._static_value(it.position, "position" in anim))
        return [self._node(name, lambda: self.scene.add_frame(name, show_axes=False, wxyz=wxyz, position=pos),
                           wxyz=wxyz, position=pos)]

    def _draw_mesh(self, it: Mesh, name, anim):
        wxyz = _tuple(self._static_value(it.wxyz, "wxyz" in anim))
        pos = _tuple(self._static_value(it.position, "position" in anim))
        scale = _tuple(it.scale)
        ck = it.__dict__.get("_theoria_key")
        if ck is None or ck[0] is not it.vertices or ck[1] is not it.faces:
            material = "toon5" if flat_faced(it.vertices, it.faces) else "standard"
            ck = (it.vertices, it.faces, _content_key(it.vertices, it.faces), material)
            it.__dict__["_theoria_key"] = ck
        sig = (ck[2], _rgb(it.color), it.opacity, it.double_sided)
        return [self._node(name, lambda: self.scene.add_mesh_simple(
            name, it.vertices, it.faces, color=_rgb(it.color), opacity=None if it.opacity >= 1 else float(it.opacity),
            material=ck[3], side="double" if it.double_sided else "front", scale=scale, wxyz=wxyz, position=pos,
            cast_shadow=False, receive_shadow=False), sig=sig, scale=scale, wxyz=wxyz, position=pos)]

    def _draw_sphere(self, it: Sphere, name, anim):
        pos = _tuple(self._static_value(it.position, "position" in anim))
        return [self._node(name, lambda: self.scene.add_icosphere(
            name, radius=float(it.radius), color=_rgb(it.color), position=pos, cast_shadow=False,
            receive_shadow=False), sig=(float(it.radius), _rgb(it.color)), position=pos)]

    def _draw_points(self, it: Points, name, anim):
        pts = _f32(it.points)
        prec = PATH_PRECISION if np.all(np.abs(pts) < FLOAT16_MAX / 8) else "float32"
        cols = _rgb(it.colors)
        return [self._node(name, lambda: self.scene.add_point_cloud(
            name, pts, cols, point_size=float(it.size), point_shape="circle", precision=prec),
            sig=(float(it.size), prec), points=pts, colors=np.asarray(cols, np.uint8))]  # viser sets no tuple

    def _draw_segments(self, it: Segments, name, anim):
        pts = _f32(self._static_value(it.points, "points" in anim))
        cols = _rgb(it.colors)
        return [self._node(name, lambda: self.scene.add_line_segments(
            name, pts, cols, thickness=float(it.thickness), thickness_units="world"),
            sig=(float(it.thickness),), points=pts, colors=np.asarray(cols, np.uint8))]  # viser sets no tuple

    def _draw_label(self, it: Label, name, anim):
        text = str(self._static_value(it.text, "text" in anim))
        pos = _tuple(self._static_value(it.position, "position" in anim))
        anchor, scale = getattr(it, "anchor", "top-left"), float(self.label_scale)
        return [self._node(name, lambda: self.scene.add_label(name, text, position=pos, anchor=anchor,
                                                              font_screen_scale=scale),
                           text=text, position=pos, anchor=anchor, font_screen_scale=scale)]

    def _draw_light(self, it: Light, name, anim):
        pos = _tuple(self._static_value(it.position, "position" in anim))
        return [self._node(name, lambda: self.scene.add_light_directional(name, intensity=float(it.intensity),
                                                                           position=pos), position=pos)]

    def _draw_arrows(self, it: Arrows, name, anim):
        style = dict(shaft_radius=float(it.shaft_radius), head_radius=float(it.head_radius),
                     head_length=float(it.head_length))
        cols = _rgb(np.asarray(it.colors, np.uint8).reshape(-1, 3) if np.ndim(it.colors) > 1 else it.colors)
        origins = _f32(np.asarray(it.origins, float).reshape(-1, 3))
        if "vectors" in anim and len(origins) == 1:
            # one arrow turning with time: a frame of its own, turned each frame; the arrow along +z
            v = np.asarray(it.vectors, float)[:, 0, :]
            poses = z_to_many(v)
            frame = self._node(name, lambda: self.scene.add_frame(name, show_axes=False, position=_tuple(origins[0])),
                               position=_tuple(origins[0]))
            col = cols if isinstance(cols, tuple) else tuple(int(x) for x in np.asarray(cols).reshape(-1, 3)[0])
            arrow = self._node(f"{name}/arrow", lambda: self.scene.add_arrows(
                f"{name}/arrow", np.zeros((1, 2, 3), np.float32), col, **style), sig=tuple(style.values()))
            label = None
            if it.labels:
                scale, anchor = float(self.label_scale), it.label_anchor(0)
                label = self._node(f"{name}/label", lambda: self.scene.add_label(
                    f"{name}/label", str(it.labels[0]), font_screen_scale=scale, anchor=anchor),
                    text=str(it.labels[0]), anchor=anchor, font_screen_scale=scale)
            self._vectors[it.name] = [frame, arrow, label, -1.0, poses]
            return [frame, arrow, label]
        vec = _f32(self._static_value(it.vectors, "vectors" in anim))
        pts = np.stack([origins, origins + vec], 1)
        out = [self._node(name, lambda: self.scene.add_arrows(name, pts, cols, **style), sig=tuple(style.values()),
                          points=pts)]
        for j, text in enumerate(it.labels):
            pos = _tuple(1.08 * pts[j, 1])
            scale, anchor = float(self.label_scale), it.label_anchor(j)
            out.append(self._node(f"{name}/label_{j}", lambda text=text, pos=pos, anchor=anchor: self.scene.add_label(
                f"{name}/label_{j}", str(text), position=pos, font_screen_scale=scale, anchor=anchor),
                text=str(text), position=pos, anchor=anchor, font_screen_scale=scale))
        return out

    def _draw_path(self, it: Path, name, anim):
        """Send the path once, as chunks whose visibility follows the playback frame."""
        chunks = path_chunks(it, self.grow_trails)
        if chunks is None:
            return []
        pieces, starts, prec, ats = chunks
        handles = []
        col = _rgb(it.color)
        for j, pts in enumerate(pieces):
            cname = f"{name}/{j}"
            handles.append(self._node(cname, lambda cname=cname, pts=pts: self.scene.add_point_cloud(
                cname, pts, col, point_size=float(it.thickness), point_shape="square", precision=prec,
                point_shading="flat"), sig=(float(it.thickness), prec, col), points=pts))
        self._chunks.setdefault(it.group, []).append(_Chunks(handles, starts, ats))
        return []  # chunk visibility is handled by _Chunks, not by the group's static list

    # ---- changing what is shown --------------------------------------------------------------
    def _apply_visibility(self, group: str, on: bool) -> None:
        for h in self._static.get(group, []):
            if h.visible != on:
                h.visible = on
        for p in self._chunks.get(group, []):
            p.set_visible(on, self.frame)
        if on:  # items visible only at some frames
            for it, hs in self._animated:
                if it.group == group and it.visible is not None:
                    self._state.pop(f"{it.name}#visible", None)

    def set_overlay(self, group: str, on: bool) -> None:
        self.overlays[group] = bool(on)
        if on and group not in self._built:
            self._build(group)  # first time on for this drawing: send its items now
        self._apply_visibility(group, bool(on))
        self.set_frame(self.frame)

    def set_frame(self, k: int, force: bool = False, moving: bool = False) -> None:
        """Move what changes with time to frame k. `moving`: the page is playing by itself (see
        `tracks()`); only what it cannot move is sent."""
        if self.n == 0:
            return
        k = min(max(int(k), 0), self.n - 1)
        self.frame = k
        moving = moving and self.page_plays
        for it, hs in self._animated:
            if not (isinstance(it, Frame) or self._on(it.group)):
                continue
            if it.name in self._vectors:
                if not moving or self._vectors[it.name][3] <= 0:  # (a zero arrow has no scale to give)
                    self._set_vector(it.name, k, force)
            elif not (moving and self._page_moves(it)):
                self._set_item(it, hs, k, force)
        if not moving:
            for group, paths in self._chunks.items():
                for p in paths:
                    p.set_frame(k)

    # ---- what the page moves by itself -----------------------------------------------------------
    @staticmethod
    def _page_moves(it: Item) -> bool:
        """Poses and visibility of every node; a label's text; the points of per-frame segments and
        of an array of arrows from fixed origins."""
        anim = set(it.animated())
        if isinstance(it, Label):
            return anim <= PAGE_ATTRS | {"text"}
        if isinstance(it, Segments):
            return anim <= {"points", "visible"}
        if isinstance(it, Arrows):
            return anim <= {"vectors", "visible"}
        return isinstance(it, (Frame, Mesh, Sphere, Light)) and anim <= PAGE_ATTRS

    def server_moves(self) -> bool:
        """Something shown changes with time that the page cannot move by itself."""
        def page(it):
            return self._vectors[it.name][3] > 0 if it.name in self._vectors else self._page_moves(it)
        return any(not page(it) and (isinstance(it, Frame) or self._on(it.group)) for it, _ in self._animated)

    def tracks(self) -> dict:
        """What the page needs to play by itself: the frames' times (0..1 of the run), and per node
        its poses, visibility or scale at every frame, base64 little-endian (quaternions as int16
        × 32767, positions float32, visibility uint8, a turning arrow's scale float32), with the
        group whose checkbox hides it. Per-frame props (`prop` tracks, given to viser as the
        server's own node updates, under `owner`): points, float16 where they fit, `per` numbers a
        frame, for every `stride`-th frame; text, each distinct string once and a uint32 index per
        `stride`-th frame. The growing paths: their chunk nodes and the frame at which each
        appears."""
        return {**self._tracks_body(), **self._tracks_head()}

    def tracks_json(self) -> str:
        """`tracks()` as JSON; the part every browser shown this drawing shares is made once."""
        d = self.drawing
        if d is None or self.n == 0:
            return json.dumps(self.tracks())
        signature = (tuple(h.name for _, hs in self._animated for h in hs),
                     tuple((v[0].name, v[1].name, v[2] and v[2].name, v[3]) for v in self._vectors.values()),
                     tuple(h.name for paths in self._chunks.values() for p in paths for h in p.handles))
        body = _tracks_cache.get(d, signature)
        if body is None:
            body = json.dumps(self._tracks_body())
            _tracks_cache.put(d, signature, body)
        return body[:-1] + ", " + json.dumps(self._tracks_head())[1:]

    def _tracks_head(self) -> dict:
        """What differs between browsers shown the same drawing: the overlays and the nodes' owner."""
        return {"groups": dict(self.overlays),
                "owner": str(getattr(self.scene, "_owner_id", ""))}  # viser 1.1 drops an update of another owner's node

    def _tracks_body(self) -> dict:
        d = self.drawing
        out = {"n": self.n, "tracks": [], "chunks": [], "props": []}
        if d is None or self.n == 0:
            return out
        out["times"] = _b64(d.paces().astype("<f4"))

        def add(node, attr, values, group):
            v = np.asarray(values, float)
            if attr == "wxyz":
                data = np.round(np.clip(v, -1, 1) * 32767).astype("<i2")
            elif attr == "visible":
                data = v.astype("u1")
            else:
                data = v.astype("<f4")
            out["tracks"].append({"node": node, "attr": attr, "data": _b64(data), "group": group})

        for it, hs in self._animated:
            if it.name in self._vectors:
                frame, arrow, label, drawn, (wxyz, lengths) = self._vectors[it.name]
                if drawn > 0:  # the arrow as drawn, turned and scaled to each frame's length
                    add(frame.name, "wxyz", wxyz, it.group)
                    add(arrow.name, "scale", np.maximum(lengths / drawn, 1e-6), it.group)  # a zero scale has no inverse
                    if label is not None:
                        pos = np.zeros((len(lengths), 3))
                        pos[:, 2] = 1.1 * lengths
                        add(label.name, "position", pos, it.group)
            elif self._page_moves(it):
                group = None if isinstance(it, Frame) else it.group
                for attr in it.animated():
                    if attr == "visible":
                        for h in hs:
                            add(h.name, attr, np.asarray(it.visible, bool), group)
                    elif attr == "text":
                        out["props"].append({"node": hs[0].name, "prop": "text", "group": group,
                                             **_text_track(it.text)})
                    elif attr in ("points", "vectors"):
                        pts = np.asarray(it.points, float) if attr == "points" else _arrow_points(it)
                        out["props"].append({"node": hs[0].name, "prop": "points", "group": group,
                                             **_points_track(pts)})
                        if attr == "vectors":  # the labels at the tips follow them
                            for j, h in enumerate(hs[1:]):
                                add(h.name, "position", 1.08 * pts[:, j, 1], group)
                    else:
                        add(hs[0].name, attr, getattr(it, attr), group)
        for group, paths in self._chunks.items():
            for p in paths:
                out["chunks"].append({"nodes": [h.name for h in p.handles], "starts": [int(x) for x in p.starts],
                                      "grow": p.growth(self.n), "group": group})
        return out

    def _changed(self, key: str, value, force: bool) -> bool:
        old = self._state.get(key)
        if not force and old is not None and (old == value if not isinstance(value, np.ndarray)
                                               else np.array_equal(old, value)):
            return False
        self._state[key] = value
        return True

    def _set_item(self, it: Item, hs: list, k: int, force: bool) -> None:
        h = hs[0]
        for attr in it.animated():
            if attr == "visible":
                v = bool(np.asarray(it.visible)[k])
                if self._changed(f"{it.name}#visible", v, force):
                    for x in hs:
                        x.visible = v
                continue
            value = np.asarray(getattr(it, attr))[k] if attr != "text" else str(it.text[k])
            if attr == "text":
                if self._changed(f"{it.name}#text", value, force):
                    h.text = value
            elif attr in ("wxyz", "position"):
                value = _tuple(value)
                if self._changed(f"{it.name}#{attr}", value, force):
                    setattr(h, attr, value)
            elif isinstance(it, Segments):
                h.points = _f32(value)
            elif isinstance(it, Arrows):
                o = _f32(np.asarray(it.origins, float).reshape(-1, 3))
                h.points = np.stack([o, o + _f32(value)], 1)
                for j, lab in enumerate(hs[1:]):  # the labels at the tips
                    lab.position = _tuple(1.08 * h.points[j, 1])

    def _set_vector(self, name: str, k: int, force: bool) -> None:
        frame, arrow, label, drawn, (wxyz, lengths) = self._vectors[name]
        length = float(lengths[k])
        frame.wxyz = wxyz[k]
        if self.page_plays:  # drawn once, at its longest: the page scales it to each frame's length (tracks())
            if drawn <= 0 and float(np.max(lengths)) > 0:
                drawn = float(np.max(lengths))
                arrow.points = np.array([[[0, 0, 0], [0, 0, drawn]]], np.float32)
                if label is not None:
                    label.position = (0.0, 0.0, 1.1 * drawn)
                self._vectors[name][3] = drawn
            if drawn > 0:
                return
        if force or drawn < 0 or abs(length - drawn) > VECTOR_LENGTH_TOL * max(drawn, 1e-9):
            arrow.points = np.array([[[0, 0, 0], [0, 0, length]]], np.float32)
            if label is not None:
                label.position = (0.0, 0.0, 1.1 * length)
            self._vectors[name][3] = length
