"""The sweep maps in a real headless Chromium at 1280×800: small versions of the two flagship sweeps
(Hyperion's chaos map, Mercury's capture into 3:2) served with `--sweep`, a pixel clicked with the
mouse, that run replayed in the scene; screenshots sweep-*.png (into docs/screenshots/ with
THEORIA_SCREENSHOTS=1).
Run: pytest -m browser tests/test_sweep_map_browser.py
"""
from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest

from test_app_browser import WAIT_MS, _free_port, _have_browser, browser  # noqa: F401  (the fixture)

pytestmark = [pytest.mark.browser, pytest.mark.slow]

if not _have_browser():
    pytest.skip("needs Debian's chromium at /usr/bin/chromium and python playwright", allow_module_level=True)

# docs/screenshots/ is refreshed only on request (THEORIA_SCREENSHOTS=1), as in test_app_browser.py:
# a test run does not modify the working tree
OUT = (Path(__file__).resolve().parent.parent / "docs" / "screenshots" if os.environ.get("THEORIA_SCREENSHOTS")
       else Path(tempfile.gettempdir()) / "theoria-screenshots")
W, H = 1280, 800

# the flagship sweeps made small (the docs' full ones take a minute and twenty minutes): fewer
# points, and for Mercury a body ten times less round with a tide twice as strong over 20,000
# orbits, so that every start reaches 3:2 within the run
SMALL = {
    "hyperion-chaos-map": dict(grid=["eccentricity=0:0.3:48", "probe_rate=0.2:3:96"], fixed={"n_orbits": 150}),
    "mercury-capture": dict(grid=["eccentricity=0.05:0.25:9", "initial_angle_deg=0:174.375:32"],
                            fixed={"omega0": 0.1, "tide_rate": 5e-5, "spin_rate": 1.8, "orbits": 20000.0}),
}


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory):
    from distributed import Client, LocalCluster

    import theoria as th
    from theoria.app.sweep import SWEEP_PRESETS, preset_kwargs

    out = {}
    d = tmp_path_factory.mktemp("maps")
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as lc, \
            Client(lc) as c:
        for name, small in SMALL.items():
            kw = preset_kwargs(name, grid=small["grid"], fixed=small["fixed"])
            out[name] = d / f"{name}.zarr"
            th.scenario(SWEEP_PRESETS[name].scenario).sweep(out=out[name], cluster=c, grid=kw["grid"], **kw["fixed"])
    return out


def _wait(cond, timeout=WAIT_MS / 1000):
    t0 = time.time()
    while not cond():
        if time.time() - t0 > timeout:
            return False
        time.sleep(0.2)
    return True


@pytest.mark.parametrize("name, target", [
    # Hyperion at e = 0.1 spun at 1.5 n: in the chaotic sea between the 1:1 and 3:2 islands
    ("hyperion-chaos-map", {"eccentricity": 0.1, "probe_rate": 1.5}),
    # the capture profile: the column at Mercury's e ≈ 0.2
    ("mercury-capture", {"eccentricity": 0.2}),
])
def test_map_click_replays_and_screenshot(browser, sweeps, name, target, tmp_path):
    from theoria.app.server import make_server

    server, sessions = make_server(port=_free_port(), host="127.0.0.1", verbose=False, sweep=sweeps[name])
    ctx = browser.new_context(viewport={"width": W, "height": H})
    try:
        page = ctx.new_page()
        page.goto(f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1")
        page.wait_for_selector("img[data-theoria-map]", timeout=WAIT_MS)
        assert _wait(lambda: sessions and next(iter(sessions.values())).updates >= 1)
        session = next(iter(sessions.values()))
        pic = session._sweep_pic
        m = pic.map
        # the map is inside the window and readable: axes and colour bar in words
        box = page.locator("img[data-theoria-map]").bounding_box()
        page.screenshot(path=str(tmp_path / "first.png"))  # to look at when it fails
        print("first screen:", tmp_path / "first.png")
        assert box["x"] >= 0 and box["x"] + box["width"] <= W and box["y"] + box["height"] <= H, box
        text = page.locator(".theoria-map").inner_text()
        words = {"hyperion-chaos-map": ["Orbital eccentricity", "Largest Lyapunov exponent", "per orbit"],
                 "mercury-capture": ["Orbital eccentricity", "Fraction captured into the 3:2 resonance",
                                     "Goldreich & Peale"]}[name]
        for w in words:
            assert w in text, (w, text)
        # a map that teaches something: more than one colour
        assert np.nanmax(m.values) - np.nanmin(m.values) > 0.2 * max(abs(np.nanmax(m.values)), 1e-9)
        # click the pixel of the target run, where a teacher would
        j = int(np.argmin(np.abs(m.x_values - target[m.x])))
        i = int(np.argmin(np.abs(m.y_values - target[m.y]))) if m.y else 0
        want = m.run_values(i, j)
        t0 = time.perf_counter()
        # the position within the image, taken when the click happens (the panel above it changes
        # height while the first run computes)
        page.locator("img[data-theoria-map]").click(position={
            "x": (j + 0.5) / pic.cols * box["width"], "y": box["height"] * (1 - (i + 0.5) / pic.rows)})
        ok = _wait(lambda: session.good_values == want and session.drawing_spec == m.scenario, 3 * WAIT_MS / 1000)
        if not ok:
            page.screenshot(path=str(tmp_path / "after.png"))
        assert ok, (tmp_path, session.good_values, want)
        time.sleep(0.5)  # the run itself, not its quick preview (which may carry the same values)
        assert _wait(lambda: session._tick_md.content.startswith("*simulated"), 3 * WAIT_MS / 1000)
        took = time.perf_counter() - t0
        assert _wait(lambda: "the run shown in the scene" in page.locator(".theoria-map").inner_html(), 30)
        shown = page.get_by_text("In the scene:").locator("xpath=..").inner_text()
        assert "Eccentricity" in shown or "eccentricity" in shown, shown
        page.wait_for_timeout(2500)  # a few frames of the replay
        OUT.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(OUT / f"sweep-{name}.png"))
        print(f"{name}: click → replay shown in {took:.2f} s")
    finally:
        ctx.close()
        server.stop()
