"""Screenshots of the ch. 16 scenes, run by hand (not a test):

    PYTHONPATH=. python tests/screenshots_ch16.py OUTDIR SPEC [SPEC ...]

SPEC = scenario[:clock[:key=0|1,...[:file-stem]]]: clock is the playback position (0..1, paused
there); key is one of the scenario's options (Scenario.options), or ov_<overlay> for an overlay.
The docs/screenshots of ch. 16 were made with

    libration-circular:0.3  moon:0.893  hyperion:0.3  precession-circular:0.5
    earth-long-view:0.6:pole_view=1,ov_axes=0,ov_vectors=0,ov_axis_trail=0

(moon at 0.893: the largest combined libration of the default run, −7.9° and +6.6°).
The scene is sent once more before the shot and the camera nudged: viser renders on change, and
labels are placed on render."""
import sys, time
from pathlib import Path
sys.path.insert(0, "tests")
from test_app_browser import CHROMIUM, ARGS, Page, _server
from playwright.sync_api import sync_playwright

OUT = Path(sys.argv[1]); OUT.mkdir(parents=True, exist_ok=True)
with sync_playwright() as p:
    b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
    for spec in sys.argv[2:]:
        parts = spec.split(":")
        name = parts[0]; clock = float(parts[1]) if len(parts) > 1 else 0.3
        opts = dict(kv.split("=") for kv in parts[2].split(",")) if len(parts) > 2 and parts[2] else {}
        server, sessions = _server(name)
        url = f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1"
        pg = Page(b, url)
        pg.page.wait_for_function("!document.body.innerText.includes('Connecting')", timeout=120000)
        t0 = time.time()
        while not sessions or next(iter(sessions.values())).result is None:
            time.sleep(0.5)
            if time.time() - t0 > 300: raise SystemExit("no result")
        s = next(iter(sessions.values()))
        s.playing = False
        for k, v in opts.items():
            if k.startswith("ov_"):
                s.toggles[k[3:]].value = v == "1"
            else:
                s.view_opts.options[k] = v == "1"
        with s._view_lock:  # the options, and the scene sent once more (labels are placed on render)
            s.drawing = s.spec.drawing(s.result, s.view_opts)
            s.view.clear()
            s.view.show(s.drawing, {k: bool(cb.value) for k, cb in s.toggles.items()})
        s.clock = clock
        s._show_clock(force=True)
        time.sleep(8.0)
        pg.assert_no_software_webgl_note()
        for k in range(3):  # a few moves: the canvas renders on change, and labels are placed on render
            s.clock = clock + 0.0005 * (k + 1)
            with s._view_lock:
                s._show_clock(force=True)
                if s.drawing.follow is None:
                    cam = s.client.camera
                    cam.position = tuple(float(x) * (1.0 + 1e-4 * (-1) ** k) for x in cam.position)
            time.sleep(1.5)
        time.sleep(1.5)
        tag = parts[3] if len(parts) > 3 else name
        pg.page.screenshot(path=str(OUT / f"{tag}.png"))
        print("shot", tag, "frame", s.view.frame, flush=True)
        pg.close(); server.stop()
    b.close()
