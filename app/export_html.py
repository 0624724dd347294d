"""`theoria export NAME --out FILE.html`: a standalone HTML replay of a run's drawing.

The same viser renderer as the live app (`app.scene.SceneView`) draws the run's `Drawing` on a
private viser server (127.0.0.1, a free port, no client); viser's scene serializer records the
nodes once and then, frame by frame, only what moves (poses, arrows, trail-chunk visibility, read-
outs). `as_html()` inlines the viser client and the recording: the file plays from file:// with no
server and no network. The camera starts where the app's does, looking at the same point, and a
panel carries the scenario's title, §, what to look for, Euler's formula and the Euler /
simulated / modern table (the serializer records no GUI, so the text is written into the page).
The page is built in memory and written whole or not at all (`app.files.write_whole`: a temporary
file beside the target, renamed over it once complete; a full disk or an interruption leaves an
older file as it was).
"""
from __future__ import annotations

import contextlib
import html as html_lib
import io
import socket

import numpy as np
import viser

from .files import write_whole
from .interrupt import signals_held
from .page import SOFTWARE_GL_JS
from .replay import HTML_DIGEST_BLANK, html_digest
from .scene import SceneView

FRAMES = 240  # frames in the replay
FPS = 30.0
# identifies theoria's own export (checked by `theoria replay FILE.html`, app/replay.py)
MARKER = ('<meta name="generator" content="theoria export_html" data-theoria-scenario="{name}" '
          'data-sha256="{digest}" />')


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def configure_scene(scene) -> None:
    """Plain lights, no image-based environment map and no shadows: in software WebGL
    (SwiftShader) the environment map alone takes the body scene from ~28 to ~10 frames/s."""
    scene.set_up_direction("+z")
    scene.configure_environment_map(hdri=None)
    scene.configure_default_lights(enabled=True, cast_shadow=False)
    scene.add_light_ambient("/lights/ambient", intensity=1.2)


PANEL_PX = 380  # the text's column; the scene takes the rest of a wide window


def text_panel(drawing, run, frames: int = FRAMES, fps: float = FPS) -> str:
    """The scenario's text as a column left of the scene (above it in a small window, both
    scrolling): its title, §, what to look for, the run's time span, Euler's formula and the
    Compare table as the app writes it (the same words, units and verdicts; the run's warnings
    first). The scene's canvas is moved beside (or below) the column, so that the column covers
    none of it (over the canvas, the table was cut to 45 % of the window and a scene's inset plot
    sat on it)."""
    from .format import human_number
    from .panel import compare_html

    e = html_lib.escape
    formula = "".join(f"<div class='f'>{e(line)}</div>" for line in drawing.formula.splitlines() if line.strip())
    # the bar below counts the replay's own seconds ("3.2"), not the run's time (a 200-s run)
    t, c = np.asarray(drawing.times, float), drawing.clock
    replay_s = min(frames, drawing.n_frames) / fps
    span = f"{human_number(t[0] * c.scale)} to {human_number(t[-1] * c.scale)}" + (f" {c.words}" if c.words else "")
    clock = (f"<p style='color:#555'>The bar below plays the whole run ({e(c.name)} = {e(span)}) in {replay_s:.0f} s; "
             "its box counts those seconds of replay.</p>") if len(t) > 1 else ""
    wide = f"@media (min-width:{2 * PANEL_PX + 120}px)"
    narrow = f"@media (max-width:{2 * PANEL_PX + 119}px)"  # a phone, a small window: the text above the scene
    return (
        f"<div id='theoria-text' style='position:fixed;top:8px;left:8px;width:{PANEL_PX}px;max-width:calc(100vw - 40px);"
        "max-height:45vh;overflow:auto;background:rgba(255,255,255,0.92);font:13px/1.35 sans-serif;"
        "padding:8px 10px;border-radius:6px;z-index:10;box-sizing:border-box'>"
        "<style>#theoria-text .f{font-family:serif;font-style:italic}"
        f"{wide}{{#theoria-text{{max-height:calc(100vh - 72px)!important}}"
        f"#root{{position:fixed!important;left:{PANEL_PX + 16}px!important;top:0;right:0;bottom:0;"
        "width:auto!important}}"
        f"{narrow}"  # (plain strings from here: their braces are the CSS's own)
        "{#theoria-text{left:0!important;top:0!important;width:100vw!important;max-width:none!important;"
        "max-height:38vh!important;border-radius:0!important}"
        "#root{position:fixed!important;top:38vh!important;left:0;right:0;bottom:0;height:auto!important}}</style>"
        f"<b>{e(drawing.title)}</b> <span style='color:#555'>({e(drawing.section)})</span>"
        f"<p>{e(drawing.summary)}</p>{clock}{formula}<div style='margin:0 -12px'>{compare_html(run)}</div></div>")


