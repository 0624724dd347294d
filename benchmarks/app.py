"""Benchmarks of the web app and the replays, measured in headless Chromium
(Debian's /usr/bin/chromium, software WebGL) and with rerun, each against a baseline run in the
same process:

- app-slider-latency: a parameter change sent by the page (the slider's own GuiUpdateMessage) →
  server → re-simulation (middle-axis-flip defaults, 6001 samples) → scene update → the page's
  polhode geometry changed (checked every animation frame). Median of 7. Baseline: the 100 ms
  target for a slider to redraw (ratio = 0.1 s / measured; ≥ 1 meets it).
- app-playback-fps: frames per second in which the page shows a new body pose during playback of
  a 20001-sample run (3000 playback frames) drawn with its growing paths (polhode, herpolhode,
  rotation-axis trail; the default overlays of a ch. 15 scene), each densified by the renderer to
  at most 10⁴ points. theoria sends the paths once and moves poses and chunk visibility; baseline:
  the naive player that re-sends the same three growing trails, up to the current frame, every
  frame.
  Times are seconds per displayed frame (ratio = baseline / theoria). Software WebGL is bound by
  pixels, so the same playback is also measured in a 960×600 window, and the floor is shown: an
  empty viser page (no node, no control) asked to redraw every frame, in the 1280×800 window.
- record-1e5-steps: a 10⁵-step recording (free tumble, one sample per step) written column-wise
  (`theoria record`'s path: the drawing's playback frames, the energy, |L| and plot series on every
  step); baseline: the body, ω, L and the same series logged row by row (set_time + log per step)
  on 10⁴ steps, scaled ×10 (linear in steps; reported as baseline_extrapolated).
"""
from __future__ import annotations

import contextlib
import io
import os
import socket
import statistics
import tempfile
import threading
import time

import numpy as np

from . import register_bench

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
        "--disable-background-networking", "--disable-component-update", "--no-first-run"]
VIEWPORT = {"width": 1280, "height": 800}
# software WebGL is bound by pixels: the playback rate is also measured on a smaller window
SMALL_VIEWPORT = {"width": 960, "height": 600}
WAIT_MS = 120_000

SIG_JS = """(name) => { const o = window.__viserMutable && window.__viserMutable.nodeRefFromName[name];
  if (!o) return null; let n = 0, s = 0;
  o.traverse(c => { const g = c.geometry; if (!g || !g.attributes) return;
    for (const k in g.attributes) { const a = g.attributes[k]; const arr = a.array || (a.data && a.data.array);
      if (!arr) continue; n += arr.length; for (let i = 0; i < arr.length; i += 3) s += Math.abs(arr[i]); } });
  return [n, s]; }"""

LATENCY_JS = """([uuid, value]) => new Promise(resolve => {
  const sig = """ + SIG_JS + """;
  const name = '/world/body/polhode/0';
  const s0 = sig(name);
  const t0 = performance.now();
  window.__viserMutable.sendMessage({type: 'GuiUpdateMessage', uuid: uuid, updates: {value: value}});
  function loop() {
    const s = sig(name);
    if (s && (s[0] !== s0[0] || s[1] !== s0[1])) { resolve(performance.now() - t0); return; }
    if (performance.now() - t0 > 20000) { resolve(-1); return; }
    requestAnimationFrame(loop);
  }
  requestAnimationFrame(loop);
})"""

