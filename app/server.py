"""`theoria serve`: the viser web app, one `ClientSession` (app/session.py) per browser, built to
be left running in front of a class.

What the server refuses, whoever asks (a student's browser or a script speaking viser's protocol):

- **Nothing leaves the machine.** viser answers a `ShareUrlRequest` from any peer by opening a
  public tunnel (two child processes and a look-up of the share host); the server drops that
  message, and every message type the app does not use, before viser sees it (each logged once);
  a frame that is not a viser message at all is ignored the same way (`Malformed`), where viser's
  reading loop ended the connection.
  The server binds 127.0.0.1 unless `--host` says otherwise, opens no browser, sends no
  analytics, and stops when its parent process dies.
- **A browser's messages are bounded**: its socket is read at most READ_RATE messages a second
  (beyond, TCP holds the sender back: `_read_with_backpressure`). GUI updates (`Gate`) carry only
  a `value` of a plain type (longer text than MAX_TEXT_CHARS is cut there, still too long to be
  taken: its control refuses it and says so); with the panel's form submits, key
  commands and localStorage answers, at most GUI_RATE a second reach the app, the rest are
  coalesced (the newest value per control wins, so a slider flood ends at its last value and
  costs the other students nothing); camera updates at most CAMERA_RATE a second.
- **Connections are bounded** (`Door`): at most `max_connections` websockets in all and
  `max_per_address` from one address; a socket that has not opened the app (viser's camera
  handshake) within HANDSHAKE_S is closed. Log lines are rate-limited.
- **Runs are bounded** (app/worker.py): a bounded pool of simulation processes, fair between
  browsers, a wall-clock limit per run, the scenario's step and memory budget checked before a
  run starts, a closed tab's run cancelled at once.

Caching: runs are deterministic, so the server keeps finished runs (memory LRU) and precomputes
every scenario's defaults and presets in the background at start-up (kept on disk for the next
start, `app.worker.RunStore`). A class switching among the same presets computes nothing.
"""
from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import io
import logging
import math
import os
import signal
import socket
import threading
import time
import traceback
import warnings
from dataclasses import dataclass

import viser
from viser import _messages as vm

from theoria.physics.errors import ParameterError
from theoria.scenarios import all_scenarios, get

from . import page
from .controls import TYPED, Typed
from .link import class_link
from .panel import comparison_markdown, info_markdown  # noqa: F401
from .session import ClientSession
from .worker import MAX_TEXT_CHARS, RateLimitedLog, SimPool, shared_pool

GUI_RATE = 10.0  # GUI updates per second a browser may send on average (the rest are coalesced)
GUI_BURST = 20.0
CAMERA_RATE = 30.0  # camera updates per second taken from a browser
HANDSHAKE_S = 10.0  # a websocket that has not opened the app by then is closed
MAX_PENDING = 64  # distinct controls with a coalesced update waiting, per browser
# Messages queued for one browser and not yet sent past which it is closed: a browser that asks
# for scene after scene and reads none held every scene in the server's memory (ten such sockets
# took the server from 0.5 to 1.4 GB in 40 s). A scene is a few hundred messages; a browser that
# reads, even slowly, is far below this.
MAX_BACKLOG = 5000
# Messages read from one websocket a second, on average and at once. Beyond them the server stops
# reading that socket for a while: a client that floods is held back by TCP itself (its own sends
# wait) instead of costing the event loop ~70 µs a message (viser decodes each and starts two
# tasks for it) that the other browsers' scenes wait behind. A browser sends far fewer: 33 a
# second orbiting the camera, 18 dragging a slider (headless Chromium, measured).
READ_RATE = 200.0
READ_BURST = 400.0
MAX_LIST = 16  # numbers in a vector value
# The largest message a browser may send (bytes). The app's page sends a camera, a control's value
# or a typed number, each well under a kilobyte; viser lets messages of 50 MB in, and a client's
# 40-MB text frames were read and decoded whole before being dropped (eight such sockets raised the
# server by 1.2 GB). Past this size a frame is refused from its header, before its payload is read,
# and its socket closed (1009: message too big).
MAX_MESSAGE_BYTES = 1 << 20

