"""What a run costs, known before it runs, and the limits it must stay within.

Every scenario states, from its parameter values alone, the integrator steps its run takes and
the memory its finished `Run` holds (`Scenario.cost(values) -> Cost`). A run beyond the limits
is refused *before* it starts with a `BudgetExceeded` (a ParameterError): the message names the
parameter that drives the cost and the value that would fit, e.g.

    step=1e-05: this run needs 2e+09 integrator steps, over the limit of 2e+07 (max_steps,
    --max-steps); step ≥ 0.0001 s fits, the other values as given

The front door (`Scenario.simulate`) and the command line (`run`, `record`, `export`) check the
limits by default; `max_steps=None` / `max_memory=None` (`--max-steps none`) lift them. The
defaults are sized from measurement (docs/robustness.md): every scenario's defaults and presets
pass (the largest, earth-long-view, takes 4.7e6 steps and ~10 MB), a run that would take hours
or tens of gigabytes does not.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Mapping

import numpy as np

from ..physics.errors import BudgetExceeded, ParameterError

if TYPE_CHECKING:
    from .base import Run, Scenario

# Measured on the 2-core machine (docs/robustness.md): the compiled free flow takes ~1.6e5 steps/s,
# a torqued body ~5e4, a body pulled by one mass (yoshida4) ~1.5e4, the lunar RK4 ~1.1e5, the spin-orbit
# ensemble ~3.6e6 member-steps/s. 2e7 steps are 2 min of a free body and ~20 min of the slowest kernel;
# the longest preset (earth-long-view, 25,800 years) takes 4.7e6.
MAX_STEPS = 20_000_000
# Arrays a finished run holds. The largest preset keeps ~10 MB; the peak during a run was measured at
# 1.3-3.4x what the run keeps (1.7x for earth-long-view keeping 108 MB), plus at most ~40 MB of work per
# chunk of steps (docs/robustness.md): 1 GB kept is at most ~3.5 GB at the peak.
MAX_MEMORY = 1_000_000_000  # bytes

# one stored state of a rigid body (physics.trajectory.Trajectory): t (1), attitude (4) and L (3)
# as integrated, then the derived ω body (3), L and ω in space (3 + 3), energy (1), |L| (1),
# rotation axis (3) and figure axis (3): 25 float64
STATE_BYTES = 8 * (1 + 4 + 3 + 3 + 3 + 3 + 1 + 1 + 3 + 3)
BODY_BYTES = 8 * 3  # a position per sample of another body
SERIES_BYTES = 8  # a scalar series per sample


@dataclass(frozen=True)
class Cost:
    """What a run would cost, from its parameter values alone.

    - `steps`: integrator steps of every integration the run makes (each member of an ensemble
      counted; adaptive integrators — DOP853, REBOUND's IAS15 — by a measured rate);
    - `samples`: states kept, `len(run.trajectory.t)` (an upper bound for runs that stop early,
      e.g. a Moon that leaves its syzygy);
    - `bytes`: the arrays the finished `Run` holds (trajectory, bodies, series, extras).
    Floats, so that an absurd value (a step of 1e-300 s) is `inf`, not an overflow."""

    steps: float
    samples: float
    bytes: float

    def within(self, max_steps: float | None = MAX_STEPS, max_memory: float | None = MAX_MEMORY) -> bool:
        return not _over(self.steps, max_steps) and not _over(self.bytes, max_memory)

    def to_dict(self) -> dict:
        def num(x):
            return float(x) if math.isfinite(x) else None

        return {"steps": num(self.steps), "samples": num(self.samples), "bytes": num(self.bytes)}


def trajectory_bytes(samples: float, bodies: int = 0, series: int = 0, extra: float = 0.0) -> float:
    """Bytes of a run's arrays: `samples` rigid-body states, `bodies` positions and `series` scalar
    series per sample (new arrays only: a series that is a view of the state costs nothing), plus
    `extra` bytes (grids, ensembles)."""
    return float(samples) * (STATE_BYTES + BODY_BYTES * bodies + SERIES_BYTES * series) + float(extra)


def default_cost(values: Mapping[str, Any]) -> Cost:
    """The estimate for a scenario that states none: a `duration` integrated at `step`, every step
    kept; nothing to count otherwise."""
    from ..physics.integrator import step_count

    try:
        n = step_count(float(values["duration"]), float(values["step"]))
    except (KeyError, TypeError, ValueError):
        return Cost(0.0, 0.0, 0.0)
    return Cost(n, n + 1, trajectory_bytes(n + 1))


def _over(x: float, limit: float | None) -> bool:
    return limit is not None and not (x <= limit)  # NaN is over any limit


def format_bytes(b: float) -> str:
    if not math.isfinite(b):
        return "unbounded memory"
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if b >= size:
            return f"{b / size:.3g} {unit}"
    return f"{b:.0f} bytes"


def format_steps(n: float) -> str:
    if not math.isfinite(n):
        return "unboundedly many"
    return f"{n:.0f}" if n < 1e6 and n == int(n) else f"{n:.3g}"


# ---- which parameter drives the cost, and what would fit -----------------------------------------

def _numeric(p, v) -> bool:
    return p.kind in ("float", "int") and isinstance(v, (int, float)) and not isinstance(v, bool)


def _quantity(cost: Cost, which: str) -> float:
    return cost.steps if which == "steps" else cost.bytes


def _safe_cost(spec: "Scenario", values: dict) -> Cost | None:
    try:
        return spec.cost_of(values)
    except (ParameterError, ArithmeticError, ValueError):
        return None


def _between(a: float, b: float, f: float) -> float:
    """The point a fraction f of the way from a to b (geometric when both have the same sign)."""
    if a > 0 and b > 0 or a < 0 and b < 0:
        return math.copysign(math.exp(math.log(abs(a)) + f * (math.log(abs(b)) - math.log(abs(a)))), a)
    return a + f * (b - a)


def _nice(x: float, toward: float, p, fits: Callable[[float], bool]) -> float:
    """x rounded to 2 significant digits (an integer for an int parameter), on the side of `toward`
    (the default) when the rounder value would not fit; x itself if nothing rounder fits."""
    if p.kind == "int":
        cands = [math.floor(x), math.ceil(x)]
    else:
        if x == 0 or not math.isfinite(x):
            return x
        e = math.floor(math.log10(abs(x))) - 1
        cands = [math.floor(x / 10**e) * 10**e, math.ceil(x / 10**e) * 10**e]
    cands.sort(key=lambda c: abs(c - toward))
    for c in reversed(cands):  # the one farther from the default first: the most the user can keep
        lo_ok = p.minimum is None or c > p.minimum or (c == p.minimum and not p.exclusive_min)
        hi_ok = p.maximum is None or c <= p.maximum
        if lo_ok and hi_ok and fits(c):
            return c
    return x


def _anchors(p) -> list[float]:
    """Values of parameter p to move toward: its default, then the ends of its range."""
    out = []
    for x in (p.default, p.minimum, p.maximum):
        try:
            v = p.parse(x)
        except (ParameterError, TypeError):
            continue
        if _numeric(p, v) and v not in out:
            out.append(v)
    return out


def _what_fits(spec: "Scenario", values: dict, name: str, fits_cost: Callable[[Cost], bool],
               anchor: float) -> float | None:
    """The value of parameter `name` nearest to its current one (the others as given) with which
    the run fits, searched between the current value and `anchor`; None if even the anchor does
    not fit."""
    p = spec.param(name)
    v0, d = float(values[name]), float(anchor)

    def fits(x: float) -> bool:
        c = _safe_cost(spec, {**values, name: int(round(x)) if p.kind == "int" else x})
        return c is not None and fits_cost(c)

    if not fits(d):
        return None
    lo, hi = 0.0, 1.0  # fraction of the way from v0 (does not fit) to d (fits)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if fits(_between(v0, d, mid)):
            hi = mid
        else:
            lo = mid
    x = _between(v0, d, hi)
    return _nice(x, d, p, fits)


def _driver(spec: "Scenario", values: dict, which: str, skip=()) -> tuple[str | None, float | None]:
    """(name, anchor) of the parameter whose own value drives the exceeded quantity most: the one
    whose move to its default lowers it the most, or (when the values are the defaults already)
    to an end of its range; (None, None) if no move lowers it."""
    base = _quantity(spec.cost_of(values), which)
    for ends in (False, True):
        best, best_q, best_anchor = None, base, None
        for p in spec.params:
            v = values.get(p.name)
            if p.name in skip or not _numeric(p, v):
                continue
            for anchor in (_anchors(p) if ends else _anchors(p)[:1]):
                if anchor == v:
                    continue
                c = _safe_cost(spec, {**values, p.name: anchor})
                if c is not None and _quantity(c, which) < best_q:
                    best, best_q, best_anchor = p.name, _quantity(c, which), anchor
        if best is not None:
            return best, best_anchor
    return None, None


def _remedy(spec: "Scenario", values: dict, which: str, fits_cost: Callable[[Cost], bool], max_params: int = 3):
    """What brings the run within the limits, parameter by parameter: [(name, value)] of those
    moved to their default (or an end of their range), then (name, value that fits) of the last
    one, or None. The driver first (`_driver`); when even its default does not fit, it is set to
    its default and the parameter driving what is left is taken next."""
    work, reset = dict(values), []
    for _ in range(max_params):
        name, anchor = _driver(spec, work, which, skip=[n for n, _ in reset])
        if name is None:
            return reset, None
        fit = _what_fits(spec, work, name, fits_cost, anchor)
        if fit is not None:
            return reset, (name, fit)
        work[name] = anchor
        reset.append((name, anchor))
        c = spec.cost_of(work)
        if fits_cost(c):
            return reset, None
        if which == "steps" and fits_cost(Cost(c.steps, 0, 0)):
            which = "bytes"  # the steps fit now: what is left is memory
    return reset, None


# ---- the limits as given: numbers, or text as the command line takes it ("4GB", "none") --------

UNLIMITED = ("none", "inf", "unlimited")
SIZE_UNITS = {"": 1, "b": 1, "k": 1e3, "kb": 1e3, "m": 1e6, "mb": 1e6, "g": 1e9, "gb": 1e9, "t": 1e12, "tb": 1e12,
              "kib": 1024, "mib": 1024**2, "gib": 1024**3, "tib": 1024**4}


def _none_word(name: str) -> str:
    return "none" if name.startswith("--") else "None"


def _limit_number(value, name: str, allowed: str) -> float:
    if isinstance(value, np.ndarray) and value.ndim == 0:  # np.array(4e9)
        value = value.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(name, value, allowed)
    try:
        return float(value)
    except OverflowError:  # 10**400: as unlimited as "1e400"
        return math.inf


def steps_limit(value, name: str = "max_steps") -> float | None:
    """A limit of integrator steps: a whole number ≥ 1 (1e7 or "1e7"), or None / "none" / infinite
    for no limit. `name`: the keyword or flag the message names."""
    from ..physics.params import read_number

    allowed = f"a whole number of integrator steps ≥ 1, or {_none_word(name)}"
    if value is None:
        return None
    if isinstance(value, str):
        if value.strip().lower() in UNLIMITED:
            return None
        try:
            v = read_number(value)
        except ValueError:
            raise ParameterError(name, value, allowed) from None
    else:
        v = _limit_number(value, name, allowed)
    if v == math.inf:
        return None
    if not (math.isfinite(v) and v >= 1 and v == int(v)):  # a run takes at least one step, and whole ones
        raise ParameterError(name, value, allowed)
    return v


def memory_limit(value, name: str = "max_memory") -> float | None:
    """A limit of bytes: a number ≥ 1, or text with an optional unit ("4GB", "500MB", "2GiB"), or
    None / "none" / infinite for no limit. `name`: the keyword or flag the message names."""
    import re

    if value is None:
        return None
    if isinstance(value, str):
        t = value.strip().lower()
        if t in UNLIMITED:
            return None
        m = re.fullmatch(r"(\d+\.?\d*|\.\d+)(e[+-]?\d+)?\s*([a-z]*)", t, re.ASCII)
        if m is None or m.group(3) not in SIZE_UNITS:
            raise ParameterError(name, value, f"bytes with an optional unit (e.g. 4GB, 500MB, 2GiB), or "
                                              f"{_none_word(name)}")
        v = float(m.group(1) + (m.group(2) or "")) * SIZE_UNITS[m.group(3)]
    else:
        v = _limit_number(value, name, f"a number of bytes ≥ 1 or a size such as \"4GB\", or {_none_word(name)}")
    if v == math.inf:
        return None
    if not (math.isfinite(v) and v >= 1):  # "0.5" (bytes) was taken, and shown as a limit of 0 bytes
        raise ParameterError(name, value, f"a size of at least one byte (e.g. 4GB), or {_none_word(name)}")
    return v


def check_budget(spec: "Scenario", values: Mapping[str, Any], max_steps: float | None = MAX_STEPS,
                 max_memory: float | None = MAX_MEMORY) -> Cost:
    """The run's Cost, or BudgetExceeded (a ParameterError) when it needs more integrator steps
    than `max_steps` or keeps more bytes than `max_memory` (None: no limit). The error names the
    parameter that drives the cost, the need, the limit and the value of that parameter that fits."""
    max_steps, max_memory = steps_limit(max_steps), memory_limit(max_memory)
    values = dict(values)
    cost = spec.cost_of(values)
    over_steps, over_mem = _over(cost.steps, max_steps), _over(cost.bytes, max_memory)
    if not (over_steps or over_mem):
        return cost
    which = "steps" if over_steps else "bytes"
    fits_cost = lambda c: c.within(max_steps, max_memory)  # noqa: E731
    reset, last = _remedy(spec, values, which, fits_cost)
    needs = []
    if over_steps:
        needs.append(f"this run needs {format_steps(cost.steps)} integrator steps, over the limit of "
                     f"{format_steps(max_steps)} (max_steps, --max-steps)")
    if over_mem:
        needs.append(("and would keep " if over_steps else "this run would keep ") +
                     f"{format_bytes(cost.bytes)} of arrays, over the limit of {format_bytes(max_memory)} "
                     "(max_memory, --max-memory)")
    text = ", ".join(needs)

    def show(name, v):
        p = spec.param(name)
        unit = f" {p.unit}" if p.unit and p.unit != "1" else ""
        return (f"{int(v)}" if p.kind == "int" else f"{v:.3g}") + unit

    first = reset[0][0] if reset else (last[0] if last else None)
    if first is None:
        raise BudgetExceeded("parameters", "these values", text + "; shorter runs or coarser steps fit",
                             cost=cost, limit_steps=max_steps, limit_bytes=max_memory)
    parts = [f"{n} = {show(n, v)}" for n, v in reset]
    if last is not None:
        name, fit = last
        rel = "≤" if fit < float(values[name]) else "≥"
        hint = (("with " + " and ".join(parts) + ", ") if parts else "") + \
            f"{name} {rel} {show(name, fit)} fits" + ("" if parts else ", the other values as given")
    elif fits_cost(spec.cost_of({**values, **dict(reset)})):
        hint = "with " + " and ".join(parts) + " it fits"
    else:
        hint = "even with " + " and ".join(parts) + " it does not fit: raise the limit"
    raise BudgetExceeded(first, values[first], f"{text}; {hint}", cost=cost, limit_steps=max_steps,
                         limit_bytes=max_memory, fit=last, reset=dict(reset))


# ---- what a finished run holds (for tests and reports) -------------------------------------------

def held_bytes(run: "Run") -> int:
    """Bytes of the numpy arrays a finished Run holds: its trajectory (with the derived paths),
    bodies, series, plot series and extras. A view counts as the whole array it keeps alive, each
    array once."""
    seen: dict[int, int] = {}

    def add(a):
        if isinstance(a, np.ndarray):
            b = a
            while isinstance(b.base, np.ndarray):
                b = b.base
            seen[id(b)] = b.nbytes
        elif isinstance(a, Mapping):
            for v in a.values():
                add(v)
        elif isinstance(a, (list, tuple)):
            for v in a:
                add(v)

    if run.trajectory is not None:
        add(list(vars(run.trajectory).values()))
    add(run.plot_series)
    add(run.extras)
    return int(sum(seen.values()))
