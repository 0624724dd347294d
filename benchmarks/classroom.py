"""A class on one laptop: 30 or 100 browsers on one `theoria serve`, each switching scenario,
choosing presets and moving sliders; optionally one abusive client flooding control updates.

The server runs in its own process (`python -m theoria.app.cli serve`), exactly as a teacher starts
it; its resident memory and CPU (with its simulation processes) are read with psutil. The clients
are protocol-level viser clients (`ViserProtocolClient`), not Chromium tabs (a hundred software-
WebGL tabs do not fit on two cores): each speaks viser's own websocket protocol as the page's
worker does (viser/client/src/WebsocketClientWorker.ts) --

- subprotocol ``viser-v<version>``; the server registers a client (and theoria builds its
  `ClientSession`) only after the first ``ViewerCameraMessage``, which the page sends on load;
- client → server: one msgpack dict per websocket message (``{"type": "GuiUpdateMessage",
  "uuid": ..., "updates": {"value": ...}}`` is what a slider or a dropdown sends);
- server → client: ``[8 B msgpack size][8 B zstd size][zstd(msgpack {"messages": [...]})]
  [aligned raw binary buffers]``. Every frame is decoded (zstd + msgpack) like the page does,
  including the playback stream, so the server pays the full per-client cost.

Action → update latency: from sending the control's value to the arrival of the batch that
holds the redrawn scene, recognised by the status line "(update #k)" with k larger than before
(the session sends the scene, the table and the status in one `client.atomic()` batch). For a
slow scenario the first update can be its quick preview; `full` latencies wait for the full run.
The page's own drawing time is not included (`app-slider-latency` measures it in Chromium).

A student: waits for the first scene, then until the soak ends thinks 1–4 s and acts: 30 %
switches to a random scenario, 20 % chooses a random preset, 50 % moves a random parameter
slider of the scenario on screen to a random value on the slider's grid. The abusive client
sends `ABUSE_MESSAGES` slider updates as fast as its socket takes them, in a loop.

Where the server's part went: the server is started with THEORIA_TIMING_LOG, one line per scene
it shows (waiting for a simulation process, simulating, waiting to be drawn, drawing and sending);
`server_*_ms_p50/p95` summarise it. CPU is split into the server's own process, its simulation
processes and the clients (this process), which share the two cores.

Memory: the server's RSS (with its children) sampled every 2 s; "flat" is judged from the second
half of the soak (slope in MB/min). Duration: env THEORIA_SOAK_S (default 60 s); the 30-minute
soak is `THEORIA_SOAK_S=1800 python -m theoria.benchmarks.classroom 100`.
"""
from __future__ import annotations

import asyncio
import json
import os
import random
import socket
import subprocess
import sys
import threading
import time

import numpy as np
from websockets.exceptions import ConnectionClosed

from ..app.browser import ADDRESS_KEY
from . import register_bench

N_CLIENTS = 30
SCENARIO = "middle-axis-flip"
SLIDER = "Spin rate"  # the label of middle-axis-flip's spin slider starts so
REDRAW_TIMEOUT_S = 30.0
FIRST_SCENE_TIMEOUT_S = 180.0
THINK_S = (1.0, 4.0)
MIX = (("switch", 0.3), ("preset", 0.2), ("slider", 0.5))
ABUSE_MESSAGES = 3000
PLAYBACK_LABELS = ("speed", "time (% of run)", "exaggerate shape")


