"""Simulations for every browser of a server: a bounded pool of processes, a run cache, and for
each browser a `SimulationWorker` in which the newest request wins.

Why processes. The server's event loop, the drawing of every scene and the 60 Hz pose stream run
in one Python process and share its interpreter lock. Numba compiles (13-80 s on first use) and a
scenario's own Python and scipy work hold that lock; in a thread they stalled every browser. In a
child process they cost the server nothing but a pipe. A child is also the only run that can be
stopped for certain: a run cancelled by a closed tab or a newer request stops at its next progress
call, and a child that has not answered within CANCEL_GRACE_S is killed (the CPU is idle within a
second or two whatever the scenario's loop does).

- `SimPool` (one per server process, `shared_pool()`): `slots` children sized to the machine
  (quick ones: one more than the cores, at most four; slow ones: one per core, at most three),
  each fed by a thread of this process. Jobs are keyed by
  (scenario, resolved values): runs are deterministic, so thirty students asking for the same
  preset make one job, and a finished run is kept in a server-wide LRU `RunCache` (bounded in
  bytes) and, for the defaults and presets computed in the background at start-up, on disk
  (`RunStore`, keyed by a digest of the physics and scenario sources, so a changed model is
  never served stale). Fairness: a browser has at most one job of its own waiting (a newer
  request replaces it), jobs are taken oldest first, and background jobs only take a slot no
  browser's job is waiting for. A flood of callbacks from one browser therefore costs the others
  nothing but its one job.
- Limits: a run is refused before it starts when the scenario's budget says so
  (`Scenario.check_budget`, when the scenario module has one), and stopped after
  RUN_SECONDS_LIMIT of wall-clock time; a closed tab cancels its job at once.
- First use on a machine (empty numba cache): a scenario whose compiled code is not on disk yet
  is run by an extra child with numba's JIT switched off (pure Python: a fraction of a second for
  the rotation scenes' previews) while the compiling children warm the cache in the background;
  `warm` marks which scenarios have been compiled on this machine. That child starts first and
  alone: the compiling ones wait until it has delivered a run (or FIRST_RUN_WAIT_S), since five
  imports at once on two cores held the first scene back by two seconds.
- `SimulationWorker` (one per browser) keeps the interface the session uses: `submit(spec,
  given)`, `adopt(spec, values)`, `current(req)`, `close()`, and calls back `on_result(req, run,
  seconds)`, `on_error(req, exc)` and `on_progress(percent or None, text)` (throttled: runs
  shorter than PROGRESS_SHOW_AFTER never show a bar). A run expected to take longer than
  PREVIEW_AFTER_S (its scenario's last measured time, scaled by the integrator steps these values
  take: `Scenario.cost_of`) is shown first from the scenario's `preview` values, then refined
  (`req.preview` is True for the coarse one).
"""
from __future__ import annotations

import ctypes
import hashlib
import heapq
import itertools
import logging
import os
import pickle
import signal
import subprocess
import sys
import threading
import time
import traceback
import weakref
from collections import OrderedDict
from dataclasses import dataclass, field, replace
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any, Callable

import numpy as np

from theoria.physics import kept
from theoria.physics.errors import Cancelled, ParameterError, show_value
from theoria.physics.params import MAX_TEXT_CHARS

from .playback import showing

log = logging.getLogger("theoria.server")

PROGRESS_SHOW_AFTER = 0.4  # s
PROGRESS_EVERY = 0.15  # s
RUN_SECONDS_LIMIT = 60.0  # wall-clock seconds one run may take on the server
CANCEL_GRACE_S = 1.0  # a cancelled child that has not stopped by then is killed
KILL_GRACE_S = 5.0  # beyond the run limit, a child that never calls progress is killed
NOJIT_SECONDS_LIMIT = 20.0
COLD_WAIT_S = 3.0  # a job waiting this long for the busy pure-Python child goes to a compiling one
# A run expected to take longer is slow: the quick children (kept for quick runs and previews) do
# not take it, and its scenario's quick preview is shown first. A hundred browsers moving sliders
# ask for several runs a second, and a slow one in a quick child makes every other browser wait for
# it. 0.15 s of CPU: once the Moon's, Cassini's and precession's runs had become cheaper (0.13-0.26 s)
# they fell under the former 0.3 s, ran unpreviewed in the quick children, and a hundred browsers'
# p95 went from 0.49-0.53 s to 0.69-1.13 s; at 0.15 s it was 0.30 s (150-s soaks, benchmarks/classroom.py).
SLOW_JOB_S = 0.15
# A run expected to take longer is shown first from its scenario's preview. At 0.1 s, when the
# previews cost as much as the runs (a Moon preview 0.26 s), p95 went from 0.6 to 1.2 s, every such
# action drawn twice by the server's one interpreter. Previews now cost 0.01-0.07 s; at 0.15 s, once
# Cassini's, Hyperion's, libration-eccentric's and precession's runs had become cheaper (0.12-0.14 s)
# they ran unpreviewed in the quick children and took 0.3-0.4 s on the loaded cores.
PREVIEW_AFTER_S = 0.08
# A run expected to take at most this much CPU is tiny (a slider on the rigid-body scenes: 3-20 ms).
# One child of the server's pool takes tiny runs only: with a hundred browsers, the three quick
# children are mostly busy with previews and runs of 50-300 ms, and a 6-ms run that waited for one
# of them waited 0.5-1.8 s at the 95th percentile.
TINY_JOB_S = 0.03
CACHE_BYTES = 1e9  # finished runs and their drawings kept in memory by the server (LRU)
# Children run below the server: its event loop and its drawing threads (one interpreter lock) are
# what every browser waits for. With a hundred browsers the server's threads spent nearly as long
# waiting for a core as running (0.4-0.5 against 0.5 of a core, /proc schedstat). 150-s soaks of a
# hundred browsers, p95: nice 5, slow ones at 15: 0.70 s; slow ones in SCHED_IDLE: 0.73, 0.88 s;
# nice 10: 0.81 s; nice 15 and SCHED_IDLE: 0.74 s; nice 10 and SCHED_IDLE: 0.38-0.51 s (four soaks).
CHILD_NICE = 10
# The child kept for tiny runs (at most TINY_JOB_S of CPU each: a slider on the rigid-body scenes)
# runs between the server and the quick children: it is busy a few percent of the time, and a
# 10-ms run that waited for a core behind the quick children made the flip's sliders the largest
# group over 200 ms. At nice 5 instead of 10: p95 0.325, 0.462 and 0.358 s (the last with tests running beside it) against
# 0.375-0.510 s; the flip's sliders over 200 ms 31 and 62 of ~262 against 48-83.
CHILD_NICE_TINY = 5
# One slow child takes only browsers' runs expected within this much CPU (runs of a second or a
# few: Hyperion's full run, a tidal capture over many orbits), never the runs of tens of seconds.
# The other slow children take anything, so two students' 30-s Earth runs held both of them and a
# third student's Hyperion run (its preview shown in 0.16 s) waited 32-42 s for one to end; now it
# starts at once and shares the cores with them (the slow children are all in SCHED_IDLE, which
# the kernel time-slices evenly). A run judged short that has taken twice this much CPU while
# another short run waits is stopped and queued again for the other slow children.
SHORT_SLOW_S = 5.0
# The children of slow runs and background work, far below the quick ones: at nice 12 two slow runs
# still took a third of the CPU a quick child wanted (at 15, a tenth). Where Linux offers it they
# run in SCHED_IDLE, which gives way at once to any other process: a quick run, the server.
CHILD_NICE_SLOW = 15
SLOW_CHILD_IDLE = True
# A run judged quick that has taken this much CPU in a quick child, while another quick run waits
# for one, is stopped and queued again as slow (a slider that made a quick scene slow): at most
# this much of its work is lost, instead of the waiting run's seconds. CPU time, not wall time: on
# a loaded machine a quick run of 50 ms can take half a second of wall time.
QUICK_OVERRUN_S = 0.5
# Browsers' runs wait their turn by when they would end if started when asked, a second of expected
# run counting as this many of waiting. Counted once (a 0.1-s run asked now went after a 20-s run
# asked 20 s earlier), a hundred browsers' slow runs (a fraction of two cores, runs of 0.1 s to 30 s)
# all waited ~25 s, previews with them: precession's 23 s at the median, Cassini's 25 s at the 95th
# percentile; counted ten times, 1 ms and 6.6 s. A long run asked earlier still goes first once it
# has waited ten times the difference of the two lengths.
SHORT_FIRST = 10.0
# threads that draw finished runs for the browsers: the drawing holds the interpreter lock, so
# more threads only take turns (with four, a hundred browsers' answers waited ~1 s longer at the
# 95th percentile than with one or two); two, so that one long drawing does not hold up the rest
APPLY_THREADS = 2


