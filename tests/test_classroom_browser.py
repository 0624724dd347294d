"""The first minutes of a class in a real headless Chromium (Debian's /usr/bin/chromium driven
by Playwright; never a downloaded browser): `theoria serve` started as a teacher starts it, on a
fresh install (an empty numba cache, no stored runs), the page opened when the URL is printed in a
browser that was already running (as a teacher's is).

What is asserted: the page is never blank (from its first frame there is either the loading
line, saying what is happening, or the scene); viser's developer panel (websocket address, "Save
Canvas", "Dev Settings", scene tree) is never shown; the tab is titled "theoria — <scenario>";
the first scene arrives; then every scenario switch first shows something (the panel names the
new scenario) and then its full scene (the tab title follows the drawn scene). The times are
measured and printed, not asserted: the machine is shared.

Run: pytest -m browser tests/test_classroom_browser.py -s
"""
from __future__ import annotations

import os
import tempfile
import time

import pytest

pytestmark = pytest.mark.browser

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
        "--disable-background-networking", "--disable-component-update", "--no-first-run"]
WAIT_S = 300.0  # generous: a fresh install compiles; 2 shared cores (not a performance limit)

STATE_JS = """() => {
  const l = document.getElementById('theoria-loading');
  const loading = l && getComputedStyle(l).display !== 'none' ? l.textContent.trim() : '';
  const M = window.__viserMutable;
  const nodes = M && M.nodeRefFromName ? Object.keys(M.nodeRefFromName).filter(k => k.startsWith('/world/')).length : 0;
  const dev = Array.from(document.querySelectorAll('*')).some(e => e.childElementCount === 0
      && ['Dev Settings', 'Save Canvas', 'Scene tree', 'Connected'].includes(e.textContent.trim())
      && getComputedStyle(e).visibility !== 'hidden' && (() => { const r = e.getBoundingClientRect();
        if (r.width <= 0 || r.height <= 0) return false;  // on top at its centre: what a person sees
        const top = document.elementFromPoint(r.x + r.width / 2, r.y + r.height / 2);
        return top !== null && (top === e || e.contains(top)); })());
  return {loading, nodes, dev, title: document.title, text: document.body.innerText.slice(0, 4000)};
}"""


def _have_browser() -> bool:
    try:
        import playwright  # noqa: F401
    except ImportError:
        return False
    return os.path.exists(CHROMIUM)


if not _have_browser():
    pytest.skip("needs Debian's chromium at /usr/bin/chromium and python playwright", allow_module_level=True)


def first_scene(scenario: str = "free-tumble", env: dict | None = None, switch_all: bool = False,
                sample_s: float = 0.1) -> dict:
    """Start `theoria serve`, open the page at the moment the URL is printed, and watch it. Returns
    the seconds from the URL to the first scene, the samples of what the page showed, and (with
    `switch_all`) per scenario the seconds to something and to the full scene."""
    from playwright.sync_api import sync_playwright

    from theoria.app.gallery import label
    from theoria.benchmarks.classroom import _free_port, start_server_process, wait_line
    from theoria.scenarios.base import all_scenarios

    port = _free_port()
    lines: list = []
    out: dict = {"samples": [], "switches": []}
    srv = None
    try:
        with sync_playwright() as p:
            # the teacher's browser is open before the server starts; the clock runs from the URL
            b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            ctx = b.new_context(viewport={"width": 1280, "height": 800})
            outside = []

            def route(r):
                u = r.request.url
                if u.startswith(("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:", "about:")):
                    r.continue_()
                else:
                    outside.append(u)
                    r.abort()

            ctx.route("**/*", route)
            page = ctx.new_page()
            page.goto("about:blank")
            t0 = time.perf_counter()
            srv = start_server_process(port, scenario, (), env=env, lines=lines)
            t_url = wait_line(lines, "open http", 120)
            assert t_url is not None, lines
            out["server_start_s"] = t_url - t0
            page.goto(f"http://127.0.0.1:{port}/?fixedDpr=1", wait_until="commit")
            while True:
                now = time.perf_counter() - t_url
                st = page.evaluate(STATE_JS)
                st["t"] = now
                out["samples"].append(st)
                if st["nodes"] and not st["loading"]:
                    out["first_scene_s"] = now
                    break
                assert now < WAIT_S, st
                time.sleep(sample_s)
            if switch_all:
                specs = [s for s in all_scenarios() if s.name != scenario]
                for spec in specs:
                    cur = page.evaluate("""() => { const i = Array.from(document.querySelectorAll('input'))
                        .find(i => i.value && i.value.includes(' · ') && i.type !== 'hidden');
                        if (i) i.setAttribute('data-theoria', 'scenario'); return i ? i.value : null; }""")
                    assert cur is not None
                    page.locator('input[data-theoria="scenario"]').click()
                    t_click = time.perf_counter()
                    page.get_by_role("option", name=label(spec)).click()
                    something = full = None
                    while full is None:
                        st = page.evaluate(STATE_JS)
                        dt = time.perf_counter() - t_click
                        if something is None and spec.title in st["text"]:
                            something = dt
                        if st["title"] == f"theoria — {spec.name}" and st["nodes"]:
                            full = dt
                            something = something if something is not None else dt
                        assert dt < WAIT_S, (spec.name, st["title"])
                        assert not st["dev"], (spec.name, "developer panel shown")
                        time.sleep(sample_s / 2)
                    out["switches"].append((spec.name, something, full))
            out["outside"] = outside
            ctx.close()
            b.close()
    finally:
        if srv is not None:
            srv.terminate()
            try:
                srv.wait(20)
            except Exception:
                srv.kill()
    out["server_lines"] = [x[2] for x in lines]
    return out


