"""What a scenario is (design.md): the unit users pick, and the Run it gives.

A `Scenario` carries its parameters (names, units, ranges, defaults, help), named presets, the §
it illustrates, the text a class reads (title, what to look for, Euler's formula), its camera and
what it draws, and a simulate function. `Scenario.simulate(**values)` validates the values once
(`theoria.ParameterError` names the parameter, the value and the allowed range) and returns a
`Run`: the one object every consumer reads (the CLI's --json, the app, the recording, the HTML
replay, a notebook).
"""
from __future__ import annotations

import dataclasses
import functools
import importlib
import json
import math
import pkgutil
import re
import sys
import types
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np

from ..physics.errors import Diverged, ParameterError, did_you_mean, show_value
from ..physics.params import POSITIVE, Param, pretty_unit, resolve
from ..physics.trajectory import Trajectory
from .budget import MAX_MEMORY, MAX_STEPS, Cost, check_budget, default_cost
from .drawing import Camera, Drawing, Option, View, declutter_labels, standard
from .units import metric_unit as unit_of_metric, rotation_units, unit_in_label


@dataclass(frozen=True)
class Comparison:
    """One "Euler says / simulated / modern" row: in a run's table, and (with `id`, `section`,
    `rel_error`, `tolerance` and `passed`) as a row of `theoria check`."""

    label: str
    euler: float | None
    simulated: float | None
    modern: float | None = None
    unit: str = ""
    note: str = ""
    # a `theoria check` row also says how far the simulation is from its reference and what it must meet
    id: str | None = None
    section: str = ""
    rel_error: float | None = None
    tolerance: float | None = None
    passed: bool | None = None
    # the modern value is an observation of a real body ("the real Earth": IAU 2006's precession),
    # compared only while the run is that body (`Scenario.real_params` at their defaults)
    observed: str = ""
    # why the run gives no simulated value here ("fewer than two flips in 30 s: …"), said beside the
    # row: in the notes alone, a folded section, the row read "no simulated value" with no reason
    missing: str = ""

    @property
    def title(self) -> str:  # a check row's title is its label
        return self.label

    def to_dict(self) -> dict:
        out = {"label": self.label, "euler": jsonable(self.euler), "simulated": jsonable(self.simulated),
               "modern": jsonable(self.modern), "unit": self.unit, "note": self.note}
        if self.missing:
            out["missing"] = self.missing
        if self.id is not None:
            out = {"id": self.id, "title": self.label, "section": self.section, **out,
                   "rel_error": jsonable(self.rel_error), "tolerance": self.tolerance, "pass": bool(self.passed)}
            del out["label"]
        return out


def jsonable(v):
    """Plain JSON values: numpy scalars and arrays as numbers and lists, NaN and ±inf as null."""
    if v is None:
        return None
    if isinstance(v, (tuple, list, np.ndarray)):
        return [jsonable(x) for x in v]
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return v if math.isfinite(v) else None
    return v