class TimeLimit(Exception):
    """A run stopped at the server's wall-clock limit (RUN_SECONDS_LIMIT)."""


# ---- keys, sizes, the cache ------------------------------------------------------------------

def _canon(v):
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, (tuple, list, np.ndarray)):
        return tuple(_canon(x) for x in v)
    return str(v)


def run_key(name: str, values: dict) -> str:
    """The cache key of a run: its scenario and its resolved values (runs are deterministic)."""
    items = tuple(sorted((k, _canon(v)) for k, v in values.items()))
    return name + ":" + hashlib.blake2b(repr(items).encode(), digest_size=16).hexdigest()


# what holds no array, passed over without a call (a drawing's per-frame text: walked item by item,
# the size of a fresh Hyperion drawing took 8 ms of the server's interpreter lock, a third of making
# the drawing)
_NO_ARRAYS = (str, bytes, int, float, complex, type(None), np.generic)


def nbytes(obj, _depth: int = 0) -> int:
    """Bytes held by the numpy arrays of a Run (its trajectory, series, extras), roughly."""
    if _depth > 6 or isinstance(obj, _NO_ARRAYS):
        return 0
    if isinstance(obj, np.ndarray):
        return int(obj.nbytes)
    if isinstance(obj, dict):
        return sum(nbytes(v, _depth + 1) for v in obj.values())
    if isinstance(obj, (list, tuple)):
        return sum(nbytes(v, _depth + 1) for v in obj[:10000] if not isinstance(v, _NO_ARRAYS))
    names = getattr(type(obj), "__dataclass_fields__", None)
    if names is not None:
        fields = sum(nbytes(getattr(obj, name, None), _depth + 1) for name in names if name != "spec")
        # and what it computed since and keeps (a Trajectory's ω, L in space, energy, axes: 55.7 MB
        # counted of 90.8 MB held for a long earth-long-view), but not the drawings and the cache's
        # own marks, counted by the cache
        extra = getattr(obj, "__dict__", {})
        return fields + sum(nbytes(v, _depth + 1) for k, v in extra.items()
                            if k not in names and k not in _COUNTED_APART)
    return 0


_COUNTED_APART = ("_theoria_drawings", "_theoria_cache", "spec")


class RunCache:
    """Finished runs by key, least recently used dropped first, at most `max_bytes` of arrays:
    the run's and those of the drawings kept with it (`drawing_of`: 2-10 times the run's)."""

    def __init__(self, max_bytes: float = CACHE_BYTES):
        self.max_bytes = max_bytes
        self._d: OrderedDict[str, tuple[Any, int, float]] = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()
        self.hits = self.misses = 0

    def get(self, key: str):
        with self._lock:
            hit = self._d.get(key)
            if hit is None:
                self.misses += 1
                return None
            self._d.move_to_end(key)
            self.hits += 1
            return hit[0], hit[2]

    def put(self, key: str, run, seconds: float) -> None:
        size = nbytes(run) + sum(nbytes(d) for d in run.__dict__.get("_theoria_drawings", {}).values())
        if size > self.max_bytes / 4:  # one huge run would push out the whole class's presets
            return
        with self._lock:
            old = self._d.pop(key, None)
            if old is not None:
                self._bytes -= old[1]
            self._d[key] = (run, size, seconds)
            self._bytes += size
            run.__dict__["_theoria_cache"] = (self, key)
            self._trim()

    def grew(self, key: str, run, delta: int) -> None:
        """`run`, cached under `key`, holds more (or fewer) bytes: a drawing was kept with it, and
        drawing it computed arrays its trajectory keeps. Measured again whole (`delta`, the
        drawing's own size, is what the caller knows)."""
        size = nbytes(run) + sum(nbytes(d) for d in run.__dict__.get("_theoria_drawings", {}).values())
        with self._lock:
            hit = self._d.get(key)
            if hit is None or hit[0] is not run:
                return
            self._d[key] = (run, size, hit[2])
            self._bytes += size - hit[1]
            self._trim()

    def _trim(self) -> None:
        while self._bytes > self.max_bytes and len(self._d) > 1:
            _, (_, s, _) = self._d.popitem(last=False)
            self._bytes -= s

    @property
    def size_bytes(self) -> int:
        return self._bytes

    def __len__(self) -> int:
        return len(self._d)


def cache_root() -> Path:
    """Where theoria keeps what it computed for this machine: $THEORIA_CACHE_DIR, else the user's
    cache directory (~/.cache/theoria)."""
    d = os.environ.get("THEORIA_CACHE_DIR")
    if d:
        return Path(d)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "theoria"


_CODE_KEY: str | None = None


def install_key() -> str:
    """A digest of where this copy of theoria is installed (numba's cache of its compiled code is
    there when NUMBA_CACHE_DIR is not set)."""
    import theoria

    where = str(Path(theoria.__file__).resolve().parent)
    return hashlib.blake2b(where.encode(), digest_size=6).hexdigest()


def code_key() -> str:
    """A digest of everything a run depends on: the physics and scenario sources and the versions
    of the numerical libraries. A stored run made by other code is never served."""
    global _CODE_KEY
    if _CODE_KEY is None:
        import importlib

        h = hashlib.blake2b(digest_size=10)
        # (theoria.scenarios the attribute is the front door's function; the package is in sys.modules)
        for pkg in (importlib.import_module("theoria.physics"), importlib.import_module("theoria.scenarios")):
            for root in pkg.__path__:
                for p in sorted(Path(root).rglob("*.py")):
                    h.update(str(p.relative_to(root)).encode())
                    h.update(p.read_bytes())
        for mod in ("numpy", "scipy", "numba", "rebound"):
            m = sys.modules.get(mod)
            h.update(f"{mod}={getattr(m, '__version__', '?')}".encode())
        _CODE_KEY = h.hexdigest()
    return _CODE_KEY


class RunStore:
    """Runs kept on disk between servers: the defaults and presets precomputed in the background,
    so that the next start serves every first scene without computing. Files are written whole
    (a temporary file renamed) and read only from this user's cache directory."""

    def __init__(self, root: Path | None = None):
        self.root = (root or cache_root()) / "runs" / code_key()

    def _path(self, key: str) -> Path:
        name, digest = key.split(":", 1)
        return self.root / name / f"{digest}.pkl.zst"

    def get(self, key: str):
        p = self._path(key)
        try:
            import zstandard

            data = zstandard.ZstdDecompressor().decompress(p.read_bytes())
            run, seconds = pickle.loads(data)
            return run, seconds
        except FileNotFoundError:
            return None
        except Exception as e:  # a damaged or foreign file: ignored, recomputed
            log.info("stored run %s unreadable (%s): recomputing", p.name, type(e).__name__)
            return None

    def put(self, key: str, run, seconds: float) -> None:
        p = self._path(key)
        try:
            import zstandard

            p.parent.mkdir(parents=True, exist_ok=True)
            data = zstandard.ZstdCompressor(level=3).compress(pickle.dumps((_portable(run), seconds), protocol=5))
            tmp = p.with_suffix(f".tmp{os.getpid()}")
            tmp.write_bytes(data)
            os.replace(tmp, p)
        except Exception as e:  # a full or read-only disk: the run is simply not kept
            log.info("could not store a run (%s: %s)", type(e).__name__, e)


def _portable(run):
    """The run without its Scenario (functions do not travel; the receiver sets it again) and
    without what this server keeps with it (its drawings, its place in the run cache)."""
    import copy

    run = copy.copy(run)
    run.spec = None
    for k in [k for k in vars(run) if k.startswith("_theoria_")]:
        del run.__dict__[k]
    return run


class WarmMarks:
    """Which scenarios' compiled code is on this machine's numba cache: a file per scenario,
    written after a compiling child has run it, in the numba cache directory when one is set.
    Without one, numba keeps the compiled code beside the installed sources, so the marks are
    kept per install: a second virtual environment with the same code was taken for warm, and a
    scenario opened there first compiled on the serving path (19–24 s to its first scene, against
    ~4 s on the path for a cold cache)."""

    def __init__(self):
        d = os.environ.get("NUMBA_CACHE_DIR")
        self.root = (Path(d) / "theoria-warm" if d else cache_root() / "warm" / install_key()) / code_key()
        self._known: set[str] = set()

    def __contains__(self, name: str) -> bool:
        if name in self._known:
            return True
        if (self.root / name).exists():
            self._known.add(name)
            return True
        return False

    def add(self, name: str) -> None:
        if name in self._known:
            return
        self._known.add(name)
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            (self.root / name).touch()
        except OSError:
            pass