def _fresh_env(tmp) -> dict:
    env = dict(os.environ)
    env["NUMBA_CACHE_DIR"] = os.path.join(tmp, "numba")  # nothing compiled yet
    env["THEORIA_CACHE_DIR"] = os.path.join(tmp, "theoria")  # no stored runs
    return env


def _check_never_blank(out: dict, scenario: str) -> None:
    for st in out["samples"]:
        assert st["loading"] or st["nodes"], f"blank page at {st['t']:.2f} s"
        assert not st["dev"], f"developer panel shown at {st['t']:.2f} s"
        assert st["title"].startswith("theoria"), st["title"]
    last = out["samples"][-1]
    assert last["title"] == f"theoria — {scenario}"
    # nothing failed on the way: on a fresh install the pure-Python simulation process (which serves
    # the first scenes while numba compiles) once died at import, printing tracebacks to the terminal
    assert not [x for x in out["server_lines"] if "Traceback" in x], out["server_lines"]
    assert out["outside"] == []


def test_first_scene_on_a_fresh_install_is_never_blank():
    with tempfile.TemporaryDirectory() as tmp:
        out = first_scene("free-tumble", env=_fresh_env(tmp))
    _check_never_blank(out, "free-tumble")
    seen = {}
    for st in out["samples"]:
        if st["loading"] and st["loading"] not in seen:
            seen[st["loading"]] = round(st["t"], 2)
    print(f"\nfresh install: URL after {out['server_start_s']:.1f} s, first scene {out['first_scene_s']:.2f} s "
          f"after the URL (load {os.getloadavg()[0]:.1f}); the loading line said (first seen, s): {seen}")


def test_every_scenario_switch_shows_something_then_its_scene():
    out = first_scene("free-tumble", switch_all=True)  # this machine's caches, as a second class would find them
    for st in out["samples"]:
        assert st["loading"] or st["nodes"], f"blank page at {st['t']:.2f} s"
        assert not st["dev"]
    from theoria.scenarios.base import all_scenarios

    assert len(out["switches"]) == len(all_scenarios()) - 1
    print(f"\nfirst scene {out['first_scene_s']:.2f} s after the URL (load {os.getloadavg()[0]:.1f})")
    for name, something, full in out["switches"]:
        print(f"  {name:28s} something {something:5.2f} s  full scene {full:5.2f} s")


def test_a_tab_over_the_limit_says_what_to_do_and_connects_when_one_closes():
    """A student's eleventh tab (the server takes ten from one address) showed "theoria —
    connecting…" for ever: the server refuses its socket, and the page never said why. After
    CONNECT_HINT_S the line says what to try; closing a tab lets it in. Here with one tab per
    address."""
    from playwright.sync_api import sync_playwright

    from theoria.app.page import CONNECT_HINT, CONNECT_HINT_S
    from theoria.benchmarks.classroom import _free_port, start_server_process, wait_line

    port = _free_port()
    lines: list = []
    srv = start_server_process(port, "free-tumble", ("--max-per-address", "1"), lines=lines)
    try:
        assert wait_line(lines, "open http", 120) is not None, lines
        with sync_playwright() as p:
            b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            ctx = b.new_context(viewport={"width": 1280, "height": 800})
            url = f"http://127.0.0.1:{port}/?fixedDpr=1"
            first = ctx.new_page()
            first.goto(url)
            t_end = time.monotonic() + WAIT_S
            while first.evaluate(STATE_JS)["loading"] or not first.evaluate(STATE_JS)["nodes"]:
                assert time.monotonic() < t_end
                time.sleep(0.2)
            second = ctx.new_page()
            t0 = time.monotonic()
            second.goto(url)
            while second.evaluate(STATE_JS)["loading"] != CONNECT_HINT:
                assert time.monotonic() - t0 < CONNECT_HINT_S + 30, second.evaluate(STATE_JS)["loading"]
                time.sleep(0.5)
            assert time.monotonic() - t0 >= CONNECT_HINT_S - 1  # not before a slow start could have connected
            first.close()  # the student closes a tab: the other one is let in
            t_end = time.monotonic() + WAIT_S
            while True:
                st = second.evaluate(STATE_JS)
                if st["nodes"] and not st["loading"]:
                    break
                assert time.monotonic() < t_end, st["loading"]
                time.sleep(0.5)
            b.close()
    finally:
        srv.terminate()
        try:
            srv.wait(20)
        except Exception:
            srv.kill()