# what a browser may send: the page's camera (which also opens the session), a control's value, and
# what the panel's forms (a typed value taken on Enter or blur), keys (viser's commands) and the
# view-as-a-link (an answer from the page's localStorage) send. Each but the camera counts against
# the same rate as control values, keyed by what it acts on.
ACTIONS = {vm.GuiFormSubmitMessage: "uuid", vm.CommandTriggerMessage: "uuid",
           vm.LocalStorageGetItemResponseMessage: "request_uuid"}
IGNORED_QUIETLY = (vm.GuiFormDirtyMessage,)  # the form's "edited" marker: nothing for the app


@dataclass
class Limits:
    """Connection limits of a server (`theoria serve --max-clients/--max-per-address`)."""

    max_connections: int = 200
    max_per_address: int = 10
    handshake_s: float = HANDSHAKE_S


class Gate:
    """What one browser's messages may do before viser dispatches them (see the module text)."""

    def __init__(self, door: "Door", inner, client_id: int, address: str):
        self.door, self.inner, self.client_id, self.address = door, inner, client_id, address
        self.closing = False
        self.tokens = GUI_BURST
        self.t = time.monotonic()
        self.pending: dict[object, object] = {}  # a control (or a click) → its message waiting for the rate
        self.flush_at: float | None = None
        self.camera_t = 0.0
        self.camera_pending = None
        self.registered = False
        self.dropped = 0
        self.coalesced = 0
        self.seen = 0  # messages read from this browser's socket

    def _refill(self) -> None:
        now = time.monotonic()
        self.tokens = min(GUI_BURST, self.tokens + (now - self.t) * GUI_RATE)
        self.t = now

    def backlog(self) -> int:
        """Messages queued for this browser and not sent yet (pushed since the last one sent)."""
        return self.pushed() - self.sent()

    def pushed(self) -> int:
        """The index of the last message queued for this browser (-1: none)."""
        buf = getattr(self, "buffer", None)
        return -1 if buf is None else buf.message_counter - 1

    def sent(self) -> int:
        """The index of the last message sent to this browser (-1: none)."""
        buf = getattr(self, "buffer", None)
        return -1 if buf is None else buf.generator_cursors.get(self.client_id, -1)

    async def __call__(self, client_id, message) -> None:
        self.seen += 1
        if self.backlog() > MAX_BACKLOG:
            if not self.closing:
                self.closing = True
                self.door.refused["not reading"] = self.door.refused.get("not reading", 0) + 1
                self.door.log.line(f"theoria: closed a connection from {self.address}: it reads nothing of what it "
                                   f"asks for ({self.backlog()} messages waiting)", once_key=("backlog", self.address))
                ws = self.door.ws._live_connections.get(client_id)
                if ws is not None:
                    self.door.loop.create_task(ws.close(1008, "not reading"))
            return
        typ = type(message)
        if typ is vm.ViewerCameraMessage:
            return self._camera(client_id, message)
        if typ is vm.GuiUpdateMessage:
            v = message.updates.get("value") if isinstance(message.updates, dict) else None
            if isinstance(v, str) and len(v) > MAX_TEXT_CHARS + 1:
                # kept too long to be taken (its control refuses it by its length, and says so),
                # not whole: a pasted megabyte is not held or passed on
                message = vm.GuiUpdateMessage(message.uuid, {**message.updates, "value": v[:MAX_TEXT_CHARS + 1]})
            why = _bad_update(message)
            if why:
                self._drop(why)
                return
            # a control's newest value replaces its older one still waiting; a click is never
            # merged (Back then Step, over the rate after a drag, had become one Step)
            key = (message.uuid, self.seen) if self._is_button(client_id, message.uuid) else message.uuid
            if key in self.pending:
                self.coalesced += 1
                del self.pending[key]  # the newest value goes to the end
            elif len(self.pending) >= MAX_PENDING:
                self.dropped += 1
                return
            self.pending[key] = message
            self._pump()
            return
        if typ in ACTIONS:
            key = getattr(message, ACTIONS[typ], None)
            if not isinstance(key, str) or len(key) > 64:
                self.dropped += 1
                return
            key = f"{typ.__name__}:{key}"
            if key in self.pending:
                self.coalesced += 1
                del self.pending[key]
            elif len(self.pending) >= MAX_PENDING:
                self.dropped += 1
                return
            self.pending[key] = message
            self._pump()
            return
        if typ in IGNORED_QUIETLY:
            return
        if typ is Malformed:
            self.dropped += 1
            self.door.refused["malformed"] = self.door.refused.get("malformed", 0) + 1
            self.door.log.line(f"theoria: ignored a frame from {self.address} that is not viser's protocol "
                               f"({message.why}; logged once)", once_key=("malformed", self.address))
            return
        self.dropped += 1
        self.door.refused[typ.__name__] = self.door.refused.get(typ.__name__, 0) + 1
        self.door.log.line(f"theoria: ignored a {typ.__name__} message from {self.address} "
                           "(not something this app offers; logged once)", once_key=("type", typ.__name__))

    def _is_button(self, client_id, uuid) -> bool:
        client = self.door.server._connected_clients.get(client_id)
        target = client and client.gui._gui_input_handle_from_uuid.get(uuid)
        return bool(target is not None and getattr(target._impl, "is_button", False))

    def _dispatch(self, client_id, message) -> None:
        if type(message) is vm.GuiUpdateMessage:
            client = self.door.server._connected_clients.get(client_id)
            target = client and client.gui._gui_input_handle_from_uuid.get(message.uuid)
            if target is not None and not self._fits(client, target, message.updates["value"]):
                return
        self.door.loop.create_task(self.inner(client_id, message))

    def _fits(self, client, target, value) -> bool:
        """Whether a value goes on to its control as viser would set it. A slider takes a finite
        number within its range (a whole one if it holds whole numbers); text typed into its box,
        and any other number (NaN, infinite, out of range, a fraction for a count: its page never
        sends one), go to the app's parser instead, which refuses them
        naming the range; the slider keeps its value and is shown it again. A checkbox takes true
        or false, a menu or a text box text; anything else is dropped (viser would set it as it
        came)."""
        current = target.value
        if _number(current):  # a slider
            if isinstance(value, str):  # text typed into its box
                self._typed(client, target, value)
                return False
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                self._drop(f"{'true/false' if isinstance(value, bool) else type(value).__name__} for a number")
                return False
            lo, hi = getattr(target, "min", None), getattr(target, "max", None)
            # a dragged slider's value may miss its end by a rounding of its step
            slack = 1e-9 * abs(hi - lo) if _number(lo) and _number(hi) else 0.0
            # a whole-number slider's page sends whole numbers (viser would cut 59.9 to 59)
            fraction = isinstance(current, int) and _number(value) and value != int(value)
            if not _number(value) or (_number(lo) and value < lo - slack) or (_number(hi) and value > hi + slack) \
                    or fraction:
                self._typed(client, target, repr(float(value)))
                # the sender's slider shows the value it keeps (viser sends a value only when it changes)
                target._impl.gui_api._websock_interface.queue_message(
                    vm.GuiUpdateMessage(target._impl.uuid, {"value": target.value}))
                return False
            return True
        if isinstance(current, bool) and not isinstance(value, bool):
            self._drop(f"{type(value).__name__} for true/false")
            return False
        if isinstance(current, str) and not isinstance(value, str):
            self._drop(f"{type(value).__name__} for text")
            return False
        return True

    def _drop(self, why: str) -> None:
        self.dropped += 1
        self.door.log.line(f"theoria: dropped a control update from {self.address}: {why}",
                           once_key=("gui", self.address, why))

    def _typed(self, client, target, text: str) -> None:
        """A number typed into a slider's box goes, as text, to the app's own parser (the slider's
        `controls.TYPED`), on viser's callback pool; viser would cast it to the slider's type."""
        take = getattr(target, TYPED, None)
        if take is None:
            self._drop("text for a number")
            return

        def failed(f) -> None:
            e = None if f.cancelled() else f.exception()
            if e is not None:
                self.door.log.line(f"theoria: error taking a typed number: {e!r}", once_key=("typed", type(e)))

        client.gui._thread_executor.submit(take, Typed(client, self.client_id, target, text)).add_done_callback(failed)

    def _pump(self) -> None:
        self.flush_at = None
        self._refill()
        while self.pending and self.tokens >= 1.0:
            uuid = next(iter(self.pending))
            msg = self.pending.pop(uuid)
            self.tokens -= 1.0
            self._dispatch(self.client_id, msg)
        if self.pending and self.flush_at is None:
            wait = (1.0 - self.tokens) / GUI_RATE
            self.flush_at = time.monotonic() + wait
            self.door.loop.call_later(wait, self._pump)

    def _camera(self, client_id, message) -> None:
        why = _bad_camera(message)
        if why:
            self.dropped += 1
            self.door.log.line(f"theoria: dropped a camera message from {self.address}: {why}",
                               once_key=("camera", self.address, why))
            return
        now = time.monotonic()
        if not self.registered or now - self.camera_t >= 1.0 / CAMERA_RATE:
            self.registered = True
            self.camera_t = now
            self._dispatch(client_id, message)
            return
        first = self.camera_pending is None
        self.camera_pending = message
        if first:
            def flush():
                m, self.camera_pending = self.camera_pending, None
                if m is not None:
                    self.camera_t = time.monotonic()
                    self._dispatch(client_id, m)

            self.door.loop.call_later(1.0 / CAMERA_RATE - (now - self.camera_t), flush)


