"""The gallery without a browser: order, labels, cameras, presets, Euler's
formulas as readable text, no stale scene objects after switching through every scenario, and a
browser session (fake viser client) choosing presets, switching scenarios and showing progress."""
from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import inspect
import math
import threading
import time
import types

import numpy as np
import pytest

from theoria.app import gallery
from theoria.app.scene import SceneView
from theoria.physics.params import Param, ParameterError
from theoria.scenarios import all_scenarios, get
from theoria.scenarios import base as scen_base
from tests.test_app_scene import FakeScene

# small runs of the scenarios whose defaults take seconds (the scene logic does not depend on length)
QUICK = {
    "earth": {"years": 0.5},
    "earth-long-view": {"years": 200.0, "sample_years": 5.0},
    "hyperion": {"n_starts": 4, "n_orbits": 20, "probe_orbits": 2.0},
    "moon": {"years": 0.5},
    "lunar-perturbation": {"duration_yr": 1.0},
    "precession-circular": {"orbits": 10.0},
    "libration-eccentric": {"orbits": 3.0},
}


def test_order_follows_groups_then_sections():
    specs = gallery.ordered(all_scenarios())
    groups = [s.group for s in specs]
    # contiguous groups in the order ch. 15, ch. 16, three bodies
    seen = [g for k, g in enumerate(groups) if k == 0 or groups[k - 1] != g]
    assert seen == [g for g in gallery.GROUP_ORDER if g in groups]
    for g in gallery.GROUP_ORDER:
        keys = [gallery.section_key(s.section) for s in specs if s.group == g]
        assert keys == sorted(keys), g
    names = [s.name for s in specs]
    assert names.index("free-tumble") < names.index("middle-axis-flip") < names.index("initial-axis")
    assert names.index("gravity-start") < names.index("libration-circular") < names.index("pole-near-axis")
    labels = [gallery.label(s) for s in specs]
    assert len(set(labels)) == len(labels)
    for s, lab in zip(specs, labels):
        assert lab.startswith(s.group) and "§" in lab and s.title in lab


def test_section_key_reads_arabic_roman_and_years():
    assert gallery.section_key("§805, §808")[1] == 805
    assert gallery.section_key("Euler 1768, §XIII–§XXXIV")[:2] == (1768, 13)
    assert gallery.section_key("§833 (beyond Euler)") > gallery.section_key("§833–838")


def test_every_scenario_has_a_curated_camera():
    for s in all_scenarios():
        assert s.camera is not None, s.name
        pos, look = (np.asarray(v, float) for v in gallery.camera_for(s))
        assert np.all(np.isfinite(pos)) and np.all(np.isfinite(look))
        d = np.linalg.norm(pos - look)
        assert 1.5 < d < 12.0, (s.name, d)  # outside the body (radius 1), the scene (radius ≤ 2.4) in view
        fwd = (look - pos) / d
        assert abs(fwd[2]) < 0.999, s.name  # not looking straight along +z (the up direction)


def test_presets_are_named_and_valid():
    for s in all_scenarios():
        assert len(s.presets) >= 2, s.name
        names = [n for n in s.presets]
        assert len(set(names)) == len(names), s.name
        for n, given in s.presets.items():
            assert n.strip() and n != gallery.CUSTOM
            assert set(given) <= {p.name for p in s.params}, (s.name, n)
            values = s.preset(n)  # through Scenario.resolve: ranges and cross-parameter checks
            assert values == s.resolve(given)
        with pytest.raises(ParameterError) as e:
            s.preset("no such preset")
        assert "preset" in str(e.value)


def test_presets_differ_from_each_other():
    for s in all_scenarios():
        seen = [s.preset(n) for n in s.presets]
        for i in range(len(seen)):
            for j in range(i):
                assert seen[i] != seen[j], (s.name, s.presets[i][0], s.presets[j][0])


