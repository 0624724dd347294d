"""A classroom on one laptop: thirty browsers on one `theoria serve`.

The server runs in its own process (`python -m theoria.app.cli serve`), exactly as a teacher starts
it; its resident memory is read with psutil. The thirty clients are protocol-level viser
clients (`ViserProtocolClient`), not Chromium tabs (thirty software-WebGL tabs do not fit on
two cores): each speaks viser's own websocket protocol as the page's worker does
(viser/client/src/WebsocketClientWorker.ts) --

- subprotocol ``viser-v<version>``; the server registers a client (and theoria builds its
  `ClientSession`) only after the first ``ViewerCameraMessage``, which the page sends on load;
- client → server: one msgpack dict per websocket message (``{"type": "GuiUpdateMessage",
  "uuid": ..., "updates": {"value": ...}}`` is what a slider sends);
- server → client: ``[8 B msgpack size][8 B zstd size][zstd(msgpack {"messages": [...]})]
  [aligned raw binary buffers]``. Every frame is decoded (zstd + msgpack) like the page does,
  including the 60 Hz playback stream, so the server pays the full per-client cost.

Slider-to-redraw latency: the client sends the slider's GuiUpdateMessage and stops the clock
when the batch holding the new scene arrives -- the path point clouds of the new result
(``.../polhode/...``, a new point cloud or an in-place ``points`` update) and the status line "(update #k)" with k larger than before (both are
sent in one `client.atomic()` batch after the re-simulation). The page's own drawing time is
not included (measured separately in Chromium by `app-slider-latency`).

Each client is a student: it waits for the first scene, then moves the "Spin rate" slider
of middle-axis-flip (6001-sample re-simulation) to a random value, waits for the redraw, thinks
for 1–4 s, and moves it again, until the soak ends. Memory: the server's RSS sampled every
2 s; "flat" is judged from the last half of the soak (slope in MB/min) and first/last values.

Duration: env THEORIA_SOAK_S (default 60 s for `theoria bench`); the 30-minute soak is
`THEORIA_SOAK_S=1800 python -m theoria.benchmarks.classroom`.
"""
from __future__ import annotations

import asyncio
import json
import os
import random
import socket
import subprocess
import sys
import time

import numpy as np

from . import register_bench

N_CLIENTS = 30
SCENARIO = "middle-axis-flip"
SLIDER = "Spin rate"  # the label of middle-axis-flip's spin slider starts so
REDRAW_TIMEOUT_S = 30.0
THINK_S = (1.0, 4.0)


