"""One browser check of the ch. 16 scenes (slow: Playwright + Debian's chromium, as
tests/test_app_browser.py): the Moon seen from the Earth fills the view with its maria.

The Moon's scene opens in space (the Moon, and beside it a copy turned to show the face the Earth
sees); its option "the whole view from the Earth" puts the camera on the Earth's direction and
keeps it there as the Moon goes round. That view is asked for by the link (`o.earth_view=1`), as a
teacher's copied link does."""
from __future__ import annotations

import time

import numpy as np
import pytest

pytestmark = pytest.mark.browser

from test_app_browser import SCREENSHOTS, WAIT_MS, Page, _canvas_pixels, _server, browser  # noqa: E402,F401


def _earth_dir_and_camera(s):
    with s._view_lock:  # the frame shown and the camera placed for it, read together
        e = s.result.trajectory.bodies["earth"][s.drawing.frames[s.view.frame]]  # the frame's sample
        pos = np.asarray(s.client.camera.position, float)
    return e / np.linalg.norm(e), pos / np.linalg.norm(pos)


def _assert_camera_on_the_earth(s):
    """The paused view's camera is on the Earth's direction of the frame shown. The camera the
    server holds is replaced by each camera message the browser sends, and a browser on a loaded
    machine may still send one from before the last frame it was given: wait for the browser to
    settle (a paused view stops moving), then compare. The pause itself is a message from the
    browser too: the camera follows the Earth while playing, so it is waited for first."""
    t0 = time.time()
    while s.playing and time.time() - t0 < WAIT_MS / 1000:
        time.sleep(0.1)
    assert not s.playing
    t0 = time.time()
    while True:
        e, cam = _earth_dir_and_camera(s)
        if np.dot(cam, e) > 0.999 or time.time() - t0 > WAIT_MS / 1000:
            break
        time.sleep(0.2)
    assert np.dot(cam, e) > 0.999, (cam, e)


def test_moon_seen_from_the_earth_fills_the_view_with_its_face(browser):  # noqa: F811
    server, sessions = _server("moon")
    try:
        # the default view: in space, the Moon and the face as seen from the Earth beside it
        p = Page(browser, f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1")
        p.page.wait_for_function("window.__viserMutable && window.__viserMutable.nodeRefFromName['/world/face/mesh/0']",
                                 timeout=WAIT_MS)
        time.sleep(1.5)
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        p.page.screenshot(path=str(SCREENSHOTS / "moon-browser-test-space.png"))
        assert p.outside == [], p.outside
        p.close()

        # the whole view from the Earth: the camera on the Earth's direction, the disc fills the view
        before = set(sessions)
        p = Page(browser, f"http://127.0.0.1:{server.get_port()}/?s=moon&fixedDpr=1&o.earth_view=1")
        p.page.wait_for_function("window.__viserMutable && window.__viserMutable.nodeRefFromName['/world/body/mesh/0']",
                                 timeout=WAIT_MS)
        t0 = time.time()
        while not any(c not in before and x.updates >= 1 for c, x in list(sessions.items())):
            assert time.time() - t0 < WAIT_MS / 1000
            time.sleep(0.2)
        s = next(x for c, x in sessions.items() if c not in before)
        assert s.drawing.follow is not None  # the option reached the drawing: a camera that follows
        assert "/world/face/mesh/0" not in p.nodes()  # no copy beside the Moon in this view
        p.page.mouse.click(300, 400)
        p.page.keyboard.press("Space")  # pause, as a teacher does to talk about the face
        _assert_camera_on_the_earth(s)
        t0 = time.time()
        while True:  # on a loaded machine the face's texture can come seconds after the disc
            pix = _canvas_pixels(p.page)  # a 540×600 crop left of the control panel
            drawn = np.abs(pix - 255.0) > 8  # not the white background
            inside = pix[drawn]
            spread = np.percentile(inside, 90) - np.percentile(inside, 10) if inside.size else 0.0
            if (drawn.mean() > 0.6 and spread > 40) or time.time() - t0 > WAIT_MS / 1000:
                break
            time.sleep(0.5)
        assert drawn.mean() > 0.6, drawn.mean()  # the disc fills most of the view
        assert spread > 40, spread  # maria and highlands: two populations of grey on the disc
        p.page.screenshot(path=str(SCREENSHOTS / "moon-browser-test.png"))
        # the camera follows: a fifth of a month later it is still on the Earth's direction
        frame = s.view.frame
        for _ in range(20):
            p.page.keyboard.press("ArrowRight")
        t0 = time.time()
        while s.view.frame < frame + 10:
            assert time.time() - t0 < WAIT_MS / 1000, (frame, s.view.frame)
            time.sleep(0.2)
        _assert_camera_on_the_earth(s)
        assert p.outside == [], p.outside
        p.close()
    finally:
        server.stop()
