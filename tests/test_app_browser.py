"""The web app in a real headless Chromium (Debian's /usr/bin/chromium driven by Playwright;
never a downloaded browser). Run: pytest -m browser tests/test_app_browser.py

Every request the page makes outside 127.0.0.1 / file:// is aborted and recorded, so "loads with
no internet" is checked, not assumed. The scene is read from the client's own scene tree
(`window.__viserMutable.nodeRefFromName`, internal to viser 1.1).
"""
from __future__ import annotations

import io
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.browser

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
        "--disable-background-networking", "--disable-component-update", "--no-first-run"]
WAIT_MS = 120_000  # generous: 2 shared cores, software WebGL (not a performance limit)
# docs/screenshots/ is refreshed only on request (THEORIA_SCREENSHOTS=1), so that a test run does
# not modify the working tree; otherwise the screenshots go to a temporary directory.
SCREENSHOTS = (Path(__file__).resolve().parent.parent / "docs" / "screenshots" if os.environ.get("THEORIA_SCREENSHOTS")
               else Path(tempfile.gettempdir()) / "theoria-screenshots")

SIGNATURE_JS = """(name) => {
  const o = window.__viserMutable && window.__viserMutable.nodeRefFromName[name];
  if (!o) return null;
  let n = 0, s = 0;
  o.traverse(c => {
    const g = c.geometry; if (!g || !g.attributes) return;
    for (const k in g.attributes) {
      const a = g.attributes[k]; const arr = a.array || (a.data && a.data.array);
      if (!arr) continue;
      n += arr.length; for (let i = 0; i < arr.length; i += 3) s += Math.abs(arr[i]);
    }
  });
  return [n, s];
}"""

INPUTS_JS = """(label) => {
  const l = Array.from(document.querySelectorAll('label')).find(x => x.innerText.trim() === label);
  if (!l) return [];
  let p = l;
  for (let k = 0; k < 8 && p; k++) {
    p = p.parentElement;
    const ins = p ? Array.from(p.querySelectorAll('input')).filter(i => i.type === 'text') : [];
    if (ins.length) return Array.from(ins);
  }
  return [];
}"""

SLIDER_JS = """(label) => {
  const l = Array.from(document.querySelectorAll('label')).find(x => x.innerText.trim() === label);
  let p = l;
  for (let k = 0; k < 8 && p; k++) { p = p.parentElement; const t = p && p.querySelector('[role=slider]'); if (t) return t; }
  return null;
}"""


def _label(scenario: str, name: str) -> str:
    """The words the panel shows for a parameter (the field's label)."""
    from theoria.scenarios import get

    return get(scenario).param(name).display()


def _have_browser() -> bool:
    try:
        import playwright  # noqa: F401
    except ImportError:
        return False
    return os.path.exists(CHROMIUM)


if not _have_browser():
    pytest.skip("needs Debian's chromium at /usr/bin/chromium and python playwright", allow_module_level=True)


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


def _server(scenario):
    from theoria.app.server import make_server

    server, sessions = make_server(port=_free_port(), host="127.0.0.1", scenario=scenario, verbose=False)
    return server, sessions


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def tumble_app():
    server, sessions = _server(None)  # default scenario: free-tumble
    yield f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1", sessions
    server.stop()


@pytest.fixture(scope="module")
def flip_app():
    server, sessions = _server("middle-axis-flip")
    yield f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1", sessions
    server.stop()