_CAMERA_VECTORS = {"wxyz": 4, "position": 3, "look_at": 3, "up_direction": 3}
_CAMERA_NUMBERS = ("fov", "near", "far", "image_height", "image_width")


def _number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


CAMERA_REACH = 1e6  # scene units: no view of a scene (a few units across) has a camera farther out


def _bad_camera(message) -> str | None:
    """Why a ViewerCameraMessage is refused (None: a camera pose of finite numbers within
    CAMERA_REACH; an up direction of 1e308s overflowed numpy's norm when the link was made)."""
    for name, n in _CAMERA_VECTORS.items():
        v = getattr(message, name, None)
        if not isinstance(v, (list, tuple)) or len(v) != n or not all(_number(x) for x in v):
            return f"{name} is not {n} finite numbers"
        if any(abs(x) > CAMERA_REACH for x in v):
            return f"{name} is beyond {CAMERA_REACH:g} scene units"
    for name in _CAMERA_NUMBERS:
        if not _number(getattr(message, name, None)):
            return f"{name} is not a finite number"
    return None


def _bad_update(message) -> str | None:
    """Why a GuiUpdateMessage is refused (None: it is a plain value for a control)."""
    up = message.updates
    if not isinstance(message.uuid, str) or len(message.uuid) > 64:
        return "not a control"
    if not isinstance(up, dict) or set(up) != {"value"}:
        return "changes something other than a value"
    v = up["value"]
    if isinstance(v, (str, bool, int, float)) or v is None:
        return None
    if isinstance(v, (list, tuple)):
        if len(v) <= MAX_LIST and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
            return None
        return "a list that is not a short list of numbers"
    return f"a value of type {type(v).__name__}"