def _decode_frame(buf: bytes) -> list[dict]:
    """One server → client websocket frame → list of message dicts (binary buffers ignored)."""
    import msgspec
    import zstandard

    n = int.from_bytes(buf[0:8], "little")
    c = int.from_bytes(buf[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(buf[16:16 + c], max_output_size=n)
    return msgspec.msgpack.decode(inner)["messages"]


class ViserProtocolClient:
    """A browser tab as the server sees it: websocket + viser's wire format, no rendering."""

    def __init__(self, url: str):
        self.url = url
        self.ws = None
        self.labels: dict[str, str] = {}  # gui label → uuid
        self.values: dict[str, object] = {}  # gui uuid → last value sent by the server
        self.status_uuid: str | None = None
        self.markdown: dict[str, str] = {}  # markdown uuid → content (info, Euler table, status)
        self.notifications: list[tuple[str, str]] = []  # (title, body) as the page would pop them up
        self.update_no = 0  # k of the last "(update #k)" seen
        self.scene_names: set[str] = set()
        self.path_msgs = 0  # path point-cloud messages received (scene rebuilds)
        self.frames = 0
        self.messages = 0
        self.changed = asyncio.Event()
        self._reader = None

    async def connect(self) -> None:
        import msgspec
        import viser
        import websockets

        self.ws = await websockets.connect(self.url, subprotocols=[f"viser-v{viser.__version__}"],
                                           max_size=None, compression=None, open_timeout=60)
        # what the page sends once its canvas exists; registers the client with the server
        await self.ws.send(msgspec.msgpack.encode({
            "type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [3.0, 2.0, 2.0],
            "fov": 1.3, "near": 0.01, "far": 1000.0, "image_height": 800, "image_width": 1280,
            "look_at": [0.0, 0.0, 0.0], "up_direction": [0.0, 0.0, 1.0]}))
        self._reader = asyncio.create_task(self._read())

    async def _read(self) -> None:
        try:
            async for raw in self.ws:
                self.frames += 1
                for m in _decode_frame(raw):
                    self._handle(m)
                self.changed.set()
        except Exception:
            pass
        finally:
            self.changed.set()

    def _handle(self, m: dict) -> None:
        self.messages += 1
        typ = m.get("type", "")
        if "Notification" in typ and isinstance(m.get("props"), dict) and "title" in m["props"]:
            self.notifications.append((m["props"].get("title", ""), m["props"].get("body", "")))
        if typ.startswith("Gui") and "props" in m and isinstance(m["props"], dict):
            label = m["props"].get("label")
            if label:
                self.labels[label] = m["uuid"]
            content = m["props"].get("_markdown", m["props"].get("content"))
            if isinstance(content, str):
                self.markdown[m["uuid"]] = content

            if isinstance(content, str) and content.startswith("*simulat"):
                self.status_uuid = m["uuid"]
                self._status(content)
            if "value" in m:
                self.values[m["uuid"]] = m["value"]
        elif typ == "GuiUpdateMessage":
            up = m.get("updates", {})
            if m.get("uuid") in self.markdown and "_markdown" in up:
                self.markdown[m["uuid"]] = up["_markdown"]
            if m.get("uuid") == self.status_uuid:
                for key in ("_markdown", "content"):
                    if key in up:
                        self._status(up[key])
            if "value" in up:
                self.values[m["uuid"]] = up["value"]
        name = m.get("name")
        if isinstance(name, str):
            self.scene_names.add(name)
            if "polhode/" in name and (typ.endswith("PointCloudMessage") or (
                    typ == "SceneNodeUpdateMessage" and "points" in m.get("updates", {}))):
                self.path_msgs += 1

    def _status(self, content: str) -> None:
        if "(update #" in content:
            self.update_no = int(content.split("(update #")[1].split(")")[0])

    def uuid_of(self, label_prefix: str) -> str:
        for label, uuid in self.labels.items():
            if label.startswith(label_prefix):
                return uuid
        raise KeyError(label_prefix)

    async def wait_for(self, cond, timeout: float) -> bool:
        t_end = time.perf_counter() + timeout
        while not cond():
            left = t_end - time.perf_counter()
            if left <= 0 or (self._reader is not None and self._reader.done()):
                return cond()
            self.changed.clear()
            try:
                await asyncio.wait_for(self.changed.wait(), left)
            except asyncio.TimeoutError:
                pass
        return True

    async def send_gui(self, uuid: str, value) -> None:
        import msgspec

        await self.ws.send(msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": uuid,
                                                    "updates": {"value": value}}))

    async def move_slider(self, label_prefix: str, value: float, timeout: float = REDRAW_TIMEOUT_S) -> float | None:
        """Seconds from sending the slider value to the arrival of the redrawn scene (None: none came)."""
        uuid = self.uuid_of(label_prefix)
        k, paths = self.update_no, self.path_msgs
        t0 = time.perf_counter()
        await self.send_gui(uuid, value)
        ok = await self.wait_for(lambda: self.update_no > k and self.path_msgs > paths, timeout)
        return time.perf_counter() - t0 if ok else None

    async def close(self) -> None:
        if self.ws is not None:
            await self.ws.close()
        if self._reader is not None:
            try:
                await asyncio.wait_for(self._reader, 10)
            except Exception:
                pass


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server_process(port: int, scenario: str = SCENARIO) -> subprocess.Popen:
    """`theoria serve` in its own process, waiting until it accepts connections."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ, PYTHONPATH=root + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "theoria.app.cli", "serve", "--port", str(port), "--scenario", scenario],
                            cwd=root, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    t0 = time.time()
    while True:
        if proc.poll() is not None:
            raise RuntimeError("theoria serve exited: " + proc.stderr.read().decode()[-500:])
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=1):
                return proc
        except OSError:
            if time.time() - t0 > 120:
                proc.kill()
                raise RuntimeError("theoria serve did not start")
            time.sleep(0.2)


async def _student(i: int, url: str, t_end: float, lat: list, failures: list, ready: list) -> None:
    rng = random.Random(i)
    c = ViserProtocolClient(url)
    await c.connect()
    try:
        if not await c.wait_for(lambda: c.update_no >= 1 and SLIDER in " ".join(c.labels), 180):
            failures.append(f"client {i}: no first scene")
            return
        ready.append(time.perf_counter())
        last = c.values.get(c.uuid_of(SLIDER))
        while time.perf_counter() < t_end:
            await asyncio.sleep(rng.uniform(*THINK_S))
            if time.perf_counter() >= t_end:
                break
            value = last
            while value == last:  # viser calls no callback for an unchanged value: always a new one
                value = round(rng.uniform(2.0, 10.0), 1)
            last = value
            dt = await c.move_slider(SLIDER, value)
            if dt is None:
                failures.append(f"client {i}: no redraw within {REDRAW_TIMEOUT_S:g} s")
            else:
                lat.append(dt)
    finally:
        await c.close()


async def _classroom(port: int, pid: int, soak_s: float, n: int) -> dict:
    import psutil

    proc = psutil.Process(pid)
    url = f"ws://127.0.0.1:{port}"
    lat: list[float] = []
    failures: list[str] = []
    ready: list[float] = []
    mem: list[tuple[float, float, int]] = []  # (t, rss MB, threads)
    t_start = time.perf_counter()
    rss0 = proc.memory_info().rss / 2**20
    stop = asyncio.Event()

    async def sampler():
        while not stop.is_set():
            try:
                mem.append((time.perf_counter() - t_start, proc.memory_info().rss / 2**20, proc.num_threads()))
            except psutil.Error:
                return
            try:
                await asyncio.wait_for(stop.wait(), 2.0)
            except asyncio.TimeoutError:
                pass

    samp = asyncio.create_task(sampler())
    # connect in a ramp (students arriving), all within a few seconds
    t_end = time.perf_counter() + soak_s
    tasks = []
    for i in range(n):
        tasks.append(asyncio.create_task(_student(i, url, t_end, lat, failures, ready)))
        await asyncio.sleep(0.1)
    res = await asyncio.gather(*tasks, return_exceptions=True)
    failures += [f"{type(r).__name__}: {r}" for r in res if isinstance(r, BaseException)]
    await asyncio.sleep(3.0)  # sessions closed: threads should be gone
    stop.set()
    await samp
    threads_after = proc.num_threads()
    rss_after = proc.memory_info().rss / 2**20
    t, rss, thr = (np.array(x) for x in zip(*mem)) if mem else (np.zeros(1),) * 3
    half = t >= t[-1] / 2
    slope = float(np.polyfit(t[half], rss[half], 1)[0] * 60) if half.sum() > 2 else None
    a = np.array(lat) if lat else np.array([np.nan])
    return {
        "clients": n, "soak_s": soak_s, "redraws": len(lat), "failures": len(failures),
        "failure_examples": failures[:3],
        "latency_ms_median": float(1000 * np.median(a)), "latency_ms_p95": float(1000 * np.percentile(a, 95)),
        "latency_ms_max": float(1000 * np.max(a)),
        "rss_mb_idle": rss0, "rss_mb_first": float(rss[0]), "rss_mb_max": float(rss.max()),
        "rss_mb_last": float(rss[-1]), "rss_mb_after_disconnect": rss_after,
        "rss_mb_per_min_second_half": slope,
        "threads_max": int(thr.max()), "threads_after_disconnect": threads_after,
        "rss_series": [(round(float(x), 1), round(float(y), 1)) for x, y in zip(t[::max(1, len(t) // 60)], rss[::max(1, len(t) // 60)])],
    }


def run_classroom(soak_s: float | None = None, n: int = N_CLIENTS) -> dict:
    soak_s = float(os.environ.get("THEORIA_SOAK_S", "60")) if soak_s is None else soak_s
    port = _free_port()
    server = start_server_process(port)
    try:
        import psutil

        threads_idle = psutil.Process(server.pid).num_threads()
        out = asyncio.run(_classroom(port, server.pid, soak_s, n))
        out["threads_idle"] = threads_idle
        return out
    finally:
        server.terminate()
        try:
            server.wait(20)
        except subprocess.TimeoutExpired:
            server.kill()


@register_bench("classroom-30-clients", needs=("psutil",))
def classroom():
    r = run_classroom()
    r.pop("rss_series", None)
    r.pop("failure_examples", None)
    p95 = r["latency_ms_p95"] / 1000
    return {"theoria_s": p95, "baseline_s": 0.2, "theoria_error": None, "baseline_error": None, **r,
            "note": "theoria_s = p95 slider-to-redraw over 30 protocol clients; baseline = the 200 ms target of a classroom"}


if __name__ == "__main__":
    r = run_classroom()
    print(json.dumps(r, indent=1))