def test_euler_formulas_are_readable_text_not_tex():
    for s in all_scenarios():
        f = s.euler_formula
        assert f.strip(), s.name
        for tex in ("$", "\\frac", "\\sqrt", "\\cos", "\\alpha", "^{", "_{", "\\,"):
            assert tex not in f, (s.name, tex)
        md = gallery.formula_markdown(f)
        assert md.count("\n> ") == len([ln for ln in f.split("\n") if ln.strip()])
        assert "§" in f or "§" in s.section
        assert "\n" not in s.summary.strip(), s.name  # one paragraph


def _alive(scene: FakeScene) -> set[str]:
    alive: set[str] = set()
    for op, _kind, name, *_ in scene.log:
        if op == "add":
            alive.add(name)
        elif op == "remove":
            alive.discard(name)
    return alive


@pytest.mark.slow
def test_switching_through_all_scenarios_leaves_no_stale_objects():
    """After each switch (as the app does it: overlays reset to the scenario's defaults), the scene
    holds exactly the nodes a fresh scene showing only that scenario would hold."""
    scene = FakeScene()
    view = SceneView(scene)
    specs = gallery.ordered(all_scenarios())
    order = specs + specs[:1]  # end where we started: the first scenario's nodes come back
    for spec in order:
        res = spec.simulate_fn(spec.resolve({**spec.preview, **QUICK.get(spec.name, {})}))
        d = spec.drawing(res)
        view.show(d)
        view.set_frame(d.n_frames // 2)
        fresh_scene = FakeScene()
        fresh = SceneView(fresh_scene)
        fresh.show(d)
        assert _alive(scene) == _alive(fresh_scene), spec.name
        assert set(view._h) == _alive(scene), spec.name
        for g in view._auto:  # every group node made for children still has a child
            assert any(n.startswith(g + "/") for n in view._h), (spec.name, g)
        if spec.kind == "rotation":
            assert "/world/body/mesh/0" in view._h, spec.name
        else:
            assert "/world/body/mesh/0" not in view._h, spec.name
            assert any(n.startswith("/world/bodies/") for n in view._h), spec.name


# ---- a session with a fake viser client ------------------------------------------------------


def _call(cb, event):
    """A GUI callback as viser calls it: a coroutine function in its event loop (here, at once),
    any other on a thread of its pool (here, on the calling thread)."""
    if inspect.iscoroutinefunction(cb):
        asyncio.run(cb(event))
    else:
        cb(event)


class FakeGuiHandle:
    def __init__(self, kind, label=None, value=None, **props):
        object.__setattr__(self, "_cbs", [])
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "label", label)
        object.__setattr__(self, "value", value)
        object.__setattr__(self, "visible", props.pop("visible", True))
        object.__setattr__(self, "removed", False)
        object.__setattr__(self, "history", [])
        for k, v in props.items():
            object.__setattr__(self, k, v)

    def __setattr__(self, key, value):
        object.__setattr__(self, key, value)
        self.history.append((key, value))
        if key == "value":  # viser calls the update callbacks synchronously on assignment
            for cb in list(self._cbs):
                _call(cb, types.SimpleNamespace(target=self, client=None))
        if key == "options" and self.value not in value:
            self.value = value[0]

    def on_update(self, cb):
        self._cbs.append(cb)
        return cb

    on_click = on_update
    on_trigger = on_update

    def on_submit(self, cb):
        object.__setattr__(self, "_submit", getattr(self, "_submit", []) + [cb])
        return cb

    def submit(self):
        for cb in getattr(self, "_submit", []):
            cb(types.SimpleNamespace(target=self, client=None))

    def add_tab(self, label, icon=None):
        return FakeGuiHandle("tab", label)

    def remove(self):
        object.__setattr__(self, "removed", True)

    def __enter__(self):
        return self

    def __exit__(self, *a):
        return False