def gate_of(server, client_id) -> "Gate | None":
    """The gate of a browser of a theoria server (None for another server, a test's fake one)."""
    door = getattr(server, "_theoria_door", None)
    return None if door is None else door.gates.get(client_id)


class Door:
    """Connection limits and the message gate of one viser server."""

    def __init__(self, server: viser.ViserServer, limits: Limits, log: RateLimitedLog):
        self.server, self.limits, self.log = server, limits, log
        self.ws = server._websock_server
        self.loop = server._event_loop
        self.open: dict[int, str] = {}  # client id → address
        self.refused: dict[str, int] = {}  # message type or reason → count
        self.gates: dict[int, Gate] = {}
        self.ws.on_client_connect(self._connect)
        self.ws.on_client_disconnect(self._disconnect)
        # server-level handlers: the share tunnel and viser's own GUI/scene of the server; the app
        # uses none of them (each browser has its own GUI), so nothing from a browser goes there
        self.ws._handle_incoming_message = self._server_level

    async def _server_level(self, client_id, message) -> None:
        """Every message also reaches the server-level handlers; none is the app's. The same
        message goes through the browser's gate, which counts and logs what it refuses."""
        return None

    def _address(self, client_id) -> str:
        conn = self.ws._live_connections.get(client_id)
        try:
            return str(conn.remote_address[0])
        except Exception:
            return "?"

    async def _connect(self, conn) -> None:
        cid = conn.client_id
        addr = self._address(cid)
        same = sum(1 for a in self.open.values() if a == addr)
        ws = self.ws._live_connections.get(cid)
        if len(self.open) >= self.limits.max_connections or same >= self.limits.max_per_address:
            why = "server full" if len(self.open) >= self.limits.max_connections else "too many from one address"
            self.refused[why] = self.refused.get(why, 0) + 1
            self.log.line(f"theoria: refused a connection from {addr}: {why} (limits: {self.limits.max_connections} "
                          f"in all, {self.limits.max_per_address} per address)", once_key=("conn", addr, why))
            if ws is not None:
                self.loop.create_task(ws.close(1013, why))
            conn._handle_incoming_message = _drop_all
            return
        self.open[cid] = addr
        gate = Gate(self, conn._handle_incoming_message, cid, addr)
        gate.buffer = conn.get_message_buffer()
        self.gates[cid] = gate
        conn._handle_incoming_message = gate
        self.loop.call_later(self.limits.handshake_s, self._check_handshake, cid)

    def _check_handshake(self, cid) -> None:
        gate = self.gates.get(cid)
        if gate is None or gate.registered:
            return
        ws = self.ws._live_connections.get(cid)
        self.refused["no handshake"] = self.refused.get("no handshake", 0) + 1
        self.log.line(f"theoria: closed an idle connection from {gate.address} (it never opened the app)",
                      once_key=("idle", gate.address))
        if ws is not None:
            self.loop.create_task(ws.close(1008, "idle"))

    async def _disconnect(self, conn) -> None:
        self.open.pop(conn.client_id, None)
        self.gates.pop(conn.client_id, None)