class Page:
    """A browser context + page, with every request off this machine aborted and recorded."""

    def __init__(self, browser, url):
        self.outside: list[str] = []
        self.ctx = browser.new_context(viewport={"width": 1280, "height": 800})

        def route(r):
            u = r.request.url
            if u.startswith(("http://127.0.0.1", "ws://127.0.0.1", "file://", "data:", "blob:")):
                r.continue_()
            else:
                self.outside.append(u)
                r.abort()

        self.ctx.route("**/*", route)
        self.page = self.ctx.new_page()
        self.page.goto(url)

    def wait_ready(self):
        pg = self.page
        pg.wait_for_function("!document.body.innerText.includes('Connecting')", timeout=WAIT_MS)
        pg.wait_for_function("window.__viserMutable && window.__viserMutable.nodeRefFromName['/world/body/polhode/0']",
                             timeout=WAIT_MS)
        return self

    def nodes(self) -> list[str]:
        return self.page.evaluate("Object.keys(window.__viserMutable.nodeRefFromName)")

    def signature(self, name):
        return self.page.evaluate(SIGNATURE_JS, name)

    def set_input(self, label, text):
        """Type `text` into the panel's field labelled `label` (a parameter's words, `Param.display()`)
        and press Enter: a typed number is taken then, as a person does it."""
        self.page.wait_for_function(f"(l) => ({INPUTS_JS})(l).length > 0", arg=label, timeout=WAIT_MS)
        el = self.page.evaluate_handle(INPUTS_JS, label).get_property("0").as_element()
        assert el is not None, f"no input for {label}"
        el.fill(str(text))
        el.press("Enter")

    def nudge_slider(self, label, key="ArrowRight"):
        """Move the slider labelled `label` one step with the keyboard (focus its thumb, press a key)."""
        self.page.wait_for_function(f"(l) => !!({SLIDER_JS})(l)", arg=label, timeout=WAIT_MS)
        self.page.evaluate_handle(SLIDER_JS, label).as_element().focus()
        self.page.keyboard.press(key)

    def wait_signature_change(self, name, before):
        self.page.wait_for_function(f"(b) => {{ const s = ({SIGNATURE_JS})('{name}'); return s && (s[0] !== b[0] || Math.abs(s[1] - b[1]) > 1e-6 * (1 + Math.abs(b[1]))); }}",
                                    arg=before, timeout=WAIT_MS)

    def assert_no_software_webgl_note(self, made: bool = False):
        """viser's "Software WebGL rendering detected" notice would sit over a projected scene all
        lesson; the page takes it down as it appears (app/page.py). This browser renders in
        software; `made`: wait until viser has made the notice (on a page's first load; a later
        page of the same run did not always get one)."""
        assert self.page.evaluate("window.__theoriaSoftwareGL") is True
        if made:
            self.page.wait_for_function("""[...document.querySelectorAll('.mantine-Notification-root')]
                .some(n => n.textContent.includes('Software WebGL'))""", timeout=WAIT_MS)
        shown = self.page.evaluate("""[...document.querySelectorAll('.mantine-Notification-root')]
            .filter(n => n.offsetParent !== null && n.textContent.includes('Software WebGL')).length""")
        assert shown == 0, "viser's software-WebGL notice is visible"

    def close(self):
        self.ctx.close()


def _canvas_pixels(page) -> np.ndarray:
    from PIL import Image

    png = page.screenshot(clip={"x": 320, "y": 160, "width": 540, "height": 600})
    return np.asarray(Image.open(io.BytesIO(png)).convert("L"), float)


def test_page_loads_offline_and_draws_the_body(browser, tumble_app):
    url, sessions = tumble_app
    p = Page(browser, url).wait_ready()
    try:
        names = set(p.nodes())
        for n in ("/world/body", "/world/body/mesh", "/world/body/axes", "/world/body/axis_labels/A",
                  "/world/omega", "/world/L", "/world/axis_trail/0", "/world/herpolhode/0",
                  "/world/body/polhode/0"):
            assert n in names, n
        time.sleep(1.0)  # let a few frames render
        pix = _canvas_pixels(p.page)
        assert pix.std() > 10.0, pix.std()  # a blank canvas has std ≈ 0
        assert np.mean(np.abs(pix - np.median(pix)) > 30) > 0.02  # ≥ 2 % of the area is drawn
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        p.assert_no_software_webgl_note(made=True)
        time.sleep(0.5)
        p.page.screenshot(path=str(SCREENSHOTS / "free-tumble.png"))
        assert p.outside == [], p.outside
        # the body moves: playback turns the body frame
        q0 = p.page.evaluate("window.__viserMutable.nodeRefFromName['/world/body'].quaternion.toArray()")
        p.page.wait_for_function("(q0) => { const q = window.__viserMutable.nodeRefFromName['/world/body'].quaternion.toArray();"
                                 " return Math.abs(q[0]-q0[0]) + Math.abs(q[1]-q0[1]) + Math.abs(q[3]-q0[3]) > 1e-3; }",
                                 arg=q0, timeout=WAIT_MS)
        # the polhode is a child of the body frame: it turns with the body (same world matrix)
        d = p.page.evaluate("""(() => { const m = window.__viserMutable.nodeRefFromName;
            const a = m['/world/body'], b = m['/world/body/polhode/0'];
            a.updateWorldMatrix(true, false); b.updateWorldMatrix(true, false);
            const x = a.matrixWorld.elements, y = b.matrixWorld.elements;
            return [x.reduce((s, v, i) => s + Math.abs(v - y[i]), 0), Math.abs(x[0] - 1) + Math.abs(x[5] - 1)]; })()""")
        assert d[0] < 1e-9 and d[1] > 1e-6, d  # equal, and not the identity (the body has turned)
    finally:
        p.close()


