"""One drawing path: for every scenario, the live app (viser), the recording (rerun) and the
standalone replay (HTML) hold the same drawn objects, at the same places at the same times.

Each output is read back from outside: the HTML file's embedded viser recording is decoded (the
messages the browser replays), the .rrd file is read with rerun's own reader, and the live scene
is what the viser renderer sends to a (fake) client. All three are compared with the scenario's
`Drawing` and so with each other.
"""
from __future__ import annotations

import base64
import re
import types
import warnings

import msgspec
import numpy as np
import pytest
import zstandard
from rerun.chunk import RrdReader

import theoria as th
from theoria.app.export_html import render_html
from theoria.app.record import record_run
from theoria.app.scene import SceneView
from theoria.physics.quaternion import to_xyzw
from theoria.scenarios.drawing import GEOMETRY, Frame, Label, Path, Sphere
from tests.test_app_scene import FakeScene

SLOW = {"earth-long-view"}  # its run alone takes tens of seconds
CASES = [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in th.scenarios()]
CREATES = ("FrameMessage", "MeshMessage", "PointCloudMessage", "LabelMessage", "ArrowMessage", "IcosphereMessage",
           "LineSegmentsMessage", "DirectionalLightMessage")


def html_messages(page: str) -> list:
    """The viser messages a standalone HTML replay plays: (time, message dict)."""
    data = base64.b64decode(re.search(r'__VISER_EMBED_DATA__="([^"]+)"', page).group(1))
    inner = zstandard.ZstdDecompressor().decompress(data[8:], max_output_size=int.from_bytes(data[:8], "little"))
    n = int.from_bytes(inner[:8], "little")
    return msgspec.msgpack.decode(inner[8:8 + n])["messages"]


def rrd_entities(path) -> dict:
    """entity path → list of (is_static, record batch) from rerun's reader."""
    out: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a file without its footer: rerun warns → error
        for c in RrdReader(str(path)).stream().to_chunks():
            out.setdefault(str(c.entity_path), []).append((c.is_static, c.to_record_batch()))
    return out


def expected_items(d) -> list:
    return [it for it in d.items if isinstance(it, GEOMETRY) and d.shown(it)]


def owner(node: str, names: set[str]) -> str | None:
    """The item a viser node belongs to: itself, or its nearest ancestor that is an item (the
    chunks of a path, the arrow and label of a turning arrow)."""
    parts = node[len("/world/"):].split("/")
    for k in range(len(parts), 0, -1):
        cand = "/".join(parts[:k])
        if cand in names:
            return cand
    return None


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    cache = {}

    def get(name):
        if name not in cache:
            sc = th.scenario(name)
            run = sc.simulate(**sc.preview)
            d = sc.drawing(run)
            rrd = tmp_path_factory.mktemp("rrd") / f"{name}.rrd"
            record_run(run, rrd)
            page = render_html(d, run, frames=40)
            live = FakeScene()
            view = SceneView(live)
            view.show(d)
            cache[name] = (d, rrd_entities(rrd), html_messages(page), live, view)
        return cache[name]

    return get


@pytest.mark.parametrize("name", CASES)
def test_app_recording_and_replay_draw_the_same_objects(outputs, name):
    d, rrd, msgs, live, view = outputs(name)
    want = {it.name for it in expected_items(d)}
    assert want, name
    names = {it.name for it in d.items}
    # the replay and the live app: every item has its node, and every node under /world is an item's
    html_nodes = {m["name"] for _, m in msgs if m.get("type") in CREATES and m["name"].startswith("/world/")}
    live_nodes = {e[2] for e in live.log if e[0] == "add" and e[2].startswith("/world/")}
    for nodes, who in ((html_nodes, "HTML replay"), (live_nodes, "live app")):
        owners = {owner(n, names) for n in nodes}
        missing = want - owners
        assert not missing, (who, name, sorted(missing))
        # nothing drawn that the drawing does not list (groups of nodes made for children are frames)
        strays = [n for n in nodes if owner(n, names) is None and not any(x.startswith(n + "/") for x in nodes)]
        assert not strays, (who, name, strays)
    # the recording: an entity for every item (lights aside: rerun lights the scene itself)
    entities = set(rrd)
    missing = {n for n in want if f"/world/{n}" not in entities}
    assert not missing, ("recording", name, sorted(missing))
    assert "/text" in entities