# ---- errors across the pipe ------------------------------------------------------------------

def _error_payload(e: BaseException) -> tuple:
    if isinstance(e, ParameterError):
        return ("param", type(e).__module__, type(e).__qualname__, e.name, show_value(e.value), e.allowed)
    if isinstance(e, TimeLimit):
        return ("timelimit", str(e))
    tb = "".join(traceback.format_exception(type(e), e, e.__traceback__))[-3000:]
    return ("error", type(e).__name__, str(e)[:500], tb)


class RemoteError(Exception):
    """An exception raised by a scenario in a child process (its type name and message kept)."""

    def __init__(self, type_name: str, message: str, tb: str = ""):
        super().__init__(message)
        self.type_name, self.remote_traceback = type_name, tb

    def __str__(self) -> str:
        return super().__str__()


def _rebuild_error(payload: tuple, spec) -> BaseException:
    kind = payload[0]
    if kind == "param":
        _, mod, qual, name, value, allowed = payload
        cls = ParameterError
        try:
            import importlib

            c = getattr(importlib.import_module(mod), qual)
            if isinstance(c, type) and issubclass(c, ParameterError):
                cls = c
        except Exception:
            pass
        try:
            return cls(name, value, allowed)
        except Exception:
            return ParameterError(name, value, allowed)
    if kind == "timelimit":
        return time_limit_error(spec)
    _, type_name, message, tb = payload
    e = RemoteError(type_name, message, tb)
    e.__class__ = type(type_name, (RemoteError,), {})  # the notification names the scenario's own error type
    return e


def time_limit_error(spec) -> ParameterError:
    names = [p.name for p in getattr(spec, "params", ())]
    name = next((n for n in ("duration", "years", "turns", "days") if n in names), "parameters")
    return ParameterError(name, "these values", f"a run may take at most {RUN_SECONDS_LIMIT:g} s of computing on "
                          "this server and this one was stopped; try a shorter duration or a larger step")


# ---- the child process -----------------------------------------------------------------------

def _die_with_parent() -> None:
    """Linux: the kernel sends SIGKILL to this child when the server process dies."""
    try:
        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except Exception:
        pass


def child_main(read_fd: int, write_fd: int) -> None:
    """A simulation child: reads ("run", job id, scenario, values, limit s) and answers
    ("done", id, run, seconds, CPU seconds, reused) | ("cancelled", id) | ("failed", id, payload), with
    ("progress", id, fraction) in between (`reused`: the run took a piece kept from an earlier one,
    physics.kept). SIGUSR1 cancels the run in progress."""
    _die_with_parent()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C in the terminal stops the server, which stops us
    cancel = {"flag": False}

    def on_usr1(signum, frame):
        cancel["flag"] = True

    signal.signal(signal.SIGUSR1, on_usr1)
    sys.stdout = sys.stderr  # the pipe carries frames only
    inbox, outbox = Connection(read_fd, writable=False), Connection(write_fd, readable=False)
    from theoria.scenarios import get
    from theoria.scenarios.base import load_all

    load_all()
    outbox.send(("ready", os.getpid()))
    while True:
        try:
            msg = inbox.recv()
        except (EOFError, OSError):
            return
        if msg[0] == "quit":
            return
        _, jid, name, values, limit = msg
        cancel["flag"] = False
        t0, cpu0, reused0 = time.perf_counter(), time.process_time(), kept.reused()
        last = [0.0]

        def progress(frac, jid=jid):
            if cancel["flag"]:
                raise Cancelled()
            now = time.perf_counter()
            if now - t0 > limit:
                raise TimeLimit(f"stopped after {limit:g} s")
            if now - last[0] > 0.1:
                last[0] = now
                try:
                    outbox.send(("progress", jid, float(frac)))
                except Exception:
                    pass

        try:
            spec = get(name)
            run = spec.simulate_fn(values, progress=progress)
            dt = time.perf_counter() - t0
            _draw_ahead(spec, run)
            run.spec = None
            outbox.send(("done", jid, run, dt, time.process_time() - cpu0, kept.reused() > reused0))
        except Cancelled:
            outbox.send(("cancelled", jid))
        except BaseException as e:  # noqa: BLE001 — every failure goes back as a message
            try:
                outbox.send(("failed", jid, _error_payload(e)))
            except Exception:
                outbox.send(("failed", jid, ("error", type(e).__name__, "the result could not be sent", "")))


# ---- jobs and the pool -----------------------------------------------------------------------

def _steps(spec, values: dict) -> float:
    """Integrator steps of a run of `values` (Scenario.cost_of), 0 when it cannot be told."""
    try:
        steps = float(spec.cost_of(values).steps)
    except Exception:
        return 0.0
    return steps if np.isfinite(steps) and steps > 0 else 0.0


_ids = itertools.count(1)


@dataclass(eq=False)
class Job:
    key: str
    spec: Any
    values: dict
    background: bool = False
    preview: bool = False
    id: int = field(default_factory=lambda: next(_ids))
    created: float = field(default_factory=time.perf_counter)
    waiters: list = field(default_factory=list)  # SimulationWorkers waiting for it
    state: str = "queued"  # queued, running, done
    slot: Any = None
    started: float | None = None
    cancel: bool = False
    preempted: bool = False  # a background job stopped to free its child for a browser (queued again)
    overran: bool = False  # judged quick, it ran past QUICK_OVERRUN_S in a quick child: slow from now on
    short_overran: bool = False  # judged short, it ran past 2 × SHORT_SLOW_S in the short child: long from now on
    cpu: float | None = None  # CPU seconds the child spent on it (for the timing log)
    nojit_tried: bool = False
    progress: float | None = None

    @property
    def steps(self) -> float:
        """Integrator steps the run takes (its scenario's cost estimate; 0: unknown)."""
        if "_steps" not in self.__dict__:
            self.__dict__["_steps"] = _steps(self.spec, self.values)
        return self.__dict__["_steps"]

    @property
    def cache_key(self) -> str:
        """The run's key in the caches (a warming job has a key of its own so that it is never
        merged with a browser's job, which a pure-Python child may be running)."""
        return self.key.split("#", 1)[0]

    @property
    def local(self) -> bool:
        """Run in a thread of this process: a scenario defined outside theoria's scenarios
        package (a test's, a notebook's) is unknown to a child."""
        mod = getattr(self.spec.simulate_fn, "__module__", "") or ""
        return not mod.startswith("theoria.scenarios.")


FIRST_CHILD_WAIT_S = 20.0  # the other children start anyway when the first has not come up by then
FIRST_RUN_WAIT_S = 3.0  # ... and when it has been up this long without a run to do


