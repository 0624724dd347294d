"""Many runs of one scenario on Dask: `theoria sweep` and `Scenario.sweep` (design.md, "Many runs").

A sweep is a grid over some parameters (`name=start:stop:count`, or `name=v1,v2,…`), optionally
with random samples of others (`name=lo:hi` with `samples`: a `sample` dimension, the same draws at
every grid point), every other parameter fixed. It is cut into chunks; each chunk is one Dask task
(a local cluster on this machine's cores by default, or an existing scheduler by address) and its
results are written by this process, chunk by chunk, as they arrive:

- Zarr (`out.zarr`): an xarray Dataset, one dimension per swept parameter (coordinates carry their
  units), one variable per metric, `status` (0 not run yet, 1 ok, 2 diverged, 3 refused, 4 failed,
  5 flagged: finished with a status of its own such as "tumbles"),
  the fixed parameters, the spec and the theoria version as attributes. A chunk counts as finished
  when its `status` is written, which happens after its metrics: `resume=True` recomputes nothing
  that finished.
- Parquet (`out.parquet`): a flat table, one row per run; the chunks go to `out.parquet.parts/`
  while the sweep runs and are joined into the one file at the end.

Scenarios with a batched path (`Scenario.batch`: many bodies advanced together on one shared
orbit) use it when every swept parameter is one the batch can vary and every asked metric is one
it computes; otherwise each chunk maps single runs.

Ctrl-C or SIGTERM: the finished chunks stay, the cluster is shut down, exit status 130.
"""
from __future__ import annotations

import contextlib
import datetime
import functools
import itertools
import json
import math
import os
import re
import shutil
import signal
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from ..physics.errors import ParameterError, did_you_mean, show_value
from ..physics.params import plain_number, read_number, whole_number
from ..scenarios.budget import MAX_MEMORY, MAX_STEPS
from .files import WriteError, mark_written, write_whole
from .interrupt import signals_held


class SweepError(RuntimeError):
    """A sweep that cannot go on (a chunk's task failed as a whole): one line, exit status 1."""


class SweepBusy(ParameterError):
    """Another sweep is writing this --out (exit status 2, like any --out refused)."""

    def __init__(self, out: str, pid: int | None):
        super().__init__("--out", out, "a result no other sweep is writing")
        self.pid = pid
        holder = f"another sweep (PID {pid})" if pid is not None else "another sweep"
        shown = out if out.isprintable() else repr(out)[1:-1]  # whole (the path is the point), on one line
        self.args = (f"{holder} is writing {shown}; wait for it to end, or give another --out",)


# flagged: the run finished but its status names what it found (e.g. "tumbles": no libration at all)
STATUS = {"not run": 0, "ok": 1, "diverged": 2, "refused": 3, "failed": 4, "flagged": 5}
SAMPLE = "sample"
MAX_MESSAGES = 1000  # messages kept in the description (docs/sweeps.md); past them the status alone says it


# ------------------------------------------------------------------------------------- the plan

@dataclass
class Axis:
    """One swept parameter: its name in the scenario, values, unit and help."""

    name: str
    values: np.ndarray
    unit: str
    help: str
    random: bool = False
    spec: str = ""


@dataclass
class Plan:
    scenario: Any
    fixed: dict[str, Any]
    grid: list[Axis]
    random: list[Axis]
    samples: int
    seed: int
    metrics: list[str] | None
    chunks: tuple[int, ...] = ()
    batched: bool = False
    limits: dict[str, float | None] = field(default_factory=dict)  # each run's budget (check_budget)

    @property
    def dims(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.grid) + ((SAMPLE,) if self.random else ())

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a.values) for a in self.grid) + ((self.samples,) if self.random else ())

    @property
    def size(self) -> int:
        return int(np.prod(self.shape)) if self.shape else 1

    def chunk_regions(self) -> list[tuple[slice, ...]]:
        ranges = [range(0, n, c) for n, c in zip(self.shape, self.chunks)]
        out = []
        for starts in np.ndindex(*[len(r) for r in ranges]):
            out.append(tuple(slice(r[i], min(r[i] + c, n)) for r, i, c, n in zip(ranges, starts, self.chunks, self.shape)))
        return out

    def points(self, region: tuple[slice, ...]) -> dict[str, np.ndarray]:
        """The swept values at every point of a region, flattened in C order."""
        idx = np.meshgrid(*[np.arange(s.start, s.stop) for s in region], indexing="ij")
        out = {}
        for k, a in enumerate(self.grid):
            out[a.name] = a.values[idx[k].ravel()]
        if self.random:
            isamp = idx[-1].ravel()
            for a in self.random:
                out[a.name] = a.values[isamp]
        return out

    def spec(self) -> dict:
        """What identifies this sweep (a resume must match it)."""
        return {
            "scenario": self.scenario.name,
            "fixed": {k: _plain(v) for k, v in self.fixed.items()},
            "grid": {a.name: [_plain(v) for v in a.values] for a in self.grid},
            "random": {a.name: a.spec for a in self.random},
            "samples": self.samples if self.random else 0,
            "seed": self.seed if self.random else None,
            "metrics": self.metrics,
            "dims": list(self.dims),
            "chunks": list(self.chunks),
            # each run's budget: a sweep resumed with another would mix runs refused under one with
            # runs made under the other
            **{k: None if v is None else float(v) for k, v in (
                ("max_steps", self.limits.get("max_steps", MAX_STEPS)),
                ("max_memory", self.limits.get("max_memory", MAX_MEMORY)))},
        }


def _differs(spec: dict, old: dict) -> list[str]:
    """What a resumed sweep's description `spec` changes of the stored one's `old` (the chunking
    aside, which the store decides; a budget only where the store recorded one: sweeps written
    before budgets were recorded resume as they did)."""
    return [k for k in spec if k != "chunks" and not (k in BUDGET_KEYS and k not in old)
            and _jsonish(spec[k]) != _jsonish(old.get(k))]


BUDGET_KEYS = ("max_steps", "max_memory")


def _plain(v):
    if isinstance(v, (np.floating, float)):
        return float(v)
    if isinstance(v, (np.integer, int)) and not isinstance(v, bool):
        return int(v)
    if isinstance(v, tuple):
        return [_plain(x) for x in v]
    return v


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def _match_param(sc, name: str, flag: str, spec: str):
    """The parameter called `name`: its exact name or the one name it begins (e.g. `e` for
    `eccentricity`); anything else is a ParameterError listing the names there are."""
    names = [p.name for p in sc.params]
    if name in names:
        return sc.param(name)
    hits = [n for n in names if n.startswith(name)] if name else []
    if len(hits) == 1:
        return sc.param(hits[0])
    known = ", ".join(names)
    what = (f"more than one parameter begins with '{show_value(name)}' ({', '.join(hits)})" if len(hits) > 1
            else f"unknown parameter '{show_value(name)}'")
    raise ParameterError(flag, spec, f"{what}; parameters of {sc.name}: {known}")  # the flag, the whole spec


def _did_you_mean(name: str, sc) -> str:
    """"; did you mean 'free_period'?" for a metric name close to one the scenario declares, or ""."""
    names = [k for k in sc.metric_units if re.fullmatch(r"[\w.]+", k)]
    return did_you_mean(name, names).replace(" (", "; ", 1).rstrip(")")


