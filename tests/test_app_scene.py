"""The viser renderer without a browser: a fake viser scene API records every call, so the rule
"send paths once, animate poses / visibility only" and the in-place updates are checked."""
from __future__ import annotations

import numpy as np
import pytest

from theoria.app.controls import slider_range
from theoria.app import scene as scene_mod
from theoria.app.scene import MAX_DRAW_POINTS, SceneView, densify
from theoria.scenarios.drawing import Option, Sphere, View, shape_semi_axes, standard
from theoria.physics.inertia import ellipsoid_moments
from theoria.physics.params import Param
from theoria.scenarios import get
from theoria.scenarios.base import Run, Scenario
from theoria.physics.trajectory import Trajectory


class FakeHandle:
    def __init__(self, log, kind, name, **props):
        object.__setattr__(self, "_log", log)
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "visible", props.pop("visible", True))
        for k, v in props.items():
            object.__setattr__(self, k, v)

    def __setattr__(self, key, value):
        self._log.append(("set", self.kind, self.name, key, np.shape(value)))
        object.__setattr__(self, key, value)

    def remove(self):
        self._log.append(("remove", self.kind, self.name, None, None))


class FakeScene:
    def __init__(self):
        self.log = []

    def __getattr__(self, method):
        if not method.startswith("add_"):
            raise AttributeError(method)

        def add(name, *args, **kw):
            self.log.append(("add", method, name, None, None))
            pts = kw.get("points", args[0] if args and isinstance(args[0], np.ndarray) else None)
            return FakeHandle(self.log, method, name, points=pts)

        return add


def _result(name, **given):
    spec = get(name)
    return spec, spec.simulate_fn(spec.resolve(given))


def _drawing(name, **given):
    spec, run = _result(name, **given)
    return spec, run, spec.drawing(run)


def test_playback_moves_poses_and_visibility_only():
    scene = FakeScene()
    view = SceneView(scene)
    spec, res, d = _drawing("free-tumble")
    view.show(d)
    adds = [e for e in scene.log if e[0] == "add"]
    names = {e[2] for e in adds}
    assert {"/world/body", "/world/body/mesh/0", "/world/body/axes", "/world/omega", "/world/L"} <= names
    assert any(n.startswith("/world/body/polhode/") for n in names)
    assert any(n.startswith("/world/axis_trail/") for n in names)
    scene.log.clear()
    for k in range(0, d.n_frames, 7):
        view.set_frame(k)
    assert not [e for e in scene.log if e[0] != "set"]  # nothing added or removed
    for _, kind, name, key, shape in scene.log:
        assert key in ("wxyz", "points", "position", "visible"), (name, key)
        if key == "points":  # only the two arrows, one arrow each
            assert kind == "add_arrows" and shape == (1, 2, 3), (name, shape)
    # the trails grow: chunk visibility switched on in time order
    vis = [e for e in scene.log if e[3] == "visible" and e[2].startswith("/world/axis_trail/")]
    assert len(vis) > 10


def test_new_parameters_update_in_place_and_overlays_build_lazily():
    scene = FakeScene()
    view = SceneView(scene)
    spec, res, d = _drawing("middle-axis-flip")
    view.show(d)
    assert not any(e[2].startswith("/world/body/energy_ellipsoid") for e in scene.log)  # off by default
    scene.log.clear()
    _, res2, d2 = _drawing("middle-axis-flip", perturbation="0.2")
    view.show(d2)
    assert not [e for e in scene.log if e[0] in ("add", "remove")]  # same nodes, new data
    assert any(e[3] == "points" and e[2].startswith("/world/body/polhode/") for e in scene.log)
    scene.log.clear()
    view.set_overlay("energy_ellipsoid", True)
    added = {e[2] for e in scene.log if e[0] == "add"}
    assert "/world/body/energy_ellipsoid" in added and any(n.startswith("/world/body/polhode_on_ellipsoid/")
                                                           for n in added)