def _cpu_seconds(pid: int) -> float:
    """CPU seconds (user + system) process `pid` has used, from /proc; 0 where there is none."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            fields = f.read().rsplit(b")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return 0.0


class _Slot:
    """One simulation child and the thread of this process that feeds it."""

    def __init__(self, pool: "SimPool", index: int, jit: bool = True, use_process: bool = True):
        self.pool, self.index, self.jit, self.use_process = pool, index, jit, use_process
        self.tiny = jit and index == pool.tiny_index  # takes tiny runs only
        self.short = jit and index == pool.short_index  # takes browsers' slow runs of a few seconds only
        self.quick = jit and (index < pool.quick_n or self.tiny)  # takes quick runs and previews only
        self.proc: subprocess.Popen | None = None
        self.inbox: Connection | None = None  # child → us
        self.outbox: Connection | None = None
        self.job: Job | None = None
        self.busy_since: float | None = None
        self.runs = 0
        self.kills = 0
        self.seen: set[str] = set()  # scenarios the child has run since it started
        self.ready = not use_process  # a child is up and has imported the scenarios
        self._thread = threading.Thread(target=self._loop, daemon=True,
                                        name=f"theoria-sim-{'jit' if jit else 'nojit'}-{index}")
        self._thread.start()

    # the child ----------------------------------------------------------------------------
    def _start(self) -> bool:
        r1, w1 = os.pipe()  # us → child
        r2, w2 = os.pipe()  # child → us
        env = dict(os.environ)
        if not self.jit:
            env["NUMBA_DISABLE_JIT"] = "1"
        # One thread a child for BLAS and for numba's parallel loops: the pool's parallelism is its
        # processes. A second thread spins on a core a sibling is using: on a busy machine the
        # Moon's preview (least-squares fits) took 0.055 CPU-seconds with two BLAS threads, 0.027
        # with one; a tidal-capture run (one body, one vector block) 0.61 with two numba threads,
        # 0.45 with one, and no sooner (0.52 s against 0.45 s).
        for var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
            env.setdefault(var, "1")
        # `python -c` puts the working folder first on sys.path: started from a checkout of theoria
        # (README's first command), the child imported the checkout's theoria/ folder, which holds
        # only the front door, instead of the installed package; the child imports what the server did
        code = ("import os,sys; sys.path[:] = [p for p in sys.path if p]; "
                "os.nice(int(sys.argv[3])) if hasattr(os,'nice') else None\n"
                "if sys.argv[4] == 'idle' and hasattr(os, 'SCHED_IDLE'):\n"
                "    try: os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))\n"
                "    except OSError: pass\n"
                "from theoria.app.worker import child_main; child_main(int(sys.argv[1]), int(sys.argv[2]))")
        slow = self.jit and not self.quick
        try:
            self.proc = subprocess.Popen([sys.executable, "-c", code, str(r1), str(w2),
                                          str(CHILD_NICE_TINY if self.tiny else CHILD_NICE if self.quick
                                              else CHILD_NICE_SLOW if self.jit
                                              else max(0, CHILD_NICE - 3)),
                                          "idle" if slow and SLOW_CHILD_IDLE else "-"],
                                         pass_fds=(r1, w2), env=env, stdin=subprocess.DEVNULL,
                                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                         close_fds=True)
        except OSError as e:
            log.warning("could not start a simulation process (%s); running in threads", e)
            for fd in (r1, w1, r2, w2):
                os.close(fd)
            self.use_process = False
            return False
        os.close(r1)
        os.close(w2)
        self.outbox = Connection(w1, readable=False)
        self.inbox = Connection(r2, writable=False)
        self.seen = set()
        threading.Thread(target=self._stderr, args=(self.proc,), daemon=True,
                         name=f"theoria-sim-log-{self.index}").start()
        if not self._wait_ready():
            self._kill("did not start")
            return False
        self.ready = True
        return True

    def _wait_ready(self, limit: float = 300.0) -> bool:
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < limit and not self.pool.closed:
            if self.proc.poll() is not None:
                return False
            if self.inbox.poll(0.2):
                try:
                    msg = self.inbox.recv()
                except (EOFError, OSError):
                    return False
                return msg[0] == "ready"
        return False

    def _stderr(self, proc) -> None:
        for line in iter(proc.stderr.readline, b""):
            self.pool.logger.line(f"simulation process: {line.decode(errors='replace').rstrip()}")

    def _kill(self, why: str) -> None:
        p = self.proc
        self.proc = None
        if p is not None and p.poll() is None:
            try:
                p.kill()
                p.wait(5)
            except Exception:
                pass
            self.kills += 1
            log.info("simulation process %d stopped: %s", p.pid, why)
        for c in (self.inbox, self.outbox):
            try:
                if c is not None:
                    c.close()
            except Exception:
                pass
        self.inbox = self.outbox = None

    def close(self) -> None:
        p = self.proc
        if p is not None and p.poll() is None:
            try:
                self.outbox.send(("quit",))
            except Exception:
                pass
            try:
                p.wait(1.0)
            except Exception:
                pass
        self._kill("server stopped")

    @property
    def pid(self) -> int | None:
        return self.proc.pid if self.proc is not None and self.proc.poll() is None else None

    # the loop ------------------------------------------------------------------------------
    def _loop(self) -> None:
        if self.use_process and self.jit and (self.index > 0 or self.pool.nojit is not None):
            self.pool._first_child.wait(FIRST_CHILD_WAIT_S)
            self.pool._first_run.wait(FIRST_RUN_WAIT_S)
        if self.use_process and not self.pool.closed:
            self._start()  # ready before the first job: a child takes seconds to import numpy and scipy
            self.pool._first_child.set()
        while True:
            job = self.pool._take(self)
            if job is None:
                return
            self.busy_since = time.perf_counter()
            try:
                if job.local or not self.use_process:
                    self._run_here(job)
                else:
                    self._run_child(job)
            except Exception:  # a bug here must not lose the slot
                self.pool.logger.line("simulation slot error:\n" + traceback.format_exc())
                self.pool._failed(job, ("error", "RuntimeError", "internal error in the simulation pool", ""), self)
            finally:
                self.busy_since = None
                self.job = None

    def _run_here(self, job: Job) -> None:
        t0, reused0 = time.perf_counter(), kept.reused()  # other threads' runs may count too: then not learned

        def progress(frac):
            if job.cancel or job.preempted or self.pool.closed:
                raise Cancelled()
            if time.perf_counter() - t0 > RUN_SECONDS_LIMIT:
                raise TimeLimit()
            self.pool._progress(job, frac)

        try:
            run = job.spec.simulate_fn(job.values, progress=progress)
        except Cancelled:
            self.pool._cancelled(job)
            return
        except BaseException as e:  # noqa: BLE001
            self.pool._failed(job, _error_payload(e), self, exc=e)
            return
        self.pool._done(job, run, time.perf_counter() - t0, self, reused=kept.reused() > reused0)

    def _run_child(self, job: Job) -> None:
        if self.proc is None or self.proc.poll() is not None:
            self._kill("exited")
            if not self._start():
                if not self.use_process:
                    return self._run_here(job)
                self.pool._requeue(job)
                time.sleep(1.0)
                return
        limit = RUN_SECONDS_LIMIT if self.jit else NOJIT_SECONDS_LIMIT
        self.outbox.send(("run", job.id, job.spec.name, job.values, limit))
        t0 = time.perf_counter()
        cpu0 = _cpu_seconds(self.proc.pid) if (self.quick or self.short) else None
        signalled = None
        while True:
            now = time.perf_counter()
            if (cpu0 is not None and self.quick and not job.overran and not job.preview and now - t0 > QUICK_OVERRUN_S
                    and _cpu_seconds(self.proc.pid) - cpu0 > QUICK_OVERRUN_S and self.pool.quick_waiting()):
                job.overran = job.preempted = True  # queued again, for a slow child
                self.pool.stats["overran"] += 1
            if (cpu0 is not None and self.short and not job.short_overran and now - t0 > 2 * SHORT_SLOW_S
                    and _cpu_seconds(self.proc.pid) - cpu0 > 2 * SHORT_SLOW_S and self.pool.short_waiting()):
                job.short_overran = job.preempted = True  # queued again, for the other slow children
                self.pool.stats["overran"] += 1
            if (job.cancel or job.preempted or self.pool.closed) and signalled is None:
                signalled = now
                try:
                    os.kill(self.proc.pid, signal.SIGUSR1)
                except (OSError, AttributeError):
                    pass
            if signalled is not None and now - signalled > CANCEL_GRACE_S:
                self._kill("a cancelled run did not stop")  # e.g. numba compiling: no progress call
                self.pool._cancelled(job)
                return
            if now - t0 > limit + KILL_GRACE_S:
                self._kill("over the time limit without a progress call")
                self.pool._failed(job, ("timelimit", "killed"), self)
                return
            try:
                ready = self.inbox.poll(0.05)
            except (OSError, EOFError, AttributeError):
                ready = False
            if self.proc is None:  # killed meanwhile (the pool closing)
                self.pool._cancelled(job)
                return
            if not ready:
                if self.proc.poll() is not None:
                    self._kill("died")
                    self.pool._failed(job, ("error", "RuntimeError", "the simulation process stopped unexpectedly", ""),
                                      self)
                    return
                continue
            try:
                msg = self.inbox.recv()
            except (EOFError, OSError, pickle.UnpicklingError) as e:
                self._kill(f"unreadable answer ({type(e).__name__})")
                self.pool._failed(job, ("error", "RuntimeError", "the simulation process stopped unexpectedly", ""), self)
                return
            kind = msg[0]
            if msg[1] != job.id:
                continue
            if kind == "progress":
                self.pool._progress(job, msg[2])
            elif kind == "done":
                self.runs += 1
                self.pool._done(job, msg[2], msg[3], self, cpu=msg[4], reused=msg[5])
                return
            elif kind == "cancelled":
                self.pool._cancelled(job)
                return
            elif kind == "failed":
                payload = msg[2]
                if not self.jit and payload[0] == "timelimit":  # too slow without numba: compile instead
                    job.nojit_tried = True
                    self.pool._requeue(job)
                    return
                self.pool._failed(job, payload, self)
                return


class RateLimitedLog:
    """Server log lines, at most `per_minute` a minute; the rest are counted and summarised."""

    def __init__(self, per_minute: int = 30, stream=None):
        self.per_minute = per_minute
        self.stream = stream
        self._window = 0.0
        self._n = 0
        self._dropped = 0
        self._once: set = set()
        self._lock = threading.Lock()

    def line(self, text: str, once_key=None) -> bool:
        with self._lock:
            if once_key is not None:
                if once_key in self._once:
                    return False
                if len(self._once) < 10000:
                    self._once.add(once_key)
            now = time.monotonic()
            if now - self._window > 60.0:
                if self._dropped:
                    self._emit(f"theoria: {self._dropped} more log lines in the last minute were not shown")
                self._window, self._n, self._dropped = now, 0, 0
            if self._n >= self.per_minute:
                self._dropped += 1
                return False
            self._n += 1
        self._emit(text[:2000])
        return True

    def _emit(self, text: str) -> None:
        stream = self.stream or sys.stderr
        try:
            stream.write(text.rstrip("\n") + "\n")
            stream.flush()
        except Exception:
            pass


class SimPool:
    """The server's simulations: `slots` compiling children, one pure-Python child while some
    scenario is not compiled on this machine yet, a run cache and a disk store."""

    def __init__(self, slots: int | None = None, use_processes: bool | None = None, store: bool = True,
                 cache_bytes: float = CACHE_BYTES, first: str | None = None, tiny: bool | None = None,
                 short: bool | None = None):
        """`first`: the scenario browsers will ask for first (see `prepare`). `tiny`: one more child
        for tiny runs only (TINY_JOB_S); `short`: one more slow child for browsers' runs of a few
        seconds only (SHORT_SLOW_S). The server's pool has both, a pool of `slots` only if asked."""
        if use_processes is None:
            use_processes = os.name == "posix" and os.environ.get("THEORIA_SIM_PROCESSES", "1") != "0"
        # the quick children (one more than the cores, at most 4) only ever take quick runs and
        # previews (a slider on a quick scene, the first picture of a slow one); the others (one
        # per core, at most 3) take slow runs and background work at a far lower priority, so that
        # on a loaded machine a quick answer is not shared out with a run of seconds (every child
        # runs below the server: the event loop comes first)
        cores = os.cpu_count() or 1
        self.quick_n = slots // 2 if slots else min(4, cores + 1)
        self.slots_n = slots or self.quick_n + min(3, cores)
        self.short_index = None  # the slow child for runs of a few seconds
        if (slots is None) if short is None else short:
            self.short_index = self.slots_n
            self.slots_n += 1
        self.tiny_index = None  # the child for tiny runs, started last (the first child shows the first scene)
        if (slots is None) if tiny is None else tiny:
            self.tiny_index = self.slots_n
            self.slots_n += 1
        self.use_processes = use_processes
        self.cache = RunCache(cache_bytes)
        self.store = RunStore() if store else None
        self.warm = WarmMarks()
        self.logger = RateLimitedLog()
        self.closed = False
        self._cv = threading.Condition()
        self._jobs: dict[str, Job] = {}  # key → queued or running job
        self._queue: list[Job] = []
        # (scenario, preview) → (seconds, integrator steps) of its last compiled run: a job's time
        # is expected in proportion to its steps (a slider at a long duration makes a slow run of
        # a scenario whose default is quick)
        self._seconds: dict[tuple, tuple[float, float, bool]] = {}  # (seconds, steps, made afresh)
        self._cheapest: dict[str, tuple[float, float, bool]] = {}  # scenario → its cheapest run per step, as above
        self._apply = FairDrawing(APPLY_THREADS)
        self._timers: list = []
        self._timer_cv = threading.Condition()
        self._timer_thread = None
        self.stats = {"jobs": 0, "coalesced": 0, "cache_hits": 0, "store_hits": 0, "cancelled": 0, "failed": 0,
                      "overran": 0}
        # children import numpy, scipy, numba and every scenario (~1.5 s of CPU each): started all
        # at once on a small machine they delay the one that draws the first scene by seconds, so
        # one starts (the pure-Python child on a fresh install), the others once it is up
        self._first_child = threading.Event()
        self._first_run = threading.Event()
        self.nojit: _Slot | None = None
        self.slots: list[_Slot] = []
        if first is not None:
            self.prepare(first)
        self.slots = [_Slot(self, i, True, use_processes) for i in range(self.slots_n)]

    def prepare(self, first: str | None) -> None:
        """Start the pure-Python child at once when the first scenario browsers will ask for is
        not compiled on this machine yet (a fresh install): it shows the first scene while the
        compiling children warm numba's cache."""
        if first is None or not self.use_processes:
            return
        with self._cv:
            try:
                from theoria.scenarios import get

                if first not in self.warm and self.nojit is None and not get(first).chaotic:
                    self.nojit = _Slot(self, self.slots_n, jit=False)
                if first not in self.warm:
                    self._warm_soon(get(first))
            except Exception:
                pass
            self._cv.notify_all()

    # ---- what the workers call ------------------------------------------------------------
    def lookup(self, name: str, values: dict):
        """A finished run of these values, from memory or disk: (run, seconds) or None."""
        key = run_key(name, values)
        hit = self.cache.get(key)
        if hit is None and self.store is not None:
            hit = self.store.get(key)
            if hit is not None:
                self.cache.put(key, hit[0], hit[1])
                # a stored run's time, as it was made then (afresh or not: unknown, so not afresh)
                self._seconds.setdefault((name, False), (hit[1], _steps(hit[0].spec, values), False))
                self.stats["store_hits"] += 1
        elif hit is not None:
            self.stats["cache_hits"] += 1
        return hit

    def expected_seconds(self, spec, values: dict, preview: bool = False, steps: float | None = None) -> float | None:
        """Seconds a compiled run of these values should take: the scenario's last run of the
        same kind (full or preview), scaled by the ratio of integrator steps; None: never timed."""
        known = self._seconds.get((spec.name, preview)) or self._seconds.get((spec.name, not preview))
        if known is None:
            return None
        seconds, then = known[:2]
        new = _steps(spec, values) if steps is None else steps
        if not (then > 0 and new > 0):
            return seconds
        return seconds * new / then

    def job_for(self, spec, values: dict, waiter, preview: bool = False) -> Job:
        """The job computing these values (an existing one is shared), with `waiter` attached."""
        key = run_key(spec.name, values)
        with self._cv:
            job = self._jobs.get(key)
            if job is not None and job.state != "done" and not job.cancel:
                self.stats["coalesced"] += 1
                if waiter not in job.waiters:
                    job.waiters.append(waiter)
                if job.background:  # a browser waits for it now: it goes before the background jobs
                    job.background = False
                    job.preempted = False
                    if job.state == "queued":
                        job.created = time.perf_counter()
                        self._preempt(job)
                self._cv.notify_all()
                return job
            job = Job(key, spec, dict(values), preview=preview, waiters=[waiter])
            self._add(job)
            return job

    def detach(self, job: Job, waiter) -> None:
        """`waiter` no longer wants `job`; a job nobody waits for is cancelled (unless it is
        background work: it then finishes for the cache)."""
        with self._cv:
            if waiter in job.waiters:
                job.waiters.remove(waiter)
            if job.waiters or job.state == "done" or job.background:
                return
            if job.state == "queued":
                self._drop(job)
                self.stats["cancelled"] += 1
            else:
                job.cancel = True
            self._cv.notify_all()

    def precompute(self, specs, first: str | None = None) -> int:
        """Background jobs for the defaults and every preset of `specs` (the `first` scenario
        first) not cached yet; returns how many were queued."""
        n = 0
        specs = sorted(specs, key=lambda s: s.name != first)
        for s in specs:
            wanted = [{}] + [dict(v) for v in s.presets.values()]
            for given in wanted:
                try:
                    values = s.resolve(given)
                except Exception:
                    continue
                key = run_key(s.name, values)
                if self.lookup(s.name, values) is not None:
                    continue
                with self._cv:
                    if key in self._jobs:
                        continue
                    self._add(Job(key, s, values, background=True))
                n += 1
        return n

    def ready(self) -> bool:
        """Every compiling child is up (they take seconds to import numpy, scipy and numba)."""
        return all(s.ready for s in self.slots)

    def pending_background(self) -> int:
        with self._cv:
            return sum(1 for j in self._jobs.values() if j.background)

    def busy(self) -> bool:
        with self._cv:
            return bool(self._jobs)

    def child_pids(self) -> list[int]:
        return [p for p in (s.pid for s in self.slots + ([self.nojit] if self.nojit else [])) if p]

    def close(self) -> None:
        with self._cv:
            self.closed = True
            self._first_child.set()
            self._first_run.set()
            for j in self._jobs.values():
                j.cancel = True
            self._cv.notify_all()
        for s in self.slots + ([self.nojit] if self.nojit else []):
            s.close()
        self._apply.close()

    # ---- scheduling -------------------------------------------------------------------------
    def _add(self, job: Job) -> None:
        self._jobs[job.key] = job
        self._queue.append(job)
        self.stats["jobs"] += 1
        if self._cold(job):
            if self.nojit is None:
                self.nojit = _Slot(self, self.slots_n, jit=False)
            self._warm_soon(job.spec)
        if not job.background:
            self._preempt(job)
        self._cv.notify_all()

    def _preempt(self, job: Job) -> None:
        """A browser's job is waiting and every compiling child that could take it is busy: a
        background job (not one compiling a scenario for the first time) is stopped and queued
        again."""
        if any(s.job is None and self._eligible(s, job) for s in self.slots):
            return
        for s in self.slots:
            j = s.job
            if j is not None and j.background and not j.key.endswith("#warm") and not j.preempted \
                    and j.spec.name in self.warm:
                j.preempted = True
                return

    def _warm_soon(self, spec) -> None:
        """Compile `spec`'s code in the background (a run of its preview), before other background work."""
        try:
            values = spec.resolve(dict(spec.preview))
        except Exception:
            return
        key = run_key(spec.name, values) + "#warm"
        job = self._jobs.get(key)
        if job is None:
            job = Job(key, spec, values, background=True, preview=True)
            self._jobs[key] = job
            self._queue.append(job)
        if job.background and job.state == "queued":
            job.created = -1.0  # first among the background jobs

    def _drop(self, job: Job) -> None:
        if self._jobs.get(job.key) is job:
            del self._jobs[job.key]
        if job in self._queue:
            self._queue.remove(job)
        job.state = "done"

    def _cold(self, job: Job) -> bool:
        """A browser's job the pure-Python child should take: its scenario is not compiled here yet
        (and not chaotic: a chaotic scene's numbers are the compiled code's only)."""
        return (self.use_processes and not job.background and not job.local and not job.nojit_tried
                and not job.spec.chaotic and job.spec.name not in self.warm)

    def _slow(self, job: Job) -> bool:
        if job.preview and not job.background:
            # a quick preview is what makes a slow run bearable: it goes before every full run,
            # unless even at its scenario's cheapest pace per step it would hold a quick child for
            # long (earth-long-view's full integration previewed over 25,800 years: 2 s at that
            # pace, 8 s of CPU in fact, while every quick run of the class waited for the child)
            return self._least_seconds(job) > SLOW_JOB_S
        if job.overran:
            return True
        t = self.expected_seconds(job.spec, job.values, job.preview, steps=job.steps)
        return t is None or t > SLOW_JOB_S

    def _least_seconds(self, job: Job) -> float:
        """CPU seconds of `job` at its scenario's cheapest pace per integrator step so far (0 when
        there is none yet): a lower bound that a loaded machine or a first run does not inflate."""
        best = self._cheapest.get(job.spec.name)
        if best is None or not best[1] > 0:
            return 0.0
        return best[0] * job.steps / best[1]

    def _tiny(self, job: Job) -> bool:
        """A run for the tiny child: its scenario's cheapest run so far, scaled by integrator steps,
        within TINY_JOB_S."""
        if job.background or job.overran or job.spec.name not in self._cheapest:
            return False
        return self._least_seconds(job) <= TINY_JOB_S

    def _short(self, job: Job) -> bool:
        """A browser's run for the slow child kept for runs of a few seconds: expected (from its
        scenario's last run, scaled by integrator steps) within SHORT_SLOW_S of CPU."""
        if job.background or job.short_overran:
            return False
        t = self.expected_seconds(job.spec, job.values, job.preview, steps=job.steps)
        return t is not None and t <= SHORT_SLOW_S

    def short_waiting(self) -> bool:
        """A browser's run of a few seconds waits in the queue."""
        with self._cv:
            return any(self._slow(j) and self._short(j) and not self._cold(j) for j in self._queue)

    def quick_waiting(self) -> bool:
        """A browser's quick run waits in the queue (for a quick child)."""
        with self._cv:
            return any(not j.background and not self._slow(j) and not self._cold(j) for j in self._queue)

    def _expected_or_zero(self, job: Job) -> float:
        return 0.0 if job.background else (self.expected_seconds(job.spec, job.values, job.preview, steps=job.steps)
                                           or 0.0)

    def _eligible(self, slot: _Slot, job: Job) -> bool:
        """Which job a child may take. The quick children take only browsers' quick runs and
        previews; the others take anything, a browser's job before background work, which gives
        way to it (`_preempt`)."""
        if not slot.jit:
            return self._cold(job)
        if slot.quick and (job.background or self._slow(job)):
            return False
        if slot.tiny and not self._tiny(job):
            return False
        if slot.short and not (self._slow(job) and self._short(job)):  # quick runs are the quick children's
            return False
        # a browser waiting goes first; compiling a scenario a browser waits for (a warm job) does not wait
        if job.background and not job.key.endswith("#warm") and any(
                not j.background and not self._cold(j) for j in self._queue):
            return False
        # compiling children leave a cold job to the idle pure-Python child (they warm the
        # scenario with a background job meanwhile)
        nj = self.nojit
        if not (self._cold(job) and nj is not None and nj.use_process):
            return True
        return nj.job is not None and time.perf_counter() - job.created > COLD_WAIT_S

    def _turn(self, job: Job) -> tuple:
        """A queued job's place (least first): browsers' jobs before background work, quick runs
        before slow ones, then by when it would end if started when asked, its expected length
        counted SHORT_FIRST times."""
        return job.background, self._slow(job), job.created + SHORT_FIRST * self._expected_or_zero(job)

    def _take(self, slot: _Slot) -> Job | None:
        with self._cv:
            while True:
                if self.closed:
                    return None
                # the eligible job whose turn comes first (`_turn`): a short run asked later goes
                # before a long one asked earlier, and nothing waits forever
                best, best_key = None, None
                for job in self._queue:
                    if not self._eligible(slot, job):
                        continue
                    key = self._turn(job)
                    if best is None or key < best_key:
                        best, best_key = job, key
                if best is not None:
                    self._queue.remove(best)
                    best.state, best.slot, best.started = "running", slot, time.perf_counter()
                    slot.job = best
                    return best
                self._cv.wait(1.0)

    def _requeue(self, job: Job) -> None:
        with self._cv:
            if job.cancel or not (job.waiters or job.background):
                self._drop(job)
                return
            job.state, job.slot = "queued", None
            self._queue.insert(0, job)
            self._cv.notify_all()

    # ---- outcomes (called from slot threads) --------------------------------------------------
    def _progress(self, job: Job, frac: float) -> None:
        job.progress = frac
        for w in list(job.waiters):
            w._job_progress(job, frac)

    def _finish(self, job: Job) -> list:
        with self._cv:
            self._drop(job)
            self._cv.notify_all()
            return list(job.waiters)

    def _done(self, job: Job, run, seconds: float, slot: _Slot, cpu: float | None = None, reused: bool = False) -> None:
        """`cpu`: the child's CPU seconds for the run. A job's size is judged by it, not by the wall
        time: on a loaded machine a 50 ms run at low priority took a second, was judged slow, went
        to the slow children behind runs of seconds, and was timed slower still. `reused`: the run
        took pieces kept from an earlier one (Hyperion's section: 24 ms against 140 ms made afresh),
        which says little of the next run's time: it is learnt only while no run made afresh is."""
        self._first_run.set()
        job.cpu = cpu
        run.spec = job.spec
        if slot.jit and slot.use_process and not job.local:
            self.warm.add(job.spec.name)
        first = job.spec.name not in slot.seen
        slot.seen.add(job.spec.name)
        if slot.jit:  # a pure-Python time says nothing about the compiled run
            took = (seconds if cpu is None else cpu, job.steps, not reused)  # (…, made afresh)
            # a child's first run of a scenario also loads its compiled code and makes the pieces a
            # process keeps (earth-long-view's calibration: 0.44 s before a 20-ms run): it teaches
            # the expected time only when nothing else has; a run made afresh replaces one that reused
            known = self._seconds.get((job.spec.name, job.preview))
            if known is None or (not first and (not reused or not known[2])):
                self._seconds[(job.spec.name, job.preview)] = took
            # per step, the cheapest run seen: a child's first run of a scenario also loads its
            # compiled code (the flip's 6-ms run took 46 ms), which says nothing about the next; a
            # run made afresh goes before every run that reused
            best = self._cheapest.get(job.spec.name)
            rank = lambda t: (not t[2], t[0] / t[1])  # noqa: E731 — made afresh first, then the cheaper
            if took[1] > 0 and (best is None or rank(took) < rank(best)):
                self._cheapest[job.spec.name] = took
        self.cache.put(job.cache_key, run, seconds)
        if job.background and self.store is not None and not job.local:
            self.store.put(job.cache_key, run, seconds)
        for w in self._finish(job):
            w._job_done(job, run, seconds)

    def _cancelled(self, job: Job) -> None:
        self.stats["cancelled"] += 1
        if job.preempted and not self.closed and not job.cancel:
            job.preempted = False
            with self._cv:
                job.state, job.slot = "queued", None
                self._queue.append(job)
                self._cv.notify_all()
            return
        if job.background and not self.closed and not job.cancel:
            return self._requeue(job)
        with self._cv:
            if job.waiters and not job.cancel and not self.closed:  # cancelled by the pool, wanted again
                job.state = "queued"
                self._queue.insert(0, job)
                self._cv.notify_all()
                return
        self._finish(job)

    def _failed(self, job: Job, payload: tuple, slot, exc: BaseException | None = None) -> None:
        self.stats["failed"] += 1
        err = exc if isinstance(exc, ParameterError) else _rebuild_error(payload, job.spec)
        if isinstance(exc, TimeLimit):
            err = time_limit_error(job.spec)
        if payload[0] == "error" and job.background:
            self.logger.line(f"theoria: precomputing {job.spec.name} failed: {payload[1]}: {payload[2]}",
                             once_key=("bg", job.key))
        for w in self._finish(job):
            w._job_failed(job, err)

    def call_later(self, delay: float, fn: Callable) -> None:
        """`fn()` after `delay` seconds on the pool's timer thread (kept short: it only posts)."""
        with self._timer_cv:
            heapq.heappush(self._timers, (time.perf_counter() + delay, next(_ids), fn))
            if self._timer_thread is None:
                self._timer_thread = threading.Thread(target=self._timer_loop, daemon=True, name="theoria-timers")
                self._timer_thread.start()
            self._timer_cv.notify()

    def _timer_loop(self) -> None:
        while not self.closed:
            with self._timer_cv:
                while not self._timers and not self.closed:
                    self._timer_cv.wait(1.0)
                if self.closed:
                    return
                when = self._timers[0][0]
                now = time.perf_counter()
                if when > now:
                    self._timer_cv.wait(when - now)
                    continue
                _, _, fn = heapq.heappop(self._timers)
            try:
                fn()
            except Exception:
                self.logger.line("theoria: timer error:\n" + traceback.format_exc())

    def submit_apply(self, fn: Callable, *args, owner=None) -> None:
        """`fn(*args)` on a drawing thread, the browser (`owner`) drawn least recently first."""
        self._apply.submit(owner, fn, *args)


