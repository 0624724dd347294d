"""One browser check of the ch. 16 scenes (slow: Playwright + Debian's chromium, as
tests/test_app_browser.py): the Moon seen from the Earth fills the view with its maria."""
from __future__ import annotations

import time

import numpy as np
import pytest

pytestmark = pytest.mark.browser

from test_app_browser import SCREENSHOTS, WAIT_MS, Page, _canvas_pixels, _server, browser  # noqa: E402,F401


def test_moon_seen_from_the_earth_fills_the_view_with_its_face(browser):  # noqa: F811
    server, sessions = _server("moon")
    try:
        p = Page(browser, f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1")
        p.page.wait_for_function("window.__viserMutable && window.__viserMutable.nodeRefFromName['/world/body/mesh/0']",
                                 timeout=WAIT_MS)
        s = next(iter(sessions.values()))
        e = s.result.trajectory.bodies["earth"][s.drawing.frames[s.view.frame]]  # the frame's sample
        pos = np.asarray(s.client.camera.position, float)
        assert np.dot(pos / np.linalg.norm(pos), e / np.linalg.norm(e)) > 0.999
        time.sleep(1.5)
        pix = _canvas_pixels(p.page)  # a 540×600 crop left of the control panel
        drawn = np.abs(pix - 255.0) > 8  # not the white background
        assert drawn.mean() > 0.6, drawn.mean()  # the disc fills most of the view
        # maria and highlands: two populations of grey on the disc
        inside = pix[drawn]
        assert np.percentile(inside, 90) - np.percentile(inside, 10) > 40
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        p.page.screenshot(path=str(SCREENSHOTS / "moon-browser-test.png"))
        assert p.outside == [], p.outside
        p.close()
    finally:
        server.stop()