def test_slider_changes_scene_and_bad_value_keeps_it(browser, flip_app):
    """A typed value (Enter) and a slider step each redraw the scene; an impossible body and an
    out-of-range number are refused by name with the rule, and the scene keeps the last good run."""
    url, sessions = flip_app
    p = Page(browser, url).wait_ready()
    nudge, spin = _label("middle-axis-flip", "perturbation"), _label("middle-axis-flip", "spin")
    inertia, duration = _label("middle-axis-flip", "inertia"), _label("middle-axis-flip", "duration")
    try:
        p.assert_no_software_webgl_note()
        time.sleep(4.0)  # let the flips play (a third of the 30 s run at speed 1 is 10 s)
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        p.page.screenshot(path=str(SCREENSHOTS / "middle-axis-flip.png"))
        before = p.signature("/world/body/polhode/0")
        p.set_input(nudge, "0.2")
        p.wait_signature_change("/world/body/polhode/0", before)
        typed = p.signature("/world/body/polhode/0")
        assert typed != before
        session = list(sessions.values())[-1]
        assert session.good_values["perturbation"] == 0.2
        # the spin's slider, one step with the keyboard: a new run, a new polhode
        spin0 = session.controls.values()["spin"]
        p.nudge_slider(spin)
        p.wait_signature_change("/world/body/polhode/0", typed)
        good = p.signature("/world/body/polhode/0")
        assert session.good_values["spin"] > spin0
        # an impossible body (A + B < C): a notification naming the control and the rule
        p.set_input(inertia, "1, 1, 5")
        p.page.wait_for_function("(w) => document.body.innerText.includes('Not allowed: ' + w)", arg=inertia,
                                 timeout=WAIT_MS)
        text = p.page.evaluate("document.body.innerText")
        assert "A+B ≥ C" in text and "triangle" in text
        time.sleep(1.0)
        assert p.signature("/world/body/polhode/0") == good  # the scene keeps the last good state
        # out of range for a number field: the allowed range is named
        p.set_input(duration, "-3")
        p.page.wait_for_function("(w) => document.body.innerText.includes('Not allowed: ' + w)", arg=duration,
                                 timeout=WAIT_MS)
        assert "(0, 1 × 10⁶] s" in p.page.evaluate("document.body.innerText")
        time.sleep(0.5)
        assert p.signature("/world/body/polhode/0") == good
        # the server is still alive: good values are simulated and drawn
        p.set_input(duration, "30")
        p.set_input(inertia, "1, 2, 2.5")
        p.wait_signature_change("/world/body/polhode/0", good)
        assert session.good_values["inertia"] == (1.0, 2.0, 2.5)
        assert p.outside == []
    finally:
        p.close()


def test_a_value_typed_just_after_leaving_another_field_is_taken(browser, flip_app):
    """viser sends a panel's messages through one throttled sender where the newest message wins
    (50 ms). A value pasted into a field 125 ms after leaving another (whose submit went out at
    120 ms) waited in that sender and was replaced by the form's "changed" signal: the server
    never saw it, and Enter ran the old value again. Done in the page's own time, as a quick
    hand does it; the server must take the new length."""
    url, sessions = flip_app
    p = Page(browser, url).wait_ready()
    nudge, duration = _label("middle-axis-flip", "perturbation"), _label("middle-axis-flip", "duration")
    try:
        session = list(sessions.values())[-1]
        p.page.evaluate("""([a, b, inputs]) => {
          const field = (l) => eval(inputs)(l)[0];
          const set = Object.getOwnPropertyDescriptor(HTMLInputElement.prototype, 'value').set;
          const A = field(a), B = field(b);
          A.form.requestSubmit();  // leaving the first field: its submit goes out 120 ms later
          setTimeout(() => {
            set.call(B, '17');  // a paste: one input event
            B.dispatchEvent(new Event('input', {bubbles: true}));
            B.form.requestSubmit();  // Enter
          }, 125);
        }""", [nudge, duration, INPUTS_JS])
        t0 = time.time()
        while session.good_values.get("duration") != 17.0 and time.time() - t0 < 20:
            time.sleep(0.1)
        assert session.good_values.get("duration") == 17.0, session.good_values
    finally:
        p.close()