FPS_JS = """(seconds) => new Promise(resolve => {
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


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def _browser():
    from playwright.sync_api import sync_playwright

    if not os.path.exists(CHROMIUM):
        raise RuntimeError(f"needs Debian's chromium at {CHROMIUM}")
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            yield b
        finally:
            b.close()


def _open(browser, url, viewport=None):
    ctx = browser.new_context(viewport=viewport or VIEWPORT)
    page = ctx.new_page()
    page.goto(url)
    page.wait_for_function("!document.body.innerText.includes('Connecting')", timeout=WAIT_MS)
    page.wait_for_function("window.__viserMutable && window.__viserMutable.nodeRefFromName['/world/body/polhode/0']",
                           timeout=WAIT_MS)
    return ctx, page


def _quiet_server(**kw):
    from theoria.app.server import make_server

    with contextlib.redirect_stdout(io.StringIO()):
        return make_server(port=_free_port(), host="127.0.0.1", verbose=False, **kw)


def _wait_updates(session, n, timeout=120.0):
    t0 = time.time()
    while session.updates < n:
        if time.time() - t0 > timeout:
            raise RuntimeError("the app did not redraw")
        time.sleep(0.02)


@register_bench("app-slider-latency", needs=("playwright",))
def slider_latency():
    srv, sessions = _quiet_server(scenario="middle-axis-flip")
    try:
        with _browser() as b:
            ctx, page = _open(b, f"http://127.0.0.1:{srv.get_port()}/?fixedDpr=1")
            session = list(sessions.values())[-1]
            _wait_updates(session, 1)
            uuid = session.controls.handles["spin"]._impl.uuid  # a slider (the nudge is a typed field)
            lat, server = [], []
            for k, v in enumerate([5.0, 6.5, 4.2, 7.1, 3.3, 8.0, 5.5, 6.2]):
                ms = page.evaluate(LATENCY_JS, [uuid, v])
                if k > 0 and ms > 0:  # the first one warms up the path
                    lat.append(ms / 1000.0)
                    tm = session.timing
                    if "shown" in tm:
                        server.append(tm["shown"] - tm["request"])
                time.sleep(0.2)
            n = len(session.result.trajectory.t)
            ctx.close()
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            srv.stop()
    if not lat:
        raise RuntimeError("no redraw observed")
    med = statistics.median(lat)
    return {"theoria_s": med, "baseline_s": 0.1, "theoria_error": None, "baseline_error": None,
            "latency_ms_median": 1000 * med, "latency_ms_max": 1000 * max(lat), "samples": n,
            "server_ms_median": 1000 * statistics.median(server) if server else None,
            "note": "baseline = the 100 ms slider-to-redraw target"}


NAIVE_PATHS = ("axis_trail", "body/polhode", "herpolhode")  # the growing paths of a ch. 15 scene, shown by default


def _drawn_paths(drawing) -> dict:
    """The points theoria draws for each growing path (densified and thinned as the renderer does),
    with the frame at which each point appears: what a player that re-sends trails must send."""
    from theoria.app.scene import path_chunks

    out = {}
    for name in NAIVE_PATHS:
        it = drawing.item(name)
        pieces, starts, _, _ = path_chunks(it, grow_trails=True)
        pts = np.concatenate(pieces)
        # each chunk's points appear at its first frame; within it, in order over its time span
        ends = list(starts[1:]) + [drawing.n_frames]
        at = np.concatenate([np.linspace(a, b, len(p), endpoint=False) for p, a, b in zip(pieces, starts, ends)])
        out[name] = (pts.astype(np.float32), at)
    return out


def _naive_server(result, spec):
    """The naive player: the same drawing, but every frame re-sends the growing trails (rotation-axis
    trail, polhode, herpolhode) up to the current frame instead of sending them once."""
    import viser

    from theoria.app.scene import SceneView
    from theoria.app.worker import drawing_of

    with contextlib.redirect_stdout(io.StringIO()):
        server = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    stop = threading.Event()
    drawing = drawing_of(spec, result)
    paths = _drawn_paths(drawing)
    colours = {name: tuple(int(c) for c in drawing.item(name).color) for name in NAIVE_PATHS}
    sizes = {name: float(drawing.item(name).thickness) for name in NAIVE_PATHS}
    # the renderer draws everything else; the growing paths are left to the naive loop
    overlays = {g: on and g not in ("axis_trail", "polhode", "herpolhode") for g, on in drawing.overlays.items()}

    @server.on_client_connect
    def _(client):
        view = SceneView(client.scene, "/world", grow_trails=False)
        view.show(drawing, overlays)

        def cloud(name, pts, col, size):
            client.scene.add_point_cloud(name, pts, col, point_size=size, point_shape="square",
                                         precision="float32", point_shading="flat")

        # the node the page waits for (and the latency probe reads) before playback starts
        cloud("/world/body/polhode/0", paths["body/polhode"][0][:2], colours["body/polhode"], sizes["body/polhode"])

        def play():
            t0 = time.perf_counter()
            while not stop.is_set():
                frac = ((time.perf_counter() - t0) / 20.0) % 1.0
                k = int(frac * (drawing.n_frames - 1))
                try:
                    with client.atomic():
                        view.set_frame(k)
                        for name, (pts, at) in paths.items():
                            j = max(2, int(np.searchsorted(at, k, side="right")))
                            node = "/world/body/polhode/0" if name == "body/polhode" else f"/world/naive/{name}"
                            cloud(node, pts[:j], colours[name], sizes[name])
                except Exception:
                    return
                time.sleep(1 / 60)

        threading.Thread(target=play, daemon=True).start()

    return server, stop, {name: len(p[0]) for name, p in paths.items()}


RENDER_JS = """(seconds) => new Promise(resolve => {
  const M = window.__viserMutable; let frames = 0; const t0 = performance.now();
  function loop() { M.requestRender(); frames++;
    if (performance.now() - t0 < seconds * 1000) requestAnimationFrame(loop);
    else resolve(frames / ((performance.now() - t0) / 1000)); }
  requestAnimationFrame(loop); })"""


def _theoria_playback(b, viewport) -> dict:
    """Playback of the 20001-sample run in theoria's own page: all three paths, then one, then none."""
    out = {}
    server, sessions = _quiet_server(scenario="middle-axis-flip")
    try:
        ctx, page = _open(b, f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1", viewport)
        session = list(sessions.values())[-1]
        _wait_updates(session, 1)
        n = session.updates
        session.request({**session.controls.values(), "duration": 100.0, "step": 0.005})
        _wait_updates(session, n + 1)
        time.sleep(1.0)
        out["theoria"] = page.evaluate(FPS_JS, 4)
        with session._view_lock:  # the same body with only one path (rotation-axis trail, ~10⁴ points)
            for k in list(session.view.overlays):
                session.view.set_overlay(k, k in ("axes", "vectors", "axis_trail"))
        time.sleep(1.0)
        out["one_trail"] = page.evaluate(FPS_JS, 3)
        with session._view_lock:
            for k in list(session.view.overlays):
                session.view.set_overlay(k, False)
        time.sleep(1.0)
        out["no_paths"] = page.evaluate(FPS_JS, 3)
        out["frames"] = int(session.drawing.n_frames)  # playback frames of the run (a trail grows over them)
        out["samples"] = len(session.result.trajectory.t)
        ctx.close()
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
    return out


def _empty_page_fps(b, viewport) -> float:
    """Frames per second of an empty viser page (no node, no control) asked to redraw every frame:
    the floor the browser's renderer sets before theoria draws anything."""
    import viser

    with contextlib.redirect_stdout(io.StringIO()):
        server = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    try:
        server.scene.world_axes.visible = False
        ctx = b.new_context(viewport=viewport)
        page = ctx.new_page()
        page.goto(f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1")
        page.wait_for_function("window.__viserMutable && window.__viserMutable.scene", timeout=WAIT_MS)
        time.sleep(1.0)
        fps = page.evaluate(RENDER_JS, 3)
        ctx.close()
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
    return fps


@register_bench("app-playback-fps", needs=("playwright",))
def playback_fps():
    from theoria.scenarios import get

    spec = get("middle-axis-flip")
    given = {"duration": "100", "step": "0.005"}  # 20001 samples → paths of up to 10⁴ points
    result = spec.simulate_fn(spec.resolve(given))
    out = {}
    with _browser() as b:
        out = _theoria_playback(b, VIEWPORT)
        small = _theoria_playback(b, SMALL_VIEWPORT)["theoria"]
        empty = _empty_page_fps(b, VIEWPORT)
        server, stop, path_points = _naive_server(result, spec)
        try:
            ctx, page = _open(b, f"http://127.0.0.1:{server.get_port()}/?fixedDpr=1")
            time.sleep(1.0)
            out["naive"] = page.evaluate(FPS_JS, 4)
            ctx.close()
        finally:
            stop.set()
            with contextlib.redirect_stdout(io.StringIO()):
                server.stop()
    fps = out["theoria"]["poses"] / out["theoria"]["seconds"]
    fps_naive = out["naive"]["poses"] / out["naive"]["seconds"]
    return {"theoria_s": 1.0 / fps, "baseline_s": 1.0 / max(fps_naive, 1e-9), "theoria_error": None,
            "baseline_error": None, "fps": fps, "fps_naive_resend": fps_naive, "frames": out["frames"],
            "path_points": path_points,
            "render_fps": out["theoria"]["frames"] / out["theoria"]["seconds"],
            "fps_one_10k_trail": out["one_trail"]["poses"] / out["one_trail"]["seconds"],
            "fps_body_only": out["no_paths"]["poses"] / out["no_paths"]["seconds"],
            f"fps_at_{SMALL_VIEWPORT['width']}x{SMALL_VIEWPORT['height']}": small["poses"] / small["seconds"],
            "empty_viser_page_fps": empty, "samples": out["samples"],
            "viewport": f"{VIEWPORT['width']}x{VIEWPORT['height']}"}


def _long_result(steps=100_000):
    from theoria.physics.integrator import integrate
    from theoria.scenarios import get
    from theoria.scenarios.base import Run
    from theoria.physics.trajectory import Trajectory

    spec = get("free-tumble")
    I = np.array([2.0, 3.0, 4.0])
    w0 = np.array([1.0, 0.5, 1.5])
    h = 0.01
    t, L, q = integrate(I, w0, steps * h, h, stride=1)
    traj = Trajectory(t, q, L, I)
    res = Run("free-tumble", spec.resolve({"duration": str(steps * h), "step": str(h)}), traj,
                 {"energy_J": float(traj.energy[0])},
                 plot_series={"ω₁": traj.omega_body[:, 0], "ω₂": traj.omega_body[:, 1], "ω₃": traj.omega_body[:, 2]})
    return spec, res


def _naive_record(res, out, steps):
    import rerun as rr

    from theoria.physics.quaternion import to_xyzw

    traj = res.trajectory
    rec = rr.RecordingStream("theoria-naive")
    try:
        rec.save(out)
        q = to_xyzw(traj.quat_wxyz)
        for i in range(steps):
            rec.set_time("step", sequence=i)
            rec.set_time("t", duration=float(traj.t[i]))
            rec.log("/world/body", rr.Transform3D(quaternion=q[i]))
            rec.log("/world/omega", rr.Arrows3D(vectors=[traj.omega_inertial[i]]))
            rec.log("/world/L", rr.Arrows3D(vectors=[traj.L_inertial[i]]))
            rec.log("/series/energy", rr.Scalars(traj.energy[i]))
            rec.log("/series/momentum_norm", rr.Scalars(traj.momentum_norm[i]))
            for k, c in enumerate("xyz"):
                rec.log(f"/series/omega/{c}", rr.Scalars(traj.omega_body[i, k]))
            for name, v in res.plot_series.items():
                rec.log(f"/series/plot/{name}", rr.Scalars(v[i]))
    finally:
        rec.disconnect()


@register_bench("record-1e5-steps")
def record_steps():
    from theoria.app.record import record_run

    steps = 100_000
    spec, res = _long_result(steps)
    n = len(res.trajectory.t)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "run.rrd")
        t0 = time.perf_counter()
        info = record_run(res, path)  # the drawing's frames and every step's series, column-wise
        t_ours = time.perf_counter() - t0
        size = os.path.getsize(path)
        sub = 10_000
        t0 = time.perf_counter()
        _naive_record(res, os.path.join(d, "naive.rrd"), sub)
        t_naive = (time.perf_counter() - t0) * (n / sub)
    return {"theoria_s": t_ours, "baseline_s": t_naive, "theoria_error": None, "baseline_error": None,
            "steps": n, "frames": info["frames"], "size_MB": size / 1e6, "baseline_extrapolated": f"row-by-row on {sub} steps x {n / sub:.1f}"}