async def _drop_all(client_id, message) -> None:
    return None


def _quiet_libraries(log: RateLimitedLog) -> None:
    """websockets and asyncio log every failed handshake or handler with a traceback: a hostile
    client could fill the terminal. Their records go through the rate-limited log."""

    class Through(logging.Filter):
        def filter(self, record):
            try:
                msg = record.getMessage()
            except Exception:
                msg = str(record.msg)
            log.line(f"{record.name}: {msg}"[:300], once_key=(record.name, msg[:60]))
            return False

    for name in ("websockets", "websockets.server", "asyncio"):
        lg = logging.getLogger(name)
        if not any(isinstance(f, Through) for f in lg.filters):
            lg.addFilter(Through())
    # viser prints a refused connection's version string (the client's own text) with rich, once
    # per connection: two hundred connections wrote 2,900 lines. Through the log, cut, once per kind.
    import rich

    if not isinstance(rich.print, _RichThroughLog):
        rich.print = _RichThroughLog(rich.print, log)
    # a message field of the wrong type is warned about with the whole value (a camera message of
    # 100,000 numbers wrote 11 MB): the gate refuses such messages itself, with one line
    warnings.filterwarnings("ignore", message=r"\[viser\] .* does not match annotation")
    # a tab closed while its scene was being drawn: the rest of that drawing goes nowhere, as it
    # should (viser warns, with its source line, on the teacher's console)
    warnings.filterwarnings("ignore", message=r"Queued a .* on a closed connection")


class _RichThroughLog:
    """`rich.print` (viser's) with a connection refused for its version sent through the
    rate-limited log (its first 200 characters); anything else prints as before."""

    def __init__(self, print_, log: RateLimitedLog):
        self._print, self._log = print_, log

    def __call__(self, *args, **kwargs):
        text = " ".join(str(a) for a in args)
        if "Version mismatch" in text:
            self._log.line(("theoria: refused a connection: " + text.split("Version mismatch", 1)[1])[:200],
                           once_key=("version",))
            return
        self._print(*args, **kwargs)