class FairDrawing:
    """The threads that draw finished runs for the browsers, the browser served least recently
    first (not first come, first served): one browser whose quick runs finish ten times a second
    (a student flooding a slider) takes its turn behind every other browser waiting, instead of a
    drawing thread of its own while ninety-nine others queue for the other."""

    def __init__(self, threads: int):
        self._heap: list = []
        self._cv = threading.Condition()
        self._served: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # owner → when last drawn
        self._seq = itertools.count()
        self._closed = False
        for i in range(threads):
            threading.Thread(target=self._loop, daemon=True, name=f"theoria-apply-{i}").start()

    def submit(self, owner, fn: Callable, *args) -> None:
        with self._cv:
            if self._closed:
                return
            last = self._served.get(owner, 0.0) if owner is not None else 0.0
            heapq.heappush(self._heap, (last, next(self._seq), owner, fn, args))
            self._cv.notify()

    def close(self) -> None:
        with self._cv:
            self._closed = True
            self._heap.clear()
            self._cv.notify_all()

    def _loop(self) -> None:
        while True:
            with self._cv:
                while not self._heap and not self._closed:
                    self._cv.wait()
                if self._closed:
                    return
                _, _, owner, fn, args = heapq.heappop(self._heap)
                if owner is not None:
                    self._served[owner] = time.perf_counter()
            try:
                fn(*args)
            except Exception:
                log.exception("theoria: error drawing a result")


