"""`theoria export NAME --out FILE.html`: a standalone HTML replay of the scene.

A private viser server (127.0.0.1, a free port, no client needed) builds the same SceneView on
`server.scene`; viser's scene serializer records the nodes once and then, frame by frame, only
the pose of the body, the two arrows and the visibility of the trail chunks (a growing trail
re-sent each frame would make the file grow quadratically). `as_html()` inlines the viser client
and the recording: the file plays from file:// with no server and no network.
"""
from __future__ import annotations

import contextlib
import io
import socket

import numpy as np
import viser

from .scene import SceneView
from .server import camera_position, configure_lighting

FRAMES = 240  # frames in the replay
# identifies theoria's own export (checked by `theoria replay FILE.html`, app/replay.py)
MARKER = '<meta name="generator" content="theoria export_html" data-theoria-scenario="{name}" />'

FPS = 30.0


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def export_result(result, spec, out: str, frames: int = FRAMES, fps: float = FPS) -> dict:
    with contextlib.redirect_stdout(io.StringIO()):  # no URL banner: nobody connects to this one
        server = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    try:
        server.scene.set_up_direction("+z")
        configure_lighting(server.scene)
        server.initial_camera.position = camera_position(spec)
        server.initial_camera.look_at = (0.0, 0.0, 0.0)
        server.initial_camera.up = (0.0, 0.0, 1.0)
        view = SceneView(server.scene, "/world")
        view.show(result, spec)
        server.scene.add_label("/title", f"{spec.title} ({spec.section})", position=(0.0, 0.0, 2.0))
        ser = server.get_scene_serializer()
        n = len(result.trajectory.t)
        idx = np.unique(np.linspace(0, n - 1, min(frames, n)).round().astype(int))
        for i in idx:
            view.set_frame(int(i))
            ser.insert_sleep(1.0 / fps)
        html = ser.as_html()
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
    html = html.replace("<head>", "<head>\n    " + MARKER.format(name=spec.name), 1)
    with open(out, "w", encoding="utf-8") as f:
        f.write(html)
    return {"path": out, "frames": int(len(idx)), "bytes": len(html.encode())}


def export(name: str, out: str, values: dict | None = None) -> dict:
    """Simulate scenario `name` with resolved parameter `values`; write a standalone HTML replay."""
    from theoria.scenarios import get

    spec = get(name)
    values = spec.resolve(values) if values is not None else spec.resolve(None)
    result = spec.simulate_fn(values)
    return export_result(result, spec, out)