def test_two_browsers_hold_independent_states(browser, flip_app):
    url, sessions = flip_app
    a = Page(browser, url).wait_ready()
    b = Page(browser, url).wait_ready()
    try:
        sig_b = b.signature("/world/body/polhode/0")
        sig_a = a.signature("/world/body/polhode/0")
        assert sig_a == sig_b  # same defaults
        a.set_input(_label("middle-axis-flip", "perturbation"), "0.3")
        a.wait_signature_change("/world/body/polhode/0", sig_a)
        time.sleep(1.0)
        assert b.signature("/world/body/polhode/0") == sig_b
        vals = sorted(s.controls.values()["perturbation"] for s in list(sessions.values())[-2:])
        assert vals == [pytest.approx(0.01), pytest.approx(0.3)]
    finally:
        a.close()
        b.close()


ATTACHED_JS = """(name) => { let o = window.__viserMutable.nodeRefFromName[name]; if (!o) return false;
  while (o.parent) o = o.parent; return o.type === 'Scene'; }"""


def test_switching_to_an_orbit_scenario_draws_its_bodies(browser, tumble_app):
    """The dropdown (grouped by chapter) switches this browser to an orbit scenario: the rotating
    body goes, a sphere and a trail per Trajectory.bodies entry come, the parameters follow."""
    from theoria.app.gallery import label as scenario_label
    from theoria.scenarios import all_scenarios

    orbit = next((s for s in all_scenarios() if s.kind == "orbit"), None)
    if orbit is None:
        pytest.skip("no orbit scenario registered")
    url, sessions = tumble_app
    p = Page(browser, url).wait_ready()
    try:
        cur = scenario_label(next(iter(s for s in sessions.values())).spec)
        p.page.evaluate("""(cur) => { const i = Array.from(document.querySelectorAll('input'))
            .find(i => i.value === cur && i.type !== 'hidden'); i.setAttribute('data-theoria', 'scenario'); }""", cur)
        p.page.locator('input[data-theoria="scenario"]').click()
        p.page.get_by_role("option", name=scenario_label(orbit)).click()
        p.page.wait_for_function("(n) => { const m = window.__viserMutable.nodeRefFromName;"
                                 " return Object.keys(m).some(k => k.startsWith('/world/bodies/') && k.split('/').length === 4); }",
                                 arg=None, timeout=WAIT_MS)
        p.page.wait_for_function(f"(() => !({ATTACHED_JS})('/world/body/mesh/0'))()", timeout=WAIT_MS)
        names = p.nodes()
        bodies = [n for n in names if n.startswith("/world/bodies/") and n.count("/") == 3]
        trails = [n for n in names if n.startswith("/world/body_trails/") and n.endswith("/0")]
        assert len(bodies) >= 2 and len(trails) == len(bodies), (bodies, trails)
        text = p.page.evaluate("document.body.innerText")
        assert orbit.title in text and orbit.section in text
        for prm in orbit.params:  # the parameters in words; the advanced ones in a closed folder
            if not prm.advanced:
                assert prm.display() in text, prm.display()
            if "_" in prm.name:
                assert prm.name not in text, prm.name
        assert "More settings" in text or not any(prm.advanced for prm in orbit.params)
        assert p.outside == []
    finally:
        p.close()