class FakeGui:
    _thread_executor = concurrent.futures.ThreadPoolExecutor(4)  # viser's pool for callbacks

    def __init__(self):
        self.handles: list[FakeGuiHandle] = []

    def configure_theme(self, **kw):
        pass

    def __getattr__(self, method):
        if not method.startswith("add_"):
            raise AttributeError(method)
        kind = method[4:]

        def add(*args, **kw):
            label = args[0] if args and isinstance(args[0], str) and kind not in ("markdown", "html") else None
            if "initial_value" in kw:
                value = kw.pop("initial_value")
            elif kind in ("number", "vector3", "text") and len(args) > 1:
                value = args[1]
            elif kind in ("dropdown", "button_group"):
                value = args[1][0]
            elif kind == "progress_bar":
                value = args[0]
            else:
                value = None
            if kind == "dropdown":
                kw["options"] = tuple(args[1])
            if kind in ("markdown", "html"):
                kw["content"] = args[0]
            h = FakeGuiHandle(kind, label, value, **kw)
            self.handles.append(h)
            return h

        return add

    def find(self, kind, label):
        hs = [h for h in self.handles if h.kind == kind and h.label == label and not h.removed]
        assert hs, (kind, label)
        return hs[-1]


class FakeClientScene(FakeScene):
    def set_up_direction(self, *a, **kw):
        pass

    def configure_environment_map(self, *a, **kw):
        pass

    def configure_default_lights(self, *a, **kw):
        pass


class FakeClient:
    client_id = 0

    def __init__(self):
        self.scene = FakeClientScene()
        self.gui = FakeGui()
        self.camera = types.SimpleNamespace(position=None, look_at=None, up_direction=None)
        self.notes = []
        self._lock = threading.RLock()

    def atomic(self):
        return self._lock

    def add_notification(self, title, body, **kw):
        self.notes.append((title, body))


@contextlib.contextmanager
def _session(scenario):
    from theoria.app.session import ClientSession

    client = FakeClient()
    s = ClientSession(None, client, scenario)
    try:
        yield s, client
    finally:
        s.close()


def _wait(cond, timeout=60.0):
    t0 = time.time()
    while not cond():
        assert time.time() - t0 < timeout, "timed out"
        time.sleep(0.01)


def test_preset_sets_the_controls_and_simulates_then_a_hand_change_leaves_it():
    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1)
        spec = get("middle-axis-flip")
        assert list(s.presets.options) == [n for n in spec.presets] + [gallery.CUSTOM]
        n = s.updates
        name, given = list(spec.presets.items())[1]  # a big nudge
        s.presets.value = name
        _wait(lambda: s.updates > n and s.good_values == spec.resolve(given))
        assert s.controls.values()["perturbation"] == pytest.approx(given["perturbation"])
        assert s.presets.value == name  # the preset's own control updates did not reset it
        assert s.result.params["perturbation"] == pytest.approx(given["perturbation"])
        # a hand change: the dropdown says so and the new value is simulated
        n = s.updates
        s.controls.handles["spin"].value = 4.0
        assert s.presets.value == gallery.CUSTOM
        _wait(lambda: s.updates > n and s.good_values["spin"] == 4.0)


def test_switching_scenario_in_the_session_updates_presets_camera_and_scene():
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1)
        target = get("collinear")
        n = s.updates
        s.dd.value = gallery.label(target)
        _wait(lambda: s.updates > n and s.drawing_spec == "collinear")
        assert s.presets.value == next(iter(target.presets))
        assert "/world/body/mesh" not in s.view._h
        pos, look = gallery.camera_for(target)
        assert client.camera.position is not None and client.camera.up_direction == (0.0, 0.0, 1.0)
        assert "(A+B)α⁵" in s.read.content and "$" not in s.read.content
        with s._view_lock:
            assert set(s.view._h) == {n for n in _alive(client.scene) if n.startswith("/world/")}  # (the root is the session's)