def render_html(drawing, run, frames: int = FRAMES, fps: float = FPS) -> str:
    """The standalone replay of `drawing` (of `run`) as one HTML string."""
    with contextlib.redirect_stdout(io.StringIO()):  # no URL banner: nobody connects to this one
        server = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    try:
        configure_scene(server.scene)
        cam = drawing.camera
        server.initial_camera.position = cam.position
        server.initial_camera.look_at = cam.look_at
        server.initial_camera.up = cam.up
        if cam.fov_deg is not None:
            server.initial_camera.fov = float(np.radians(cam.fov_deg))
        view = SceneView(server.scene, "/world")
        view.show(drawing)
        ser = server.get_scene_serializer()
        n = drawing.n_frames
        for k in np.unique(np.linspace(0, n - 1, min(frames, n)).round().astype(int)):
            view.set_frame(int(k))
            ser.insert_sleep(1.0 / fps)
        page = ser.as_html()
    finally:
        # viser's server thread says "Server stopped" on stdout as it ends: the redirection lasts
        # until it has, and a Ctrl-C meanwhile waits (the line came out before "interrupted")
        with signals_held(), contextlib.redirect_stdout(io.StringIO()):
            server.stop()
            thread = getattr(getattr(server, "_websock_server", None), "_server_thread", None)
            if thread is not None:  # stop() waits a second for it, a loaded machine may take longer
                thread.join(timeout=10.0)
    marker = MARKER.format(name=html_lib.escape(run.scenario), digest=HTML_DIGEST_BLANK)
    # the live page's own start: no "Software WebGL rendering detected" notice over the replay,
    # and no multisampling where WebGL runs in software (app/page.py)
    page = page.replace("<head>", "<head>\n    " + marker +
                        f"\n    <title>theoria — {html_lib.escape(drawing.title)}</title>"
                        f"\n    <script>{SOFTWARE_GL_JS}</script>", 1)
    text = text_panel(drawing, run, frames, fps)
    page = (page.replace("<body>", "<body>\n" + text, 1) if "<body>" in page
            else page.replace("</body>", text + "</body>", 1))
    # the digest of the whole page goes into its marker: `theoria replay` finds a damaged copy
    return page.replace(f'data-sha256="{HTML_DIGEST_BLANK}"', f'data-sha256="{html_digest(page)}"', 1)


def export_run(run, out, frames: int = FRAMES, fps: float = FPS, view=None) -> dict:
    """Write the standalone HTML replay of `run` to `out`."""
    drawing = run._spec().drawing(run, view)
    page = render_html(drawing, run, frames, fps)
    data = page.encode("utf-8")
    write_whole(out, data)
    return {"path": str(out), "frames": int(min(frames, drawing.n_frames)), "bytes": len(data)}


def export(name: str, out: str, values: dict | None = None) -> dict:
    """Simulate scenario `name` with `values` and write its standalone HTML replay."""
    from theoria.scenarios import get

    spec = get(name)
    run = spec.simulate_fn(spec.resolve(values))
    return export_run(run, out)
