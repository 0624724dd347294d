"""The teacher's face in a real headless Chromium (Debian's /usr/bin/chromium driven by Playwright):
the panel in words for every scenario (no raw identifier visible, at most two screens tall at
1280×800), typed numbers taken exactly, a copied link restoring the view in a fresh browser, and
presenter mode with its keys. Run: pytest -m browser tests/test_teacher_browser.py
"""
from __future__ import annotations

import contextlib
import re
import time
from urllib.parse import urlencode

import pytest

from test_app_browser import WAIT_MS, _free_port, _have_browser, browser  # noqa: F401  (the fixture)

pytestmark = pytest.mark.browser

if not _have_browser():
    pytest.skip("needs Debian's chromium at /usr/bin/chromium and python playwright", allow_module_level=True)

W, H = 1280, 800

# the panel: viser's floating control panel (a Mantine Paper holding a scroll area)
PANEL_JS = """() => Array.from(document.querySelectorAll('.mantine-Paper-root')).find(e => e.querySelector('.mantine-ScrollArea-root'))"""
PANEL_TEXT_JS = f"""() => {{ const p = ({PANEL_JS})(); return p ? p.innerText : ''; }}"""
# how tall the panel's content is, in screens of the window: its header plus its scrolled content
PANEL_SCREENS_JS = f"""() => {{
  const p = ({PANEL_JS})(); if (!p) return null;
  const v = p.querySelector('.mantine-ScrollArea-viewport');
  const header = v.getBoundingClientRect().top - p.getBoundingClientRect().top;
  return (header + v.scrollHeight) / window.innerHeight; }}"""
# the values of the panel's number boxes, and those a box shows only in part
CUT_BOXES_JS = """() => {
  const boxes = [...document.querySelectorAll('input.mantine-NumberInput-input')].filter(i => i.offsetParent);
  return {shown: boxes.map(i => i.value), cut: boxes.filter(i => i.scrollWidth > i.clientWidth + 1).map(i => i.value)}; }"""
# the first element matching `css` near the control labelled `label` (in its row of the panel)
NEAR_LABEL_JS = """([label, css]) => {
  const l = Array.from(document.querySelectorAll('label')).find(x => x.innerText.trim() === label);
  if (!l) return null;
  let p = l;
  for (let k = 0; k < 8 && p; k++) { p = p.parentElement; const i = p && p.querySelector(css); if (i) return i; }
  return null; }"""
INPUT_JS = f"""(label) => ({NEAR_LABEL_JS})([label, 'input'])"""


def _near(page, label: str, css: str):
    return page.evaluate_handle(NEAR_LABEL_JS, [label, css]).as_element()


# the page's camera position in the scene's own coordinates (the link's): three.js holds it in its
# y-up world, the scene's root node carries the turn from viser's world (z up) to it
CAMERA_WORLD_JS = """(() => { const m = window.__viserMutable, root = m.nodeRefFromName[''];
  root.updateWorldMatrix(true, false);
  return m.camera.position.clone().applyMatrix4(root.matrixWorld.clone().invert()).toArray(); })()"""


@pytest.fixture(scope="module")
def app():
    from theoria.app.server import make_server

    server, sessions = make_server(port=_free_port(), host="127.0.0.1", verbose=False)
    yield f"http://127.0.0.1:{server.get_port()}/", sessions
    server.stop()


def _open(browser, url, w=W, h=H):
    ctx = browser.new_context(viewport={"width": w, "height": h})
    page = ctx.new_page()
    page.goto(url)
    return ctx, page