_SHARED: SimPool | None = None
_SHARED_LOCK = threading.Lock()


def shared_pool(first: str | None = None) -> SimPool:
    """The pool of this process (created on first use, closed at exit); `first`: the scenario
    browsers will ask for first."""
    global _SHARED
    with _SHARED_LOCK:
        if _SHARED is None or _SHARED.closed:
            import atexit

            _SHARED = SimPool(first=first)
            atexit.register(_SHARED.close)
        return _SHARED


# ---- one browser's requests ------------------------------------------------------------------

@dataclass
class Request:
    gen: int
    spec: Any  # theoria.scenarios.Scenario
    given: dict
    values: dict | None = None
    stamps: dict[str, float] = field(default_factory=dict)  # perf_counter times (bench, tests)
    preview: bool = False  # True for the coarse first picture of a run still being refined


def check_text_lengths(given: dict) -> None:
    """A parameter given as text longer than MAX_TEXT_CHARS is refused before anything parses it
    (the message shows the start only)."""
    for k, v in given.items():
        if isinstance(v, str) and len(v) > MAX_TEXT_CHARS:
            raise ParameterError(str(k)[:40], v, f"a value of at most {MAX_TEXT_CHARS} characters")
        if isinstance(v, (tuple, list)) and (len(v) > 16 or any(isinstance(x, str) and len(x) > MAX_TEXT_CHARS
                                                                  for x in v)):
            raise ParameterError(str(k)[:40], v, "a short list of numbers")