def test_switching_kind_prunes_and_orbit_bodies_are_drawn():
    scene = FakeScene()
    view = SceneView(scene)
    spec, res, d = _drawing("free-tumble")
    view.show(d)
    n = 40
    t = np.linspace(0, 1, n)
    pos = np.stack([np.cos(t), np.sin(t), 0 * t], 1) * 3.8e8  # astronomical units are rescaled
    traj = Trajectory(t, np.tile([1.0, 0, 0, 0], (n, 1)), np.zeros((n, 3)), (1.0, 1.0, 1.0),
                      bodies={"earth": 0 * pos, "moon": pos})
    orbit = Scenario("demo-orbit", "demo", "§0", "three bodies", "demo", (), lambda v, progress=None: None,
                     kind="orbit")
    scene.log.clear()
    view.show(orbit.drawing(Run("demo-orbit", {}, traj, {}, spec=orbit)))
    assert any(e[0] == "remove" and e[2] == "/world/body/mesh/0" for e in scene.log)
    added = {e[2] for e in scene.log if e[0] == "add"}
    assert {"/world/bodies/earth", "/world/bodies/moon"} <= added
    view.set_frame(n - 1)
    moon = view._h["/world/bodies/moon"]
    assert np.linalg.norm(moon.position) == pytest.approx(2.0)  # largest distance drawn at ORBIT_RADIUS


def test_body_has_the_proportions_of_its_moments():
    """The drawn ellipsoid (exaggerate = 1) has moments proportional to (A, B, C)."""
    inertia = np.array([2.0, 3.0, 4.0])
    semi = shape_semi_axes(inertia)
    m = ellipsoid_moments(semi)
    assert np.allclose(m / m.sum(), inertia / inertia.sum(), rtol=1e-12)
    # exaggeration moves the semi-axes away from their mean, ordering kept
    ex = shape_semi_axes(np.array([1.0, 1.01, 1.02]), exaggerate=20)
    plain = shape_semi_axes(np.array([1.0, 1.01, 1.02]))
    assert np.ptp(ex) > 10 * np.ptp(plain) and np.all(np.argsort(ex) == np.argsort(plain))


def test_densify_is_uniform_and_keeps_the_ends():
    th = np.linspace(0, 2 * np.pi, 50)
    path = np.stack([np.cos(th), np.sin(th), 0 * th], 1)
    out, idx = densify(path, np.arange(50.0), 0.01, MAX_DRAW_POINTS)
    gaps = np.linalg.norm(np.diff(out, axis=0), axis=1)
    assert np.allclose(out[0], path[0]) and np.allclose(out[-1], path[-1])
    assert gaps.max() <= 0.0101 and idx[0] == 0 and idx[-1] == 49
    assert len(densify(path, np.arange(50.0), 1e-6, 1000)[0]) == 1000  # capped


def test_controls_choose_sliders_only_for_usable_ranges():
    assert slider_range(Param("spin", 6.0, -50.0, 50.0, "rad/s", step=0.1)) == (-50.0, 50.0, 0.1)
    assert slider_range(Param("duration", 30.0, 0.0, 1e6, "s", exclusive_min=True, step=1.0)) is None
    lo, hi, step = slider_range(Param("dt", 0.5, 0.0, 1.0, "s", exclusive_min=True, step=0.01))
    assert lo == pytest.approx(0.01) and hi == 1.0  # the excluded minimum is not offered
    assert slider_range(Param("v", (1, 2, 3), kind="vec3", minimum=0, maximum=5)) is None
    # a default small against its range gets a number input, not a slider that would clamp it
    assert slider_range(Param("tidal", 1.0, 0.0, 1e6, "1/s^2", exclusive_min=True)) is None
    assert slider_range(Param("a", 0.05, 0.0, 20.0, "deg")) is None  # 0.05 is under one step (0.1)
    assert slider_range(Param("e", 0.1, 0.0, 0.5, ""), presets=[0.7]) is None  # a preset out of reach