def _session_for(sessions, before: set, name: str | None = None, timeout: float = WAIT_MS / 1000):
    """The session of the page just opened (a client id not in `before`), once it shows a run."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        new = [s for cid, s in list(sessions.items()) if cid not in before]
        if new and new[-1].updates >= 1 and (name is None or new[-1].drawing_spec == name):
            return new[-1]
        time.sleep(0.2)
    raise AssertionError(f"no session showed {name}")


@contextlib.contextmanager
def _scene(browser, app, spec):
    """A fresh page showing `spec` (with its quick preview values) and its session; closed after."""
    base, sessions = app
    before = set(sessions)
    ctx, page = _open(browser, base + "?" + _query(spec))
    try:
        yield page, _session_for(sessions, before, spec.name)
    finally:
        ctx.close()


def _query(spec, **extra) -> str:
    """A link to the scenario with its quick preview values (the panel's words are the same)."""
    q = [("s", spec.name), ("fixedDpr", "1")] + [(f"p.{k}", str(v)) for k, v in spec.preview.items()]
    q += list(extra.items())
    return urlencode(q)


def raw_identifiers(text: str, spec, run) -> list[str]:
    """Words in `text` that are keys scripts use, not words a class reads: snake_case names, the
    scenario's slug, parameter / metric / option / overlay keys that are not plain words."""
    from theoria.scenarios import all_scenarios
    from theoria.scenarios.drawing import OVERLAYS

    keys = {p.name for p in spec.params} | set(run.metrics) | set(spec.options) | set(OVERLAYS) | set(run.plot_series)
    nonword = {k for k in keys if not re.fullmatch(r"[A-Za-z]+", k) or k in ("gm",)}
    slugs = {s.name for s in all_scenarios() if "-" in s.name}  # "moon", "syzygy" are words too
    found = []
    for tok in re.findall(r"[A-Za-z0-9_\-+.]+", text):
        tok = tok.strip(".")
        if (re.fullmatch(r"_?[A-Za-z][A-Za-z0-9]*(?:_[A-Za-z0-9]+)+", tok) or tok in nonword or tok in slugs
                or re.fullmatch(r"[+-]?\d+(?:\.\d+)?[eE][+-]?\d+", tok)):  # a programmer's 1e-06
            found.append(tok)
    found += re.findall(r"[<>]=|`", text)  # ">=" for ≥, code in backquotes
    found += re.findall(r"(?:^|(?<=\s))--(?=\s|$)", text)  # a value no one has: a plot legend's "--"
    return found


def _field(page, label: str):
    """The input of the panel's control labelled `label`, once the panel shows it (the session
    has drawn its run before the page has laid out the panel's controls)."""
    page.wait_for_function(f"(l) => !!({INPUT_JS})(l)", arg=label, timeout=WAIT_MS)
    field = page.evaluate_handle(INPUT_JS, label).as_element()
    assert field is not None, label
    return field


def _tab(page, name: str) -> None:
    page.get_by_role("tab", name=name).click()
    time.sleep(0.4)


def test_every_panel_is_in_words_and_fits_two_screens(browser, app):
    from theoria.scenarios import all_scenarios

    base, sessions = app
    bad, screens, titles, cut = [], {}, {}, {}
    for spec in all_scenarios():
        # one more try when the page's first session did not show the link's scene: on a loaded
        # machine a page can be slow to answer its address (the link); the
        # words and the size of the panel are what this test is about
        for attempt in range(2):
            before = set(sessions)
            ctx, page = _open(browser, base + "?" + _query(spec))
            try:
                s = _session_for(sessions, before, spec.name)
                break
            except AssertionError:
                ctx.close()
                if attempt:
                    raise
        try:
            # the page is titled "theoria" from its first byte; the session then names the scenario
            page.wait_for_function("document.title.startsWith('theoria — ')", timeout=WAIT_MS)
            titles[spec.name] = page.title()
            for tab in ("Explore", "Compare", "Read"):
                _tab(page, tab)
                text = page.evaluate(PANEL_TEXT_JS)
                ids = raw_identifiers(text, spec, s.result)
                if ids:
                    bad.append((spec.name, tab, sorted(set(ids))))
                screens[(spec.name, tab)] = page.evaluate(PANEL_SCREENS_JS)
                if tab == "Explore":  # every number box shows its whole value
                    cut[spec.name] = page.evaluate(CUT_BOXES_JS)
        finally:
            ctx.close()
    assert bad == [], bad
    assert "0.00002" in cut["tidal-capture"]["shown"], cut["tidal-capture"]  # the tide's rate has a box
    assert {k: v["cut"] for k, v in cut.items() if v["cut"]} == {}, cut
    too_tall = {k: round(v, 2) for k, v in screens.items() if v is None or v > 2.0}
    assert too_tall == {}, too_tall
    assert all(t == f"theoria — {name}" for name, t in titles.items()), titles


def test_typed_numbers_are_taken_exactly_on_enter_or_blur(browser, app):
    from theoria.scenarios import get

    flip, pull = get("middle-axis-flip"), get("gravity-start")
    with _scene(browser, app, flip) as (page, s):
        field = _field(page, flip.param("perturbation").display())
        n = s.updates
        field.click()
        field.fill("")
        page.keyboard.type("1e-3", delay=120)  # typed one key at a time: nothing runs per keystroke
        time.sleep(1.0)
        assert s.updates == n and s.controls.values()["perturbation"] == 0.01
        page.mouse.click(300, 400)  # the field loses focus: the value is taken
        page.wait_for_function("1", timeout=WAIT_MS)  # a round trip to the page
        t0 = time.time()
        while s.good_values["perturbation"] != 1e-3:
            assert time.time() - t0 < WAIT_MS / 1000
            time.sleep(0.1)
        assert s.result.params["perturbation"] == 1e-3
    with _scene(browser, app, pull) as (page, s):
        field = _field(page, pull.param("gm").display())
        field.fill("2.5e6")
        field.press("Enter")
        t0 = time.time()
        while s.good_values["gm"] != 2.5e6:
            assert time.time() - t0 < WAIT_MS / 1000
            time.sleep(0.1)
        assert s.result.params["gm"] == 2.5e6
        # a value out of range is refused with the allowed range, and the last good value stays
        field = _field(page, pull.param("distance").display())
        n = s.updates
        field.fill("-0.5")
        field.press("Enter")
        page.wait_for_function("document.body.innerText.includes('Not allowed')", timeout=WAIT_MS)
        text = page.evaluate("document.body.innerText")
        assert "Distance s of F" in text and "1 × 10⁹" in text
        time.sleep(0.5)
        assert s.updates == n and s.good_values["distance"] == 10.0
        assert page.evaluate("(e) => e.value", field) == "10"


def test_a_number_typed_into_a_sliders_box_is_taken_exactly_or_refused(browser, app):
    """The box beside a slider takes what is typed on Enter or blur, never per keystroke, exactly:
    "1e-2" (Mantine's box dropped the "e" and sent -12, refused), "0.1234" between the slider's
    0.001 marks (shown whole), "5" above the range refused naming it and the range, the box and the
    value back on the last good one; an emptied box shows the value again."""
    from theoria.scenarios import get

    ecc = get("libration-eccentric")
    label = ecc.param("eccentricity").display()
    with _scene(browser, app, ecc) as (page, s):
        page.wait_for_function(f"(l) => !!({NEAR_LABEL_JS})([l, 'input.mantine-NumberInput-input'])", arg=label,
                               timeout=WAIT_MS)
        box = _near(page, label, "input.mantine-NumberInput-input")

        def typed(text: str, end: str = "Enter") -> None:
            box.click()
            box.press("Control+a")
            n = s.updates
            box.type(text, delay=150)
            time.sleep(0.8)
            assert box.input_value() == text and s.updates == n  # nothing sent while typing
            if end == "Enter":
                box.press("Enter")
            else:
                page.mouse.click(300, 400)  # the box loses focus

        for text, want, end in (("1e-2", 0.01, "Enter"), ("0.1234", 0.1234, "blur")):
            typed(text, end)
            assert _wait_for(lambda: s.good_values["eccentricity"] == want and s.result.params["eccentricity"] == want,
                             limit=WAIT_MS / 1000), (text, s.controls.values())
            assert _wait_for(lambda: box.input_value() == str(want)), (text, box.input_value())
        typed("5")
        page.wait_for_function("document.body.innerText.includes('Not allowed')", timeout=WAIT_MS)
        text = page.evaluate("document.body.innerText")
        assert label in text and "“5”" in text and "[0, 0.5]" in text
        time.sleep(0.5)
        assert s.controls.values()["eccentricity"] == 0.1234 and box.input_value() == "0.1234"
        box.click()
        box.press("Control+a")
        box.press("Backspace")
        box.press("Enter")
        assert _wait_for(lambda: box.input_value() == "0.1234") and s.controls.values()["eccentricity"] == 0.1234


def test_a_copied_link_restores_scenario_parameters_time_and_camera(browser, app):
    from theoria.scenarios import get

    sessions = app[1]
    flip = get("middle-axis-flip")
    with _scene(browser, app, flip) as (page, s):
        field = _field(page, flip.param("perturbation").display())
        field.fill("0.002")
        field.press("Enter")
        while s.good_values["perturbation"] != 0.002:
            time.sleep(0.1)
        page.mouse.click(300, 400)
        page.keyboard.press("Space")  # pause
        for _ in range(3):
            page.keyboard.press("ArrowRight")
        # orbit the camera with the mouse
        page.mouse.move(400, 400)
        page.mouse.down()
        page.mouse.move(480, 360, steps=8)
        page.mouse.up()
        page.wait_for_function("location.search.includes('play=0') && location.search.includes('p.perturbation=0.002')",
                               timeout=WAIT_MS)
        time.sleep(1.5)  # the address follows the camera within a second
        # ... and the time once the steps are taken (the keys are the browser's events, taken in
        # turn: on a loaded machine the address was read before the third step had reached it)
        t_end = time.time() + WAIT_MS / 1000
        while True:
            url = page.url
            want_t = float(re.search(r"[?&]t=([^&]+)", url).group(1))
            if not s.playing and abs(want_t - s.drawing.times[s.view.frame]) < 1e-6 * max(1, want_t):
                break
            assert time.time() < t_end, (url, s.playing, s.drawing.times[s.view.frame])
            time.sleep(0.2)
        want_cam = [float(x) for x in re.search(r"[?&]cam=([^&]+)", url).group(1).split(",")]
    before = set(sessions)
    ctx, page = _open(browser, url)  # a fresh browser context: nothing shared but the address
    try:
        r = _session_for(sessions, before, flip.name)
        assert r.spec.name == flip.name
        assert r.good_values == flip.resolve({"perturbation": 0.002})
        assert not r.playing
        # the very frame: the address holds it to 8 digits
        assert abs(r.drawing.times[r.view.frame] - want_t) < 1e-6 * max(1, want_t), (r.drawing.times[r.view.frame], want_t)
        time.sleep(1.0)
        cam = page.evaluate(CAMERA_WORLD_JS)
        assert max(abs(a - b) for a, b in zip(cam, want_cam[:3])) < 1e-3 * (1 + max(abs(x) for x in want_cam[:3])), (cam, want_cam)
    finally:
        ctx.close()


def test_presenter_mode_large_type_no_controls_and_keys(browser, app):
    from theoria.scenarios import get

    base, sessions = app
    flip = get("middle-axis-flip")
    before = set(sessions)
    ctx, page = _open(browser, base + "?" + _query(flip, present="1"), 1920, 1080)
    try:
        s = _session_for(sessions, before, flip.name)
        assert s.present
        page.wait_for_function("!!document.getElementById('theoria-present')", timeout=WAIT_MS)
        text = page.evaluate(PANEL_TEXT_JS)
        assert "Playback speed" not in text and flip.param("spin").display() not in text
        assert flip.title in text
        page.mouse.click(300, 500)
        playing = s.playing
        page.keyboard.press("Space")
        t0 = time.time()
        while s.playing == playing:
            assert time.time() - t0 < 10
            time.sleep(0.05)
        clock = s.clock
        page.keyboard.press("ArrowRight")
        t0 = time.time()
        while s.clock == clock:
            assert time.time() - t0 < 10
            time.sleep(0.05)
        assert not s.playing
        name = list(flip.presets)[1]
        page.keyboard.press("2")
        t0 = time.time()
        while s.good_values != flip.preset(name):
            assert time.time() - t0 < WAIT_MS / 1000
            time.sleep(0.1)
        assert s.presets.value == name
    finally:
        ctx.close()


def test_an_arrow_key_on_a_focused_slider_moves_the_slider_only(browser, app):
    """← and → step the clock (a command's hotkey), but not for a slider that has the focus: one
    key moved the slider and stepped the clock, two actions at once."""
    from theoria.scenarios import get

    flip = get("middle-axis-flip")
    with _scene(browser, app, flip) as (page, s):
        page.get_by_role("button", name="Pause").click()
        assert _wait_for(lambda: not s.playing)
        time.sleep(0.5)
        clock, speed = s.clock, s.speed.value
        thumb = _near(page, "Playback speed (1: the run in 20 s)", "[role=slider]")
        thumb.focus()
        page.keyboard.press("ArrowRight")
        assert _wait_for(lambda: s.speed.value > speed, limit=10.0)
        time.sleep(1.0)
        assert s.clock == clock and not s.playing
        page.mouse.click(300, 500)  # away from the panel, the key steps the clock again
        page.keyboard.press("ArrowRight")
        assert _wait_for(lambda: s.clock > clock, limit=10.0)


def test_keys_keep_playing_and_stepping_after_a_typed_time_and_a_chosen_scene(browser, app):
    """Three ways the keys were taken from a teacher: after a time typed into its box, the number
    field, which had not seen the box lose the focus, took it back when playback moved the time
    (Space and ← → then typed into the box); ← → also turned the camera; and a scene chosen from its
    list kept the focus in the list's search box (Space and the digits were typed as a search)."""
    from theoria.app import gallery
    from theoria.scenarios import get

    flip, tumble = get("middle-axis-flip"), get("free-tumble")
    with _scene(browser, app, flip) as (page, s):
        page.get_by_role("button", name="Pause").click()
        assert _wait_for(lambda: not s.playing)
        box = _near(page, "Time (% of the run)", "input.mantine-NumberInput-input")
        box.click()
        box.press("Control+a")
        box.type("50")
        box.press("Enter")
        assert _wait_for(lambda: abs(s.scrub.value - 50) < 1e-9)
        page.mouse.click(300, 500)
        camera = page.evaluate(CAMERA_WORLD_JS)
        page.keyboard.press("Space")
        assert _wait_for(lambda: s.playing, limit=10.0)
        time.sleep(2.0)  # playback moves the time's box four times
        assert page.evaluate("document.activeElement.tagName") == "BODY"
        page.keyboard.press("Space")
        assert _wait_for(lambda: not s.playing, limit=10.0)
        clock = s.clock
        page.keyboard.down("ArrowRight")  # held a moment, as a hand does: the camera turned while it was down
        time.sleep(0.4)
        page.keyboard.up("ArrowRight")
        assert _wait_for(lambda: s.clock > clock, limit=10.0)
        time.sleep(0.5)
        assert max(abs(a - b) for a, b in zip(page.evaluate(CAMERA_WORLD_JS), camera)) < 1e-6, "the key turned the camera"
        _near(page, "Scene", ".mantine-Select-input").click()
        page.locator("[role=option]", has_text=gallery.label(tumble)).first.click()
        assert _wait_for(lambda: s.drawing_spec == tumble.name and s.updates >= 1, limit=WAIT_MS / 1000)
        assert _wait_for(lambda: page.evaluate("document.activeElement.tagName") == "BODY", limit=5.0)
        # the new scene's keys are registered with its panel: a Space sent before they are is not one
        playing, toggled = s.playing, False
        for _ in range(3):
            page.keyboard.press("Space")
            if _wait_for(lambda: s.playing != playing, limit=5.0):
                toggled = True
                break
        assert toggled and page.evaluate("document.activeElement.tagName") == "BODY"


# where each of the scene's bodies is drawn on the canvas, in the camera's normalised coordinates
# (−1 … 1 across the canvas): the bodies' nodes, projected by the page's own camera
BODIES_ON_CANVAS_JS = """() => { const m = window.__viserMutable, out = {};
  m.camera.updateMatrixWorld(); m.camera.updateProjectionMatrix();
  for (const [name, o] of Object.entries(m.nodeRefFromName)) {
    if (!o || !/^\\/world\\/bodies\\/[^/]+$/.test(name)) continue;
    const p = new o.position.constructor(); o.getWorldPosition(p); p.project(m.camera);
    out[name] = [p.x, p.y];
  }
  return out; }"""


def test_a_narrow_window_shows_every_body_of_the_scene(browser, app):
    """At 800x600 the canvas beside the docked panel is 412 px wide, narrower than high: the
    scene, framed for 1280x800, lost its sides (collinear's third body C under the panel's edge).
    The camera zooms out until the scene is as wide as in the canvas it was framed for."""
    from theoria.scenarios import get

    base, sessions = app
    spec = get("collinear")
    before = set(sessions)
    ctx, page = _open(browser, base + "?" + _query(spec, play="0"), 800, 600)
    try:
        _session_for(sessions, before, spec.name)
        page.wait_for_function(f"Object.keys(({BODIES_ON_CANVAS_JS})()).length >= 3", timeout=WAIT_MS)
        # the page frames the camera every half second, once the scene's own camera has come (on a
        # loaded machine, seconds after its bodies: CI once looked 1 s after and found C far off)
        try:
            page.wait_for_function(f"""() => {{ const v = Object.values(({BODIES_ON_CANVAS_JS})());
                return v.length >= 3 && v.every(([x, y]) => Math.abs(x) < 1 && Math.abs(y) < 1); }}""",
                                   timeout=30_000)
        except Exception:  # noqa: BLE001 — said below, with where each body is
            pass
        where = page.evaluate(BODIES_ON_CANVAS_JS)
        assert len(where) >= 3 and all(abs(x) < 1 and abs(y) < 1 for x, y in where.values()), where
    finally:
        ctx.close()


# the body's orientation on the page, each animation frame for `seconds`: frames drawn, poses seen
POSES_JS = """(seconds) => new Promise(resolve => {
  const m = window.__viserMutable.nodeRefFromName;
  let last = null, frames = 0, poses = 0; const t0 = performance.now();
  function loop() {
    const o = m['/world/body']; const q = o ? o.quaternion.toArray().join(',') : '';
    frames++; if (q !== last) { poses++; last = q; }
    if (performance.now() - t0 < seconds * 1000) requestAnimationFrame(loop);
    else resolve({frames: frames, poses: poses, seconds: (performance.now() - t0) / 1000});
  }
  requestAnimationFrame(loop);
})"""
# a page with nothing but an animation loop: the frame rate the browser gives any page
EMPTY_RATE_JS = """(seconds) => new Promise(resolve => { let f = 0; const t0 = performance.now();
  function loop() { f++; if (performance.now() - t0 < seconds * 1000) requestAnimationFrame(loop);
    else resolve(f / ((performance.now() - t0) / 1000)); }
  requestAnimationFrame(loop); })"""
BODY_Q_JS = "() => window.__viserMutable.nodeRefFromName['/world/body'].quaternion.toArray()"


def _page_plays(page):
    page.wait_for_function("window.theoria && window.theoria.P.hooked && window.theoria.P.d && "
                           "window.theoria.P.d.tracks.length > 0", timeout=WAIT_MS)


def _same_rotation(q_three, wxyz) -> bool:
    """three.js (x, y, z, w) and viser (w, x, y, z) name the same rotation (q and -q alike)."""
    import numpy as np

    a = np.array([q_three[3], *q_three[:3]])
    b = np.asarray(wxyz, float)
    return min(np.abs(a - b).max(), np.abs(a + b).max()) < 1e-3


def test_the_page_plays_by_itself_and_stops_where_the_server_does(browser, app):
    """Playing, the body turns on the page from the tracks it was sent (the server sends no frame:
    tests/test_classroom.py); paused or stepped, the page shows exactly the server's frame."""
    from theoria.scenarios import get

    spec = get("free-tumble")
    with _scene(browser, app, spec) as (page, s):
        assert s.page_plays and s.tick_hz() < 10  # the server ticks only for the time read-out
        _page_plays(page)
        seen = page.evaluate(POSES_JS, 2)
        assert seen["poses"] >= 4, seen  # the body turns
        assert _wait_for(lambda: s.scrub.value > 0)  # ... and the time scrubber follows it
        page.get_by_role("button", name="Pause").click()
        assert _wait_for(lambda: not s.playing)
        time.sleep(0.8)
        k = page.evaluate("() => window.theoria.P.frame")
        assert k == s.view.frame
        assert _same_rotation(page.evaluate(BODY_Q_JS), s.view._h["/world/body"].wxyz)
        assert page.evaluate(POSES_JS, 1)["poses"] == 1  # it stands still
        page.get_by_role("button", name="Step ▶").click()
        assert _wait_for(lambda: s.view.frame > k)
        time.sleep(0.8)
        assert page.evaluate("() => window.theoria.P.frame") == s.view.frame
        assert _same_rotation(page.evaluate(BODY_Q_JS), s.view._h["/world/body"].wxyz)
        assert s.scrub.value == round(100 * s.clock, 1)
        # playing again, a time typed into the scrubber's field is where the run plays on from
        page.get_by_role("button", name="Play").click()
        assert _wait_for(lambda: s.playing)
        # the scrubber's track (a click there sends one value; its number field is rewritten twice
        # a second)
        track = _near(page, "Time (% of the run)", ".mantine-Slider-track")
        assert s.clock < 0.6 and s.speed.value == 1  # played on from here, 0.9 is 6 s away
        box = track.bounding_box()
        page.mouse.click(box["x"] + 0.9 * box["width"], box["y"] + box["height"] / 2)
        assert _wait_for(lambda: 0.85 <= s.clock < 0.95, limit=3.0), s.clock
        # typed into its number field while it plays: playback does not rewrite the field while it has
        # the focus, the time is taken on Enter
        page.get_by_role("button", name="Reset").click()
        assert _wait_for(lambda: s.clock < 0.2)
        field = _near(page, "Time (% of the run)", "input:not([type=hidden])")
        field.click()
        field.press("Control+a")
        field.type("70.5", delay=600)
        field.press("Enter")
        assert _wait_for(lambda: 0.7 <= s.clock < 0.8, limit=3.0), (s.clock, field.input_value())


# the points of a line-segments node as the page draws them (its three.js geometry)
SEGMENT_JS = """(name) => { const g = window.__viserMutable.nodeRefFromName[name]; let out = null;
  if (g) g.traverse(o => { if (!out && o.isLineSegments2) out = Array.from(o.geometry.attributes.instanceStart.data.array); });
  return out; }"""
# frames drawn while playing, and those in which a moving node's world matrix (what viser's labels
# read their place from, in a render-loop callback after the player's) was not yet this frame's:
# counted just after the player moves the nodes, before the labels read them
STALE_JS = """(seconds) => new Promise((resolve) => {
  const m = window.__viserMutable, root = m.scene.__r3f.root, T = window.theoria;
  const names = T.P.d.tracks.filter(t => t.attr === 'wxyz' || t.attr === 'position').map(t => t.node);
  const M = m.scene.matrixWorld.clone();
  let frames = 0, stale = 0;
  const stop = root.getState().internal.subscribe({current: () => {
    frames++;
    for (const n of names) {
      const o = m.nodeRefFromName[n];
      if (!o) continue;
      M.copy(o.matrixWorld); o.updateWorldMatrix(true, false);
      if (!M.equals(o.matrixWorld)) { stale++; break; }
    }
  }}, -998, root);
  setTimeout(() => { stop(); resolve([frames, stale]); }, seconds * 1000); })"""
# every node update the page's player hands to viser, recorded as (node, text) for label text
SPY_JS = """() => { const q = window.__viserMutable.messageQueue; window.__texts = [];
  const push = q.push.bind(q);
  q.push = (...ms) => { for (const m of ms) if (m.type === 'SceneNodeUpdateMessage' && 'text' in m.updates)
    window.__texts.push([m.name, m.updates.text, window.theoria.P.frame]); return push(...ms); }; }"""


def test_the_page_plays_label_text_and_segments_and_stops_where_the_server_does(browser, app):
    """Libration in a circular orbit: the line from the body to F, the arc of the phase angle and its
    read-out change every frame. Playing, the page moves them itself (the server's own handles do
    not change: it sends nothing): the line is the run's line of the very frame whose poses are on
    screen (through viser's node update it came 3-40 frames late, and on a fast run pointed away
    from F), the labels on moving frames are placed from this frame's poses (they were a drawn
    frame behind: the body's "A = ..." beside no axis), and the text it gives viser is the run's
    own text at the frame the page shows. Paused, the page draws exactly the server's line."""
    import numpy as np

    from theoria.scenarios import get

    spec = get("libration-circular")
    with _scene(browser, app, spec) as (page, s):
        assert s.page_plays and s.tick_hz() < 10  # nothing for the server to move
        _page_plays(page)
        server_line = np.array(s.view._h["/world/f_direction"].points, float).ravel()
        page.evaluate(SPY_JS)
        drawn = np.asarray(next(it for it in s.drawing.items if it.name == "f_direction").points, float)
        drawn = drawn.reshape(len(drawn), -1)
        seen = set()
        tol = 2e-3 * max(1.0, np.abs(drawn).max())  # the page's float16 copy of the run's line
        for _ in range(12):
            line, k = page.evaluate(f"() => [({SEGMENT_JS})('/world/f_direction'), window.theoria.P.frame]")
            seen.add(tuple(np.round(line, 4)))
            assert np.abs(drawn[k] - np.asarray(line)).max() < tol, (k, np.abs(drawn - line).max(axis=1).argmin())
            time.sleep(0.15)
        assert len(seen) >= 4, seen  # the line to F turns on the page
        frames, stale = page.evaluate(STALE_JS, 2)
        assert frames >= 5 and stale == 0, (frames, stale)
        assert np.array_equal(np.array(s.view._h["/world/f_direction"].points, float).ravel(), server_line)
        texts = page.evaluate("() => window.__texts")
        label = next(it for it in s.drawing.items if it.name == "zeta_label")
        assert len({t for _, t, _ in texts}) >= 4, texts
        for name, text, k in texts:  # the text of the frame shown (the track keeps every frame's here)
            assert name == "/world/zeta_label" and text == str(label.text[k]), (text, k)
        page.get_by_role("button", name="Pause").click()
        assert _wait_for(lambda: not s.playing)
        time.sleep(0.8)
        k = page.evaluate("() => window.theoria.P.frame")
        assert k == s.view.frame
        line = np.array(page.evaluate(SEGMENT_JS, "/world/f_direction"))
        want = np.asarray(next(it for it in s.drawing.items if it.name == "f_direction").points[k], float).ravel()
        assert np.abs(line - want).max() < 1e-5, (line, want)


def _wait_for(cond, limit: float = 20.0) -> bool:
    t0 = time.time()
    while not cond():
        if time.time() - t0 > limit:
            return False
        time.sleep(0.05)
    return True


@contextlib.contextmanager
def _paused_at(browser, app, spec, t: str):
    """A fresh page of `spec` paused at time `t` (a link), once it shows the server's frame:
    (page, session, frame)."""
    base, sessions = app
    before = set(sessions)
    ctx, page = _open(browser, base + "?" + _query(spec, t=t, play="0"))
    try:
        s = _session_for(sessions, before, spec.name)
        _page_plays(page)
        page.wait_for_function("(k) => window.theoria.P.frame === k", arg=s.view.frame, timeout=WAIT_MS)
        time.sleep(0.5)
        yield page, s, s.view.frame
    finally:
        ctx.close()


DRAWN_POINTS_JS = """() => {
  const d = window.theoria.P.d, R = window.__viserMutable.nodeRefFromName, out = [];
  for (const c of d.chunks) {
    let n = 0;
    for (const name of c.nodes) {
      const o = R[name]; if (!o || !o.visible) continue;
      const g = window.theoria.pointsOf(o); if (!g) continue;
      n += Math.min(g.drawRange.count, g.attributes.position.count);
    }
    out.push(n);
  }
  return out;
}"""


@pytest.mark.parametrize("name, t", [("collinear", "0"), ("collinear", "0.3"), ("free-tumble", "0")])
def test_a_growing_trail_ends_at_the_frame_shown(browser, app, name, t):
    """A trail was sent as twelve chunks, each shown whole from its first frame: at t = 0 the
    collinear bodies had 60° of their coming paths drawn ahead of them, and a long free tumble its
    whole polhode. The page draws, at each frame, the points that have appeared by then."""
    import numpy as np
    from theoria.scenarios import get

    with _paused_at(browser, app, get(name), t) as (page, s, k):
        drawn = page.evaluate(DRAWN_POINTS_JS)
        want = [int(sum(np.count_nonzero(np.asarray(at) <= k) for at in p.ats))
                for paths in s.view._chunks.values() for p in paths]
        assert want and drawn == want, (k, drawn, want)
        total = [sum(len(at) for at in p.ats) for paths in s.view._chunks.values() for p in paths]
        assert any(w < n for w, n in zip(want, total))  # the trails have not all been drawn yet


def test_playback_frame_rate_against_an_empty_page(browser, app):
    """Frames a second in which the page shows a new pose of the body while it plays, as a ratio to
    a page with only an animation loop in the same browser and run. The goal is 0.8; in software
    WebGL (SwiftShader, no GPU) on two cores this scene plays at ~0.6-0.7 of an empty page with the
    panel docked beside it, its three paths (~9,000 points) costing most of the rest (docs/app.md),
    so there the measurement is reported and the goal marked as not reached.

    Playback is measured once the scene has played for a few seconds: in the first three seconds
    after a scene arrives the page draws at about half the later rate (17-19 against 36-38 poses a
    second here), once per scene rather than while a class watches; that rate is reported too."""
    from theoria.scenarios import get

    base, sessions = app
    spec = get("middle-axis-flip")
    before = set(sessions)
    ctx, page = _open(browser, base + "?" + _query(spec))
    try:
        _session_for(sessions, before, spec.name)
        _page_plays(page)
        first = page.evaluate(POSES_JS, 3)
        time.sleep(3.0)
        played = page.evaluate(POSES_JS, 3)
        empty_page = ctx.new_page()
        empty_page.goto("about:blank")
        empty = empty_page.evaluate(EMPTY_RATE_JS, 3)
        empty_page.close()
    finally:
        ctx.close()
    rate = played["poses"] / played["seconds"]
    ratio = rate / empty
    print(f"\nplayback {rate:.1f} poses/s (its first 3 s: {first['poses'] / first['seconds']:.1f}), "
          f"empty page {empty:.1f} frames/s: ratio {ratio:.2f} (goal 0.8)")
    assert played["poses"] >= 3 and empty > 10, (played, empty)
    assert played["poses"] <= played["frames"]  # a pose at most per frame drawn: a frame rate, not a count
    if ratio < 0.8:
        pytest.xfail(f"playback at {ratio:.2f} of an empty page's frame rate ({rate:.1f} / {empty:.1f}); "
                     "software WebGL on two cores")


def test_the_letters_of_turning_arrows_sit_at_their_tips_in_a_paused_page(browser, app):
    """A turning ω or L is drawn once and scaled by the page to each frame's length; its letter
    was moved on a node viser's labels do not read, so it stayed where the server first put it:
    a body at rest at t = 0 showed "ω" and "L" floating above it, far from any arrow."""
    import numpy as np
    from theoria.scenarios import get

    spec = get("initial-axis")
    for t in ("0", "2.5"):
        with _paused_at(browser, app, spec, t) as (page, s, k):
            for name in ("omega", "L"):
                arrows = next(it for it in s.drawing.items if it.name == name)
                tip = 1.1 * float(np.linalg.norm(np.asarray(arrows.vectors, float)[k, 0]))
                pos = page.evaluate("(n) => window.__viserMutable.nodePoseData[n].position", f"/world/{name}/label")
                assert np.allclose(pos, [0.0, 0.0, tip], atol=1e-4 * max(1.0, tip)), (t, name, pos, tip)


def test_one_click_on_save_downloads_the_page(browser, app):
    """"Save this scene as a web page" sent the file, and the browser showed a notice with a link
    to click ("theoria-libration-circular." cut off): nothing was saved on the click a teacher
    made. One click downloads the page, whole (its marker's digest checks), and it plays from a
    file."""
    from theoria.app.replay import check_html
    from theoria.app.session import SAVE_PAGE_LABEL
    from theoria.scenarios import get

    with _scene(browser, app, get("libration-circular")) as (page, s):
        _tab(page, "Read")
        with page.expect_download(timeout=WAIT_MS) as got:
            page.get_by_role("button", name=SAVE_PAGE_LABEL).click()
        download = got.value
        assert download.suggested_filename == "theoria-libration-circular.html"
        path = download.path()
        assert check_html(str(path))["scenario"] == "libration-circular"  # whole: it raises otherwise