@dataclass(eq=False)  # one run is itself (its arrays have no single truth value to compare)
class Run:
    """One simulation: parameters, trajectory, metrics, the Euler / simulated / modern table and
    the warnings. Every consumer (CLI, app, recorder, HTML replay, a notebook) reads this object.

    - `metrics`: name → number, exactly the CLI's `--json` "metrics"; `metric_units` gives each
      one's unit (in the name where it is a common one: `polhode_period_s`).
    - `comparisons`: the Euler / simulated / modern rows.
    - `warnings`: one sentence per result outside the validity of a formula or of the numerics
      (empty when the run is inside every limit; docs/validity.md lists them); `status` is "ok"
      or says what went wrong ("diverged": only the finite part before the trouble is kept;
      "tumbles": no libration, so no libration values are reported).
    - `trajectory`: times, attitudes (w, x, y, z), ω and L on the body axes, positions of other
      bodies, and the derived paths (numpy arrays).
    """

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
    status: str = "ok"
    warnings: list[str] = field(default_factory=list)
    spec: "Scenario | None" = field(default=None, repr=False, compare=False)  # set by Scenario.simulate

    def __repr__(self) -> str:
        """One line a notebook can show: the scenario, its status, the size of the trajectory and
        how many metrics, rows and warnings there are (the arrays themselves are in the fields)."""
        def count(k: int, what: str) -> str:
            return f"{k:,} {what}{'' if k == 1 else 's'}"

        parts = ["no trajectory" if self.trajectory is None else count(len(self.trajectory.t), "state"),
                 count(len(self.metrics), "metric"), count(len(self.comparisons), "comparison")]
        if self.warnings:
            parts.append(count(len(self.warnings), "warning"))
        return f"<theoria run of {self.scenario!r}, {self.status}: {', '.join(parts)}>"

    @property
    def metric_units(self) -> dict[str, str | None]:
        """name → the unit of each metric ("" for a pure number), as `Param.unit` writes units."""
        spec = self._spec()
        return {k: spec.metric_unit(k) for k in self.metrics}

    @property
    def diverged(self) -> bool:
        return self.status == "diverged"

    def _spec(self) -> "Scenario":
        return self.spec if self.spec is not None else get(self.scenario)

    def to_dict(self) -> dict:
        """Scenario, params (with units), metrics, comparisons, notes, status, warnings, and for
        rotation scenarios the final state, as plain JSON values (NaN and ±inf as None)."""
        spec = self._spec()
        out = {
            "scenario": self.scenario,
            "params": {p.name: {"value": jsonable(self.params[p.name]), "unit": p.unit} for p in spec.params},
            "metrics": {k: jsonable(v) for k, v in self.metrics.items()},
            "metric_units": self.metric_units,
            "comparisons": [c.to_dict() for c in self.comparisons],
            "notes": list(self.notes),
            "status": self.status,
            "warnings": list(self.warnings),
        }
        if self.trajectory is not None and spec.kind == "rotation":
            out["final_state"] = self.trajectory.final_state()
        return out

    def to_json(self, indent: int | None = 2) -> str:
        """`to_dict()` as strict JSON text: what `theoria run NAME --json` prints."""
        return json.dumps(self.to_dict(), indent=indent, allow_nan=False)

    def to_dataframe(self):
        """One row per sample: t, the attitude, ω and L on the body axes, the other bodies'
        positions and every per-sample series of the run (a pandas DataFrame).
        `df.attrs["units"]` holds the unit of each column that has one (`column_units`)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("Run.to_dataframe needs pandas: pip install pandas "
                              "(or theoria-motus[pandas])") from None
        df = pd.DataFrame(self.columns())
        df.attrs["units"] = self.column_units()
        return df

    def column_units(self) -> dict[str, str]:
        """The unit of each column of `columns()` that has one, as parameters write units ("1" for
        a pure number): t in the trajectory's time unit, the quaternion "1", ω, L and the kinetic
        energy in the time unit and the moments' unit of the run ("rad/s", "kg m^2/s", "J" for a
        body given in SI; "n", "C n", "C n^2" where time is counted in orbits' radians and the
        moments as fractions of C), and a series whose name ends in a unit (`obliquity_deg`,
        "obliquity of date (deg)")."""
        tr = self.trajectory
        if tr is None:
            return {}
        units = {f"t_{tr.time_unit}": tr.time_unit}
        if self._spec().kind == "rotation":
            units.update({f"q_{c}": "1" for c in "wxyz"})
            if of := rotation_units(tr.time_unit, tr.moment_unit):
                units.update({f"omega_body_{c}": of["omega"] for c in "xyz"})
                units.update({f"L_body_{c}": of["L"] for c in "xyz"})
                units["energy"] = of["energy"]
        declared = self._spec().series_units
        for name in self.columns():
            unit = unit_in_label(name) or unit_of_metric(name, declared)
            if name not in units and unit is not None:
                units[name] = unit
        return units

    def columns(self) -> dict[str, np.ndarray]:
        """The per-sample columns of `to_dataframe` as numpy arrays (name → (N,)); their units are
        `column_units()` (t's is in its name)."""
        tr = self.trajectory
        if tr is None:
            return {}
        n = len(tr.t)
        cols: dict[str, np.ndarray] = {f"t_{tr.time_unit}": tr.t}
        if self._spec().kind == "rotation":
            for k, c in enumerate("wxyz"):
                cols[f"q_{c}"] = tr.quat_wxyz[:, k]
            for k, c in enumerate("xyz"):
                cols[f"omega_body_{c}"] = tr.omega_body[:, k]
            for k, c in enumerate("xyz"):
                cols[f"L_body_{c}"] = tr.L_body[:, k]
            cols["energy"] = tr.energy
        for name, pos in tr.bodies.items():
            pos = np.asarray(pos, float)
            if pos.shape == (n, 3):
                for k, c in enumerate("xyz"):
                    cols[f"{name}_{c}"] = pos[:, k]
        for src in (tr.series, self.plot_series):
            for name, v in src.items():
                v = np.asarray(v)
                if v.shape == (n,) and name not in cols and not (src is self.plot_series and any(
                        c is v or (c.dtype == v.dtype and np.array_equal(c, v)) for c in cols.values())):
                    cols[name] = v  # (a plot's curve that is a column already, ω on an axis, is not repeated)
        return cols

    # ---- the app's writers: the Run hands itself over (physics stays free of viser and rerun) ----
    def record(self, path, view: View | None = None, force: bool = True) -> dict:
        """Write a rerun recording (.rrd) of this run: the app's drawing, camera and text, whole or
        not at all. `force=False` refuses to replace an existing file."""
        from ..app.record import record_run

        return record_run(self, _out_path(path, ".rrd", force), view=_view(view))

    def export_html(self, path, frames: int = 240, fps: float = 30.0, view: View | None = None,
                    force: bool = True) -> dict:
        """Write a standalone HTML replay of this run (plays from file://, no network), whole or
        not at all: `frames` pictures (at most the run's) played at `fps`. `force=False` refuses
        to replace an existing file."""
        from ..app.export_html import export_run

        if isinstance(frames, bool) or not isinstance(frames, (int, np.integer)) or not 2 <= frames <= 100_000:
            raise ParameterError("frames", frames, "a whole number from 2 to 100000")
        if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)) or not 0 < fps <= 240:
            raise ParameterError("fps", fps, "frames a second, above 0 and at most 240")
        return export_run(self, _out_path(path, (".html", ".htm"), force), frames=int(frames), fps=float(fps),
                          view=_view(view))

    def show(self, port: int = 8080, host: str = "127.0.0.1", block: bool | None = None):
        """Serve this run in the app (http://127.0.0.1:8080 by default) with its parameters. Blocks
        until Ctrl-C in a script (SIGTERM ends the script: exit status 143); returns at once in an
        interactive session (the server runs on in the background: call `.stop()` on what this
        returns)."""
        from ..app.server import show_run

        return show_run(self, port=port, host=host, block=block)