def parse_grid(sc, spec: str) -> Axis:
    """`name=start:stop:count` (count values from start to stop, both included) or `name=v1,v2,…`."""
    form = "name=start:stop:count (count ≥ 1 values, both ends included) or name=v1,v2,…"
    if not isinstance(spec, str) or "=" not in spec:
        raise ParameterError("--grid", spec, form)
    name, rhs = (s.strip() for s in spec.split("=", 1))
    p = _match_param(sc, name, "--grid", spec)
    if p.kind == "vec3":
        raise ParameterError(p.name, rhs, "a vector parameter cannot be swept; sweep a number parameter")
    if ":" in rhs:
        parts = [plain_number(x) for x in rhs.split(":")]  # as a person writes them: "−0.5", "10⁴"
        if len(parts) != 3 or not all(re.fullmatch(_NUM, x) for x in parts[:2]):
            raise ParameterError("--grid", spec, form)
        try:  # "1000", "1e3"
            count = whole_number(parts[2])
        except (ValueError, OverflowError):
            raise ParameterError("--grid", spec, f"count must be a whole number ≥ 1; {form}") from None
        if count < 1:
            raise ParameterError("--grid", spec, f"count must be at least 1; {form}")
        if count > 10_000_000:
            raise ParameterError("--grid", spec, "count at most 10,000,000")
        lo, hi = p.parse(parts[0].strip()), p.parse(parts[1].strip())
        if count == 1 and lo != hi:  # both ends included: one value cannot be both (it kept the start only)
            raise ParameterError("--grid", spec, f"one value holds both ends only when they are equal; a count of "
                                 f"at least 2 runs from {parts[0]} to {parts[1]}; {form}")
        vals = np.linspace(lo, hi, count)
        if p.kind == "int":
            if not np.all(vals == np.round(vals)):
                raise ParameterError(p.name, rhs, f"whole numbers: {count} values from {lo} to {hi} are not "
                                     "(choose a count that steps by whole numbers)")
            vals = np.round(vals).astype(np.int64)
    else:
        items = [x.strip() for x in rhs.split(",") if x.strip()]
        if not items:
            raise ParameterError("--grid", spec, form)
        vals = [p.parse(x) for x in items]
        vals = np.array(vals, dtype=object if p.kind == "choice" else (np.int64 if p.kind == "int" else float))
    for v in np.unique(vals) if vals.dtype != object else vals:  # every value in range
        p.parse(v.item() if hasattr(v, "item") else v)
    # the same run twice is no more knowledge, and a coordinate with a repeated value cannot be
    # selected by that value (xarray's .sel)
    seen = [str(v) for v in vals] if vals.dtype == object else vals
    if len(np.unique(seen)) < len(vals):
        twice = sorted({v for v, k in zip(*np.unique(seen, return_counts=True)) if k > 1}, key=str)
        raise ParameterError("--grid", spec, "start and stop that differ, for a count above 1" if ":" in rhs else
                             f"each value once ({', '.join(map(str, twice[:3]))} given more than once)")
    return Axis(p.name, vals, p.unit, p.help, spec=spec)


def parse_random(sc, spec: str, samples: int, rng) -> Axis:
    """`name=lo:hi`: `samples` values drawn uniformly in [lo, hi] (whole numbers for an int parameter)."""
    form = "name=lo:hi"
    if not isinstance(spec, str) or "=" not in spec:
        raise ParameterError("--random", spec, form)
    name, rhs = (s.strip() for s in spec.split("=", 1))
    p = _match_param(sc, name, "--random", spec)
    parts = [plain_number(x) for x in rhs.split(":")]
    if len(parts) != 2 or not all(re.fullmatch(_NUM, x) for x in parts):
        raise ParameterError("--random", spec, form)
    if p.kind not in ("float", "int"):
        raise ParameterError(p.name, rhs, "random sampling needs a number parameter")
    lo, hi = p.parse(parts[0].strip()), p.parse(parts[1].strip())
    if hi < lo:
        raise ParameterError("--random", spec, "lo ≤ hi")
    if p.kind == "int":
        vals = rng.integers(int(lo), int(hi) + 1, size=samples)
    else:
        vals = rng.uniform(lo, hi, size=samples)
        if p.exclusive_min and p.minimum is not None:
            vals = np.where(vals <= p.minimum, np.nextafter(p.minimum, np.inf), vals)
    return Axis(p.name, vals, p.unit, p.help, random=True, spec=rhs)


def make_plan(sc, grid=None, random=None, samples=None, fixed=None, preset=None, metrics=None, seed=0,
              chunk=None, workers=1) -> Plan:
    """Check everything about a sweep before any work: the swept names and ranges, the fixed
    values, every grid point against the scenario's own cross-parameter check."""
    grid = _as_specs(grid, "--grid")
    random = _as_specs(random, "--random")
    if random and samples is None:
        raise ParameterError("--samples", "(not given)", "a number of samples ≥ 1 with --random")
    if samples is not None:
        samples = _count(samples, "--samples", 10_000_000, "a whole number from 1 to 10,000,000")
        if not random:
            raise ParameterError("--samples", samples, "only with --random name=lo:hi")
    if not grid and not random:
        raise ParameterError("--grid", "(none given)", "at least one --grid name=start:stop:count (or --random name=lo:hi)")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError("--seed", seed, "a whole number ≥ 0")
    axes = [parse_grid(sc, g) for g in grid]
    rng = np.random.default_rng(seed)
    raxes = [parse_random(sc, r, samples, rng) for r in random]
    names = [a.name for a in axes + raxes]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ParameterError(dup[0], "swept twice", "each parameter in one --grid or --random only")
    given: dict[str, Any] = {}
    if preset is not None:
        try:
            given.update(sc.presets[sc.preset_name(preset)])
        except ParameterError as e:
            raise ParameterError("--preset", preset, e.allowed) from None
    for k, v in dict(fixed or {}).items():
        p = _match_param(sc, k, "--set", f"{k}={v}")
        if p.name in names:
            raise ParameterError(p.name, v, "is swept; a --set value would be ignored")
        given[p.name] = v
    given = {k: v for k, v in given.items() if k not in names}
    values = sc.resolve(given)
    fixed_values = {k: v for k, v in values.items() if k not in names}
    if metrics is not None:
        metrics = [m.strip() for m in (metrics.split(",") if isinstance(metrics, str) else metrics) if m.strip()]
        if not metrics:
            raise ParameterError("--metrics", "", "one or more metric names, comma-separated")
        # every metric of a scenario has a unit, declared or in its name (tests/test_metric_units.py):
        # a name with neither is none of its metrics, refused before a cluster starts (a name that
        # could be one is checked against what the first chunk's runs report)
        for m in metrics:
            if sc.metric_unit(m) is None:
                raise ParameterError("--metrics", m, f"not a metric of {sc.name} (`theoria run {sc.name} --json` "
                                     "lists them)" + _did_you_mean(m, sc))
    plan = Plan(sc, fixed_values, axes, raxes, int(samples or 0), int(seed), metrics)
    if plan.size > 50_000_000:
        raise ParameterError("--grid", "x".join(map(str, plan.shape)), "at most 50,000,000 runs in one sweep")
    # the scenario's cross-parameter check at every point (a bad corner is found now)
    if sc.check is not None:
        _check_every_point(sc.check, plan)
    batch = getattr(sc, "batch", None)
    plan.batched = bool(batch is not None and set(names) <= set(batch.sweepable)
                        and (metrics is None or set(metrics) <= set(batch.metrics)))
    plan.chunks = _chunk_shape(plan, chunk, workers)
    return plan


class _Reads(dict):
    """Values that note which of them a check reads."""

    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        self.read: set = set()

    def __getitem__(self, k):
        self.read.add(k)
        return super().__getitem__(k)

    def get(self, k, default=None):
        self.read.add(k)
        return super().get(k, default)

    def __contains__(self, k):
        self.read.add(k)
        return super().__contains__(k)

    def _all(self):
        self.read.update(super().keys())

    def keys(self):
        self._all()
        return super().keys()

    def items(self):
        self._all()
        return super().items()

    def values(self):
        self._all()
        return super().values()

    def __iter__(self):
        self._all()
        return super().__iter__()


def _check_every_point(check, plan) -> None:
    """`check` at every point of the plan. On a grid, a check that reads only some of the swept
    parameters is run once per combination of theirs (the flip's check reads the spin, not the
    nudge: 1,000 calls instead of a million, which took 27 s before anything ran). A check is a pure
    function of what it reads, so the combinations decide every point; should any call read a
    parameter outside them, every point is checked."""
    fixed = plan.fixed

    def every_point():
        pts = plan.points(tuple(slice(0, n) for n in plan.shape))
        for i in range(plan.size):
            check({**fixed, **{k: _item(v[i]) for k, v in pts.items()}})

    if plan.random:
        return every_point()
    axes = {a.name: a.values for a in plan.grid}
    first = _Reads({**fixed, **{k: _item(v[0]) for k, v in axes.items()}})
    check(first)
    used = [k for k in axes if k in first.read]
    for combo in itertools.product(*(range(len(axes[k])) for k in used)):
        vals = _Reads({**fixed, **{k: _item(v[0]) for k, v in axes.items()}})
        vals.update({k: _item(axes[k][j]) for k, j in zip(used, combo)})
        vals.read.clear()
        check(vals)
        if not vals.read <= set(used) | set(fixed):  # it read another swept value: every point, then
            return every_point()


def _as_specs(x, flag) -> list[str]:
    """Specs as strings. From Python also a mapping: name → "0:0.5:64", (start, stop, count) for a
    grid or (lo, hi) for random draws, or a list of values."""
    if x is None:
        return []
    if isinstance(x, str):
        return [x]
    if not isinstance(x, Mapping):
        return [str(s) for s in x]
    out = []
    for k, v in x.items():
        if isinstance(v, str):
            out.append(f"{k}={v}")
        elif isinstance(v, tuple) and (len(v) == 3 and flag == "--grid" or len(v) == 2 and flag == "--random"):
            out.append(f"{k}=" + ":".join(repr(_plain(i)) for i in v))
        elif flag == "--grid" and isinstance(v, (list, np.ndarray)):
            out.append(f"{k}=" + ",".join(i if isinstance(i, str) else repr(_plain(i)) for i in v))
        else:
            want = "(start, stop, count), a list of values or 'start:stop:count'" if flag == "--grid" else "(lo, hi) or 'lo:hi'"
            raise ParameterError(flag, f"{k}={v!r}", want)
    return out