def _decode_frame(buf: bytes) -> list[dict]:
    """One server → client websocket frame → list of message dicts (binary buffers ignored)."""
    import msgspec
    import zstandard

    n = int.from_bytes(buf[0:8], "little")
    c = int.from_bytes(buf[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(buf[16:16 + c], max_output_size=n)
    return msgspec.msgpack.decode(inner)["messages"]


# the sliders of the panel itself (app/session.py), not of a scenario's parameters
PANEL_SLIDERS = ("Time (", "Playback speed", "Exaggerate the shape")


class ViserProtocolClient:
    """A browser tab as the server sees it: websocket + viser's wire format, no rendering."""

    def __init__(self, url: str, runs_js: bool = True):
        self.url = url
        self.runs_js = runs_js  # answers the address probe, as a page running theoria's JavaScript does
        self.poses: dict[str, int] = {}  # node → orientations received (playback sent by the server)
        self.ws = None
        self.labels: dict[str, str] = {}  # gui label → uuid
        self.values: dict[str, object] = {}  # gui uuid → last value sent by the server
        self.components: dict[str, dict] = {}  # gui uuid → {type, label, container, props}
        self.status_uuid: str | None = None
        self.status = ""
        self.markdown: dict[str, str] = {}  # markdown uuid → content (info, Euler table, status)
        self.notifications: list[tuple[str, str]] = []  # (title, body) as the page would pop them up
        self.scripts: list[str] = []  # JavaScript the server ran in the page (title, loading line)
        self.scenario = ""  # the scenario whose scene is drawn (from the tab title the server sets)
        self.update_no = 0  # k of the last "(update #k)" seen
        self.full_no = 0  # k of the last update that was not a quick preview
        self.scene_names: set[str] = set()
        self.path_msgs = 0  # path point-cloud messages received (scene rebuilds)
        self.frames = 0
        self.messages = 0
        self.types: dict[str, int] = {}  # message type → how many arrived
        self.bytes = 0
        self.changed = asyncio.Event()
        self._reader = None
        self.closed_code = None

    async def connect(self, handshake: bool = True) -> None:
        import msgspec
        import viser
        import websockets

        self.ws = await websockets.connect(self.url, subprotocols=[f"viser-v{viser.__version__}"],
                                           max_size=None, compression=None, open_timeout=60)
        if handshake:  # what the page sends once its canvas exists; registers the client with the server
            await self.ws.send(msgspec.msgpack.encode({
                "type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [3.0, 2.0, 2.0],
                "fov": 1.3, "near": 0.01, "far": 1000.0, "image_height": 800, "image_width": 1280,
                "look_at": [0.0, 0.0, 0.0], "up_direction": [0.0, 0.0, 1.0]}))
        self._reader = asyncio.create_task(self._read())

    async def send_raw(self, message: dict) -> None:
        import msgspec

        await self.ws.send(msgspec.msgpack.encode(message))

    async def _read(self) -> None:
        try:
            async for raw in self.ws:
                self.frames += 1
                self.bytes += len(raw)
                for m in _decode_frame(raw):
                    self._handle(m)
                self.changed.set()
        except Exception:
            pass
        finally:
            try:
                self.closed_code = self.ws.close_code
            except Exception:
                pass
            self.changed.set()

    def _handle(self, m: dict) -> None:
        self.messages += 1
        typ = m.get("type", "")
        self.types[typ] = self.types.get(typ, 0) + 1
        if typ == "LocalStorageGetItemRequestMessage":
            # the page answers at once: asked for its address (app/browser.py), a page gives it, which
            # tells the server it runs theoria's JavaScript and plays the scene by itself; else nothing
            value = "http" + self.url[2:] + "/" if (self.runs_js and str(m.get("key", "")).endswith(ADDRESS_KEY)) else None
            asyncio.get_running_loop().create_task(self.send_raw({
                "type": "LocalStorageGetItemResponseMessage", "value": value, "error": None,
                "request_uuid": m.get("request_uuid")}))
        if "Notification" in typ and isinstance(m.get("props"), dict) and "title" in m["props"]:
            self.notifications.append((m["props"].get("title", ""), m["props"].get("body", "")))
        if typ == "SetOrientationMessage":
            self.poses[m.get("name", "")] = self.poses.get(m.get("name", ""), 0) + 1
        if typ == "RunJavascriptMessage":
            src = m.get("source", "")
            self.scripts.append(src)
            if "theoria.title(" in src:  # "theoria — <scenario>": the scenario shown
                try:
                    arg = src.split("theoria.title(", 1)[1].rsplit(")", 1)[0]
                    self.scenario = json.loads(arg).split(" — ")[-1]
                except Exception:
                    pass
        if typ.startswith("Gui") and "props" in m and isinstance(m["props"], dict):
            label = m["props"].get("label")
            if label:
                self.labels[label] = m["uuid"]
            self.components[m["uuid"]] = {"type": typ, "label": label, "container": m.get("container_uuid"),
                                          "props": m["props"]}
            content = m["props"].get("_markdown", m["props"].get("content"))
            if isinstance(content, str):
                self.markdown[m["uuid"]] = content
            # the run's counter; made after a quick preview was shown, it starts with that
            if isinstance(content, str) and content.startswith(("*simulat", "*quick preview")):
                self.status_uuid = m["uuid"]
                self._status(content)
            if "value" in m:
                self.values[m["uuid"]] = m["value"]
        elif typ == "GuiUpdateMessage":
            up = m.get("updates", {})
            if m.get("uuid") in self.markdown:  # a markdown's or an HTML element's new text
                for key in ("_markdown", "content"):
                    if isinstance(up.get(key), str):
                        self.markdown[m["uuid"]] = up[key]
            if m.get("uuid") == self.status_uuid:
                for key in ("_markdown", "content"):
                    if key in up:
                        self._status(up[key])
            if "value" in up:
                self.values[m["uuid"]] = up["value"]
            comp = self.components.get(m.get("uuid"))
            if comp is not None:
                comp["props"].update({k: v for k, v in up.items() if k != "value"})
        elif typ == "GuiRemoveMessage":
            self._remove(m.get("uuid"))
        name = m.get("name")
        if isinstance(name, str):
            self.scene_names.add(name)
            if "polhode/" in name and (typ.endswith("PointCloudMessage") or (
                    typ == "SceneNodeUpdateMessage" and "points" in m.get("updates", {}))):
                self.path_msgs += 1

    def _remove(self, uuid) -> None:
        gone = {uuid}
        changed = True
        while changed:  # a folder takes its children with it
            changed = False
            for u, c in self.components.items():
                if u not in gone and c["container"] in gone:
                    gone.add(u)
                    changed = True
        for u in gone:
            c = self.components.pop(u, None)
            if c is not None and c["label"] and self.labels.get(c["label"]) == u:
                del self.labels[c["label"]]

    def _status(self, content: str) -> None:
        self.status = content
        if "(update #" in content:
            self.update_no = int(content.split("(update #")[1].split(")")[0])
            if "preview" not in content:
                self.full_no = self.update_no

    def uuid_of(self, label_prefix: str) -> str:
        for label, uuid in self.labels.items():
            if label.startswith(label_prefix):
                return uuid
        raise KeyError(label_prefix)

    def dropdown(self, label: str) -> tuple[str, list[str]]:
        uuid = self.labels[label]
        return uuid, list(self.components[uuid]["props"].get("options", []))

    def param_sliders(self) -> list[tuple[str, dict]]:
        """(uuid, props) of the sliders of the scenario's parameters now shown (every slider but the
        panel's own: time, playback speed, shape exaggeration)."""
        return [(u, c["props"]) for u, c in self.components.items()
                if c["type"] == "GuiSliderMessage" and not str(c["label"]).startswith(PANEL_SLIDERS)]

    def number_fields(self) -> list[str]:
        """uuids of the typed fields (a text field in a form) that hold one number now."""
        out = []
        for u, c in self.components.items():
            if c["type"] != "GuiTextMessage" or self.components.get(c["container"], {}).get("type") != "GuiFormMessage":
                continue
            try:
                float(str(self.values.get(u)))
            except ValueError:
                continue
            out.append(u)
        return out

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
        await self.send_raw({"type": "GuiUpdateMessage", "uuid": uuid, "updates": {"value": value}})
        self.values[uuid] = value  # the page shows what it sent (the server echoes only its own changes)

    async def enter(self, label_prefix: str, text: str) -> None:
        """Type `text` into a parameter's field and press Enter, as the page does: the field's value,
        then the submit of the form that holds it."""
        uuid = self.uuid_of(label_prefix)
        await self.send_gui(uuid, str(text))
        form = self.components[uuid]["container"]
        await self.send_raw({"type": "GuiFormSubmitMessage", "uuid": form})

    async def act(self, uuid: str, value, timeout: float | None = None) -> tuple[float | None, float | None]:
        """Send a control's value; seconds to the first redraw (a preview counts) and to the full
        one (None: none came in time, or the server answered with a notification instead, e.g. a
        run stopped at its time limit: see `answered`)."""
        timeout = REDRAW_TIMEOUT_S if timeout is None else timeout
        k, kf, kn = self.update_no, self.full_no, len(self.notifications)
        t0 = time.perf_counter()
        await self.send_gui(uuid, value)
        first = full = None
        self.answered = False
        if await self.wait_for(lambda: self.update_no > k or len(self.notifications) > kn, timeout):
            self.answered = True
        if self.update_no > k:
            first = time.perf_counter() - t0
            if await self.wait_for(lambda: self.full_no > kf or len(self.notifications) > kn, max(0.0, timeout - first)) \
                    and self.full_no > kf:
                full = time.perf_counter() - t0
        return first, full

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
            try:
                await self.ws.close()
            except Exception:  # noqa: BLE001 — the server closed it first (websockets can race asyncio there)
                pass
        if self._reader is not None:
            try:
                await asyncio.wait_for(self._reader, 10)
            except Exception:
                pass


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server_process(port: int, scenario: str = SCENARIO, extra: tuple = (), env: dict | None = None,
                         lines: list | None = None) -> subprocess.Popen:
    """`theoria serve` in its own process, waiting until it accepts connections; its stdout lines
    are collected into `lines` (with the perf_counter time each arrived)."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ if env is None else env)
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.Popen([sys.executable, "-m", "theoria.app.cli", "serve", "--port", str(port), "--scenario", scenario,
                             *extra], cwd=root, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out = lines if lines is not None else []

    def pump(stream, tag):
        for line in iter(stream.readline, b""):
            out.append((time.perf_counter(), tag, line.decode(errors="replace").rstrip()))

    threading.Thread(target=pump, args=(proc.stdout, "out"), daemon=True).start()
    threading.Thread(target=pump, args=(proc.stderr, "err"), daemon=True).start()
    t0 = time.time()
    while True:
        if proc.poll() is not None:
            time.sleep(0.2)
            raise RuntimeError("theoria serve exited: " + "\n".join(x[2] for x in out[-10:]))
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=1):
                return proc
        except OSError:
            if time.time() - t0 > 120:
                proc.kill()
                raise RuntimeError("theoria serve did not start")
            time.sleep(0.2)


def wait_line(lines: list, text: str, timeout: float) -> float | None:
    """perf_counter time of the first collected line containing `text` (None: not within timeout)."""
    t_end = time.perf_counter() + timeout
    while time.perf_counter() < t_end:
        for t, _, line in list(lines):
            if text in line:
                return t
        time.sleep(0.2)
    return None


def tree_cpu_seconds(pid: int, split: bool = False):
    """CPU seconds used so far by a process and its children (the simulation processes); with
    `split`, (the process's own, its children's)."""
    import psutil

    try:
        p = psutil.Process(pid)
        procs = [p] + p.children(recursive=True)
    except psutil.Error:
        return (0.0, 0.0) if split else 0.0
    own = kids = 0.0
    for q in procs:
        try:
            c = q.cpu_times()
        except psutil.Error:
            continue
        if q.pid == pid:
            own += c.user + c.system
            kids += c.children_user + c.children_system  # simulation processes that were stopped
        else:
            kids += c.user + c.system
    return (own, kids) if split else own + kids


def own_cpu_seconds() -> float:
    """CPU seconds of this process (the protocol clients): they share the machine with the server."""
    t = os.times()
    return t.user + t.system


def tree_rss_mb(pid: int) -> tuple[float, float]:
    """(server RSS, server + children RSS) in MB."""
    import psutil

    p = psutil.Process(pid)
    own = p.memory_info().rss
    kids = 0
    for q in p.children(recursive=True):
        try:
            kids += q.memory_info().rss
        except psutil.Error:
            pass
    return own / 2**20, (own + kids) / 2**20


async def _student(i: int, url: str, t_end: float, rec: dict, scenarios=None) -> None:
    """`scenarios`: the scenario labels (dropdown options) this student may switch to (all: None)."""
    rng = random.Random(i)
    c = ViserProtocolClient(url)
    t0 = time.perf_counter()
    await c.connect()
    try:
        if not await c.wait_for(lambda: c.update_no >= 1, FIRST_SCENE_TIMEOUT_S):
            rec["never_served"].append(i)
            return
        rec["first_scene"].append(time.perf_counter() - t0)
        while time.perf_counter() < t_end:
            await asyncio.sleep(rng.uniform(*THINK_S))
            if time.perf_counter() >= t_end:
                break
            kind = rng.choices([k for k, _ in MIX], [w for _, w in MIX])[0]
            uuid = value = None
            if kind == "switch":
                uuid, options = c.dropdown("Scene")
                options = [o for o in options if o != c.values.get(uuid) and (scenarios is None or
                                                                            any(x in o for x in scenarios))]
                if not options:
                    continue
                value = rng.choice(options)
            elif kind == "preset":
                uuid, options = c.dropdown("Start from")
                options = [o for o in options if o != c.values.get(uuid) and "your own" not in o.lower()]
                value = rng.choice(options) if options else None
            else:
                sliders = c.param_sliders()
                if sliders:
                    uuid, props = rng.choice(sliders)
                    lo, hi, step = float(props["min"]), float(props["max"]), float(props.get("step") or 0.01)
                    cur = c.values.get(uuid)
                    for _ in range(10):
                        value = round(lo + step * rng.randint(0, max(0, int((hi - lo) / step))), 10)
                        if value != cur:
                            break
            if uuid is None or value is None:
                continue
            scen = c.scenario
            first, full = await c.act(uuid, value)
            rec["actions"].append({"kind": kind, "first": first, "full": full, "client": i, "scenario": scen,
                                   "answered": c.answered, "value": value if kind != "preset" else value,
                                   "control": c.components.get(uuid, {}).get("label") if kind == "slider" else None})
    except Exception as e:  # noqa: BLE001 — a client's crash is counted, not fatal
        rec["errors"].append(f"client {i}: {type(e).__name__}: {e}")
    finally:
        await c.close()


async def _abuser(url: str, t_end: float, rec: dict) -> None:
    """One client that floods a slider with ABUSE_MESSAGES updates as fast as the socket takes
    them, again and again until the soak ends."""
    c = ViserProtocolClient(url)
    await c.connect()
    t_start = time.perf_counter()
    try:
        if not await c.wait_for(lambda: c.update_no >= 1, FIRST_SCENE_TIMEOUT_S):
            return
        sliders = c.param_sliders()
        if sliders:  # a slider: values inside its range, each one a new run
            uuid, _ = sliders[0]
            comp = c.components[uuid]
            v0 = float(c.values[uuid])
            lo = float(comp["props"].get("min") if comp["props"].get("min") is not None else v0 * 0.5)
            hi = float(comp["props"].get("max") if comp["props"].get("max") is not None else v0 * 2.0)
            lo, hi = max(lo, v0 * 0.5 if v0 > 0 else lo), min(hi, v0 * 2.0 if v0 > 0 else hi)

            async def send(k):
                await c.send_gui(uuid, lo + (hi - lo) * ((k % 97) / 97.0))
        else:  # no slider in this scene: a typed number field, typed and entered
            uuid = c.number_fields()[0]
            v0 = float(c.values[uuid])

            async def send(k):
                await c.send_gui(uuid, f"{v0 * (0.5 + (k % 97) / 97.0):.6g}")
                await c.send_raw({"type": "GuiFormSubmitMessage", "uuid": c.components[uuid]["container"]})
        while time.perf_counter() < t_end:
            for k in range(ABUSE_MESSAGES):
                if time.perf_counter() >= t_end:
                    break
                await send(k)
                rec["abuse_sent"] = rec.get("abuse_sent", 0) + 1
            await asyncio.sleep(0.5)
        rec["abuser_updates"] = c.update_no
    except Exception as e:  # noqa: BLE001
        state = getattr(getattr(getattr(c, "ws", None), "state", None), "name", "")
        if isinstance(e, ConnectionClosed) or state in ("CLOSING", "CLOSED"):
            # the server may close a client that floods it (its keepalive waits behind the flood);
            # a send racing that close can fail inside asyncio with another error
            rec["abuser_closed_after_s"] = time.perf_counter() - t_start
            rec["abuser_closed"] = f"{type(e).__name__}: {e}"
        else:
            rec["errors"].append(f"abuser: {type(e).__name__}: {e}")
    finally:
        await c.close()


def _pct(xs, q):
    return float(1000 * np.percentile(xs, q)) if len(xs) else float("nan")


async def _classroom(port: int, pid: int, soak_s: float, n: int, abusive: bool) -> dict:
    import psutil

    proc = psutil.Process(pid)
    url = f"ws://127.0.0.1:{port}"
    rec: dict = {"actions": [], "first_scene": [], "never_served": [], "errors": []}
    mem: list[tuple[float, float, float, int]] = []  # (t, server RSS MB, with children MB, threads)
    t_start = time.perf_counter()
    rss0 = tree_rss_mb(pid)
    cpu0 = tree_cpu_seconds(pid, split=True)
    clients0 = own_cpu_seconds()
    stop = asyncio.Event()

    async def sampler():
        while not stop.is_set():
            try:
                own, total = tree_rss_mb(pid)
                mem.append((time.perf_counter() - t_start, own, total, proc.num_threads()))
            except psutil.Error:
                return
            try:
                await asyncio.wait_for(stop.wait(), 2.0)
            except asyncio.TimeoutError:
                pass

    samp = asyncio.create_task(sampler())
    t_end = time.perf_counter() + soak_s
    tasks = []
    if abusive:
        tasks.append(asyncio.create_task(_abuser(url, t_end, rec)))
    ramp = min(0.1, 10.0 / max(n, 1))  # students arriving within ten seconds
    for i in range(n):
        tasks.append(asyncio.create_task(_student(i, url, t_end, rec)))
        await asyncio.sleep(ramp)
    res = await asyncio.gather(*tasks, return_exceptions=True)
    rec["errors"] += [f"{type(r).__name__}: {r}" for r in res if isinstance(r, BaseException)]
    cpu_end = tree_cpu_seconds(pid, split=True)
    clients_end = own_cpu_seconds()
    t_busy = time.perf_counter() - t_start
    await asyncio.sleep(2.0)  # sessions closed: nothing may run on
    cpu_idle = tree_cpu_seconds(pid)
    t_quiet = time.perf_counter()
    await asyncio.sleep(2.0)
    cpu_idle2 = tree_cpu_seconds(pid)
    stop.set()
    await samp
    rss_after = tree_rss_mb(pid)
    t, own, total, thr = (np.array(x) for x in zip(*mem)) if mem else (np.zeros(1),) * 4
    half = t >= t[-1] / 2
    slope = float(np.polyfit(t[half], own[half], 1)[0] * 60) if half.sum() > 2 else None
    acts = rec["actions"]
    first = [a["first"] for a in acts if a["first"] is not None]
    full = [a["full"] for a in acts if a["full"] is not None]
    out = {
        "clients": n, "abusive_client": abusive, "soak_s": soak_s, "actions": len(acts),
        "never_served": len(rec["never_served"]), "no_redraw": sum(1 for a in acts if a["first"] is None),
        "errors": len(rec["errors"]), "error_examples": rec["errors"][:3],
        "latency_ms_p50": _pct(first, 50), "latency_ms_p95": _pct(first, 95),
        "latency_ms_max": float(1000 * max(first)) if first else float("nan"),
        "full_ms_p50": _pct(full, 50), "full_ms_p95": _pct(full, 95),
        "first_scene_s_p50": float(np.median(rec["first_scene"])) if rec["first_scene"] else float("nan"),
        "first_scene_s_max": float(max(rec["first_scene"])) if rec["first_scene"] else float("nan"),
        "cpu_cores_busy": (sum(cpu_end) - sum(cpu0)) / t_busy,
        "cpu_cores_server": (cpu_end[0] - cpu0[0]) / t_busy,
        "cpu_cores_simulations": (cpu_end[1] - cpu0[1]) / t_busy,
        "cpu_cores_clients": (clients_end - clients0) / t_busy,
        "cpu_s_after_disconnect": cpu_idle2 - cpu_idle, "cpu_window_s": time.perf_counter() - t_quiet,
        "rss_mb_idle": rss0[0], "rss_mb_max": float(own.max()), "rss_mb_last": float(own[-1]),
        "rss_mb_with_children_max": float(total.max()),
        "rss_mb_after_disconnect": rss_after[0], "rss_mb_per_min_second_half": slope,
        "threads_max": int(thr.max()),
        "abuse_sent": rec.get("abuse_sent", 0),
        "abuser_closed_after_s": rec.get("abuser_closed_after_s"),
    }
    for kind, _ in MIX:
        xs = [a["first"] for a in acts if a["kind"] == kind and a["first"] is not None]
        fs = [a["full"] for a in acts if a["kind"] == kind and a["full"] is not None]
        out[f"{kind}_n"] = len([a for a in acts if a["kind"] == kind])
        out[f"{kind}_ms_p95"] = _pct(xs, 95)
        out[f"{kind}_full_ms_p95"] = _pct(fs, 95)
    out["rss_series"] = [(round(float(x), 1), round(float(y), 1)) for x, y in
                         zip(t[::max(1, len(t) // 60)], own[::max(1, len(t) // 60)])]
    out["actions_raw"] = acts
    return out


def run_classroom(soak_s: float | None = None, n: int = N_CLIENTS, abusive: bool = False,
                  scenario: str = SCENARIO, wait_ready_s: float = 900.0) -> dict:
    """Start `theoria serve`, wait until its background preparation is done (the defaults and
    presets of every scenario: at most wait_ready_s), then run the class."""
    import tempfile

    soak_s = float(os.environ.get("THEORIA_SOAK_S", "60")) if soak_s is None else soak_s
    port = _free_port()
    lines: list = []
    t0 = time.perf_counter()
    timing = tempfile.NamedTemporaryFile(prefix="theoria-timing-", suffix=".jsonl", delete=False)
    timing.close()
    env = dict(os.environ, THEORIA_TIMING_LOG=timing.name)
    server = start_server_process(port, scenario, ("--max-per-address", str(n + 10), "--max-clients", str(n + 50)),
                                  lines=lines, env=env)
    try:
        t_url = wait_line(lines, "open http", 60)
        t_ready = wait_line(lines, "are ready", wait_ready_s)
        out = asyncio.run(_classroom(port, server.pid, soak_s, n, abusive))
        out["prepared_s"] = (t_ready - t_url) if (t_ready and t_url) else None
        out["server_start_s"] = (t_url - t0) if t_url else None
        out["load_avg_1min"] = os.getloadavg()[0]
        out["server_log_tail"] = [x[2] for x in lines if x[1] == "err"][-5:]
        out.update(server_side(timing.name))
        return out
    finally:
        server.terminate()
        try:
            server.wait(20)
        except subprocess.TimeoutExpired:
            server.kill()
        os.unlink(timing.name)


def server_side(path: str) -> dict:
    """Where the server's part of an answer went, from its timing log (one line per scene shown):
    p50/p95 in ms of waiting for a simulation process, simulating, waiting to be drawn, drawing and
    sending; runs from the cache have no wait and no simulation. And the CPU seconds of the runs
    shown, summed by scenario."""
    try:
        rows = [json.loads(line) for line in open(path)]
    except (OSError, ValueError):
        return {}
    out = {"server_scenes_shown": len(rows), "server_scenes_from_cache": sum(r["cached"] for r in rows)}
    parts = {"queued": lambda r: r["queued_s"], "simulating": lambda r: r["run_s"],
             "waiting_to_draw": lambda r: r["show_s"] - r.get("draw_s", 0.0), "drawing": lambda r: r.get("draw_s", 0.0)}
    computed = [r for r in rows if not r["cached"]]
    for name, f in parts.items():
        xs = [f(r) for r in (computed if name in ("queued", "simulating") else rows)]
        out[f"server_{name}_ms_p50"], out[f"server_{name}_ms_p95"] = _pct(xs, 50), _pct(xs, 95)
    # CPU of the runs shown, by scenario: where the simulation processes' cores went
    cpu: dict[str, float] = {}
    for r in computed:
        if r.get("cpu_s") is not None:
            cpu[r["scenario"]] = cpu.get(r["scenario"], 0.0) + r["cpu_s"]
    out["server_run_cpu_s_by_scenario"] = {k: round(v, 2) for k, v in sorted(cpu.items(), key=lambda kv: -kv[1])}
    return out


def _row(r: dict, target_s: float, note: str) -> dict:
    r = dict(r)
    for k in ("rss_series", "actions_raw", "error_examples", "failure_examples", "server_log_tail"):
        r.pop(k, None)
    p95 = r["latency_ms_p95"] / 1000
    return {"theoria_s": p95, "baseline_s": target_s, "theoria_error": None, "baseline_error": None, **r, "note": note}


@register_bench("classroom-30-clients", needs=("psutil",))
def classroom():
    r = run_classroom(n=30)
    return _row(r, 0.2, "theoria_s = p95 action→update over 30 protocol clients switching scenario, "
                        "choosing presets and moving sliders; baseline = 200 ms target")


@register_bench("classroom-100-clients", needs=("psutil",))
def classroom_100():
    r = run_classroom(n=100)
    return _row(r, 0.2, "theoria_s = p95 action→update over 100 protocol clients; baseline = 200 ms target")


@register_bench("classroom-100-abusive", needs=("psutil",))
def classroom_100_abusive():
    r = run_classroom(n=100, abusive=True)
    return _row(r, 0.4, "theoria_s = p95 action→update of 100 clients while one more floods a slider "
                        f"({ABUSE_MESSAGES} updates per burst); baseline = 400 ms target")


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else N_CLIENTS
    r = run_classroom(n=n, abusive="--abusive" in sys.argv)
    r.pop("actions_raw", None)
    print(json.dumps(r, indent=1, default=float))
