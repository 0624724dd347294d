"""Playback of every browser's scene by one thread, within a share of one core.

A frame of playback is a handful of pose updates (the body's attitude, the ω and L arrows, the
visibility of a trail chunk) that viser turns into messages for one browser: ~1 ms of the
server's CPU under its interpreter lock. One thread per browser at a fixed rate made a hundred
browsers ask for 1,200 such frames a second, more than the server's core holds, and every slider
and scenario switch queued behind them.

`Ticker` runs each playing session's `_tick()` in turn from one thread. It measures what a tick
costs (thread CPU time) and gives all playing sessions together PLAY_CPU_SHARE of a core: each
session plays at min(PLAY_HZ, that budget / sessions playing), never below PLAY_HZ_MIN. One
browser plays at 60 frames a second; thirty at ~10; a hundred at ~3 (the run's clock keeps real
time, frames are skipped, not slowed). A paused session costs nothing.

A page that plays by itself (app/scene.py `tracks()`) moves the poses on its own at its own frame
rate, label text and per-frame lines included; its session asks for ticks only for the time
read-out (`tick_hz()`, 2 a second), unless the server moves the camera (the Moon seen from the
Earth).

While a browser's action is being answered (a new scene drawn and sent: `showing()`), playback
takes PLAY_CPU_SHARE_ACTING instead: the frames are the ones skipped, not the answer delayed. A
student who moved a slider waits for its result; the bodies turning on the other screens lose a
few frames.
"""
from __future__ import annotations

import contextlib
import threading
import time
import traceback

_acting = {"n": 0}
_acting_lock = threading.Lock()


@contextlib.contextmanager
def showing():
    """An answer to a browser's action is being drawn and sent: playback gives way meanwhile."""
    with _acting_lock:
        _acting["n"] += 1
    try:
        yield
    finally:
        with _acting_lock:
            _acting["n"] -= 1

PLAY_HZ = 60.0  # at most, for one browser (viser sends messages each 1/60 s)
PLAY_HZ_MIN = 2.0
PLAY_CPU_SHARE = 0.35  # of one core, for the playback of all browsers together
PLAY_CPU_SHARE_ACTING = 0.1  # the same while some browser's action is being answered
TICK_COST_START = 1e-3  # s of CPU per tick, until measured


class Ticker:
    def __init__(self, share: float = PLAY_CPU_SHARE):
        self.share = share
        self._sessions: list = []
        self._next: dict[int, float] = {}
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self.cost = TICK_COST_START  # running mean CPU seconds per tick
        self.ticks = 0
        self._thread = threading.Thread(target=self._loop, daemon=True, name="theoria-playback")
        self._thread.start()

    def add(self, session) -> None:
        with self._lock:
            if session not in self._sessions:
                self._sessions.append(session)
                self._next[id(session)] = 0.0
        self._wake.set()

    def remove(self, session) -> None:
        with self._lock:
            if session in self._sessions:
                self._sessions.remove(session)
            self._next.pop(id(session), None)

    def rate(self, playing: int | None = None) -> float:
        """Frames a second each playing session gets now."""
        if playing is None:
            playing = sum(1 for s in list(self._sessions) if s.wants_ticks())
        share = min(self.share, PLAY_CPU_SHARE_ACTING) if _acting["n"] else self.share
        budget = share / max(self.cost, 1e-5)
        return max(PLAY_HZ_MIN, min(PLAY_HZ, budget / max(1, playing)))

    def _loop(self) -> None:
        while True:
            with self._lock:
                sessions = list(self._sessions)
            playing = [s for s in sessions if s.wants_ticks()]
            if not playing:
                self._wake.wait(0.25)
                self._wake.clear()
                continue
            # the share of a core goes to the sessions that want every frame from the server
            period = 1.0 / self.rate(sum(1 for s in playing if _max_hz(s) >= PLAY_HZ))
            now = time.perf_counter()
            soonest = now + period
            c0, ticked = time.thread_time(), 0  # one CPU-clock read per pass (a system call each)
            for s in playing:
                due = self._next.get(id(s), 0.0)
                if due <= now:
                    try:
                        s._tick(now)
                    except Exception:
                        if not getattr(s, "_closed", False):
                            traceback.print_exc()
                    ticked += 1
                    # no catching up after a stall: frames are skipped
                    due = max(due + max(period, 1.0 / _max_hz(s)), now)
                    if id(s) in self._next:
                        self._next[id(s)] = due
                soonest = min(soonest, due)
            if ticked:
                c = (time.thread_time() - c0) / ticked
                self.cost += (1.0 - 0.98 ** ticked) * (c - self.cost)  # as 0.02 per tick
                self.ticks += ticked
            time.sleep(max(0.001, soonest - time.perf_counter()))


def _max_hz(session) -> float:
    """Ticks a second a session wants at most: PLAY_HZ, or fewer for a page that plays by itself."""
    f = getattr(session, "tick_hz", None)
    return f() if f is not None else PLAY_HZ


_TICKER: Ticker | None = None
_TICKER_LOCK = threading.Lock()


def ticker() -> Ticker:
    global _TICKER
    with _TICKER_LOCK:
        if _TICKER is None:
            _TICKER = Ticker()
        return _TICKER