def test_long_run_shows_throttled_progress_then_hides_it(monkeypatch):
    from theoria.app import worker as server_mod

    steps = 40

    def slow(values, progress=None):
        for k in range(steps):
            time.sleep(0.02)
            if progress is not None:
                progress((k + 1) / steps)
        return get("free-tumble").simulate_fn(get("free-tumble").resolve({"duration": 2.0}))

    spec = scen_base.Scenario("test-slow", "slow", "§0", "ch. 15", "a slow run", (Param("x", 1.0, 0.0, 2.0),),
                              slow, euler_formula="x = 1", presets=(("Slow: one", {}), ("Slow: two", {"x": 2.0})))
    monkeypatch.setitem(scen_base.REGISTRY, "test-slow", spec)
    monkeypatch.setattr(server_mod, "PROGRESS_SHOW_AFTER", 0.1)
    with _session("test-slow") as (s, client):
        _wait(lambda: s.updates >= 1)
        bar = s.progress
        values = [v for k, v in bar.history if k == "value"]
        shown = [v for k, v in bar.history if k == "visible"]
        assert values, "no progress shown for a 0.8 s run"
        assert values == sorted(values) and 0 < values[-1] <= 100
        # throttled: at most one update per PROGRESS_EVERY seconds over the ~0.8 s run
        assert len(values) <= math.ceil(steps * 0.02 / server_mod.PROGRESS_EVERY) + 2
        assert shown[0] is True and shown[-1] is False and bar.visible is False


def test_long_run_without_progress_reports_still_shows_the_bar(monkeypatch):
    """A run in a phase that reports nothing (e.g. the REBOUND calibration before a long
    integration) shows the bar at 0 after PROGRESS_SHOW_AFTER and hides it at the end."""
    from theoria.app import worker as server_mod

    def silent(values, progress=None):
        time.sleep(0.6)
        return get("free-tumble").simulate_fn(get("free-tumble").resolve({"duration": 2.0}))

    spec = scen_base.Scenario("test-silent", "silent", "§0", "ch. 15", "a silent run", (Param("x", 1.0, 0.0, 2.0),),
                              silent, euler_formula="x = 1", presets=(("Silent: one", {}), ("Silent: two", {"x": 2.0})))
    monkeypatch.setitem(scen_base.REGISTRY, "test-silent", spec)
    monkeypatch.setattr(server_mod, "PROGRESS_SHOW_AFTER", 0.1)
    with _session("test-silent") as (s, client):
        _wait(lambda: s.updates >= 1)
        _wait(lambda: s.progress.visible is False)
        shown = [v for k, v in s.progress.history if k == "visible"]
        assert shown == [True, False]
    # a quick run never shows it
    monkeypatch.setattr(server_mod, "PROGRESS_SHOW_AFTER", 5.0)
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1)
        time.sleep(0.2)
        assert [v for k, v in s.progress.history if k == "visible"] == []


def test_the_bar_of_a_run_replaced_while_it_computed_goes_with_it(monkeypatch):
    """A long run showing its bar, then a quick one asked for (another preset, a value typed): the
    long run is cancelled, the quick one drawn, and its bar hidden (it stayed at its last percent)."""
    from theoria.app import worker as server_mod

    def slow_or_quick(values, progress=None):
        steps = 100 if values["x"] == 1.0 else 0
        for k in range(steps):
            time.sleep(0.03)
            if progress is not None:
                progress((k + 1) / steps)
        return get("free-tumble").simulate_fn(get("free-tumble").resolve({"duration": 2.0}))

    spec = scen_base.Scenario("test-replaced", "replaced", "§0", "ch. 15", "a run replaced", (Param("x", 2.0, 0.0, 2.0),),
                              slow_or_quick, euler_formula="x = 1", presets=(("Replaced: quick", {}),))
    monkeypatch.setitem(scen_base.REGISTRY, "test-replaced", spec)
    monkeypatch.setattr(server_mod, "PROGRESS_SHOW_AFTER", 0.1)
    with _session("test-replaced") as (s, client):
        _wait(lambda: s.updates >= 1)
        s.controls.enter("x", "1")
        _wait(lambda: s.progress.visible is True and s.progress.value > 0)
        assert "“replaced”" in s.status.content and "test-replaced" not in s.status.content  # its title, not its key
        n = s.updates
        s.controls.enter("x", "0.5")
        _wait(lambda: s.updates > n and s.good_values["x"] == 0.5)
        time.sleep(0.5)
        assert s.progress.visible is False


def test_a_playing_session_advances_its_clock_and_a_paused_one_does_not():
    """The one playback thread (app/playback.py) moves every playing session's clock by real time;
    a paused session's clock stays where it is."""
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1)
        assert s.playing
        c0 = s.clock
        _wait(lambda: s.clock != c0, timeout=10.0)
        s._toggle_play()
        assert not s.playing
        time.sleep(0.3)  # a tick in flight may still land
        c1 = s.clock
        time.sleep(0.5)
        assert s.clock == c1


