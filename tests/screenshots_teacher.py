"""Screenshots of every scenario as a class sees it, into docs/screenshots/: <name>.png at 1280×800
(the panel on its Explore tab) and <name>-present.png in presenter mode at 1920×1080 (key P).

    python tests/screenshots_teacher.py [NAME ...]

Each scenario runs at its defaults (what `theoria serve` shows first). Labels in software WebGL
take a while to build: each shot waits LABEL_WAIT_S after the scene is shown.
"""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from test_app_browser import ARGS, CHROMIUM, _free_port  # noqa: E402

OUT = HERE.parent / "docs" / "screenshots"
LABEL_WAIT_S = float(os.environ.get("LABEL_WAIT_S", "20"))


def main(names: list[str]) -> None:
    from playwright.sync_api import sync_playwright

    from theoria.app.server import make_server
    from theoria.scenarios import all_scenarios

    specs = [s for s in all_scenarios() if not names or s.name in names]
    server, sessions = make_server(port=_free_port(), host="127.0.0.1", verbose=False)
    base = f"http://127.0.0.1:{server.get_port()}/"
    OUT.mkdir(parents=True, exist_ok=True)
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            for spec in specs:
                before = set(sessions)
                ctx = browser.new_context(viewport={"width": 1280, "height": 800})
                page = ctx.new_page()
                t0 = time.time()
                page.goto(base + f"?fixedDpr=1&s={spec.name}")
                s = None
                while time.time() - t0 < 900:
                    new = [v for k, v in list(sessions.items()) if k not in before]
                    if new and new[-1].updates >= 1:
                        s = new[-1]
                        break
                    time.sleep(0.5)
                if s is None:
                    print(f"{spec.name}: no scene", flush=True)
                    ctx.close()
                    continue
                shown = time.time() - t0
                time.sleep(LABEL_WAIT_S)
                # paused a moment into the run: in software WebGL the labels of a fast-turning body
                # trail it while it plays
                page.mouse.click(200, 700)
                page.keyboard.press("Space")
                time.sleep(5)
                page.screenshot(path=str(OUT / f"{spec.name}.png"))
                page.keyboard.press("p")
                page.set_viewport_size({"width": 1920, "height": 1080})
                time.sleep(LABEL_WAIT_S)
                time.sleep(0.5)
                page.screenshot(path=str(OUT / f"{spec.name}-present.png"))
                print(f"{spec.name}: scene after {shown:.0f} s, present={s.present}", flush=True)
                ctx.close()
            browser.close()
    finally:
        server.stop()


if __name__ == "__main__":
    main(sys.argv[1:])
