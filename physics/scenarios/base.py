"""What a scenario is: the unit users pick (design.md).

A scenario carries its parameter spec (names, units, ranges, defaults, help), the § it
illustrates, a simulate function returning one `Result` (a Trajectory plus metrics), and the
side-by-side comparison of Euler's value, the simulated value and the modern one.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..params import Param, ParameterError, resolve
from ..trajectory import Trajectory


@dataclass(frozen=True)
class Comparison:
    """One "Euler says / simulated / modern" row."""

    label: str
    euler: float | None
    simulated: float | None
    modern: float | None = None
    unit: str = ""
    note: str = ""


@dataclass
class Result:
    scenario: str
    params: dict[str, Any]
    trajectory: Trajectory | None
    metrics: dict[str, float]
    comparisons: list[Comparison] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    # key quantities over time for the live plot: name → (N,) on trajectory.t
    plot_series: dict[str, np.ndarray] = field(default_factory=dict)
    # data for drawing that is not a time series (e.g. a zero-velocity grid): name → anything
    extras: dict[str, Any] = field(default_factory=dict)
    # "ok", or "diverged": non-finite values appeared at some time and only the finite part before
    # it is kept (set by `guard_result`, which every Scenario.simulate_fn goes through)
    status: str = "ok"
    warnings: list[str] = field(default_factory=list)

    @property
    def diverged(self) -> bool:
        return self.status == "diverged"

    def to_json(self, spec: "Scenario") -> dict:
        out = {
            "scenario": self.scenario,
            "params": {
                p.name: {"value": _jsonable(self.params[p.name]), "unit": p.unit} for p in spec.params
            },
            "metrics": {k: _jsonable(v) for k, v in self.metrics.items()},
            "comparisons": [
                {
                    "label": c.label,
                    "euler": _jsonable(c.euler),
                    "simulated": _jsonable(c.simulated),
                    "modern": _jsonable(c.modern),
                    "unit": c.unit,
                    "note": c.note,
                }
                for c in self.comparisons
            ],
            "notes": list(self.notes),
            "status": self.status,
            "warnings": list(self.warnings),
        }
        if self.trajectory is not None and spec.kind == "rotation":
            out["final_state"] = self.trajectory.final_state()
        return out


def _jsonable(v):
    if v is None:
        return None
    if isinstance(v, (tuple, list, np.ndarray)):
        return [_jsonable(x) for x in v]
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return v if math.isfinite(v) else None  # JSON has no NaN/inf
    return v


DIVERGENCE_LIMIT = 1e100  # |x| beyond this in a trajectory is an overflow in the making, not physics


class Diverged(ParameterError):
    """The run has no finite sample at all: these parameter values cannot be simulated."""


def _first_bad(a) -> int | None:
    """Index of the first sample (axis 0) holding a non-finite or absurdly large value."""
    a = np.asarray(a)
    if a.ndim == 0 or a.size == 0 or not np.issubdtype(a.dtype, np.number):
        return None
    flat = a.reshape(len(a), -1)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(flat) | (np.abs(flat) > DIVERGENCE_LIMIT)
    rows = np.flatnonzero(bad.any(axis=1))
    return int(rows[0]) if rows.size else None


def guard_result(result):
    """Divergence check applied centrally to every scenario's result (issue 7, faults).

    A run in which NaN, ±inf or values beyond DIVERGENCE_LIMIT appear (a step too large, a body
    thrown out, an overflow) is not drawn as garbage: the trajectory and the plot series are cut
    just before the first bad sample, `status` becomes "diverged", and a warning "diverged at
    t=..." goes into `warnings` and `notes` (the app shows the notes beside the scene; the JSON
    carries status and warnings). With no finite sample at all, `Diverged` (a ParameterError)
    is raised: the CLI exits 2 with one line, the app keeps the last good state.
    """
    import dataclasses

    tr = getattr(result, "trajectory", None)
    if not isinstance(result, Result) or tr is None:
        return result
    n = len(tr.t)
    per_sample = {"t": tr.t, "attitude": tr.quat_wxyz, "angular momentum": tr.L_body, "ω": tr.omega_body}
    per_sample.update({f"position of {k}": v for k, v in tr.bodies.items()})
    per_sample.update({f"series {k}": v for k, v in tr.series.items()})
    per_sample.update({f"plot {k}": v for k, v in result.plot_series.items()})
    first: dict[str, int] = {}
    for name, arr in per_sample.items():
        arr = np.asarray(arr)
        if arr.ndim >= 1 and len(arr) == n:
            k = _first_bad(arr)
            if k is not None:
                first[name] = k
    if not first:
        return result
    k = min(first.values())
    what = ", ".join(name for name, i in first.items() if i == k)
    t_bad = tr.t[k] if np.isfinite(tr.t[k]) else (tr.t[k - 1] if k > 0 else float("nan"))
    unit = tr.time_unit
    if k == 0:
        raise Diverged("parameters", "these values",
                       f"diverged at the start (non-finite {what}); try a smaller step or less extreme values")

    def cut(d):
        return {key: (np.asarray(v)[:k] if np.ndim(v) >= 1 and len(v) == n else v) for key, v in d.items()}

    result.trajectory = dataclasses.replace(
        tr, t=tr.t[:k], quat_wxyz=tr.quat_wxyz[:k], L_body=tr.L_body[:k], bodies=cut(tr.bodies), series=cut(tr.series))
    result.plot_series = cut(result.plot_series)
    msg = (f"diverged at t={t_bad:.6g} {unit}: non-finite or overflowing {what}; showing the finite part "
           f"up to t={tr.t[k - 1]:.6g} {unit} ({k} of {n} samples)")
    result.status = "diverged"
    result.warnings.append(msg)
    result.notes.append(msg)
    return result


def _rename_error(e: ParameterError, params, values) -> ParameterError:
    """A ParameterError about a derived quantity (e.g. the integrator's `step`, computed from
    steps_per_turn) is re-worded to name the scenario's own parameter that sets it, with its
    allowed range (found by tests/test_fuzz.py: pole-near-axis said "step=157080: ...")."""
    names = [p.name for p in params]
    if e.name in names or e.name in ("parameters", "scenario", "preset"):
        return e
    stem = e.name.split("_")[0]
    related = [p for p in params if p.name.startswith(stem) or stem in p.name]
    if len(related) == 1:
        p = related[0]
        return ParameterError(p.name, values.get(p.name) if isinstance(values, dict) else None,
                              f"gives {e}; {p.allowed()}")
    return ParameterError("parameters", "these values", str(e))


def _guarded(fn, params=()):
    if getattr(fn, "__theoria_guarded__", False):
        return fn
    import functools

    @functools.wraps(fn)
    def simulate_fn(values, *args, **kwargs):
        try:
            result = fn(values, *args, **kwargs)
        except ParameterError as e:
            raise _rename_error(e, params, values) from None
        return guard_result(result)

    simulate_fn.__theoria_guarded__ = True
    return simulate_fn


@dataclass(frozen=True)
class Scenario:
    name: str
    title: str
    section: str  # e.g. "§805, §808"
    group: str  # "ch. 15", "ch. 16", "three bodies"
    summary: str  # what to look for, one paragraph
    params: tuple[Param, ...]
    simulate_fn: Callable[..., Result]
    euler_formula: str = ""  # shown beside the scene: plain Unicode text (no TeX: neither viser's
    # markdown nor rerun's text panel renders math)
    kind: str = "rotation"  # "rotation" scenes draw a body; "orbit" scenes draw bodies only
    check: Callable[[dict[str, Any]], None] | None = None  # cross-parameter validation
    # named starting points, each named after what it shows ("Brick: the flip"): (name, {param: value});
    # the values are partial (the rest keep their defaults) and go through `resolve` like any input
    presets: tuple[tuple[str, dict[str, Any]], ...] = ()

    def __post_init__(self):
        # every caller (CLI, app, record, export, tests) gets the central divergence check
        object.__setattr__(self, "simulate_fn", _guarded(self.simulate_fn, self.params))

    def resolve(self, given: dict[str, Any] | None = None) -> dict[str, Any]:
        values = resolve(self.params, given)
        if self.check is not None:
            self.check(values)
        return values

    def simulate(self, given: dict[str, Any] | None = None, progress=None) -> Result:
        values = self.resolve(given)
        return self.simulate_fn(values, progress=progress)

    def preset(self, name: str) -> dict[str, Any]:
        """The full, validated values of preset `name` (defaults for the parameters it leaves out)."""
        for n, given in self.presets:
            if n == name:
                return self.resolve(given)
        raise ParameterError("preset", name, "one of " + ", ".join(n for n, _ in self.presets))

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)


REGISTRY: dict[str, Scenario] = {}


def register(s: Scenario) -> Scenario:
    REGISTRY[s.name] = s
    return s


def get(name: str) -> Scenario:
    from . import _load_all  # noqa: F401  (registers every scenario module)

    if name not in REGISTRY:
        raise ParameterError("scenario", name, "one of " + ", ".join(sorted(REGISTRY)))
    return REGISTRY[name]


def all_scenarios() -> list[Scenario]:
    from . import _load_all  # noqa: F401

    return list(REGISTRY.values())