def _read_with_backpressure() -> None:
    """viser reads each websocket in a loop (`viser.infra._infra._message_consumer`: receive,
    decode, hand over) as fast as messages come. The same loop, with a token bucket per socket:
    past READ_BURST messages at READ_RATE a second it waits before the next read. The websocket
    library then holds at most its small queue and stops reading the socket, and the flooding
    client's own writes stall. A message over MAX_MESSAGE_BYTES closes the socket unread. Guarded:
    a viser whose loop looks different is left as it is."""
    import asyncio
    import inspect

    from viser.infra import _infra

    current = getattr(_infra, "_message_consumer", None)
    if current is None or getattr(current, "_theoria", False):
        return
    try:
        params = list(inspect.signature(current).parameters)
    except (TypeError, ValueError):
        return
    if params != ["websocket", "handle_message", "message_class"]:
        return

    async def consumer(websocket, handle_message, message_class) -> None:
        protocol = getattr(websocket, "protocol", None)
        if hasattr(protocol, "max_message_size"):  # websockets ≥ 13; checked against each frame's header
            protocol.max_message_size = MAX_MESSAGE_BYTES
        tokens, last = READ_BURST, time.monotonic()
        while True:
            raw = await websocket.recv()
            now = time.monotonic()
            tokens = min(READ_BURST, tokens + (now - last) * READ_RATE)
            last = now
            if tokens < 1.0:
                await asyncio.sleep((1.0 - tokens) / READ_RATE)
                tokens, last = 1.0, time.monotonic()
            tokens -= 1.0
            if not isinstance(raw, bytes):  # viser's client sends binary frames only
                handle_message(Malformed("a text frame"))
                continue
            try:
                message = message_class.deserialize(raw)
            except Exception as e:  # noqa: BLE001 — whatever a peer sends must not end its handler
                handle_message(Malformed(_undecodable(raw, e, message_class)))
                continue
            handle_message(message)

    consumer._theoria = True
    _infra._message_consumer = consumer


@dataclass
class Malformed:
    """A websocket frame that is not one of viser's messages (not msgpack, not a dict, no known
    `type`, fields missing): handed to the browser's gate instead of ending its connection."""

    why: str


def _undecodable(raw: bytes, e: Exception, message_class) -> str:
    """What was wrong with a frame, in a few words (never the peer's own bytes)."""
    import msgspec

    try:
        mapping = msgspec.msgpack.decode(raw)
    except Exception:  # noqa: BLE001
        return "not msgpack"
    if not isinstance(mapping, dict):
        return f"a msgpack {type(mapping).__name__}, not a message"
    if not isinstance(mapping.get("type"), str):
        return "a message without a type"
    try:
        if mapping["type"] not in message_class._subclass_from_type_string():
            return "a message of a type viser does not have"
    except Exception:  # noqa: BLE001 — a viser without the registry: the generic words below
        pass
    return f"a message viser cannot read ({type(e).__name__})"


def _refuse_share(server: viser.ViserServer, log: RateLimitedLog) -> None:
    """No share tunnel, whatever arrives: the handlers are removed and the methods they call
    replaced on this server."""
    for cls in (vm.ShareUrlRequest, vm.ShareUrlDisconnect):
        try:
            server._websock_server.unregister_handler(cls)
        except (AssertionError, KeyError, ValueError):
            pass

    def refused(*args, **kwargs):
        log.line("theoria: a share link was requested and refused (this server makes no outbound connection)",
                 once_key="share")
        return None

    server.request_share_url = refused
    server.disconnect_share_url = refused


def check_address(host, port, flag: str = "") -> None:
    """A port and a host this machine can listen on, or ParameterError naming `flag`port or
    `flag`host (viser started its listening thread anyway: it printed a traceback there, and the
    server waited for ever)."""
    import socket

    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ParameterError(f"{flag}port", port, "a whole number from 0 to 65535")
    allowed = "an address of this machine: 127.0.0.1 (this machine only), 0.0.0.0 (every network) or its name"
    try:
        infos = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except (OSError, UnicodeError, TypeError):
        raise ParameterError(f"{flag}host", host, allowed) from None
    for family, kind, proto, _, addr in infos:
        try:
            with socket.socket(family, kind, proto) as s:
                s.bind((addr[0], 0))  # an address of this machine (the port is viser's to take)
            return
        except OSError:
            continue
    raise ParameterError(f"{flag}host", host, allowed)


