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