def test_every_control_starts_at_the_scenarios_defaults_and_presets_set_them_exactly():
    """The app simulates what its controls hold: for every scenario the controls give exactly the
    defaults of the spec (pole-near-axis once started with tidal = 1000 and 10 turns, gravity-start
    with GM = 10¹⁷: sliders clamped the defaults to their first step), and every preset exactly."""
    import contextlib
    import io

    import viser

    from theoria.app.controls import ParamControls
    from theoria.scenarios import all_scenarios

    with contextlib.redirect_stdout(io.StringIO()):
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        for spec in all_scenarios():
            c = ParamControls(server.gui, spec)
            assert spec.resolve(c.values()) == spec.resolve(None), spec.name
            for name in spec.presets:
                c.set_values(spec.preset(name))
                assert spec.resolve(c.values()) == spec.preset(name), (spec.name, name)
            c.remove()
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()


def test_a_scenarios_own_drawing_moves_redraws_on_its_option_and_is_pruned():
    """A scenario's own `draw` adds items to the standard drawing: they are sent, moved by
    set_frame, drawn anew when one of its options changes, and removed when another scenario is
    shown."""
    def draw(run, spec, view):
        d = standard(run, spec, view)
        k = np.arange(d.n_frames, dtype=float)
        radius = 0.2 if view.option("big", spec) else 0.1
        d.add(Sphere(name="marker", radius=radius, color=(255, 0, 0),
                     position=np.stack([np.cos(k / 50), np.sin(k / 50), 0 * k], 1)))
        return d

    base = get("middle-axis-flip")
    import dataclasses

    spec = dataclasses.replace(base, draw=draw, options={"big": Option("a big marker", False)})
    run = spec.simulate(duration=5)
    fake = FakeScene()
    view = SceneView(fake)
    view.show(spec.drawing(run))
    assert ("add", "add_icosphere", "/world/marker", None, None) in fake.log
    fake.log.clear()
    view.set_frame(5)
    assert ("set", "add_icosphere", "/world/marker", "position", (3,)) in fake.log
    fake.log.clear()
    view.show(spec.drawing(run, View(options={"big": True})))  # a new radius: the marker is made anew
    assert ("remove", "add_icosphere", "/world/marker", None, None) in fake.log
    assert ("add", "add_icosphere", "/world/marker", None, None) in fake.log
    spec2, res2, d2 = _drawing("free-tumble")
    view.show(d2)
    assert "/world/marker" not in view._h


def _decoded(track: dict) -> np.ndarray:
    """A `prop` track as the page decodes it (app/browser.py): one row per kept frame."""
    import base64

    raw = base64.b64decode(track["data"])
    if "strings" in track:
        return np.asarray(track["strings"], object)[np.frombuffer(raw, "<u4")]
    return np.frombuffer(raw, "<f2" if track["dtype"] == "f2" else "<f4").astype(float).reshape(-1, track["per"])