def make_server(port: int = 8080, host: str = "127.0.0.1", scenario: str | None = None, verbose: bool = True,
                run=None, limits: Limits | None = None, pool: SimPool | None = None, sweep=None):
    """A running viser server with one ClientSession per browser; returns (server, sessions).
    `run`: a finished Run every new browser is shown first (its scenario and parameters).
    `sweep`: a sweep result (a Zarr path, or app.sweep_map.SweepMaps) every browser gets as a map
    in a Sweep tab; its scenario is the first scene. A path that is not a theoria sweep raises
    ParameterError before the server starts, as do a port or host it cannot listen on."""
    check_address(host, port)
    if sweep is not None and not hasattr(sweep, "picture"):
        from .sweep_map import SweepMaps

        sweep = SweepMaps(sweep)
    if sweep is not None:
        scenario = scenario or sweep.scenario.name
        sweep.picture_async(sweep.metrics[0], sweep.default_view(sweep.metrics[0]))  # the first map, ready early
    if run is not None:
        scenario = run.scenario
    if scenario is not None:
        get(scenario)  # a bad name raises ParameterError before the server starts
    log = RateLimitedLog()
    _quiet_libraries(log)
    _read_with_backpressure()
    with page.themed_client():
        if verbose:
            server = viser.ViserServer(host=host, port=port, verbose=True)
        else:
            with contextlib.redirect_stdout(io.StringIO()):  # viser prints its banner even when not verbose
                server = viser.ViserServer(host=host, port=port, verbose=False)
    _refuse_share(server, log)
    door = Door(server, limits or Limits(), log)
    server._theoria_door = door
    pool = pool or shared_pool()
    pool.prepare(scenario or "free-tumble")
    server._theoria_pool = pool
    server._theoria_sweep = sweep
    sessions: dict[int, ClientSession] = {}

    # A session starts by asking the page for its address (up to 10 s for a page that never
    # answers): on threads of its own, one per connection the door lets in, not on viser's pool of
    # 32 callback threads, which forty silent sockets from four addresses held for 10 s at a time
    # (every new student waited that long for a first scene).
    starts = concurrent.futures.ThreadPoolExecutor(max_workers=door.limits.max_connections + 8,
                                                   thread_name_prefix="theoria-session-start")
    gone: set[int] = set()  # clients that left while their session was starting
    lock = threading.Lock()

    def start(client: viser.ClientHandle) -> None:
        try:
            session = ClientSession(server, client, scenario, run=run, sweep=sweep)
        except Exception as e:
            log.line("theoria: a browser's session could not start:\n" + traceback.format_exc())
            try:
                client.add_notification("Error", f"{type(e).__name__}: {e}", color="red")
            except Exception:
                pass
            with lock:
                gone.discard(client.client_id)
            return
        with lock:
            left = client.client_id in gone
            gone.discard(client.client_id)
            if not left:
                sessions[client.client_id] = session
        if left:
            session.close()

    @server.on_client_connect
    async def _(client: viser.ClientHandle) -> None:
        await asyncio.get_running_loop().run_in_executor(starts, start, client)

    @server.on_client_disconnect
    def _(client: viser.ClientHandle) -> None:
        with lock:
            s = sessions.pop(client.client_id, None)
            if s is None:
                gone.add(client.client_id)
        if s is not None:
            s.close()

    return server, sessions