def _html_value_at(msgs, node: str, kind: str, key: str, t: float):
    """The last value of `key` set on `node` by a message of type `kind` at or before time t."""
    val = None
    for when, m in msgs:
        if when > t + 1e-9:
            break
        if m.get("name") == node:
            if m.get("type") == kind:
                val = m[key]
            elif m.get("type") in CREATES:  # a node starts at the identity pose unless told
                val = m.get("props", {}).get(key, (1.0, 0.0, 0.0, 0.0) if key == "wxyz" else (0.0, 0.0, 0.0))
    return None if val is None else np.asarray(val, float)


def _rrd_value_at(batches, column: str, frame: int):
    for static, rb in batches:
        if not static and column in rb.schema.names and "frame" in rb.schema.names:
            frames = np.asarray(rb.column("frame").to_pylist())
            j = int(np.searchsorted(frames, frame, side="right")) - 1
            if j >= 0:
                return np.asarray(rb.column(column)[j].as_py(), float).reshape(-1)
    for static, rb in batches:
        if static and column in rb.schema.names:
            return np.asarray(rb.column(column)[0].as_py(), float).reshape(-1)
    return None


@pytest.mark.parametrize("name", CASES)
def test_what_moves_is_at_the_same_place_at_the_same_time(outputs, name):
    """Poses of moving frames and positions of moving markers and labels, at sampled frames, in the
    drawing, in the HTML replay (its message stream at that frame's time) and in the recording."""
    d, rrd, msgs, live, view = outputs(name)
    F = d.n_frames
    html_frames = np.unique(np.linspace(0, F - 1, min(40, F)).round().astype(int))
    checked = 0
    for it in expected_items(d):
        anim = it.animated()
        for attr, kind, col in (("wxyz", "SetOrientationMessage", "Transform3D:quaternion"),
                                ("position", "SetPositionMessage", "Transform3D:translation")):
            if attr not in anim or not isinstance(it, (Frame, Sphere, Label)):
                continue
            values = np.asarray(getattr(it, attr), float)
            for j in (0, len(html_frames) // 2, len(html_frames) - 1):
                k = int(html_frames[j])
                want = values[k]
                got_html = _html_value_at(msgs, f"/world/{it.name}", kind, attr, j / 30.0)
                got_rrd = _rrd_value_at(rrd.get(f"/world/{it.name}", []), col, k)
                if attr == "wxyz":
                    got_rrd = None if got_rrd is None else np.r_[got_rrd[3], got_rrd[:3]]  # rerun is xyzw
                    sign = lambda q: q * np.sign(q[np.argmax(np.abs(q))])  # noqa: E731  (q and −q: one attitude)
                    want, got_html = sign(want), None if got_html is None else sign(got_html)
                    got_rrd = None if got_rrd is None else sign(got_rrd)
                assert got_html is not None and np.allclose(got_html, want, atol=2e-6), (name, it.name, attr, k)
                assert got_rrd is not None and np.allclose(got_rrd, want, atol=2e-6), (name, it.name, attr, k)
                checked += 1
    # static geometry: the paths hold the same points in the recording as in the drawing
    for it in expected_items(d):
        if isinstance(it, Path):
            (static, rb), = [b for b in rrd[f"/world/{it.name}"] if b[0]]
            strip = np.asarray(rb.column("LineStrips3D:strips")[0].as_py()[0], float)
            assert np.allclose(strip, np.asarray(it.points, np.float32), atol=1e-5), (name, it.name)
    if d.rotation:
        assert checked >= 3, name  # the body's attitude at least


def test_camera_and_text_travel_with_the_replays(outputs):
    d, rrd, msgs, live, view = outputs("middle-axis-flip")
    pos = [m for _, m in msgs if m.get("type") == "SetCameraPositionMessage"]
    look = [m for _, m in msgs if m.get("type") == "SetCameraLookAtMessage"]
    assert np.allclose(pos[-1]["position"], d.camera.position) and np.allclose(look[-1]["look_at"], d.camera.look_at)
    (static, rb), = rrd["/text"]
    text = rb.column("TextDocument:text")[0].as_py()[0]
    assert d.title in text and d.section in text and d.summary[:40] in text
    # the recording's quaternions are the trajectory's at the frames, in rerun's (x, y, z, w) order
    (static, rb), = [b for b in rrd["/world/body"] if not b[0]]
    q = np.asarray(rb.column("Transform3D:quaternion").to_pylist(), float).reshape(-1, 4)
    assert np.allclose(q, to_xyzw(np.asarray(d.item("body").wxyz, float)), atol=1e-6)


def test_a_fixed_label_is_turned_off_the_path_of_a_moving_one():
    """A label that stays put was placed against the other fixed labels only: on the Moon's scene
    "the Moon in space" sat on the C axis's label, which turns with the body. The places a moving
    label passes through (its frame turning about the view's axis) count as taken. Checked in
    pixels of the camera's view, computed here from the geometry (a 75° view from +x)."""
    from theoria.physics import quaternion as quat
    from theoria.scenarios.drawing import Camera, Drawing, Frame, Label, declutter_labels

    F = 40
    angles = np.linspace(0.0, 0.6, F)  # the frame turns about x, the line of sight: its tip sweeps sideways
    wxyz = np.stack([np.cos(angles / 2), np.sin(angles / 2), 0 * angles, 0 * angles], 1)
    d = Drawing(frames=np.arange(F), times=np.arange(F, dtype=float), time_unit="s",
                camera=Camera(position=(10.0, 0.0, 0.0), look_at=(0.0, 0.0, 0.0), fov_deg=75.0))
    d.add(Frame(name="body", wxyz=wxyz),
          Label(name="body/tip", text="C = 1", position=(0.0, 0.0, 1.0)),
          Label(name="caption", text="the body in space", position=(0.0, 0.0, 1.2), anchor="top-left"))
    # where the tip is drawn, by hand: a point (0, y, z) seen from x = 10 with a 75° vertical view
    # is at pixel (640 − 640 y / (10 tan 37.5° · 1.6), 400 − 400 z / (10 tan 37.5°))
    tip = quat.rotate(wxyz, np.array([0.0, 0.0, 1.0]))
    t = np.tan(np.radians(37.5)) * 10.0
    px = np.stack([640 - 640 * tip[:, 1] / (t * 1.6), 400 - 400 * tip[:, 2] / t], 1)
    cap = (640.0, 400 - 400 * 1.2 / t)
    assert np.any(np.hypot(*(px - cap).T) < 12), "the tip passes over the caption's point"
    assert declutter_labels(d) == 1
    assert d.item("caption").anchor != "top-left" and d.item("body/tip").anchor == "top-left"


def _apart_at_one_point(a: str, b: str) -> bool:
    """Two text boxes hung on the same point by anchors a and b cannot meet: one is above and the
    other below it, or one left and the other right (whatever the boxes' sizes)."""
    (va, ha), (vb, hb) = a.split("-"), b.split("-")
    return ({va, vb} == {"top", "bottom"}) or ({ha, hb} == {"left", "right"})


def _letter_and_label_on_one_point():
    from theoria.scenarios.drawing import Arrows, Camera, Drawing, Label

    F = 20
    d = Drawing(frames=np.arange(F), times=np.arange(F, dtype=float), time_unit="s",
                camera=Camera(position=(10.0, 0.0, 0.0), look_at=(0.0, 0.0, 0.0), fov_deg=75.0))
    # ω along C, its letter written at 1.1 of its length: where the C axis's label is
    d.add(Arrows(name="omega", origins=np.zeros((1, 3)), vectors=np.array([[0.0, 0.0, 1.0]]), colors=(200, 0, 200),
                 labels=("ω",)),
          Label(name="c_axis", text="C = 1", position=(0.0, 0.0, 1.1)))
    return d


def test_an_arrows_letter_and_a_label_on_one_point_are_put_on_different_sides():
    """The letters at arrow tips (ω, L) were left out of the label placement: with ω along C, its
    letter and "C = 1" sat on one point, one over the other (the libration scenes, seen down C).
    Now the letters are placed with the labels."""
    from theoria.scenarios.drawing import declutter_labels

    d = _letter_and_label_on_one_point()
    assert d.item("omega").label_anchor(0) == d.item("c_axis").anchor == "top-left"  # as made: on each other
    assert declutter_labels(d) == 1
    assert _apart_at_one_point(d.item("omega").label_anchor(0), d.item("c_axis").anchor)


def test_what_the_scene_shows_when_it_opens_is_placed_before_what_is_switched_off():
    """A letter of an overlay that is off when the scene opens (ω's, with the arrows off) took the
    side a shown label then had to leave: what is shown keeps its side, and the letter, if switched
    on, fits around it."""
    from theoria.scenarios.drawing import declutter_labels

    d = _letter_and_label_on_one_point()
    d.item("omega").group = "vectors"
    d.overlays["vectors"] = False
    assert declutter_labels(d) == 1
    assert d.item("c_axis").anchor == "top-left"  # shown: kept where it was made
    assert _apart_at_one_point(d.item("omega").label_anchor(0), d.item("c_axis").anchor)


def test_the_scene_writes_an_arrows_letter_on_the_side_chosen_for_it():
    """What the placement chose reaches the page: the letter's label is made with its anchor."""
    from theoria.app.scene import SceneView
    from theoria.scenarios.drawing import declutter_labels

    made = {}

    class Scene:
        def __getattr__(self, method):
            def add(name, *args, **kw):
                if method == "add_label":
                    made[name] = (args[0], kw.get("anchor", "top-left"))
                return types.SimpleNamespace(name=name, visible=True, remove=lambda: None)
            return add

    d = _letter_and_label_on_one_point()
    d.item("omega").label_anchors = ("bottom-right",)
    declutter_labels(d)
    SceneView(Scene()).show(d)
    assert made["/world/omega/label_0"] == ("ω", "bottom-right")
    assert made["/world/c_axis"] == ("C = 1", "top-left")


def test_two_labels_riding_together_are_put_on_different_sides():
    """Two labels on a turning body a few pixels apart (the tip of the C axis and a mark beside
    it) covered each other all run long: the second is turned to a side where its box, over the
    run, meets the first one's none of the time."""
    from theoria.scenarios.drawing import Camera, Drawing, Frame, Label, _box, _overlap, _project, _world, declutter_labels

    F = 30
    angles = np.linspace(0.0, 0.5, F)
    wxyz = np.stack([np.cos(angles / 2), np.sin(angles / 2), 0 * angles, 0 * angles], 1)
    d = Drawing(frames=np.arange(F), times=np.arange(F, dtype=float), time_unit="s",
                camera=Camera(position=(10.0, 0.0, 0.0), look_at=(0.0, 0.0, 0.0), fov_deg=75.0))
    d.add(Frame(name="body", wxyz=wxyz),
          Label(name="body/c", text="C = 1", position=(0.0, 0.0, 1.0)),
          Label(name="body/mark", text="the pole", position=(0.0, 0.02, 1.0)))
    ks = np.arange(F)

    def meetings() -> int:
        boxes = {}
        for name in ("body/c", "body/mark"):
            it = d.item(name)
            xy, _ = _project(_world(d, it, ks)[0], d.camera)
            boxes[name] = [_box(p, it.text, it.anchor) for p in xy]
        return sum(_overlap(a, b) for a, b in zip(boxes["body/c"], boxes["body/mark"]))

    assert meetings() == F  # as made: on top of each other in every frame
    declutter_labels(d)
    assert meetings() == 0 and d.item("body/c").anchor == "top-left"


def test_labels_that_pass_the_same_places_at_other_times_are_left_where_they_are():
    """Two moving labels along one line, each where the other was half a run before: they never
    meet. Sides were chosen against every place an earlier label passes through, at any time, so
    the second was turned (and labels riding one body together were turned onto each other)."""
    from theoria.scenarios.drawing import Camera, Drawing, Label, declutter_labels

    F = 12
    x = np.linspace(-3.0, 3.0, F)
    d = Drawing(frames=np.arange(F), times=np.arange(F, dtype=float), time_unit="s",
                camera=Camera(position=(0.0, -10.0, 0.0), look_at=(0.0, 0.0, 0.0), fov_deg=75.0))
    a = np.stack([x, 0 * x, 0 * x], 1)
    d.add(Label(name="a", text="first", position=a), Label(name="b", text="second", position=np.roll(a, F // 2, 0)))
    assert declutter_labels(d) == 0 and d.item("b").anchor == "top-left"


@pytest.mark.parametrize("name", ["libration-circular", "moon"])
def test_labels_on_a_turning_body_meet_in_no_frame_at_either_size(name):
    """The axis labels and the letters of ω and L ride one turning body: placed for the app's
    size and for presenter mode's larger type (each for its own), no two of them meet in any of
    the frames looked at (presenter mode's L sat on "C = 1" all run long)."""
    import theoria as th
    from theoria.scenarios.drawing import SWEPT_FRAMES, View, _box, _overlap, _project, _texts

    spec = th.scenario(name)
    run = spec.simulate()
    for scale in (1.0, 1.6 * 800 / 1080):
        d = spec.drawing(run, View(text_scale=scale))
        ks = np.unique(np.linspace(0, d.n_frames - 1, SWEPT_FRAMES).round().astype(int))
        texts = [t for t in _texts(d, ks) if t.shown_first and t.moves]
        assert len(texts) >= 3, [t.text for t in texts]
        for k in range(len(ks)):
            boxes = [(t.text, _box(_project(t.pos[k:k + 1], d.camera)[0][0], t.text, t.anchor, scale))
                     for t in texts if t.shown[k]]
            for i, (p, b1) in enumerate(boxes):
                for q, b2 in boxes[i + 1:]:
                    assert not _overlap(b1, b2), (scale, k, p, q)


@pytest.mark.parametrize("name, together", [("earth", True), ("precession-circular", True), ("free-tumble", False),
                                            ("middle-axis-flip", False)])
def test_omega_and_l_on_one_line_get_one_letter(name, together):
    """The Earth's ω and L are 10⁻⁶ rad apart: their arrows are one line, and "ω", "L" and "C = 1"
    were printed over each other at the pole. Where the two directions stay within a degree all
    run long (the angle measured here from the run's own vectors, by arccos), one letter says both;
    where they part (a tumbling body), each keeps its own."""
    import theoria as th

    spec = th.scenario(name)
    run = spec.simulate()
    tr = run.trajectory
    w, L = tr.omega_inertial, tr.L_inertial
    apart = np.degrees(np.arccos(np.clip(np.sum(w * L, 1) / np.linalg.norm(w, axis=1) / np.linalg.norm(L, axis=1),
                                         -1, 1))).max()
    assert (apart < 1.0) == together, apart
    d = spec.drawing(run)
    letters = {it.name: tuple(it.labels) for it in d.items if it.name in ("omega", "L")}
    assert letters == ({"omega": ("ω, L",), "L": ()} if together else {"omega": ("ω",), "L": ("L",)})


def test_a_label_near_the_edge_of_the_canvas_is_written_inward():
    """A label near the left edge of the canvas beside the panel, written to the left of its
    point, was cut by the edge (libration-circular's axes note in presenter mode): it is turned to
    write inward; so is one near the right edge written to the right."""
    from theoria.scenarios.drawing import SHOWN_WIDTH_PX, Camera, Drawing, Label, _project, declutter_labels

    cam = Camera(position=(0.0, -10.0, 0.0), look_at=(0.0, 0.0, 0.0), fov_deg=75.0)
    d = Drawing(frames=np.arange(2), times=np.arange(2, dtype=float), time_unit="s", camera=cam)
    d.add(Label(name="left", text="a note near the left edge", position=(-8.0, 0.0, 1.0), anchor="top-right"),
          Label(name="right", text="a note near the right edge", position=(8.0, 0.0, -1.0), anchor="top-left"))
    xs = _project(np.array([[-8.0, 0.0, 1.0], [8.0, 0.0, -1.0]]), cam)[0][:, 0]
    edge = (1280 - SHOWN_WIDTH_PX) / 2
    assert edge < xs[0] < edge + 40 and 1280 - edge - 40 < xs[1] < 1280 - edge  # inside, near the edges
    assert declutter_labels(d) == 2
    assert d.item("left").anchor.endswith("-left") and d.item("right").anchor.endswith("-right")


def test_a_star_name_that_covers_a_texts_place_on_every_side_gives_way():
    """The sky's star names crowded the pole of earth-long-view: the star "Polaris" written on the
    pole's "AD 2000" (and beside "Polaris: AD 2100 (0.5°)"), "Deneb" under "C = 1". A name that
    yields and covers another text on whichever side it is turned is left out; one that fits stays,
    and a text that does not yield is never left out."""
    from theoria.scenarios.drawing import Camera, Drawing, Label, _box, _overlap, _project, _texts, declutter_labels

    cam = Camera(position=(0.0, -10.0, 0.0), look_at=(0.0, 0.0, 0.0), fov_deg=75.0)
    d = Drawing(frames=np.arange(2), times=np.arange(2, dtype=float), time_unit="s", camera=cam)
    # four texts around one point take its sides; a star name there has nowhere left to go
    d.add(*[Label(name=f"pole/{k}", text=f"AD {2000 + 100 * k}", position=(0.0, 0.0, 1.0)) for k in range(4)],
          Label(name="stars/Polaris", text="Polaris", position=(0.0, 0.0, 1.0), yields=True),
          Label(name="stars/Vega", text="Vega", position=(6.0, 0.0, -3.0), yields=True),
          Label(name="note", text="a scene's own note", position=(0.05, 0.0, 1.0)),
          Label(name="stars/Thuban", text="Thuban", position=(-6.0, 0.0, -3.0), yields=True),
          Label(name="thuban_then", text="Thuban: AD 22305 (1.4°)", position=(-3.0, 0.0, 3.0)))
    declutter_labels(d)
    names = [it.name for it in d.items]
    assert "stars/Polaris" not in names and "stars/Vega" in names and "note" in names
    assert "stars/Thuban" not in names and "thuban_then" in names  # said already, where the pole passes it
    assert all(f"pole/{k}" in names for k in range(4))
    import theoria as th

    for name in ("earth", "earth-long-view"):  # the sky's names cover nothing when the scene opens
        spec = th.scenario(name)
        run = spec.simulate(**{k: v for k, v in spec.preview.items() if not isinstance(v, str)})
        d = spec.drawing(run)
        texts = [t for t in _texts(d, np.array([0])) if t.shown_first and t.shown[0]]
        boxes = [(t, _box(_project(t.pos, d.camera)[0][0], t.text, t.anchor)) for t in texts]
        for i, (a, b1) in enumerate(boxes):
            for c, b2 in boxes[i + 1:]:
                if (a.label is not None and a.label.yields) or (c.label is not None and c.label.yields):
                    assert not _overlap(b1, b2), (name, a.text, c.text)


def test_the_earth_moon_lagrange_points_draw_the_earth_and_the_moon():
    """Euler's restricted problem with the Moon/Earth mass ratio (the L1 and L2 presets): the Earth
    was a yellow ball, the Sun's colour, and the key read "yellow: primary"; another ratio is
    not the Earth and the Moon, and keeps the general names."""
    import theoria as th
    from theoria.physics.constants import MOON_EARTH_MASS_RATIO
    from theoria.scenarios.drawing import BODY_COLOURS, Sphere

    spec = th.scenario("collinear")
    for ratio, names in ((MOON_EARTH_MASS_RATIO, ("earth", "moon")), (0.001, ("primary", "secondary"))):
        run = spec.simulate(motion="restricted", lagrange_point="L2", mass_ratio=ratio)
        d = spec.drawing(run)
        balls = {it.name.split("/")[1]: it.color for it in d.items
                 if isinstance(it, Sphere) and it.name.startswith("bodies/") and it.name.count("/") == 1}
        assert set(balls) == {*names, "satellite"}, balls
        key = next(it.text for it in d.items if it.name == "body_key")
        if names[0] == "earth":
            assert balls["earth"] == BODY_COLOURS["earth"] and balls["moon"] == BODY_COLOURS["moon"]
            assert key.startswith("blue: Earth · white: Moon · "), key
        else:
            assert "primary" in key and "Earth" not in key


@pytest.mark.parametrize("name", ["earth", "lunar-perturbation", "syzygy", "moon"])
def test_the_sun_earth_and_moon_look_and_are_named_alike_in_every_scene(name):
    """The Moon was a large yellow ball in one scene and purple in another, the Earth green, and
    the labels read "sun", "moon", "earth": the bodies a class knows keep one colour and their
    proper names wherever they are drawn."""
    import theoria as th
    from theoria.scenarios.drawing import BODY_COLOURS, Label, Sphere

    spec = th.scenario(name)
    run = spec.simulate(**{k: v for k, v in spec.preview.items() if not isinstance(v, str)})
    d = spec.drawing(run)
    balls = {it.name.split("/")[1]: it for it in d.items if isinstance(it, Sphere) and it.name.startswith("bodies/")}
    known = {k: v for k, v in balls.items() if k in BODY_COLOURS}
    assert known, list(balls)
    for key, ball in known.items():
        assert tuple(ball.color) == BODY_COLOURS[key], (key, ball.color)
    texts = {it.text for it in d.items if isinstance(it, Label) and isinstance(it.text, str)}
    assert not texts & {"sun", "moon", "earth", "attractor"}, texts