class SimulationWorker:
    """One browser's simulations on the shared pool: the newest request wins; an older job this
    browser alone waited for is cancelled."""

    def __init__(self, name: str, on_result: Callable, on_error: Callable, on_progress: Callable,
                 pool: SimPool | None = None):
        self.name = name
        self.on_result, self.on_error, self.on_progress = on_result, on_error, on_progress
        self.pool = pool or shared_pool()
        self._lock = threading.RLock()
        self._gen = 0
        self._closed = False
        self.last: Request | None = None
        self._jobs: dict[int, tuple[Job, Request]] = {}  # job id → (job, the request it serves)
        self._pending = None  # the newest (fn, args) for the apply thread
        self._applying = False
        self._shown = {"t": 0.0, "pct": -1.0}

    # ---- the session's side ---------------------------------------------------------------
    def submit(self, spec, given: dict) -> Request:
        """Post a request; any older one still waiting or running is superseded."""
        with self._lock:
            self._gen += 1
            req = Request(self._gen, spec, dict(given), stamps={"request": time.perf_counter()})
            self.last = req
            self._release_jobs()
            shown, self._shown = self._shown["pct"] >= 0, {"t": 0.0, "pct": -1.0}
        if shown:  # the bar of the run this one replaces (cancelled): this one shows its own
            try:
                self.on_progress(None, None)
            except Exception:
                pass
        try:
            check_text_lengths(req.given)
            req.values = spec.resolve(req.given)
            budget = getattr(spec, "check_budget", None)
            if budget is not None:  # steps and memory, before anything runs
                budget(req.values)
        except Exception as e:
            self._deliver(self.on_error, req, e)
            return req
        hit = self.pool.lookup(spec.name, req.values)
        if hit is not None:
            run, seconds = hit
            req.stamps["start"] = req.stamps["simulated"] = time.perf_counter()
            req.stamps["cached"] = 1.0
            self._deliver(self.on_result, req, run, seconds)
            return req
        with self._lock:
            if not self.current(req):
                return req
            expected = self.pool.expected_seconds(spec, req.values)
            req.stamps["expected"] = -1.0 if expected is None else expected
            if spec.preview and (expected is None or expected > PREVIEW_AFTER_S):
                self._preview(spec, req)
            job = self.pool.job_for(spec, req.values, self)
            self._jobs[job.id] = (job, req)
        self.pool.call_later(PROGRESS_SHOW_AFTER, lambda: self._still_running(req))
        return req

    def _still_running(self, req: Request) -> None:
        """A run still going after PROGRESS_SHOW_AFTER that has reported nothing yet (a set-up
        phase, a compile) shows the bar at 0."""
        with self._lock:
            waiting = self.current(req) and any(r is req for _, r in self._jobs.values())
            if not waiting or self._shown["pct"] >= 0:
                return
            self._shown.update(t=time.perf_counter(), pct=0.0)
        try:
            self.on_progress(0.0, f"computing “{req.spec.title}”…")
        except Exception:
            pass

    def _preview(self, spec, req: Request) -> None:
        """The coarse first picture of a slow run: the preview values over the given ones, from
        the cache, else as a job of its own ahead of the full run."""
        try:
            pvals = spec.resolve({**req.given, **dict(spec.preview)})
        except Exception:
            return
        if run_key(spec.name, pvals) == run_key(spec.name, req.values) or _steps(spec, pvals) >= _steps(spec, req.values) > 0:
            return  # the preview would cost as much as the run itself
        preq = Request(req.gen, spec, req.given, pvals, {"request": req.stamps["request"]}, preview=True)
        hit = self.pool.lookup(spec.name, pvals)
        if hit is not None:
            self._deliver(self.on_result, preq, hit[0], hit[1])
        else:
            job = self.pool.job_for(spec, pvals, self, preview=True)
            self._jobs[job.id] = (job, preq)

    def adopt(self, spec, values: dict) -> Request:
        """A request for a run computed elsewhere (shown as if this worker had run it)."""
        with self._lock:
            self._gen += 1
            self._release_jobs()
            self.last = Request(self._gen, spec, dict(values), dict(values), {"request": time.perf_counter()})
            return self.last

    def current(self, req: Request) -> bool:
        return req.gen == self._gen and not self._closed

    def close(self) -> None:
        with self._lock:
            self._closed = True
            self._pending = None
            self._release_jobs()

    def _release_jobs(self) -> None:
        jobs, self._jobs = [j for j, _ in self._jobs.values()], {}
        for job in jobs:
            self.pool.detach(job, self)

    # ---- the pool's side (slot threads) -------------------------------------------------------
    def _take_req(self, job: Job, pop: bool) -> Request | None:
        with self._lock:
            item = self._jobs.pop(job.id, None) if pop else self._jobs.get(job.id)
            if item is None or not self.current(item[1]):
                return None
            return item[1]

    def _job_progress(self, job: Job, frac: float) -> None:
        req = self._take_req(job, pop=False)
        if req is None or req.preview:
            return
        req.stamps.setdefault("start", job.started or time.perf_counter())
        now = time.perf_counter()
        if now - req.stamps["request"] < PROGRESS_SHOW_AFTER or now - self._shown["t"] < PROGRESS_EVERY:
            return
        try:
            pct = min(max(100.0 * float(frac), 0.0), 100.0)
        except (TypeError, ValueError):
            return
        if not np.isfinite(pct) or abs(pct - self._shown["pct"]) < 0.5:
            return
        self._shown.update(t=now, pct=pct)
        try:
            self.on_progress(pct, f"computing “{req.spec.title}”… {pct:.0f} %")
        except Exception:
            pass

    def _hide_progress(self) -> None:
        if self._shown["pct"] >= 0:
            self._shown["pct"] = -1.0
            try:
                self.on_progress(None, None)
            except Exception:
                pass

    def _job_done(self, job: Job, run, seconds: float) -> None:
        req = self._take_req(job, pop=True)
        if req is None:
            return
        req.stamps.setdefault("start", job.started or req.stamps["request"])
        req.stamps["simulated"] = time.perf_counter()
        if job.cpu is not None:
            req.stamps["cpu"] = job.cpu
        if req.preview:
            with self._lock:
                full_pending = any(not r.preview and r.gen == req.gen for _, r in self._jobs.values())
            if not full_pending:
                return  # the full run came first (or failed): the coarse one is not shown after it
        else:
            self._hide_progress()
        self._deliver(self.on_result, req, run, seconds)

    def _job_failed(self, job: Job, err: BaseException) -> None:
        req = self._take_req(job, pop=True)
        if req is None or req.preview:  # a preview's failure: the full run will say what is wrong
            return
        self._hide_progress()
        self._deliver(self.on_error, req, err)

    # ---- showing, off the pool's threads, newest first ---------------------------------------
    def _deliver(self, fn, *args) -> None:
        with self._lock:
            if self._closed:
                return
            self._pending = (fn, args)
            if self._applying:
                return
            self._applying = True
        self.pool.submit_apply(self._drain, owner=self)

    def _drain(self) -> None:
        """Show the newest delivery; one more that came meanwhile is queued again behind the
        browsers drawn less recently (`FairDrawing`)."""
        with self._lock:
            item, self._pending = self._pending, None
            if item is None or self._closed:
                self._applying = False
                return
        fn, args = item
        if self.current(args[0]):
            try:
                with showing():
                    fn(*args)
            except Exception:
                self.pool.logger.line("theoria: error showing a result:\n" + traceback.format_exc())
        with self._lock:
            again = self._pending is not None and not self._closed
            if not again:
                self._applying = False
        if again:
            self.pool.submit_apply(self._drain, owner=self)