def _watch_parent() -> None:
    """Stop with the process that started us: the kernel signals us when it dies (Linux), and a
    watcher notices being re-parented anywhere else."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except Exception:
        pass
    parent = os.getppid()

    def watch():
        while True:
            time.sleep(1.0)
            if os.getppid() != parent:
                os.kill(os.getpid(), signal.SIGTERM)
                return

    threading.Thread(target=watch, daemon=True, name="theoria-parent-watch").start()


def _raise_fd_limit() -> None:
    try:
        import resource

        soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
        want = hard if hard != resource.RLIM_INFINITY else 65536
        if soft < want:
            resource.setrlimit(resource.RLIMIT_NOFILE, (want, hard))
    except Exception:
        pass


def serve(port: int = 8080, host: str = "127.0.0.1", scenario: str | None = None, run=None,
          limits: Limits | None = None, precompute: bool = True, sweep=None) -> str:
    """Run the web app until interrupted (Ctrl-C, SIGTERM, or the parent process gone), printing
    the URL to open. Returns what ended it, "SIGINT" or "SIGTERM", once everything it started
    has stopped."""
    check_address(host, port)  # before the simulation processes start
    _raise_fd_limit()
    _watch_parent()
    ended = {"by": "SIGINT"}

    def on_term(signum, frame):
        ended["by"] = "SIGTERM"
        raise KeyboardInterrupt

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, on_term)
    t0 = time.perf_counter()
    pool = server = None
    try:  # from here a Ctrl-C (as soon as the URL is printed) stops whatever has started, and only that
        # the pool starts with the child that draws the first scene (a sweep's scenario is read later)
        pool = shared_pool(run.scenario if run is not None else scenario if scenario or sweep else "free-tumble")
        server, _ = make_server(port=port, host=host, scenario=scenario, verbose=False, run=run, limits=limits,
                                pool=pool, sweep=sweep)
        sweep = server._theoria_sweep
        asked, port = port, server.get_port()
        if asked and port != asked:  # viser takes the next free port: a link to the asked one would not open
            print(f"theoria: port {asked} is in use; serving on port {port} instead", flush=True)
        if host in ("0.0.0.0", "::", ""):
            # the students' address is the one the panel shows (this machine's network address): a
            # host name such as "vm" may resolve only on this machine
            students = class_link(host, port) or f"http://{socket.gethostname()}:{port}/"
            print(f"theoria: listening on all interfaces, port {port}; students open {students} "
                  f"(on this machine http://127.0.0.1:{port}/). Ctrl-C to stop.", flush=True)
        else:
            print(f"theoria: open http://{host}:{port}/ in a browser (Ctrl-C to stop)", flush=True)
        if precompute:
            first = run.scenario if run is not None else (scenario or (sweep.scenario.name if sweep else "free-tumble"))
            n = pool.precompute(all_scenarios(), first=first)
            if n:
                print(f"theoria: preparing {n} scenes in the background (defaults and presets, kept for the next "
                      f"start); started in {time.perf_counter() - t0:.1f} s", flush=True)
        announced = not precompute
        while True:
            time.sleep(1.0)
            if not announced and pool.pending_background() == 0 and pool.ready():
                announced = True
                print(f"theoria: every scenario's defaults and presets are ready "
                      f"({time.perf_counter() - t0:.0f} s after start)", flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        if server is not None:
            with contextlib.redirect_stdout(io.StringIO()):
                server.stop()
        if pool is not None:
            pool.close()
        if sweep is not None and server is not None:
            sweep.close()
    return ended["by"]


class Shown:
    """A server showing one run in the background (`Run.show()` in a notebook): `.url`, `.stop()`."""

    def __init__(self, server):
        self.server = server
        self.url = f"http://127.0.0.1:{server.get_port()}/"

    def stop(self) -> None:
        self.server.stop()

    def __repr__(self) -> str:
        return f"<theoria app showing a run at {self.url}>"


def _interactive() -> bool:
    import sys

    return hasattr(sys, "ps1") or bool(sys.flags.interactive) or "ipykernel" in sys.modules


def show_run(run, port: int = 8080, host: str = "127.0.0.1", block: bool | None = None):
    """Serve `run` in the app. Blocks until Ctrl-C in a script (SIGTERM ends the script, exit
    status 143); in an interactive session (a notebook, the REPL) returns a `Shown` handle at once
    and serves in the background."""
    block = (not _interactive()) if block is None else block
    if block:
        if serve(port=port, host=host, run=run, precompute=False) == "SIGTERM":
            # a script asked to end ends (a batch job's kill, a container's stop): the code after
            # show() does not run on as if a student had closed the app; Ctrl-C returns to it
            raise SystemExit(128 + signal.SIGTERM)
        return None
    server, _ = make_server(port=port, host=host, verbose=False, run=run)
    shown = Shown(server)
    print(f"theoria: open {shown.url} in a browser (.stop() to stop)", flush=True)
    return shown