def _item(v):
    return v.item() if hasattr(v, "item") else v


def _count(value, flag: str, most, allowed: str) -> int:
    """A count given on the command line or from Python, from 1 to `most`."""
    try:
        n = whole_number(value)
    except (TypeError, ValueError, OverflowError):
        n = 0
    if not 1 <= n <= most:
        raise ParameterError(flag, value, allowed)
    return n


def _chunk_shape(plan: Plan, chunk, workers) -> tuple[int, ...]:
    """Runs per chunk: `chunk` if given; else what the scenario's batch asks for (`Batch.chunk`:
    whole rows of the last dimensions share an orbit) or up to 16 single runs, with at least ~4
    chunks per worker. Filled from the last dimension backwards."""
    total = plan.size
    if chunk is not None:
        target = _count(chunk, "--chunk", math.inf, "a whole number of runs ≥ 1")
    else:
        cap = int(plan.scenario.batch.chunk) if plan.batched else 16
        target = max(1, min(cap, total // max(1, 4 * workers)))
    out = []
    left = target
    for n in reversed(plan.shape):
        c = max(1, min(n, left))
        out.append(c)
        left = max(1, left // c)
    return tuple(reversed(out))


# --------------------------------------------------------------------------- the work of a chunk

def _read_json(path: str, flag: str):
    """A sweep's own description file, or one line saying it cannot be read (an older theoria's
    write cut by a full disk left it empty)."""
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        raise ParameterError(flag, os.path.dirname(path), f"its {os.path.basename(path)} cannot be read "
                             f"({type(e).__name__}); --force starts the sweep again") from None


def ok_with_warnings(warnings) -> str:
    """The message of a run that finished ok with warnings (what its numbers cannot be read as),
    as a single run's and a batched run's are stored alike."""
    return "ok, with warnings: " + "; ".join(warnings)


def run_chunk(task: dict) -> dict:
    """One chunk, on a worker: the batched path, or single runs one after another. Returns metric
    arrays (name → (n,)), `status` codes and messages for the runs that did not finish ok."""
    from ..scenarios import get

    t0 = time.perf_counter()
    sc = get(task["scenario"])
    fixed, points, metrics = task["fixed"], task["points"], task["metrics"]
    n = len(next(iter(points.values())))
    if task.get("threads"):
        try:
            import numba

            numba.set_num_threads(max(1, min(int(task["threads"]), numba.config.NUMBA_NUM_THREADS)))
        except Exception:  # noqa: BLE001 — threads are a hint
            pass
    status = np.full(n, STATUS["ok"], np.int8)
    messages: dict[int, str] = {}
    out: dict[str, np.ndarray] = {}
    reported: set[str] = set()  # every metric the runs reported (to name them if --metrics asks for another)
    if task["batched"]:
        # each run's budget, as on the single-run path and in `simulate`: a batch of runs of 10⁸
        # steps each was run when the same values alone were refused
        keep = np.ones(n, bool)
        for i in range(n):
            values = {**fixed, **{k: _item(v[i]) for k, v in points.items()}}
            try:
                sc.check_budget(sc.resolve(values), **task.get("limits", {}))
            except ParameterError as e:
                keep[i] = False
                status[i] = STATUS["refused"]
                messages[i] = str(e)
        idx = np.flatnonzero(keep)
        if len(idx):
            res = sc.batch.fn(dict(fixed), {k: np.asarray(v)[idx] for k, v in points.items()})
            st = res.pop("_status", None)
            if st is not None:
                status[idx] = st
            messages.update({int(idx[int(j)]): m for j, m in res.pop("_messages", {}).items()})
            reported.update(res)
            for k, v in res.items():
                if metrics is None or k in metrics:
                    out[k] = np.full(n, np.nan)
                    out[k][idx] = np.asarray(v, float)
    else:
        for i in range(n):
            values = {**fixed, **{k: _item(v[i]) for k, v in points.items()}}
            try:
                values = sc.resolve(values)
                sc.check_budget(values, **task.get("limits", {}))  # as every run: hours of steps are refused
                run = sc.simulate_fn(values)
            except ParameterError as e:
                status[i] = STATUS["refused"]
                messages[i] = str(e)
                continue
            except Exception as e:  # noqa: BLE001 — one run's failure is its status, not the sweep's
                status[i] = STATUS["failed"]
                messages[i] = f"{type(e).__name__}: {e}"
                continue
            if run.status != "ok":
                status[i] = STATUS["diverged"] if run.status == "diverged" else STATUS["flagged"]
                messages[i] = f"{run.status}: " + "; ".join(run.warnings)
            elif run.warnings:  # ok, but a warning says what its numbers cannot be read as (a NaN's reason)
                messages[i] = ok_with_warnings(run.warnings)
            reported.update(run.metrics)
            for k, v in run.metrics.items():
                if metrics is not None and k not in metrics:
                    continue
                try:
                    x = float(v)
                except (TypeError, ValueError):
                    continue
                if k not in out:
                    out[k] = np.full(n, np.nan)
                out[k][i] = x
    for k in metrics or ():  # a metric asked for is in the store even where no run gave it (all refused)
        out.setdefault(k, np.full(n, np.nan))
    return {"metrics": out, "status": status, "messages": messages, "seconds": time.perf_counter() - t0,
            "worker_pid": os.getpid(), "reported": sorted(reported)}


# ------------------------------------------------------------------------------------- writers

def _held(method):
    """The method's zarr reads and writes run to their end before a Ctrl-C or SIGTERM is taken
    (`signals_held`): zarr does them on its own thread, which an exit would cut off mid-write."""
    @functools.wraps(method)
    def run(*args, **kw):
        with signals_held():
            return method(*args, **kw)
    return run


class ZarrWriter:
    """The sweep as a Zarr store at OUT, each chunk's status written last. A sweep that replaces an
    older one (--force) is written beside it, in OUT.new/, and takes its place only once whole
    (`finish`): interrupted, it leaves the older store as it was and its own chunks for --resume."""

    def __init__(self, path: str, plan: Plan, resume: bool, make: bool = True):
        import xarray as xr
        import zarr

        self.path, self.plan = path, plan
        self._xr, self._zarr = xr, zarr
        staging = path.rstrip("/" + os.sep) + ".new"
        spec = plan.spec()
        if resume and (os.path.exists(staging) or os.path.exists(path)):
            self.store = staging if os.path.exists(staging) else path  # a replacing sweep first
            shown = os.path.basename(self.store.rstrip("/" + os.sep))
            try:
                with signals_held():
                    g = zarr.open_group(self.store, mode="r+")
                    old = dict(g.attrs).get("theoria_sweep")
                    chunks = tuple(g["status"].chunks) if old is not None else None
            except Exception:  # noqa: BLE001 — not a store this writes (stores are made whole: `_create`)
                old = None
            if old is None:
                raise ParameterError("--resume", shown, "is not a theoria sweep (no theoria_sweep attribute)")
            # the chunking of the file decides; everything else must match
            plan.chunks = chunks
            spec = plan.spec()
            diff = _differs(spec, old)
            if diff:
                raise ParameterError("--resume", shown, "was written by a different sweep (it differs in: "
                                     + ", ".join(diff) + "); give another --out, or --force to replace it")
            self.group = g
            self.new = False
        else:
            if os.path.exists(path) and not _is_sweep_store(path):
                raise ParameterError("--out", path, "exists and is not a theoria sweep: choose a new name")
            self.store = staging if os.path.exists(path) else path
            self.new, self.group, self._spec = True, None, spec  # made by `create`, once the sweep can run
        self.kept = self.store
        if make or not self.new:
            self.create()

    @property
    def in_place(self) -> bool:
        """The store resumed is OUT itself (not a replacing OUT.new/): once every chunk is done, it is
        the finished sweep, left as it is."""
        return not self.new and self.store == self.path

    def create(self):
        """A new sweep's store, made once everything is checked and the cluster answers."""
        if self.new and self.group is None:
            staging = self.path.rstrip("/" + os.sep) + ".new"
            if os.path.exists(staging):  # an earlier replacing sweep, not resumed
                shutil.rmtree(staging)
            self._create(self._spec)
            with signals_held():
                self.group = self._zarr.open_group(self.store, mode="r+")
        self.metric_names = [k for k in self.group.array_keys() if k not in ("status",) and k not in
                             (set(self.plan.dims) | {a.name for a in self.plan.random})]

    def _create(self, spec):
        xr, plan = self._xr, self.plan
        sc = plan.scenario
        coords = {}
        for a in plan.grid:
            vals = a.values.astype(str) if a.values.dtype == object else a.values
            coords[a.name] = (a.name, vals, {"units": a.unit or "1", "long_name": a.help})
        if plan.random:
            coords[SAMPLE] = (SAMPLE, np.arange(plan.samples), {"long_name": "random sample"})
            for a in plan.random:
                coords[a.name] = (SAMPLE, a.values, {"units": a.unit or "1", "long_name": a.help + " (random)"})
        status = xr.DataArray(np.zeros(plan.shape, np.int8), dims=plan.dims, attrs={
            "flag_values": list(STATUS.values()), "flag_meanings": " ".join(k.replace(" ", "_") for k in STATUS),
            "long_name": "run status"})
        ds = xr.Dataset({"status": status}, coords=coords)
        ds["status"].encoding = {"chunks": plan.chunks}
        from .. import __version__

        ds.attrs.update({
            "scenario": sc.name, "title": sc.title, "section": sc.section, "theoria_version": __version__,
            "fixed_parameters": {k: {"value": _plain(v), "unit": sc.param(k).unit or "1"} for k, v in plan.fixed.items()},
            "swept_parameters": {a.name: {"unit": a.unit or "1", "spec": a.spec, "random": a.random}
                                 for a in plan.grid + plan.random},
            "theoria_sweep": spec, "messages": {}, "sessions": [],
            "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        })
        # made whole beside its place, then renamed there: a store cut short while being created
        # (coordinates missing) is never taken for one to resume
        making = self.store.rstrip("/" + os.sep) + f".making-{os.getpid()}"
        shutil.rmtree(making, ignore_errors=True)
        try:
            with signals_held():  # zarr's own thread writes it: Ctrl-C is taken once it is written
                ds.to_zarr(making, mode="w", consolidated=False)
            os.rename(making, self.store)
        finally:
            shutil.rmtree(making, ignore_errors=True)

    @_held
    def done_regions(self, regions) -> set[int]:
        st = self.group["status"]
        done = set()
        for i, r in enumerate(regions):
            try:
                if np.all(st[r] != 0):
                    done.add(i)
            except Exception:  # noqa: BLE001 — a chunk cut off mid-write is simply not done
                pass
        return done

    @_held
    def add_metrics(self, names):
        import dask.array as da

        new = [n for n in names if n not in self.metric_names]
        if not new:
            return
        plan = self.plan
        ds = self._xr.Dataset({n: (plan.dims, da.full(plan.shape, np.nan, chunks=plan.chunks)) for n in new})
        for n in new:
            ds[n].attrs["units"] = _unit_of_metric(plan.scenario, n)
        ds.attrs = dict(self.group.attrs)  # appending variables rewrites the group's attributes
        ds.to_zarr(self.store, mode="a", compute=False, consolidated=False)
        self.group = self._zarr.open_group(self.store, mode="r+")
        self.metric_names += new

    @_held
    def write(self, index, region, result):
        shape = tuple(s.stop - s.start for s in region)
        self.add_metrics(list(result["metrics"]))
        for name in self.metric_names:
            v = result["metrics"].get(name)
            if v is None:
                continue  # stays NaN (the fill value)
            self.group[name][region] = np.asarray(v, float).reshape(shape)
        if result["messages"]:
            attrs = dict(self.group.attrs)
            msgs = dict(attrs.get("messages", {}))
            for i, m in result["messages"].items():
                if len(msgs) >= MAX_MESSAGES:
                    break
                idx = np.unravel_index(int(i), shape)
                key = ",".join(str(s.start + j) for s, j in zip(region, idx))
                msgs[key] = m
            self.group.attrs["messages"] = msgs
        self.group["status"][region] = result["status"].reshape(shape)  # last: the chunk is finished

    @_held
    def session(self, info):
        sessions = list(dict(self.group.attrs).get("sessions", []))
        sessions.append(info)
        self.group.attrs["sessions"] = sessions

    @_held
    def finish(self):
        """A replacing sweep, whole, takes the older store's place (which is then removed)."""
        if self.store == self.path:
            return
        older = None
        try:
            if os.path.lexists(self.path):
                older = self.path.rstrip("/" + os.sep) + f".old-{os.getpid()}"  # a name nobody else uses
                os.rename(self.path, older)
            os.rename(self.store, self.path)
        except OSError as e:
            if older is not None and not os.path.lexists(self.path):
                os.rename(older, self.path)  # the older store back in its place
            raise WriteError(f"cannot put the finished sweep in place of {self.path} ({e.strerror or e}); it is "
                             f"whole in {self.store}", e.errno) from None
        if older is not None:
            if os.path.islink(older) or not os.path.isdir(older):
                os.remove(older)
            else:
                shutil.rmtree(older, ignore_errors=True)
        self.store = self.kept = self.path
        self.group = self._zarr.open_group(self.store, mode="r+")

    def discard(self):
        """A new sweep refused or failed before any chunk of it finished (a --metrics name no run
        reports, a full disk, a cluster that fell over): nothing of it stays, and an older store
        it was to replace is left as it was."""
        if self.new:
            shutil.rmtree(self.store, ignore_errors=True)

    @_held
    def open(self):
        return self._xr.open_zarr(self.store, consolidated=False)


class ParquetWriter:
    """Chunks as parquet parts in OUT.parts/ (each written whole, then renamed); joined into the
    one flat table OUT when every chunk is there."""

    def __init__(self, path: str, plan: Plan, resume: bool, make: bool = True):
        self.path, self.plan = path, plan
        self.parts = path + ".parts"
        self.complete = False  # resumed over its own finished table: nothing to run, nothing to write
        spec = plan.spec()
        specfile = os.path.join(self.parts, "_sweep.json")
        if resume and os.path.exists(specfile):
            old = _read_json(specfile, "--resume")
            plan.chunks = tuple(old["chunks"])
            spec = plan.spec()
            diff = _differs(spec, old)
            if diff:
                raise ParameterError("--resume", os.path.basename(self.parts), "was written by a different sweep "
                                     "(it differs in: " + ", ".join(diff) + "); give another --out, or --force to "
                                     "replace it")
        elif resume and os.path.exists(path):  # a finished table: the same sweep is done, another refused
            try:
                import pyarrow.parquet as pq

                old = json.loads(pq.read_schema(path).metadata[b"theoria_sweep"])
            except Exception:  # noqa: BLE001 — not a table this writes
                raise ParameterError("--resume", path, "is not a theoria sweep (no theoria_sweep in its metadata)") from None
            diff = _differs(spec, old)
            if diff:
                raise ParameterError("--resume", path, "was written by a different sweep (it differs in: "
                                     + ", ".join(diff) + "); give another --out, or --force to replace it")
            self.complete = True
        self.new = not self.complete and not (resume and os.path.exists(specfile))
        self._spec = spec
        self.sessions_file = os.path.join(self.parts, "_sessions.json")
        self.kept = self.parts
        if make:
            self.create()

    @property
    def in_place(self) -> bool:
        return self.complete

    def create(self):
        """A new sweep's OUT.parts/, made once everything is checked and the cluster answers."""
        if not self.new:
            return
        if os.path.exists(self.parts):
            shutil.rmtree(self.parts)
        os.makedirs(self.parts)
        try:
            write_whole(os.path.join(self.parts, "_sweep.json"), json.dumps(self._spec).encode())
        except BaseException:  # a full disk: no empty OUT.parts/ that a next sweep would take for a sweep
            shutil.rmtree(self.parts, ignore_errors=True)
            raise

    def _part(self, i):
        return os.path.join(self.parts, f"part-{i:07d}.parquet")

    def done_regions(self, regions):
        if self.complete:
            return set(range(len(regions)))
        return {i for i in range(len(regions)) if os.path.exists(self._part(i))}

    def write(self, index, region, result):
        import pyarrow as pa
        import pyarrow.parquet as pq

        plan = self.plan
        pts = plan.points(region)
        cols = {}
        for k, v in pts.items():
            cols[k] = v.astype(str) if v.dtype == object else v
        if plan.random:
            cols[SAMPLE] = np.meshgrid(*[np.arange(s.start, s.stop) for s in region], indexing="ij")[-1].ravel()
        for k, v in result["metrics"].items():
            cols[k] = np.asarray(v, float)
        cols["status"] = np.asarray(result["status"], np.int8)
        n = len(cols["status"])
        cols["message"] = np.array([result["messages"].get(i, "") for i in range(n)], dtype=object)
        table = pa.table(cols)
        tmp = self._part(index) + ".tmp"
        pq.write_table(table, tmp)
        os.replace(tmp, self._part(index))

    def session(self, info):
        if self.complete:
            return
        sessions = []
        if os.path.exists(self.sessions_file):
            sessions = _read_json(self.sessions_file, "--resume")
        sessions.append(info)
        write_whole(self.sessions_file, json.dumps(sessions).encode())
        self.sessions = sessions

    def discard(self):
        """A new sweep refused or failed before any chunk of it finished (a --metrics name no run
        reports, a full disk, a cluster that fell over): nothing of it stays."""
        if self.new:
            shutil.rmtree(self.parts, ignore_errors=True)

    def finish(self):
        if self.complete:
            return
        import pyarrow as pa
        import pyarrow.parquet as pq
        from .. import __version__

        files = sorted(f for f in os.listdir(self.parts) if f.startswith("part-") and f.endswith(".parquet"))
        tables = [pq.read_table(os.path.join(self.parts, f)) for f in files]
        table = pa.concat_tables(tables, promote_options="default")
        sc = self.plan.scenario
        units = {a.name: a.unit or "1" for a in self.plan.grid + self.plan.random}
        metrics = [c for c in table.column_names if c not in units and c not in (SAMPLE, "status", "message")]
        units.update({m: _unit_of_metric(sc, m) for m in metrics})
        meta = {"theoria_sweep": json.dumps(self.plan.spec()), "theoria_version": __version__,
                "scenario": sc.name, "units": json.dumps(units),
                "sessions": json.dumps(getattr(self, "sessions", [])),
                # what pandas reads into DataFrame.attrs: the units as `run --out F.parquet` gives them
                "PANDAS_ATTRS": json.dumps({"units": units, "scenario": sc.name})}
        table = table.replace_schema_metadata({**(table.schema.metadata or {}), **{k.encode(): v.encode() for k, v in meta.items()}})
        tmp = self.path + ".tmp"
        try:
            pq.write_table(table, tmp)
            os.replace(tmp, self.path)
        except BaseException as e:  # a full disk, a second Ctrl-C: no half table beside the parts
            with contextlib.suppress(OSError):
                os.remove(tmp)
            if isinstance(e, OSError):
                raise WriteError(f"{self.path}: cannot write ({e.strerror or e}); the finished chunks are kept in "
                                 f"{self.parts}, --resume joins them", e.errno) from None
            raise
        shutil.rmtree(self.parts)

    def open(self):
        import pandas as pd

        return pd.read_parquet(self.path)


def _jsonish(x):
    return json.loads(json.dumps(x, default=_plain))


def _is_sweep_store(path):
    try:
        with open(os.path.join(path, "zarr.json")) as f:
            return "theoria_sweep" in json.load(f).get("attributes", {})
    except (OSError, ValueError):
        return False


def _is_sweep_table(path) -> bool:
    """A Parquet table a theoria sweep wrote (its schema metadata says so)."""
    try:
        import pyarrow.parquet as pq

        return b"theoria_sweep" in (pq.read_schema(path).metadata or {})
    except Exception:  # noqa: BLE001 — not Parquet, unreadable, a folder
        return False


def _unit_of_metric(sc, name: str) -> str:
    """A metric's unit as the stores write units ("1" for a pure number, as CF conventions do)."""
    unit = sc.metric_unit(name)
    return "1" if unit in ("", None) else unit


# ------------------------------------------------------------------------------------- running

@dataclass
class Summary:
    out: str
    runs: int
    chunks: int
    chunks_done_before: int
    chunks_computed: int
    path: str  # "batched" or "single runs"
    seconds: float
    statuses: dict[str, int] = field(default_factory=dict)
    interrupted: bool = False
    signal: str = ""
    cluster: str = ""
    # where an interrupted sweep's finished chunks are (OUT itself, OUT.parts/, OUT.new/); None: nothing kept
    kept: str | None = ""
    complete: bool = False  # OUT holds the whole sweep (every chunk done), now or before
    found_complete: bool = False  # resumed, and found already finished: nothing was run or written

    def line(self) -> str:
        if self.found_complete:
            return (f"sweep: {_n(self.runs, 'run')} in {_n(self.chunks, 'chunk')}; computed 0 chunks now, "
                    f"{self.chunks_done_before} were done before: the sweep is complete, left as it is → {self.out}")
        st = ", ".join(f"{v} {k}" for k, v in self.statuses.items() if v)
        if self.interrupted and self.kept is None:
            return (f"sweep: {_n(self.runs, 'run')} in {_n(self.chunks, 'chunk')} ({self.path}); "
                    f"{self.seconds:.1f} s — interrupted before any chunk finished: nothing written" + (
                        f"; {self.out} is as it was" if os.path.exists(self.out) else ""))
        where = self.kept or self.out
        return (f"sweep: {_n(self.runs, 'run')} in {_n(self.chunks, 'chunk')} ({self.path}); "
                f"computed {_n(self.chunks_computed, 'chunk')} "
                f"now, {self.chunks_done_before} were done before; {self.seconds:.1f} s"
                + (f"; {st}" if st else "")
                + (f" — interrupted, finished chunks kept in {where} (--resume continues)" + (
                    f"; {self.out} is as it was" if where != self.out and os.path.exists(self.out) else "")
                   if self.interrupted else f" → {self.out}"))


def _n(n: int, word: str) -> str:
    """"1 chunk", "2 chunks"."""
    return f"{n} {word}" + ("" if n == 1 else "s")


class _Stop:
    """SIGINT/SIGTERM during a sweep set a flag (a second one raises): the main loop stops between
    two chunk writes, so no chunk is left half written."""

    def __init__(self):
        self.flag = False
        self.signum = None
        self.old = {}

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for s in (signal.SIGINT, signal.SIGTERM):
                self.old[s] = signal.signal(s, self._handler)
        return self

    def _handler(self, signum, frame):
        if self.flag:
            raise KeyboardInterrupt
        self.flag, self.signum = True, signum

    def __exit__(self, *exc):
        for s, h in self.old.items():
            signal.signal(s, h)
        return False


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def _client(cluster, workers):
    """A dask.distributed Client: a LocalCluster on this machine's cores (bound to 127.0.0.1, no
    dashboard) by default, or the scheduler at `cluster` (tcp://host:port), or a Client given."""
    import logging

    from distributed import Client, LocalCluster

    if cluster is None:
        n = int(workers or _cores())
        # A terminal's Ctrl-C goes to the whole process group: the workers start with SIGINT ignored
        # (`_workers_ignore_ctrl_c`), so that only this process sees it and stops the sweep cleanly.
        # This process keeps it: a Ctrl-C while the cluster starts is noted and raised once it has
        # started (ignored here too, as before, it was lost and the sweep ran to its end, exit 0).
        main = threading.current_thread() is threading.main_thread()
        noted: list[int] = []
        old = signal.signal(signal.SIGINT, lambda signum, frame: noted.append(signum)) if main else None
        lc = None
        try:
            with _workers_ignore_ctrl_c(), _main_file_only_if_it_exists():
                lc = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address="127.0.0.1:0", worker_dashboard_address="127.0.0.1:0",
                                  silence_logs=logging.CRITICAL)
            if noted:
                raise KeyboardInterrupt
            return Client(lc), lc, f"local cluster, {n} workers", True
        except BaseException:
            if lc is not None:
                lc.close()
            raise
        finally:
            if main:
                signal.signal(signal.SIGINT, old)
    if isinstance(cluster, str):
        if not re.match(r"^(tcp|tls|inproc|ws|wss)://", cluster):
            raise ParameterError("--cluster", cluster, "a scheduler address such as tcp://127.0.0.1:8786")
        try:
            c = Client(cluster, timeout=10)
        except (OSError, TimeoutError) as e:
            raise ParameterError("--cluster", cluster, f"no Dask scheduler answers there ({type(e).__name__})") from None
        return c, None, f"scheduler {cluster}", True
    if not all(callable(getattr(cluster, m, None)) for m in ("submit", "gather")):
        raise ParameterError("cluster", cluster, "None (a local cluster), a scheduler address such as "
                             "tcp://127.0.0.1:8786, or a dask.distributed Client")
    return cluster, None, "the given client", False  # the caller's: left open


@contextlib.contextmanager
def _workers_ignore_ctrl_c():
    """Processes multiprocessing spawns meanwhile (the local cluster's nannies, and through them
    its workers) start with SIGINT ignored: they are started through a launcher that ignores it
    and runs this Python (an ignored signal stays ignored across exec, and Python then installs
    no handler of its own). Where there is no POSIX shell, nothing is changed."""
    import multiprocessing.spawn as mp_spawn
    import shlex
    import tempfile

    if os.name != "posix" or not os.path.exists("/bin/sh"):
        yield
        return
    where = tempfile.mkdtemp(prefix="theoria-workers-")
    launcher = os.path.join(where, "python")
    with open(launcher, "w") as f:
        f.write(f"#!/bin/sh\ntrap '' INT\nexec {shlex.quote(sys.executable)} \"$@\"\n")
    os.chmod(launcher, 0o755)
    before = mp_spawn.get_executable()
    mp_spawn.set_executable(launcher)
    try:
        yield
    finally:
        mp_spawn.set_executable(before)
        shutil.rmtree(where, ignore_errors=True)


@contextlib.contextmanager
def _main_file_only_if_it_exists():
    """A program read from standard input (`python - <<EOF`, a pipe) has the `__main__.__file__`
    "<stdin>": the workers multiprocessing spawns meanwhile tried to run that file again on their
    way in, and the sweep died with "FileNotFoundError: '<stdin>'" and "Nanny failed to start",
    three tracebacks. While they start, such a name is hidden, as for `python -c` (which has none):
    the workers run only theoria's code, which is all a sweep sends them."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if not isinstance(path, str) or os.path.isfile(path):
        yield
        return
    del main.__file__
    try:
        yield
    finally:
        main.__file__ = path


GUARD_ADVICE = "put the sweep under `if __name__ == \"__main__\":` in that script, so that it runs once, in the process you started"


def _unguarded_script() -> str | None:
    """The Python file this process runs, which the local cluster's workers will run again on
    their way in, when it tests `__name__ == "__main__"` nowhere (None for a console, a notebook,
    the theoria command, `python -m pkg` (spawn never runs a package's __main__ again), a script
    with the test, or a file that cannot be read)."""
    import ast
    import tokenize

    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    spec = getattr(main, "__spec__", None)
    if spec is not None and (spec.name == "__main__" or spec.name.endswith(".__main__")):
        return None  # multiprocessing's spawn leaves such a module alone
    if not isinstance(path, str) or not path.endswith(".py"):
        return None
    try:
        with tokenize.open(path) as f:  # its declared or BOM-marked encoding
            tree = ast.parse(f.read(), path)
    except (OSError, SyntaxError, ValueError):
        return None

    def is_main_test(t) -> bool:  # __name__ == "__main__", either way round
        if not (isinstance(t, ast.Compare) and len(t.ops) == 1 and isinstance(t.ops[0], ast.Eq)):
            return False
        sides = [t.left, t.comparators[0]]
        return (any(isinstance(x, ast.Name) and x.id == "__name__" for x in sides)
                and any(isinstance(x, ast.Constant) and x.value == "__main__" for x in sides))

    # anywhere: `if __name__ == "__main__" and …:`, a guard inside a try; a miss here is caught in
    # the worker (run_sweep's first check)
    guarded = any(is_main_test(node) for node in ast.walk(tree))
    return None if guarded else path


def run_sweep(sc, grid=None, random=None, samples=None, out=None, cluster=None, resume=False, metrics=None,
              fixed=None, preset=None, seed=0, chunk=None, workers=None, progress=True,
              on_chunk=None, force=False, limits=None) -> tuple[Summary, Any]:
    """Plan, check, run and write a sweep. Returns (Summary, the opened result). `limits`:
    {"max_steps": …, "max_memory": …} for each run (default the app's; a run over them is not run,
    its status 'refused' with the budget's message)."""
    import multiprocessing

    if (getattr(sys.modules.get("__main__"), "__name__", None) == "__mp_main__"
            or getattr(multiprocessing.current_process(), "_inheriting", False)):
        # a worker process of the local cluster re-running the user's script on its way in (the
        # script is its __mp_main__): were it to sweep too, every worker would start a cluster of
        # its own on the same OUT
        raise RuntimeError("a sweep was started while a local Dask worker re-imported the script that "
                           "started it: " + GUARD_ADVICE)
    script = _unguarded_script() if cluster is None else None
    if script is not None:  # said here, before any worker starts (each would fail with this in its own
        # traceback, and the sweep with "Nanny failed to start")
        raise RuntimeError(f"{script} starts a sweep without `if __name__ == \"__main__\":`: the local Dask "
                           "cluster's workers import the script again on their way in; " + GUARD_ADVICE)
    if resume and force:
        raise ParameterError("--resume", "--force", "one of the two: --resume completes the sweep at --out, "
                             "--force replaces it")
    if not isinstance(out, (str, os.PathLike)):
        raise ParameterError("--out", out, "a file name ending in .zarr or .parquet")
    out = os.fspath(out)
    if not isinstance(out, str):
        raise ParameterError("--out", out, "a file name ending in .zarr or .parquet, as text")
    if "\0" in out:
        raise ParameterError("--out", repr(out), "a file name without a NUL character")
    # each run's budget, read before anything starts ("4GB" as the command line writes it)
    from ..scenarios.budget import memory_limit, steps_limit

    limits = {k: (steps_limit if k == "max_steps" else memory_limit)(v, k) for k, v in (limits or {}).items()}
    kind = "zarr" if out.rstrip("/").endswith(".zarr") else "parquet" if out.endswith(".parquet") else None
    if kind is None:
        raise ParameterError("--out", out, "a name ending in .zarr (xarray/Zarr) or .parquet (flat table)")
    parent = os.path.dirname(os.path.abspath(out)) or "."
    if not os.path.isdir(parent) or not os.access(parent, os.W_OK):
        raise ParameterError("--out", out, f"its folder {parent} must exist and be writable")
    try:
        os.stat(out)
    except FileNotFoundError:
        pass
    except OSError as e:  # a name too long for the file system, a loop of links
        raise ParameterError("--out", out, f"a path this system takes ({e.strerror or type(e).__name__})") from None
    if kind == "parquet" and os.path.isdir(out):
        raise ParameterError("--out", out, "a file name: this is a directory")
    if workers is not None:
        workers = _count(workers, "--workers", 256, "a whole number from 1 to 256")
    nworkers = workers or (_cores() if cluster is None else 1)
    plan = make_plan(sc, grid, random, samples, fixed, preset, metrics, seed, chunk, nworkers)
    plan.limits = dict(limits or {})
    with _one_sweep_writes(out):
        return _run_locked(sc, plan, out, kind, cluster, resume, force, workers, progress, on_chunk)


def _lock_path(out: str) -> str:
    """The lock file beside OUT: `.NAME.lock` in OUT's folder."""
    out = os.path.abspath(out.rstrip("/" + os.sep))
    return os.path.join(os.path.dirname(out), "." + os.path.basename(out) + ".lock")


@contextlib.contextmanager
def _one_sweep_writes(out: str):
    """While the block runs, no other sweep writes OUT (or its OUT.new/, OUT.parts/): an exclusive
    `flock` on `.NAME.lock` beside it, with this process's PID in it. A second sweep on the same OUT
    (plain, --force or --resume) is refused at once, naming the PID that holds it. The kernel
    releases the lock when its process ends however it ends, so a sweep killed outright leaves at
    most the file, never a lock; the file is removed when the sweep ends."""
    import fcntl

    path = _lock_path(out)
    while True:
        fd = -1
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            try:
                pid = os.read(fd, 32).decode("ascii", "replace").strip()
            finally:
                os.close(fd)
            raise SweepBusy(out, int(pid) if pid.isdigit() else None) from None
        except OSError as e:  # a name too long once `.lock` is added, a file system without locks
            if fd >= 0:
                os.close(fd)
            raise ParameterError("--out", out, f"a place where {os.path.basename(path)} can be made and locked "
                                 f"({e.strerror or type(e).__name__})") from None
        # the sweep that held it may have removed the file between our open and our lock: then
        # this lock is on a file nobody else sees, and the one now at `path` is taken again
        try:
            st, now = os.fstat(fd), os.stat(path)
            if (st.st_dev, st.st_ino) == (now.st_dev, now.st_ino):
                break
        except FileNotFoundError:
            pass
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        yield
    finally:
        try:
            os.unlink(path)  # before the lock is let go: a sweep that opened it meanwhile makes a new one
        except OSError:
            pass
        os.close(fd)


def _run_locked(sc, plan, out, kind, cluster, resume, force, workers, progress, on_chunk):
    """`run_sweep` once OUT is this sweep's alone."""
    earlier = os.path.exists(out) or os.path.exists(out + ".parts" if kind == "parquet" else out.rstrip("/") + ".new")
    if os.path.exists(out) and not (_is_sweep_store(out) if kind == "zarr" else _is_sweep_table(out)):
        # a file of the user's (a run's table, anything): a sweep replaces only a sweep, even with
        # --force (a Parquet file that was no sweep was said to hold one, and --force overwrote it)
        raise ParameterError("--out", out, "a new path: it exists and is not a theoria sweep, which a sweep "
                             "does not replace; choose another name")
    if earlier and not (resume or force):  # hours of runs are not replaced by a command repeated by mistake
        raise ParameterError("--out", out, "a new path: it holds a sweep; add --resume to complete it or "
                             "--force to replace it")
    # an older table or store at `out` stays as it is until the new one replaces it whole
    # (`finish`): an interrupted sweep leaves it, and its own finished chunks (OUT.parts/, OUT.new/)
    # for --resume. The writer only checks here; a new sweep's store is made (`create`) once the
    # cluster answers, so that a sweep refused (a wrong --cluster) writes nothing.
    writer = (ZarrWriter if kind == "zarr" else ParquetWriter)(out, plan, resume, make=False)
    regions = plan.chunk_regions()
    done = writer.done_regions(regions) if not writer.new else set()
    todo = [i for i in range(len(regions)) if i not in done]
    t0, started = time.perf_counter(), datetime.datetime.now(datetime.timezone.utc)
    summary = Summary(out, plan.size, len(regions), len(done), 0, "batched" if plan.batched else "single runs", 0.0)
    counts = {k: 0 for k in STATUS if k != "not run"}
    interrupted = False
    if not todo and writer.in_place:
        # a finished sweep resumed: it is complete, and left byte for byte as it is
        summary.seconds = time.perf_counter() - t0
        summary.complete = summary.found_complete = True
        with signals_held() as held:
            mark_written(out)
            result = writer.open()
            held.drop()
        return summary, result
    # From the cluster's shutdown to the sweep's recorded end a Ctrl-C or SIGTERM waits (a second
    # one still stops it): the invocation that computed the chunks is always written down, and a
    # sweep whose every chunk is done is reported done.
    with contextlib.ExitStack() as to_the_end:
        held = None
        if todo:
            client, local, where, owned = _client(cluster, workers)
            summary.cluster = where
            threads = 1 if local is not None else None
            failed = False
            with _quiet_distributed(local is not None):  # to the cluster's last line
                try:
                    writer.create()
                    # held from here (the chunks' own stop handler in front while they run), so that
                    # none comes between that handler's end and the shutdown
                    held = to_the_end.enter_context(signals_held())
                    with _Stop() as stop, _progress(progress, plan.size, sum(_nruns(regions[i]) for i in done),
                                                    sc.name) as bar:
                        if held.signals:  # one came just before the chunks' handler: it stops them
                            stop.flag, stop.signum = True, held.signals[0]
                            held.drop()
                        interrupted = _drive(client, plan, regions, todo, writer, stop, bar, counts, summary,
                                             threads, on_chunk)
                        if interrupted:
                            summary.signal = signal.Signals(stop.signum).name if stop.signum else "KeyboardInterrupt"
                except BaseException:
                    failed = True
                    if summary.chunks_computed == 0:  # a new sweep that failed with nothing finished leaves nothing
                        writer.discard()
                    raise
                finally:
                    held = held or to_the_end.enter_context(signals_held())
                    try:
                        if (interrupted or failed) and local is not None:
                            _stop_workers(local)  # a worker deep in a long chunk would hold the exit for minutes
                        if owned:
                            client.close()
                        if local is not None:
                            local.close(timeout=20)
                    except Exception:  # noqa: BLE001 — shutting down after Ctrl-C
                        pass
        summary.seconds = time.perf_counter() - t0
        summary.statuses = counts
        summary.interrupted = interrupted
        summary.kept = writer.kept if interrupted else ""
        held = held or to_the_end.enter_context(signals_held())
        if interrupted and summary.chunks_computed == 0 and writer.new:
            # stopped before any chunk of a new sweep finished: nothing is worth keeping, and the
            # same command run again starts afresh (it was told to add --resume to resume nothing)
            writer.discard()
            summary.kept = None
            held.drop()
            return summary, None
        writer.session({"started": started.isoformat(timespec="seconds"),  # when it started, not when it ended
                        "chunks_computed": summary.chunks_computed, "chunks_done_before": summary.chunks_done_before,
                        "path": summary.path, "seconds": round(summary.seconds, 3), "interrupted": interrupted,
                        "where": summary.cluster})
        if interrupted:  # a stop during the shutdown asked for what is already happening
            held.drop()
            return summary, None
        # the finished result takes the place of OUT and is opened: it is then too late to undo it
        # (the sweep is reported done)
        writer.finish()
        mark_written(out)
        summary.complete = True
        result = writer.open()
        held.drop()
    return summary, result


@contextlib.contextmanager
def _quiet_distributed(local: bool):
    """A local cluster's own log lines (a comm closed while its workers are stopped, a heartbeat
    missed) are silenced from its start to the end of its shutdown: the sweep reports every run's
    status itself, and Ctrl-C must end in the sweep's one summary line, not a dask traceback."""
    import logging

    logger = logging.getLogger("distributed")
    level = logger.level
    if local:
        logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        logger.setLevel(level)


def _stop_workers(local):
    """SIGTERM to the local cluster's worker processes (this process started them), so that an
    interrupted sweep exits at once instead of waiting for the chunks in flight."""
    for nanny in list(getattr(local, "workers", {}).values()):
        try:
            pid = nanny.pid
            if pid:
                os.kill(pid, signal.SIGTERM)
        except Exception:  # noqa: BLE001 — already gone
            pass


def _nruns(region):
    return int(np.prod([s.stop - s.start for s in region]))


def _drive(client, plan, regions, todo, writer, stop, bar, counts, summary, threads, on_chunk) -> bool:
    from distributed import as_completed

    sc = plan.scenario
    futures = {}
    for i in todo:
        task = {"scenario": sc.name, "fixed": plan.fixed, "points": plan.points(regions[i]),
                "metrics": plan.metrics, "batched": plan.batched, "threads": threads,
                "limits": plan.limits}
        fut = client.submit(run_chunk, task, pure=False, key=f"theoria-sweep-{sc.name}-{i}-{os.getpid()}-{time.time_ns()}")
        futures[fut] = i
    ac = as_completed(list(futures))
    checked_metrics = plan.metrics is None
    try:
        while True:
            if summary.chunks_computed == len(todo):  # every chunk written: a stop now changes nothing
                return False
            if stop.flag:
                return True
            try:
                fut = next(_next_with_timeout(ac, 0.2))
            except StopIteration:
                return False
            if fut is None:
                continue
            i = futures[fut]
            try:
                res = fut.result()
            except Exception as e:  # noqa: BLE001 — a task that failed as a whole (a worker died, an import failed)
                if summary.chunks_computed == 0 and writer.new:
                    raise SweepError(f"chunk {i} failed on a worker ({type(e).__name__}: {e}); no chunk had "
                                     f"finished, nothing was written") from None
                raise SweepError(f"chunk {i} failed on a worker ({type(e).__name__}: {e}); the finished chunks "
                                 f"are kept in {writer.kept}, --resume continues") from None
            if not checked_metrics:
                seen = set(res.get("reported", ()))  # not res["metrics"]: it holds the asked-for names too, NaN
                known = set(getattr(getattr(sc, "batch", None), "metrics", ()) or ())
                missing = [m for m in plan.metrics if m not in seen and m not in known]
                if missing and np.any(res["status"] == STATUS["ok"]):
                    raise ParameterError("--metrics", missing[0], "not a metric of " + sc.name + "; its metrics: "
                                         + ", ".join(sorted(seen | known)))
                checked_metrics = True
            writer.write(i, regions[i], res)
            summary.chunks_computed += 1
            for name, code in STATUS.items():
                if name != "not run":
                    counts[name] += int(np.count_nonzero(res["status"] == code))
            bar(_nruns(regions[i]))
            if on_chunk is not None:
                on_chunk(i, res)
    finally:
        for f in futures:
            if not f.done():
                f.cancel()


def _next_with_timeout(ac, timeout):
    """One finished future, or None after `timeout` s (so that a stop flag is seen promptly)."""
    if ac.is_empty():
        return iter(())
    if ac.has_ready():
        return iter([next(ac)])
    t_end = time.monotonic() + timeout
    while time.monotonic() < t_end:
        if ac.has_ready():
            return iter([next(ac)])
        time.sleep(0.02)
    return iter([None])


class _progress:
    """A rich progress bar on stderr: runs done of the total, runs per second, time left."""

    def __init__(self, enabled, total, done, label):
        self.enabled, self.total, self.done, self.label = enabled, total, done, label
        self.p = None

    def __enter__(self):
        console = None
        if self.enabled:
            from rich.console import Console

            console = Console(stderr=True)
        # a terminal or a notebook: with stderr in a file or a pipe the bar's last frame was written
        # there before the summary line (docs/sweeps.md: only the summary)
        if console is not None and (console.is_terminal or console.is_jupyter):
            from rich.progress import (BarColumn, MofNCompleteColumn, Progress, TaskProgressColumn, TextColumn,
                                       TimeElapsedColumn, TimeRemainingColumn)

            class Rate(TextColumn):
                def render(self, task):
                    from rich.text import Text

                    sp = task.finished_speed or task.speed
                    return Text(f"{sp:.3g} runs/s" if sp else "– runs/s")

            self.p = Progress(TextColumn(f"sweep {self.label}"), BarColumn(), MofNCompleteColumn(),
                              TaskProgressColumn(), Rate(""), TimeElapsedColumn(), TextColumn("left"),
                              TimeRemainingColumn(), console=console, transient=False)
            self.p.__enter__()
            self.task = self.p.add_task("runs", total=self.total, completed=self.done)
        return self

    def __call__(self, n):
        if self.p is not None:
            self.p.advance(self.task, n)

    def __exit__(self, *exc):
        if self.p is not None:
            self.p.__exit__(*exc)
        return False


# ------------------------------------------------------------------------------- reading a map

@dataclass
class MapData:
    """What a map of one metric over two swept parameters needs (the app draws it)."""

    values: np.ndarray  # (len(y), len(x)): rows along y, columns along x
    metric: str
    metric_unit: str
    x: str
    x_unit: str
    x_values: np.ndarray
    y: str
    y_unit: str
    y_values: np.ndarray
    scenario: str
    reduced: str  # how other swept dimensions were reduced ("" if none)
    status: np.ndarray  # (len(y), len(x)) int codes (STATUS) or the fraction finished when reduced
    _dataset: Any = field(repr=False, default=None)

    def run_values(self, i: int, j: int, sample: int | None = None) -> dict[str, Any]:
        """The full parameter values of the run at row i (y), column j (x): to replay it with
        `th.scenario(map.scenario).simulate(**values)`. With a sample dimension, `sample` picks
        one draw (default 0); other swept dimensions take their first value."""
        ds = self._dataset
        spec = ds.attrs["theoria_sweep"]
        values = dict(spec["fixed"])
        for d in spec["dims"]:
            if d == SAMPLE:
                k = 0 if sample is None else int(sample)
                for name in spec["random"]:
                    values[name] = _item(ds[name].values[k])
            elif d == self.x:
                values[d] = _item(ds[d].values[j])
            elif d == self.y:
                values[d] = _item(ds[d].values[i])
            else:
                values[d] = _item(ds[d].values[0])
        for k, v in list(values.items()):
            if isinstance(v, list):
                values[k] = tuple(v)
        return values


def open_map(path, metric: str, x: str | None = None, y: str | bool | None = None, reduce: str = "mean") -> MapData:
    """Open a sweep result (Zarr, or an xarray Dataset already opened) and return one metric as a
    2-D array over two swept parameters (x: columns, y: rows; by default the last two swept
    parameters), with axis names, units and values, and `run_values(i, j)` for the full parameters
    of any pixel. `y=False` gives a profile along x (one row). Any other dimension (e.g. the random `sample`, or the starting angle of a
    capture sweep) is reduced with `reduce` ("mean", "median", "max", "min", or "fraction" of runs
    where the metric is nonzero — a capture probability)."""
    import xarray as xr

    ds = path if isinstance(path, xr.Dataset) else xr.open_zarr(os.fspath(path), consolidated=False)
    if "theoria_sweep" not in ds.attrs:
        raise ParameterError("sweep", path, "a Zarr store written by theoria sweep")
    if metric not in ds.data_vars or metric == "status":
        raise ParameterError("metric", metric, "one of " + ", ".join(v for v in ds.data_vars if v != "status"))
    dims = list(ds[metric].dims)
    grid_dims = [d for d in dims if d != SAMPLE] or dims
    if x is None and y is None:  # the last two swept parameters (the first of them along y)
        x = grid_dims[-1]
        y = grid_dims[-2] if len(grid_dims) >= 2 else False
    elif x is None:
        x = next((d for d in reversed(grid_dims) if d != y), None)
    elif y is None:
        y = next((d for d in reversed(grid_dims) if d != x), False)
    y = y or None  # y=False: a profile along x (every other dimension reduced)
    for name in (x, y):
        if name is not None and name not in dims:
            raise ParameterError("axis", name, "one of " + ", ".join(dims))
    if x is None or x == y:
        raise ParameterError("axis", x, "two different swept parameters (or y=False for a profile along x)")
    da = ds[metric]
    st = ds["status"]
    other = [d for d in dims if d not in (x, y)]
    if other:
        if reduce == "fraction":
            v = da.where(np.isfinite(da))
            da = (v != 0).where(v.notnull()).mean(other)
        elif reduce in ("mean", "median", "max", "min"):
            da = getattr(da, reduce)(other, skipna=True)
        else:
            raise ParameterError("reduce", reduce, "one of mean, median, max, min, fraction")
        st = (st != 0).mean(other)
    if y is None:
        vals = np.asarray(da.transpose(x).values)[None, :]
        stv = np.asarray(st.transpose(x).values)[None, :]
        yv = np.array([0.0])
        yu = ""
    else:
        vals = np.asarray(da.transpose(y, x).values)
        stv = np.asarray(st.transpose(y, x).values)
        yv = np.asarray(ds[y].values)
        yu = ds[y].attrs.get("units", "")
    return MapData(vals, metric, ds[metric].attrs.get("units", ""), x, ds[x].attrs.get("units", ""),
                   np.asarray(ds[x].values), y or "", yu, yv, ds.attrs.get("scenario", ""),
                   f"{reduce} over {', '.join(other)}" if other else "", stv, ds)


# -------------------------------------------------------------------------------- named sweeps

@dataclass(frozen=True)
class SweepPreset:
    """A named sweep: scenario, grid, random draws, fixed values, and the map it is for
    (`open_map(out, metric, reduce=…)`). `theoria sweep NAME --out F.zarr` runs it; --grid, --set,
    --random override or add to it."""

    name: str
    scenario: str
    description: str
    grid: tuple[str, ...] = ()
    random: tuple[str, ...] = ()
    samples: int | None = None
    fixed: Mapping[str, Any] = field(default_factory=dict)
    metric: str = ""
    reduce: str = "mean"


SWEEP_PRESETS: dict[str, SweepPreset] = {p.name: p for p in (
    SweepPreset(
        "hyperion-chaos-map", "hyperion",
        "Hyperion's chaos map (Wisdom, Peale & Mignard 1984): the largest Lyapunov exponent per orbit of a start "
        "at periapse with the long axis toward Saturn, over the eccentricity and the starting spin θ̇/n, ω₀ = 0.89. "
        "Dark: regular (the 1:2, 1:1, 3:2, 2:1 islands); bright: the chaotic sea that opens as e grows.",
        grid=("eccentricity=0:0.3:128", "probe_rate=0.2:3:256"),
        fixed={"omega0": 0.89, "probe_theta_deg": 0.0, "n_orbits": 300, "steps_per_orbit": 48},
        metric="lyapunov_probe_per_orbit"),
    SweepPreset(
        "mercury-capture", "tidal-capture",
        "Mercury's capture into the 3:2 resonance against the eccentricity: a Mercury-like body (ω₀ = 0.019, "
        "(B − A)/C = 1.2e-4) despun by a constant-time-lag tide from θ̇ = 1.7 n, 128 starting angles per "
        "eccentricity; the fraction captured beside Goldreich & Peale's probability (metric "
        "gp_capture_probability_3_2). At e = 0.2056 both are ≈ 7–8 %.",
        grid=("eccentricity=0.1:0.25:16", "initial_angle_deg=0:177.1875:128"),
        fixed={"omega0": 0.019, "tide_rate": 2e-6, "spin_rate": 1.7, "orbits": 100000.0, "steps_per_orbit": 48},
        metric="captured_3_2", reduce="mean"),
)}


def preset_kwargs(name: str, grid=None, random=None, samples=None, fixed=None) -> dict:
    """The arguments of `run_sweep` for sweep preset `name`, with extra or overriding specs."""
    p = SWEEP_PRESETS[name]
    gnames = {g.split("=", 1)[0] for g in (grid or [])}
    g = [x for x in p.grid if x.split("=", 1)[0] not in gnames] + list(grid or [])
    return {"grid": g, "random": list(p.random) + list(random or []), "samples": samples or p.samples,
            "fixed": {**{k: v for k, v in p.fixed.items() if k not in gnames}, **dict(fixed or {})}}