@pytest.mark.parametrize("name", ["libration-circular", "lunar-perturbation", "syzygy", "initial-axis"])
def test_a_page_that_plays_is_given_everything_that_moves(name):
    """With the page playing by itself, the server moves nothing during playback: every label's
    text and every per-frame segment is in the tracks, and decoded as the page decodes them they are
    the drawing's own values at each kept frame (within float16's 1e-3 of a scene unit). A turning
    arrow that starts at zero length (at rest) is drawn at its longest and scaled by the page."""
    from theoria.scenarios.drawing import Label, Segments

    scene = FakeScene()
    view = SceneView(scene)
    view.page_plays = True
    spec, res, d = _drawing(name, **get(name).preview)
    view.show(d)
    assert not view.server_moves()
    tr = view.tracks()
    props = {(p["node"], p["prop"]): p for p in tr["props"]}
    checked = 0
    for it in d.items:
        anim = it.animated() if view._on(it.group) else []
        if isinstance(it, Label) and "text" in anim:
            p = props[(f"/world/{it.name}", "text")]
            assert list(_decoded(p)) == [str(t) for t in it.text][::p["stride"]]
            checked += 1
        if isinstance(it, Segments) and "points" in anim:
            p = props[(f"/world/{it.name}", "points")]
            want = np.asarray(it.points, float)[::p["stride"]].reshape(len(_decoded(p)), -1)
            assert np.abs(_decoded(p) - want).max() <= 2e-3 * max(1.0, np.abs(want).max())
            assert p["stride"] == 1 or len(p["data"]) * 3 / 4 <= 1.05 * scene_mod.TRACK_POINTS_BYTES
            checked += 1
    assert checked or name == "initial-axis"
    scene.log.clear()
    for k in range(0, d.n_frames, max(1, d.n_frames // 50)):
        view.set_frame(k, moving=True)
    assert not scene.log  # playing: not one message from the server
    scales = [t for t in tr["tracks"] if t["attr"] == "scale"]
    assert len(scales) == sum(1 for v in view._vectors.values() if v[3] > 0) and (name != "initial-axis" or scales)


def test_browsers_shown_one_drawing_share_its_tracks_and_each_gets_its_own_owner_and_overlays():
    """The tracks sent as JSON are `tracks()`, exactly. Two views shown the same Drawing (a class
    on a cached scene) share the body, made once; each keeps its own node owner and overlay
    checkboxes. A view of another drawing, or of the same one with a group built that the first
    did not build, gets its own tracks."""
    import json

    _, _, d = _drawing("initial-axis", **get("initial-axis").preview)
    views = []
    for owner in ("a", "b"):
        scene = FakeScene()
        scene._owner_id = owner
        v = SceneView(scene)
        v.page_plays = True
        v.show(d)
        views.append(v)
    views[1].overlays[next(iter(views[1].overlays))] = False
    made = []
    body = scene_mod.SceneView._tracks_body
    scene_mod.SceneView._tracks_body = lambda self: made.append(1) or body(self)
    try:
        texts = [v.tracks_json() for v in views]
    finally:
        scene_mod.SceneView._tracks_body = body
    assert len(made) == 1  # the second browser reused the first one's
    for v, text in zip(views, texts):
        assert json.loads(text) == json.loads(json.dumps(v.tracks()))
    assert json.loads(texts[0])["owner"] == "a" and json.loads(texts[1])["owner"] == "b"
    assert json.loads(texts[0])["groups"] != json.loads(texts[1])["groups"]
    _, _, other = _drawing("initial-axis", **{**get("initial-axis").preview, "duration": 1.5})
    views[1].show(other)
    assert json.loads(views[1].tracks_json()) == json.loads(json.dumps(views[1].tracks()))
    assert json.loads(views[1].tracks_json())["times"] != json.loads(texts[0])["times"]


def test_the_shared_tracks_stay_within_their_bytes_and_forget_a_dropped_drawing():
    import gc

    class D:  # stands for a Drawing
        pass

    cache = scene_mod._TracksCache(max_bytes=25)
    a, b, c = D(), D(), D()
    for d in (a, b, c):
        cache.put(d, "sig", "x" * 10)
    assert cache.get(a, "sig") is None and cache.get(b, "sig") == cache.get(c, "sig") == "x" * 10
    assert cache.get(b, "other") is None
    ident = id(c)
    del c, d
    gc.collect()
    # held weakly: the dropped drawing is gone, and a new object at its address does not match
    assert sum(ref() is None for ref, _ in cache._items.values()) == 1
    e = D()
    if id(e) == ident:
        assert cache.get(e, "sig") is None


def test_a_long_runs_props_are_kept_for_every_sth_frame_within_the_budget():
    """A trail of 28 segments over 3,000 frames (1 MB in float16) is given for every s-th frame, the
    smallest s that fits TRACK_POINTS_BYTES; text beyond TRACK_TEXT_CHARS likewise."""
    from theoria.app.scene import TRACK_POINTS_BYTES, TRACK_TEXT_CHARS, _points_track, _text_track

    pts = np.random.default_rng(1).uniform(-2, 2, (3000, 28, 2, 3))
    p = _points_track(pts)
    per_frame = 28 * 6 * 2
    s = p["stride"]
    assert -(-3000 // s) * per_frame <= TRACK_POINTS_BYTES < -(-3000 // (s - 1)) * per_frame
    assert np.abs(_decoded(p) - pts[::s].reshape(-1, 168)).max() < 2e-3
    texts = [f"t = {k:.4f} yr, a read-out of some length" for k in range(3000)]
    t = _text_track(texts)
    assert sum(map(len, t["strings"])) <= TRACK_TEXT_CHARS and t["stride"] > 1
    assert sum(map(len, set(texts[::t["stride"] - 1]))) > TRACK_TEXT_CHARS  # the smallest stride that fits
    assert list(_decoded(t)) == texts[::t["stride"]]
    assert _text_track(["a", "b", "a"])["strings"] == ["a", "b"]  # each distinct string once
    big = _points_track(np.full((10, 1, 2, 3), 1e6))  # beyond float16: float32
    assert big["dtype"] == "f4" and np.allclose(_decoded(big), 1e6)


def test_viser_pose_updates_are_sent_exactly_when_numpy_would_send_them():
    """theoria replaces viser's "did the pose change?" test (np.allclose on four numbers) by the same
    test in plain Python: for random, equal, nearly equal and NaN poses it sends a message exactly
    when np.allclose(new, old) is false, and the node then holds the new pose."""
    from viser import _scene_handles as sh

    import theoria.app.scene  # noqa: F401  (installs it)

    if getattr(sh._set_pose_vector, "__wrapped__", None) is None:
        pytest.skip("this viser has no _set_pose_vector of the expected form")
    rng = np.random.default_rng(3)
    cases = []
    for _ in range(400):
        old = rng.normal(size=4)
        kind = rng.integers(4)
        new = (old.copy() if kind == 0 else old * (1 + rng.choice([1e-7, 1e-6, 3e-6, 1e-4, 1e-3]) * rng.normal(size=4))
               if kind == 1 else old + rng.choice([1e-9, 1e-8, 3e-8, 1e-6]) * rng.normal(size=4) if kind == 2
               else rng.normal(size=4))
        cases.append((old, new))
    cases += [(np.zeros(4), np.array([np.nan, 0, 0, 0])), (np.array([np.nan, 0, 0, 0]), np.array([np.nan, 0, 0, 0])),
              (np.zeros(4), np.array([1e-8, 0, 0, 0])), (np.zeros(4), np.array([1.1e-8, 0, 0, 0]))]
    sent_when = []
    for old, new in cases:
        current, queued = old.astype(np.float64).copy(), []
        sh._set_pose_vector(current, tuple(new), 4, queued.append, lambda v: v)
        sent_when.append(bool(queued))
        assert not np.allclose(new, old) == bool(queued), (old, new)
        if queued:
            assert len(queued) == 1 and np.array_equal(current, new, equal_nan=True)
            assert np.array_equal(np.asarray(queued[0], float), new, equal_nan=True)
    assert 0 < sum(sent_when) < len(cases)  # both outcomes were tried


def test_viser_casts_every_property_as_its_own_casting_does():
    """theoria replaces viser's casting of a property value (which builds npt.NDArray[...] anew for
    each comparison) by the same comparisons against aliases built once: for every property of
    every node and control viser declares, and values of every kind a property is given (lists,
    float and int arrays, colours, tuples, text, numbers), the result is what viser's own gives,
    in type, dtype and value."""
    import typing

    from viser import _assignable_props_api as apa
    from viser import _messages as msgs

    import theoria.app.scene  # noqa: F401  (installs it)

    cast = apa.AssignablePropsBase._cast_value_recursive
    own = getattr(cast, "__wrapped__", None)
    if own is None:
        pytest.skip("this viser casts in its own way; theoria left it alone")
    rng = np.random.default_rng(4)
    values = [[1.0, 2.0, 3.0], (0.5, 0.25, 1.0), rng.normal(size=(5, 3)), rng.integers(0, 255, (4, 3)),
              np.array([10, 20, 30], np.uint8), (255, 0, 0), "text", 3, 2.5, None, True,
              (rng.normal(size=3), rng.normal(size=3)), ((1.0, 2.0), (3.0, 4.0))]
    props = [c for c in vars(msgs).values() if isinstance(c, type) and c.__name__.endswith("Props")]
    assert len(props) > 20

    class Handle:  # what each casting recurses through
        def __init__(self, fn):
            self._cast_value_recursive = lambda hint, value, name: fn(self, hint, value, name)

    theirs, ours = Handle(own), Handle(cast)
    compared = 0
    for cls in props:
        for name, hint in typing.get_type_hints(cls).items():
            for value in values:
                try:
                    want = theirs._cast_value_recursive(hint, value, name)
                except Exception as e:  # noqa: BLE001 — what viser raises, theoria must raise too
                    with pytest.raises(type(e)):
                        ours._cast_value_recursive(hint, value, name)
                    continue
                got = ours._cast_value_recursive(hint, value, name)
                assert type(got) is type(want), (cls.__name__, name, value)
                if isinstance(want, np.ndarray):
                    assert got.dtype == want.dtype and np.array_equal(got, want, equal_nan=got.dtype.kind == "f"), \
                        (cls.__name__, name)
                else:
                    assert repr(got) == repr(want), (cls.__name__, name, value)
                compared += 1
    assert compared > 1000


def _octahedron(shared: bool):
    """Eight triangles about the origin: six corners shared by four faces each, or three corners
    of its own for every face (24 vertices)."""
    corners = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    tris = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    if shared:
        return corners, tris
    return corners[tris.ravel()], np.arange(24).reshape(8, 3)


def test_a_mesh_is_flat_faced_when_each_vertex_lies_in_one_plane_of_faces():
    assert scene_mod.flat_faced(*_octahedron(shared=False))
    assert not scene_mod.flat_faced(*_octahedron(shared=True))  # the renderer smooths across its edges
    v, f = _octahedron(shared=False)
    two = np.concatenate([f[:1], f[1:2]])  # two faces in one plane sharing an edge are still flat
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    assert scene_mod.flat_faced(square, np.array([[0, 1, 2], [0, 2, 3]]))
    assert scene_mod.flat_faced(v, two)
    assert not scene_mod.flat_faced(square, np.zeros((0, 3), int))


def test_the_flips_brick_is_drawn_diffuse_and_a_smooth_body_as_it_was():
    """A flat-faced body looks the same in the diffuse material, which costs a software renderer
    less per pixel; a smooth ellipsoid keeps the physically based one (its sheen shows its shape)."""
    asked = {}

    class Recorder(FakeScene):
        def __getattr__(self, method):
            add = super().__getattr__(method)

            def record(name, *args, **kw):
                if method == "add_mesh_simple":
                    asked[name] = kw.get("material", "standard")
                return add(name, *args, **kw)

            return record

    for name in ("middle-axis-flip", "free-tumble"):
        SceneView(Recorder()).show(_drawing(name)[2])
        body = {k: v for k, v in asked.items() if k.startswith("/world/body/mesh/")}
        assert body and set(body.values()) == {"toon5" if name == "middle-axis-flip" else "standard"}, (name, body)
        asked.clear()
