"""The three-body scenes in a real headless Chromium (see tests/test_app_browser.py): each
scene's drawings reach the browser, and (with THEORIA_SCREENSHOTS=1) the screenshots of
docs/screenshots/{collinear,syzygy,lunar-perturbation}.png are refreshed. Slow (~30 s each)."""
from __future__ import annotations

import os
import time

import pytest

from test_app_browser import SCREENSHOTS, WAIT_MS, Page, _canvas_pixels, _have_browser, _server

pytestmark = pytest.mark.browser

if not _have_browser():
    pytest.skip("needs Debian's chromium at /usr/bin/chromium and python playwright", allow_module_level=True)


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path="/usr/bin/chromium",
                              args=["--headless=new", "--no-sandbox", "--use-angle=swiftshader",
                                    "--enable-unsafe-swiftshader", "--disable-background-networking",
                                    "--disable-component-update", "--no-first-run"])
        yield b
        b.close()


CASES = [
    # scenario, parameter values, scene options, node that must arrive, fraction of the run shown
    ("collinear", {"motion": "restricted", "lagrange_point": "L1", "turns": 3.0}, {"corotating": True},
     "/world/turning/zero_velocity/L1", 0.8),
    ("syzygy", {}, {}, "/world/inset/moon", 0.97),
    ("lunar-perturbation", {}, {}, "/world/plane/disc", 0.45),
]


@pytest.mark.parametrize("name,values,options,node,when", CASES, ids=[c[0] for c in CASES])
def test_three_body_scene_reaches_the_browser(browser, name, values, options, node, when):
    server, sessions = _server(name)
    try:
        p = Page(browser, f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1")
        try:
            p.page.wait_for_function("!document.body.innerText.includes('Connecting')", timeout=WAIT_MS)
            deadline = time.time() + WAIT_MS / 1000
            while not sessions and time.time() < deadline:
                time.sleep(0.1)
            s = next(iter(sessions.values()))
            while s.result is None and time.time() < deadline:
                time.sleep(0.1)
            if values:
                s.controls.set_values(values)
                s.request()
            p.page.wait_for_function(f"window.__viserMutable && window.__viserMutable.nodeRefFromName['{node}']",
                                     timeout=WAIT_MS)
            deadline = time.time() + WAIT_MS / 1000
            while (s.result is None or any(str(s.result.params[k]) != str(v) for k, v in values.items())) \
                    and time.time() < deadline:
                time.sleep(0.2)
            if options:  # a scene option: the run drawn again, as the checkbox does
                s.view_opts.options.update(options)
                s._redraw()
            names = set(p.nodes())
            assert "/world/readout" in names
            s.playing = False
            s.clock = when
            s._show_clock(force=True)
            p.assert_no_software_webgl_note()
            # labels are WebGL text whose glyphs are built in the page: on a loaded machine (software
            # WebGL, other jobs) that took up to ~20 s
            time.sleep(float(os.environ.get("THEORIA_LABEL_WAIT", "4")))
            pix = _canvas_pixels(p.page)
            assert pix.std() > 5.0, pix.std()
            SCREENSHOTS.mkdir(parents=True, exist_ok=True)
            p.page.screenshot(path=str(SCREENSHOTS / f"{name}.png"))
            assert p.outside == [], p.outside
        finally:
            p.close()
    finally:
        server.stop()