def test_a_browser_flooding_a_control_holds_one_thread_and_has_its_newest_value_drawn(monkeypatch):
    """Ten browsers dragging "Exaggerate the shape" at the gate's rate stalled every other student
    for seconds: each value waited in its own thread of viser's pool for the session's drawing
    before it, the pool's threads all waiting, and minutes of drawings ran on after the tabs closed.
    A value arriving while its session is busy returns at once and takes the place of the older
    value still waiting: the session draws the first and then the newest."""
    from theoria.app import session as session_mod

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1)
        drawn, drawing, release = [], threading.Event(), threading.Event()
        real = session_mod.drawing_of

        def slow(spec, run, view=None):
            drawn.append(view.exaggerate)
            drawing.set()
            release.wait(30)
            return real(spec, run, view)

        monkeypatch.setattr(session_mod, "drawing_of", slow)
        browser = object()
        exag = s.exag

        def send(value):  # as viser does: the value is set, then the callbacks run on a pool thread
            object.__setattr__(exag, "value", value)
            for cb in exag._cbs:
                cb(types.SimpleNamespace(target=exag, client=browser))

        first = threading.Thread(target=send, args=(2.0,))
        first.start()
        assert drawing.wait(30)
        later = threading.Thread(target=lambda: [send(2.0 + 0.5 * k) for k in range(1, 36)])
        later.start()
        later.join(10)
        assert not later.is_alive(), "a value waited for the drawing before it"
        release.set()
        first.join(30)
        _wait(lambda: len(drawn) >= 2)
        time.sleep(0.5)  # (a slider's settling time: nothing more is drawn)
        assert drawn == [2.0, 19.5] and s.view_opts.exaggerate == 19.5


def test_clicks_sent_while_the_session_is_busy_are_each_handled():
    """Values of one control waiting together are one; clicks are not: two Steps are two."""
    from theoria.app.session import FORWARD, STEP_FRACTION

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1)
        s._step(1)  # paused, off the start
        before = s.clock
        browser = object()
        bar = s.playback

        def click():
            object.__setattr__(bar, "value", FORWARD)
            for cb in bar._cbs:
                _call(cb, types.SimpleNamespace(target=bar, client=browser))

        with s._callback_lock:  # the session busy with an earlier event
            clicks = [threading.Thread(target=click) for _ in range(2)]
            for t in clicks:
                t.start()
                time.sleep(0.1)
        for t in clicks:
            t.join(10)
        _wait(lambda: s.clock > before + 1.5 * STEP_FRACTION)
        step = max(STEP_FRACTION, 1.0 / max(s.drawing.n_frames - 1, 1))
        assert s.clock == pytest.approx(before + 2 * step)


def test_a_newer_value_waits_behind_the_actions_before_it():
    """Scrub to 10 %, Step, scrub to 50 %, all while the session is busy: the newer scrub took the
    older one's place in the line, ahead of the Step, and the clock ended a step past 50 %. The
    newer value goes last, where the user's latest action is: the clock ends at 50 %."""
    from theoria.app.session import FORWARD

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1)
        s._set_playing(False)
        browser, bar, scrub = object(), s.playback, s.scrub

        def hold():  # an earlier event of the browser, still being handled
            pass

        def move(value):  # as viser does: the value and its time set as the message arrives
            object.__setattr__(scrub, "value", value)
            object.__setattr__(scrub, "update_timestamp", time.time())
            for cb in scrub._cbs:
                cb(types.SimpleNamespace(target=scrub, client=browser))

        def click(button):
            object.__setattr__(bar, "value", button)
            for cb in bar._cbs:
                _call(cb, types.SimpleNamespace(target=bar, client=browser))

        with s._callback_lock:
            first = threading.Thread(target=s._browser_event, args=(hold,))
            first.start()
            _wait(lambda: s._handling and not s._waiting)  # its thread waits for the session
            move(10.0)
            click(FORWARD)
            move(50.0)
        first.join(10)
        _wait(lambda: not s._handling)
        assert s.clock == pytest.approx(0.5) and not s.playing