def test_exported_html_plays_from_file(browser, tmp_path):
    from theoria.app.export_html import export
    from theoria.scenarios import get

    out = tmp_path / "tumble.html"
    info = export("free-tumble", str(out), get("free-tumble").resolve({"duration": "10"}))
    assert info["frames"] > 100 and out.stat().st_size == info["bytes"]
    p = Page(browser, out.as_uri())
    try:
        p.page.wait_for_function("window.__viserMutable && window.__viserMutable.nodeRefFromName['/world/body/mesh/0']",
                                 timeout=WAIT_MS)
        names = set(p.nodes())
        assert {"/world/body", "/world/axis_trail/0", "/world/body/polhode/0"} <= names
        q0 = p.page.evaluate("window.__viserMutable.nodeRefFromName['/world/body'].quaternion.toArray()")
        p.page.wait_for_function("(q0) => { const q = window.__viserMutable.nodeRefFromName['/world/body'].quaternion.toArray();"
                                 " return Math.abs(q[0]-q0[0]) + Math.abs(q[1]-q0[1]) + Math.abs(q[3]-q0[3]) > 1e-3; }",
                                 arg=q0, timeout=WAIT_MS)
        assert p.outside == [], p.outside
    finally:
        p.close()


def test_an_exported_pages_text_is_whole_and_beside_the_scene(browser, tmp_path):
    """The saved page's table lay over the scene, cut to 45 % of the window half-way through its
    second row, a scene's inset plot on top of it, and read "16.73 unit" where the app reads
    orbits. At 1280×800 the text is a column left of the canvas, every row of the table is in
    view, and the table is the app's (units, verdicts)."""
    from theoria.app.export_html import export

    out = tmp_path / "libration.html"
    export("libration-circular", str(out))
    p = Page(browser, out.as_uri())
    try:
        p.page.wait_for_function("window.__viserMutable && document.querySelector('canvas')", timeout=WAIT_MS)
        box = p.page.evaluate("""() => {
            const t = document.getElementById('theoria-text').getBoundingClientRect();
            const c = document.querySelector('canvas').getBoundingClientRect();
            const rows = Array.from(document.querySelectorAll('#theoria-text tr')).map(r => r.getBoundingClientRect());
            return {text_right: t.right, text_bottom: t.bottom, canvas_left: c.left, canvas_width: c.width,
                    last_row_bottom: Math.max(...rows.map(r => r.bottom)), words: document.getElementById('theoria-text').innerText};
        }""")
        assert box["canvas_left"] >= box["text_right"] and box["canvas_width"] > 600, box
        assert box["last_row_bottom"] <= min(box["text_bottom"], 800), box
        assert "(orbits)" in box["words"] and "largest digression" in box["words"] and " unit" not in box["words"]
        assert "Euler and the simulation are within" in box["words"]  # the app's verdict
        # the bar's box counts the replay's seconds: the run's own time is said beside it
        assert "The bar below plays the whole run (t = 0 to 10.65 orbits) in 8 s" in box["words"], box["words"]
        # a small window (800×600): the text above the scene, not over it
        p.page.set_viewport_size({"width": 800, "height": 600})
        time.sleep(1.0)
        small = p.page.evaluate("""() => ({text: document.getElementById('theoria-text').getBoundingClientRect().bottom,
            canvas: document.querySelector('canvas').getBoundingClientRect().top})""")
        assert small["canvas"] >= small["text"] - 1, small
    finally:
        p.close()


def test_a_failing_scenario_never_kills_the_server(browser):
    """A scenario whose simulation raises: the browser is told, the server keeps serving."""
    from theoria.scenarios import base
    from theoria.physics.params import Param

    def boom(values, progress=None):
        raise RuntimeError("deliberate failure in a test scenario")

    spec = base.Scenario("test-broken", "broken", "§0", "ch. 15", "raises", (Param("x", 1.0, 0.0, 2.0),), boom)
    base.REGISTRY[spec.name] = spec
    try:
        server, sessions = _server("test-broken")
        url = f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1"
        a = Page(browser, url)
        try:
            a.page.wait_for_function("document.body.innerText.includes('deliberate failure')", timeout=WAIT_MS)
            assert f"Error in {spec.title}" in a.page.evaluate("document.body.innerText")  # named in words
        finally:
            a.close()
        b = Page(browser, url)  # a new browser is still served
        try:
            b.page.wait_for_function("document.body.innerText.includes('deliberate failure')", timeout=WAIT_MS)
        finally:
            b.close()
        server.stop()
    finally:
        base.REGISTRY.pop(spec.name, None)
