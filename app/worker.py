"""Simulations for one browser, off the event loop: the newest request wins.

A `SimulationWorker` takes requests (scenario, raw values). A newer request supersedes an older
one: a run in progress is cancelled from its progress callback (`Cancelled`), and a run that
finishes after a newer request arrived is dropped. The outcome goes to the session through three
callbacks: `on_result(request, run, seconds)`, `on_error(request, exception)` and
`on_progress(percent or None, text)` (throttled: runs shorter than PROGRESS_SHOW_AFTER never show
a bar, longer ones send at most 1/PROGRESS_EVERY updates a second).
"""
from __future__ import annotations

import threading
import time
import traceback
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from theoria.physics.errors import Cancelled

PROGRESS_SHOW_AFTER = 0.4  # s
PROGRESS_EVERY = 0.15  # s


@dataclass
class Request:
    gen: int
    spec: Any  # theoria.scenarios.Scenario
    given: dict
    values: dict | None = None
    stamps: dict[str, float] = field(default_factory=dict)  # perf_counter times (bench, tests)


class SimulationWorker:
    def __init__(self, name: str, on_result: Callable, on_error: Callable, on_progress: Callable):
        self.on_result, self.on_error, self.on_progress = on_result, on_error, on_progress
        self._cv = threading.Condition()
        self._pending: Request | None = None
        self._gen = 0
        self._closed = False
        self.last: Request | None = None
        self._thread = threading.Thread(target=self._loop, daemon=True, name=name)
        self._thread.start()

    def submit(self, spec, given: dict) -> Request:
        """Post a request; any older one still waiting or running is superseded."""
        with self._cv:
            self._gen += 1
            req = Request(self._gen, spec, dict(given), stamps={"request": time.perf_counter()})
            self._pending = self.last = req
            self._cv.notify()
            return req

    def adopt(self, spec, values: dict) -> Request:
        """A request for a run computed elsewhere (shown as if this worker had run it)."""
        with self._cv:
            self._gen += 1
            self.last = Request(self._gen, spec, dict(values), dict(values), {"request": time.perf_counter()})
            return self.last

    def current(self, req: Request) -> bool:
        return req.gen == self._gen and not self._closed

    def close(self) -> None:
        with self._cv:
            self._closed = True
            self._cv.notify()

    def _loop(self) -> None:
        while True:
            with self._cv:
                while self._pending is None and not self._closed:
                    self._cv.wait()
                if self._closed:
                    return
                req, self._pending = self._pending, None
            try:
                self._run(req)
            except Cancelled:
                continue
            except Exception as e:  # a bad value or a bug in a scenario never reaches viser's loop
                if not isinstance(e, ValueError):
                    traceback.print_exc()
                self.on_error(req, e)

    def _run(self, req: Request) -> None:
        spec = req.spec
        req.values = spec.resolve(req.given)
        req.stamps["start"] = t0 = time.perf_counter()
        shown = {"t": 0.0, "pct": -1.0, "done": False}
        lock = threading.Lock()

        def progress(frac):
            if not self.current(req):
                raise Cancelled()
            now = time.perf_counter()
            if now - t0 < PROGRESS_SHOW_AFTER or now - shown["t"] < PROGRESS_EVERY:
                return
            try:
                pct = min(max(100.0 * float(frac), 0.0), 100.0)
            except (TypeError, ValueError):
                return
            if not np.isfinite(pct) or abs(pct - shown["pct"]) < 0.5:
                return
            with lock:
                if not shown["done"]:
                    shown["t"], shown["pct"] = now, pct
                    self.on_progress(pct, f"simulating {spec.name}… {pct:.0f}%")

        def still_running():  # a long run with no progress yet (a setup phase) shows the bar at 0
            with lock:
                if not shown["done"] and shown["pct"] < 0 and self.current(req):
                    shown["pct"] = 0.0
                    self.on_progress(0.0, f"simulating {spec.name}…")

        timer = threading.Timer(PROGRESS_SHOW_AFTER, still_running)
        timer.daemon = True
        timer.start()
        try:
            run = spec.simulate_fn(req.values, progress=progress)
        finally:
            timer.cancel()
            with lock:
                shown["done"] = True
                if shown["pct"] >= 0:
                    self.on_progress(None, None)
        req.stamps["simulated"] = time.perf_counter()
        if not self.current(req):
            raise Cancelled()
        self.on_result(req, run, req.stamps["simulated"] - t0)