def test_an_error_past_a_callbacks_guard_does_not_strand_the_events_behind_it(monkeypatch):
    """Something raising past a callback's own guard left the session's line without a thread while
    the events behind it waited (a slider's last value never applied until the browser sent another).
    It is logged and the line goes on."""
    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1)
        done = []
        real = s._safe

        def broken(fn, *args):
            if fn is boom:
                raise RuntimeError("past the guard")
            return real(fn, *args)

        def boom():
            pass

        def hold():
            pass

        monkeypatch.setattr(s, "_safe", broken)
        with s._callback_lock:
            first = threading.Thread(target=s._browser_event, args=(hold,))
            first.start()
            _wait(lambda: s._handling and not s._waiting)  # its thread waits for the session
            s._browser_event(boom)
            s._browser_event(lambda: done.append("after"))
        first.join(10)
        _wait(lambda: not s._handling)
        assert done == ["after"] and not s._waiting


def test_two_different_clicks_close_together_are_each_the_button_clicked():
    """Pause, then a step forward, while the session is busy: viser sets the group's value to each
    button in turn and runs the callbacks later; both clicks were read as the step (the run played
    on, two steps taken). Each click is the button it was: paused, then one step."""
    from theoria.app.session import FORWARD, PAUSE

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1)
        s._set_playing(True)
        bar, browser = s.playback, object()

        def click(button):  # viser's loop: the value set, then the callbacks: a coroutine at once, others on its pool
            object.__setattr__(bar, "value", button)
            for cb in bar._cbs:
                event = types.SimpleNamespace(target=bar, client=browser)
                if inspect.iscoroutinefunction(cb):
                    asyncio.run(cb(event))
                else:
                    FakeGui._thread_executor.submit(cb, event)

        done = []
        real_step, real_toggle = s._step, s._toggle_play
        s._step = lambda k: (done.append(("step", k)), real_step(k))
        s._toggle_play = lambda: (done.append("play/pause"), real_toggle())
        with s._callback_lock:  # the session busy with an earlier event
            loop = threading.Thread(target=lambda: (click(PAUSE), click(FORWARD)))
            loop.start()
            loop.join(10)
            time.sleep(0.2)
            assert done == []
        _wait(lambda: len(done) >= 2)
        time.sleep(0.2)
        assert done == ["play/pause", ("step", 1)] and not s.playing


def test_a_scene_being_computed_shows_nothing_of_the_scene_before():
    """A switch on a loaded machine: the panel said "Hyperion" while the clock read the Moon's
    "t = 176 of 365.2 days", and the plot, the bodies and the Compare table were the Moon's, for
    seconds. Until the new run is drawn, the old one's bodies and plot are hidden, its clock and
    table taken down; then the new scene shows."""
    from theoria.app import session as session_mod

    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1)
        gate = threading.Event()
        real = s.worker.on_result

        def held(*a, **kw):  # the new run waits: the panel shows the switch in the meantime
            gate.wait(60)
            return real(*a, **kw)

        s.worker.on_result = held
        target = get("middle-axis-flip")
        n = s.updates
        s.dd.value = gallery.label(target)
        _wait(lambda: s.spec.name == "middle-axis-flip")
        assert s._world.visible is False and s.plot.visible is False
        assert s.compare.content == session_mod.compare_html(None)
        assert s.time_md.content == f"*computing {target.title}…*"
        before = s.scrub.value
        with s._clock_lock:
            s.clock = 0.5 if before != 50.0 else 0.25
        s._time_gui()  # the playback's tick: the old scene's clock is not written under the new title
        assert s.time_md.content == f"*computing {target.title}…*" and s.scrub.value == before
        assert s.link_query() == "s=middle-axis-flip"  # the address names the scene chosen, at once
        gate.set()
        _wait(lambda: s.updates > n and s.drawing_spec == "middle-axis-flip")
        assert s._world.visible is True and s.plot.visible is True
        assert s.time_md.content.startswith("t = ")