def _out_path(path, suffixes: str | tuple[str, ...], force: bool):
    """A file `Run.record` / `Run.export_html` may write (app/files.py `check_out`), named `path`
    with one of `suffixes` (those `theoria record` / `export` take)."""
    from ..app.files import check_out

    suffixes = (suffixes,) if isinstance(suffixes, str) else tuple(suffixes)
    if not isinstance(path, (str, bytes)) and not hasattr(path, "__fspath__"):
        raise ParameterError("path", path, f"a file name ending in {' or '.join(suffixes)}")
    return check_out(path, suffixes, force=bool(force), what="path")


def _view(view):
    if view is not None and not isinstance(view, View):
        raise ParameterError("view", view, "None or a theoria View (the drawing's options)")
    return view


DIVERGENCE_LIMIT = 1e100  # |x| beyond this in a trajectory is an overflow in the making, not physics


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
    """The divergence check every scenario's run goes through.

    A run in which NaN, ±inf or values beyond DIVERGENCE_LIMIT appear (a step too large, a body
    thrown out, an overflow) is not drawn as garbage: the trajectory and the plot series are cut
    just before the first bad sample, `status` becomes "diverged", and a warning "diverged at
    t=..." goes into `warnings` and `notes`. With no finite sample at all, `Diverged` (a
    ParameterError) is raised: the CLI exits 2 with one line, the app keeps the last good state.
    """
    if isinstance(result, Run):  # every metric a Python float (a script's type checks, json, a sweep's table)
        result.metrics = {k: float(v) if isinstance(v, (np.floating, np.integer)) else v
                          for k, v in result.metrics.items()}
    tr = getattr(result, "trajectory", None)
    if not isinstance(result, Run) or tr is None:
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
    allowed range (pole-near-axis once said "step=157080: ...", a name the user never typed)."""
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


@dataclass(frozen=True)
class Batch:
    """A scenario's batched path for sweeps: many runs advanced together (one shared orbit, a
    compiled kernel over the batch) instead of one after another.

    - `fn(values, swept)`: `values` the fixed parameters (validated), `swept` name → (n,) arrays of
      the swept ones; returns name → (n,) metric arrays (the same names and values, to round-off,
      as `simulate` gives for each point), optionally "_status" (codes of app.sweep.STATUS) and
      "_messages" (index → sentence) for points it refuses.
    - `sweepable`: the parameters that may vary across one batch (a sweep over any other one maps
      single runs);
    - `metrics`: the metrics `fn` computes (a sweep asking for others maps single runs);
    - `chunk`: runs per chunk that suit it (few where each point has costly set-up of its own, many
      where the kernel is all the work)."""

    fn: Callable[[dict[str, Any], dict[str, np.ndarray]], dict[str, np.ndarray]]
    sweepable: tuple[str, ...]
    metrics: tuple[str, ...]
    chunk: int = 256


RESERVED = ("progress", "preset", "max_steps", "max_memory")  # keywords of Scenario.simulate: no parameter may be called so


def in_python_words(e: ParameterError) -> ParameterError:
    """A ParameterError of the command line's (`--out=…`, `--set=k=v`, `--resume=--force`) as a
    Python caller reads it: the keywords for the flags (`out=…`, `k=v`, `resume=True, force=True`)."""
    name, value, allowed = e.name, e.value, str(e.allowed)
    if not (isinstance(name, str) and name.startswith("--")):
        return e
    standard = e.args[:1] == (f"{show_value(name)}={show_value(value)}: {allowed}",)
    if name == "--set" and isinstance(value, str) and "=" in value:  # a scenario parameter
        name, value = value.split("=", 1)
    else:
        name = name[2:].replace("-", "_")
        if isinstance(value, str) and value.startswith("--"):  # two flags that cannot go together
            name, value = f"{name}=True, {value[2:].replace('-', '_')}", True
    allowed = re.sub(r"--([a-z][a-z-]*)", lambda m: m[1].replace("-", "_"), allowed)
    out = type(e).__new__(type(e))  # the same kind (a SweepBusy stays one), its other fields kept
    out.__dict__.update(e.__dict__)
    out.name, out.value, out.allowed = name, value, allowed
    # a message of its own (a SweepBusy's: the other sweep's PID, what to do) is kept
    out.args = (f"{show_value(name)}={show_value(value)}: {allowed}",) if standard else e.args
    return out


@dataclass(frozen=True)
class Scenario:
    """A scenario: what a user picks in the app, `theoria run NAME` runs and `theoria.scenario(NAME)`
    returns. Everything about it is declared once, here, in its own module."""

    name: str
    title: str
    section: str  # e.g. "§805, §808"
    group: str  # "ch. 15", "ch. 16", "three bodies"
    summary: str  # what to look for, one paragraph
    params: tuple[Param, ...]
    simulate_fn: Callable[..., Run]
    euler_formula: str = ""  # plain Unicode text (no TeX: neither viser's markdown nor rerun's text panel renders math)
    kind: str = "rotation"  # "rotation" scenes draw a body; "orbit" scenes draw bodies only
    check: Callable[[dict[str, Any]], None] | None = None  # cross-parameter validation
    # named starting points, each named after what it shows ("Brick: the flip"): name → {param: value};
    # partial (the rest keep their defaults), validated like any input. Given as a dict or as pairs.
    presets: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    camera: Camera | None = None  # the curated view; None: a default for the kind of scene
    # overlays switched on/off against the default for the scene's group (drawings that say nothing here)
    overlays: Mapping[str, bool] = field(default_factory=dict)
    # what it draws: draw(run, spec, view) -> Drawing (default: Poinsot's construction and the other
    # bodies, `drawing.standard`), and the checkboxes of its own that change the drawing
    draw: Callable[..., Drawing] | None = None
    options: Mapping[str, Option] = field(default_factory=dict)
    # values that make a quick, coarser run of the same scene (shorter or with a larger step): the
    # first picture while the full run computes, and the tests' runs; {} when the defaults are quick
    preview: Mapping[str, Any] = field(default_factory=dict)
    batch: Batch | None = None  # the batched path of sweeps (many runs on one compiled kernel), if any
    # what a run costs before it runs: validated values -> Cost(steps, samples, bytes) (scenarios.budget);
    # None: a `duration` integrated at `step`, every step kept
    cost_fn: Callable[[dict[str, Any]], Cost] | None = None
    # chaotic: its numbers hang on the last bit of every step, and pure Python (numba's JIT off)
    # rounds differently from the compiled code (Hyperion's preview: Lyapunov probe 0.47 against
    # 0.96 per orbit). Such a scenario is computed only by the compiled code, so that the app, the
    # command line and a sweep show the same numbers for the same values.
    chaotic: bool = False
    # the units of the metrics whose names do not end in one (scenarios.units): name or whole-name
    # pattern → unit as `Param.unit` writes it; "" for a pure number (a ratio, a cosine, a count)
    metric_units: Mapping[str, str] = field(default_factory=dict)
    # the same for the per-sample columns of `Run.to_dataframe` that do not say theirs: the other
    # bodies' positions ("attractor_[xyz]": "a", the orbit's semi-major axis) and the series
    series_units: Mapping[str, str] = field(default_factory=dict)
    # the parameters whose defaults make the run a real body (the Earth's H and obliquity): away
    # from them, a comparison's observed modern value (`Comparison.observed`) is not compared
    real_params: tuple[str, ...] = ()

    def __post_init__(self):
        for p in self.params:
            if p.name in RESERVED:
                raise ValueError(f"scenario {self.name}: a parameter may not be called {p.name!r}")
            for k, allowed in (pair for alt in p.applies for pair in alt):
                if allowed == (POSITIVE,) and any(q.name == k and q.kind in ("float", "int") for q in self.params):
                    continue
                choice = next((q for q in self.params if q.name == k and q.kind == "choice"), None)
                if choice is None or not set(map(str, allowed)) <= set(map(str, choice.choices)):
                    raise ValueError(f"scenario {self.name}: {p.name} applies with {k} = {allowed}, "
                                     f"which is not a choice parameter's choices")
        presets = self.presets.items() if isinstance(self.presets, Mapping) else self.presets
        object.__setattr__(self, "presets", types.MappingProxyType({n: types.MappingProxyType(dict(v)) for n, v in presets}))
        object.__setattr__(self, "overlays", types.MappingProxyType(dict(self.overlays)))
        object.__setattr__(self, "options", types.MappingProxyType(dict(self.options)))
        object.__setattr__(self, "preview", types.MappingProxyType(dict(self.preview)))
        object.__setattr__(self, "simulate_fn", self._guarded(self.simulate_fn))

    def __reduce__(self):
        # a scenario travels by its name (a pickled run, a joblib or Dask task, copy.copy): the one
        # registered under it is the same code and the same data
        return (get, (self.name,))

    def _guarded(self, fn):
        """Every caller (front door, CLI, app, record, export, checks, tests) gets the same contract:
        derived-quantity errors reworded to name this scenario's parameters, the divergence check,
        and the run tied to its scenario."""
        if getattr(fn, "__theoria_guarded__", False):
            return fn

        @functools.wraps(fn)
        def simulate_fn(values, *args, **kwargs):
            try:
                run = fn(values, *args, **kwargs)
            except ParameterError as e:
                raise _rename_error(e, self.params, values) from None
            run = guard_result(run)
            if isinstance(run, Run):
                run.spec = self
                self._observed_only_for_the_real_body(run, values)
            return run

        simulate_fn.__theoria_guarded__ = True
        return simulate_fn

    def _observed_only_for_the_real_body(self, run: Run, values) -> None:
        """With H = 10⁻⁹ the Earth's precession is nearly nil, and IAU 2006's 50.4″/yr for the real
        Earth beside it read "differ by 100 %": an observed modern value is compared only while
        the run is that body; otherwise it goes into the note, the modern column left empty."""
        changed = [p for p in self.params if p.name in self.real_params and p.name in values
                   and values[p.name] != p.parse(p.default)]
        if not changed:
            return
        which = " and ".join(p.title() for p in changed)

        def apart(c: Comparison) -> Comparison:
            if not c.observed or c.modern is None:
                return c
            unit = pretty_unit(c.unit)
            seen = f"{c.modern:.6g}" + ("" if not unit else unit if unit[0] in "°″′" else f" {unit}")
            return dataclasses.replace(c, modern=None, note=(f"{c.note}; " if c.note else "") + (
                f"modern: {c.observed}'s {seen}, not compared: this run's {which} "
                f"{'is' if len(changed) == 1 else 'are'} not {c.observed}'s"))

        run.comparisons = [apart(c) for c in run.comparisons]

    # ---- the front door ------------------------------------------------------------------------
    @property
    def parameters(self) -> Mapping[str, Param]:
        """name → Param (unit, allowed range, default, help), in the order the app shows them."""
        return types.MappingProxyType({p.name: p for p in self.params})

    @property
    def defaults(self) -> dict[str, Any]:
        return self.resolve(None)

    def simulate(self, given: Mapping[str, Any] | None = None, /, *, preset: str | None = None,
                 progress: Callable[[float], None] | None = None, max_steps: float | None = MAX_STEPS,
                 max_memory: float | None = MAX_MEMORY, **values) -> Run:
        """Run the scenario. Values come from the defaults, then `preset` (its name), then `given`
        (a mapping, e.g. of strings from a command line) and the keywords; every value is checked
        (`ParameterError` names the parameter, the value and the allowed range).

        A run that would need more than `max_steps` integrator steps or keep more than
        `max_memory` bytes is refused before it starts (`BudgetExceeded`, a ParameterError naming
        the parameter that drives the cost and the value that fits); None lifts a limit."""
        merged = self._merge(given, preset, values)
        resolved = self.resolve(merged)
        check_budget(self, resolved, max_steps, max_memory)
        run = self.simulate_fn(resolved, progress=progress)
        run.warnings.extend(self.unused(resolved, merged))
        return run

    def unused(self, values: Mapping[str, Any], given) -> list[str]:
        """One sentence for each parameter named in `given` that these values leave unused
        (collinear's turns when the line collapses): a value typed for nothing is said, not lost."""
        return [f"{p.name} = {show_value(values[p.name])} is not used here: it applies only {p.applies_text()}"
                for p in self.params if p.name in given and not p.applies_to(values)]

    def metric_unit(self, key: str) -> str | None:
        """The unit of metric `key` ("" for a pure number; None when neither its name nor the
        scenario says, which the tests do not allow for any metric a scenario returns)."""
        return unit_of_metric(key, self.metric_units)

    def cost(self, given: Mapping[str, Any] | None = None, /, *, preset: str | None = None, **values) -> Cost:
        """What `simulate` with the same values would cost, without running it: integrator steps,
        samples kept and bytes held (`scenarios.budget.Cost`)."""
        return self.cost_of(self.resolve(self._merge(given, preset, values)))

    def cost_of(self, values: dict[str, Any]) -> Cost:
        """The Cost of a run with these validated values (`resolve`); unbounded where counting it
        overflows (a tiny sampling interval over a long run)."""
        try:
            return (self.cost_fn or default_cost)(values)
        except OverflowError:
            return Cost(math.inf, math.inf, math.inf)

    def check_budget(self, values: dict[str, Any], max_steps: float | None = MAX_STEPS,
                     max_memory: float | None = MAX_MEMORY) -> Cost:
        """The Cost of a run with these validated values, or `BudgetExceeded` before it starts."""
        return check_budget(self, values, max_steps, max_memory)

    def _merge(self, given, preset, values) -> dict[str, Any]:
        if given is not None and not isinstance(given, Mapping):
            raise ParameterError("given", given, "a mapping of parameter names to values (or keywords: "
                                 f"simulate({self.params[0].name}=...))" if self.params else "a mapping")
        merged: dict[str, Any] = {}
        if preset is not None:
            merged.update(self.presets.get(self.preset_name(preset), {}))
        merged.update(given or {})
        merged.update(values)
        return merged

    def sweep(self, grid=None, random=None, samples=None, out=None, cluster=None, resume=False, metrics=None,
              preset=None, seed=0, chunk=None, workers=None, progress=False, force=False,
              max_steps: float | None = MAX_STEPS, max_memory: float | None = MAX_MEMORY, **values):
        """Many runs on Dask (a local cluster on this machine's cores, or `cluster="tcp://…"`),
        written chunk by chunk to `out` (.zarr: an xarray Dataset, one dimension per swept
        parameter; .parquet: a flat table) and returned opened.

        grid: {name: (start, stop, count)} or {name: "start:stop:count"} or {name: [values]};
        random: {name: (lo, hi)} with `samples` draws (a `sample` dimension, `seed`); the other
        parameters from `preset` and the keywords. `resume=True` keeps every finished chunk of
        `out`. `metrics`: the metric names to keep (default all). An `out` that holds an earlier
        sweep needs `resume=True` or `force=True` (replace it). Each run is held to `max_steps` and
        `max_memory` as `simulate` is (None lifts a limit); one over them is not run, its status
        "refused". See docs/sweeps.md."""
        from ..app.sweep import run_sweep

        try:
            summary, result = run_sweep(self, grid=grid, random=random, samples=samples, out=out, cluster=cluster,
                                        resume=resume, metrics=metrics, fixed=values, preset=preset, seed=seed,
                                        chunk=chunk, workers=workers, progress=progress, force=force,
                                        limits={"max_steps": max_steps, "max_memory": max_memory})
        except ParameterError as e:
            raise in_python_words(e) from None
        if result is None:
            raise KeyboardInterrupt(summary.line())
        return result

    def resolve(self, given: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The full, validated values: defaults overridden by `given`."""
        values = resolve(self.params, dict(given or {}))
        if self.check is not None:
            self.check(values)
        return values

    def preset(self, name: str) -> dict[str, Any]:
        """The full, validated values of preset `name` (defaults for the parameters it leaves out)."""
        return self.resolve(self.presets[self.preset_name(name)])

    def preset_name(self, text: str) -> str:
        """The preset called `text`: its exact name, or the one preset whose name contains it (any case)."""
        names = list(self.presets)
        if text in names:
            return text
        hits = [n for n in names if str(text).casefold() in n.casefold()]
        if len(hits) == 1:
            return hits[0]
        allowed = "; ".join(f'"{n}"' for n in names) if names else "none (this scenario has no presets)"
        raise ParameterError("preset", text, ("one of " if names else "") + allowed +
                             (" (more than one matches)" if len(hits) > 1 else ""))

    def drawing(self, run: Run, view: View | None = None) -> Drawing:
        """What `run` draws (the one list the app, the recording and the HTML replay render)."""
        view = view or View()
        d = (self.draw or standard)(run, self, view)
        declutter_labels(d, text_scale=view.text_scale)  # labels turned so that none covers another
        return d

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)

    def __repr__(self) -> str:
        return f"<theoria scenario {self.name!r}: {self.title} ({self.section})>"


REGISTRY: dict[str, Scenario] = {}


def register(s: Scenario) -> Scenario:
    if s.name in REGISTRY and REGISTRY[s.name].simulate_fn.__module__ != s.simulate_fn.__module__:
        raise ValueError(f"two scenarios are called {s.name!r}")
    REGISTRY[s.name] = s
    return s


NOT_SCENARIOS = ("base", "budget", "checks", "drawing")


def load_all() -> None:
    """Import every scenario module of this package (each registers itself): no list to keep."""
    pkg = sys.modules[__package__]
    for m in pkgutil.iter_modules(pkg.__path__):
        if not m.name.startswith("_") and m.name not in NOT_SCENARIOS:
            importlib.import_module(f"{__package__}.{m.name}")


def get(name: str) -> Scenario:
    load_all()
    if isinstance(name, Scenario):  # already one (th.scenario(sc))
        return name
    if isinstance(name, str) and name not in REGISTRY:  # "Middle-Axis-Flip", "middle_axis_flip"
        name = {k.lower(): k for k in REGISTRY}.get("-".join(name.strip().lower().replace("_", " ").split()), name)
    if not isinstance(name, str) or name not in REGISTRY:
        raise ParameterError("scenario", name, "one of " + ", ".join(s.name for s in all_scenarios())
                             + did_you_mean(name, REGISTRY).replace(" (", "; ", 1).rstrip(")"))
    return REGISTRY[name]


GROUP_ORDER = ("ch. 15", "ch. 16", "three bodies")
_ROMAN = {"I": 1, "V": 5, "X": 10, "L": 50, "C": 100}


def _roman(s: str) -> int:
    total = 0
    for a, b in zip(s, s[1:] + " "):
        v = _ROMAN[a]
        total += -v if _ROMAN.get(b, 0) > v else v
    return total


def section_key(section: str) -> tuple:
    """Sort key of a § string: (year of the paper, first §, 1 if the scene goes beyond Euler)."""
    year = re.search(r"\b(1[78]\d\d)\b", section)
    m = re.search(r"§\s*(\d+|[IVXLC]+)", section)
    first = 0
    if m:
        first = int(m.group(1)) if m.group(1).isdigit() else _roman(m.group(1))
    beyond = 1 if "(" in section else 0  # "(modern values)", "(beyond Euler)" after Euler's own
    return (int(year.group(1)) if year else 0, first, beyond)


def all_scenarios() -> list[Scenario]:
    """Every scenario in gallery order: Euler's ch. 15, ch. 16, then the three-body papers, each in
    the order of the § it illustrates."""
    load_all()

    def key(s):
        g = GROUP_ORDER.index(s.group) if s.group in GROUP_ORDER else len(GROUP_ORDER)
        return (g, s.group, section_key(s.section), s.name)

    return sorted(REGISTRY.values(), key=key)