DRAWINGS_PER_RUN = 3
_TIMING = {"file": None, "lock": threading.Lock()}


def timing_log(name: str, req: Request, pool: "SimPool | None" = None) -> None:
    """One line of JSON per scene shown, when THEORIA_TIMING_LOG names a file: where an action's
    time went (waiting for a child, simulating, drawing and sending). For `theoria bench`."""
    path = os.environ.get("THEORIA_TIMING_LOG")
    if not path:
        return
    import json

    st = req.stamps
    r = st.get("request", 0.0)
    line = json.dumps({"scenario": name, "preview": bool(req.preview), "cached": bool(st.get("cached")),
                       "queued_s": st.get("start", r) - r, "run_s": st.get("simulated", r) - st.get("start", r),
                       "show_s": st.get("shown", r) - st.get("simulated", r), "total_s": st.get("shown", r) - r,
                       "draw_s": st.get("shown", r) - st.get("drawing", r), "cpu_s": st.get("cpu"),
                       "expected_s": st.get("expected"),
                       **({"pool": {**pool.stats, "kills": sum(s.kills for s in pool.slots),
                                    "queued": len(pool._queue), "busy": sum(s.job is not None for s in pool.slots)}}
                          if pool is not None else {})})
    with _TIMING["lock"]:
        if _TIMING["file"] is None:
            _TIMING["file"] = open(path, "a", buffering=1)
        _TIMING["file"].write(line + "\n")


def limits_text() -> str:
    """The limits a browser's runs are held to, in a sentence for the panel (docs/classroom.md)."""
    budget = ""
    try:
        from theoria.scenarios.budget import MAX_MEMORY, MAX_STEPS  # the step and memory budget, when present

        budget = f", at most {MAX_STEPS / 1e6:g} million integrator steps and {MAX_MEMORY / 1e9:g} GB"
    except ImportError:
        pass
    return (f"*This server runs one simulation per browser at a time (a newer request replaces it){budget}, "
            f"each for at most {RUN_SECONDS_LIMIT:g} s of computing.*")


def _draw_ahead(spec, run) -> None:
    """In a simulation child: the default view's drawing of `run`, kept in the run and sent with it
    (`drawing_of`), instead of made under the server's one interpreter lock, which every browser's
    answer waits for: 1-15 ms a drawing (the Moon's 46 ms) against 0.3-2 ms to unpickle it (in
    100-browser soaks the server's own CPU went from 0.43-0.46 to 0.39 cores). Its paths are still
    cut into chunks by the server (`scene.path_chunks`): done here too, they made the flip's runs
    in the child kept for tiny runs 10 → 17 ms of CPU (8 ms without the drawing), its queue at p95
    went from 0.02 to 0.14 s, and the server's CPU did not fall further."""
    try:
        drawing_of(spec, run)
    except Exception:  # noqa: BLE001 — drawn by the server, which reports what is wrong
        run.__dict__.pop("_theoria_drawings", None)


def drawing_of(spec, run, view=None):
    """`spec.drawing(run, view)`, kept with the run: thirty browsers shown the same cached run with
    the same view options share one Drawing (a Drawing is plain data, read and never changed by
    the renderers)."""
    from theoria.scenarios.drawing import View

    # a copy: a browser's thread may change its options while another draws with them, and the
    # drawing must be the one its key names
    view = view or View()
    view = replace(view, options=dict(view.options))
    key = (spec.name, repr(sorted(view.options.items())), float(view.exaggerate), float(view.text_scale))
    store = run.__dict__.setdefault("_theoria_drawings", OrderedDict())
    d = store.get(key)
    if d is None:
        d = spec.drawing(run, view)
        store[key] = d
        delta = nbytes(d)
        while len(store) > DRAWINGS_PER_RUN:
            delta -= nbytes(store.popitem(last=False)[1])
        owner = run.__dict__.get("_theoria_cache")
        if owner is not None:  # the server's run cache counts what its runs hold
            owner[0].grew(owner[1], run, delta)
    return d
