"""Bad input, everywhere: every parameter of every registered scenario fuzzed
with hypothesis through `Scenario.resolve`, the validation the CLI (`--set key=value`) and the
app (every GUI value goes through `resolve`) share.

1. Validation: NaN, ±inf, huge and negative numbers, integers too large for a float, wrong
   arity, strings, None, nested lists, unknown keys. Either `ParameterError` whose message is ONE
   line naming the parameter (the fuzzed one, or for a cross-parameter check one of the
   scenario's) and its allowed range, or a value set in which every number is finite, inside
   its Param range and of the right kind / arity.
2. Simulation of valid sets (durations and sample counts capped so the file stays fast; the
   physical parameters roam their full ranges, edges included): no exception other than
   ParameterError; nothing non-finite in `Run.to_dict` (strict JSON), in the trajectory
   arrays, or in any number the scene sends to viser (a recording fake scene API).
   A run that diverges must say so (status "diverged" and a "diverged at t=" warning).

The counts of cases are printed at the end (`-s` to see them).

CI runs the same examples every time (hypothesis `derandomize`), so a red CI means a change broke
something rather than a new draw turning up an old edge case. To explore with fresh random draws
(how findings 14–16 of docs/robustness.md were made), run with THEORIA_FUZZ_RANDOM=1.
"""
from __future__ import annotations

import json
import math
import os
from collections import Counter

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from theoria.physics.params import ParameterError

DERANDOMIZE = os.environ.get("THEORIA_FUZZ_RANDOM") != "1"
from theoria.scenarios import all_scenarios

SCENARIOS = sorted(all_scenarios(), key=lambda s: s.name)
NAMES = [s.name for s in SCENARIOS]
# cases marked slow (over ~5 s each with `pytest --durations` on the shared 2-core machine): they
# still run in CI, not in `pytest -m "not slow"`
LONG_VALIDATION = {"collinear"}
LONG_SIMULATION = {"syzygy", "moon", "pole-near-axis", "precession-circular"}
STATS: Counter = Counter()
FOUND: list[str] = []  # runs refused while simulating, or reported diverged (printed at the end)

# ---- 1. validation -------------------------------------------------------------------------

NASTY = st.sampled_from([
    float("nan"), float("inf"), -float("inf"), 1e308, -1e308, 1e-320, -0.0, 10 ** 400, -(10 ** 400),
    "nan", "NaN", "inf", "-inf", "1e400", "-1e400", "", " ", "1,2", "1,2,3", "1,2,3,4", "a,b,c", "nan,1,1",
    "1,inf,1", "0x10", "1_000", "١٢", "1e-400", "\n", "3\n4", "None", "True", None, True, False,
    [], [1.0], [1.0, 2.0], [1.0, 2.0, 3.0, 4.0], [[1.0], 2.0, 3.0], {"a": 1}, (float("nan"), 1.0, 1.0),
])
RAW = st.one_of(
    NASTY,
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(),
    st.text(max_size=12),
    st.lists(st.one_of(st.floats(), st.text(max_size=4), st.integers()), max_size=5),
    st.from_regex(r"-?[0-9]{1,4}(\.[0-9]{0,3})?(e-?[0-9]{1,3})?", fullmatch=True),
)


def in_range(p, draw_float):
    """A value drawn inside p's range (edges included), as the app or CLI would pass it."""
    if p.kind == "choice":
        return st.sampled_from([str(c) for c in p.choices])
    lo = -1e6 if p.minimum is None else float(p.minimum)
    hi = 1e6 if p.maximum is None else float(p.maximum)
    # above an open minimum: a hair (a billionth of the range) and the least a float allows
    # there (probe_time=1e-300 s made the initial axis 0/0)
    edges = [lo, hi] if not p.exclusive_min else [hi, lo + (hi - lo) * 1e-9 or 1e-12, lo + max(abs(lo), 1.0) * 1e-300]
    if p.kind == "int":
        num = st.integers(int(math.ceil(lo)), int(math.floor(hi)))
    else:
        num = st.one_of(st.sampled_from(edges), draw_float(lo, hi))
    if p.kind == "vec3":
        return st.tuples(num, num, num)
    return num


def _floats(lo, hi):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


def check_valid_values(spec, values):
    for p in spec.params:
        v = values[p.name]
        if p.kind == "choice":
            assert v in [str(c) for c in p.choices]
            continue
        comps = v if p.kind == "vec3" else (v,)
        if p.kind == "vec3":
            assert isinstance(v, tuple) and len(v) == 3, (p.name, v)
        for x in comps:
            assert isinstance(x, (int, float)) and not isinstance(x, bool) or p.kind == "int", (p.name, v)
            assert math.isfinite(x), (p.name, v)
            if p.minimum is not None:
                assert x > p.minimum if p.exclusive_min else x >= p.minimum, (p.name, v)
            if p.maximum is not None:
                assert x <= p.maximum, (p.name, v)
            if p.kind == "int":
                assert isinstance(x, int), (p.name, v)


def check_error(spec, err: ParameterError, fuzzed: set[str]):
    msg = str(err)
    assert "\n" not in msg and "\r" not in msg, repr(msg)
    assert len(msg) < 400, msg
    names = {p.name for p in spec.params}
    assert err.name in fuzzed or err.name in names, (err.name, msg)
    assert msg.startswith(err.name), msg
    assert err.allowed and err.allowed in msg, msg


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in LONG_VALIDATION else n for n in NAMES])
@settings(max_examples=80, deadline=None, database=None, derandomize=DERANDOMIZE, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_validation_fuzz(name, data):
    spec = next(s for s in SCENARIOS if s.name == name)
    chosen = data.draw(st.lists(st.sampled_from([p.name for p in spec.params]), min_size=1, max_size=3, unique=True))
    given_ = {}
    for n in chosen:
        p = spec.param(n)
        given_[n] = data.draw(st.one_of(RAW, in_range(p, _floats)), label=n)
    if data.draw(st.booleans()) and data.draw(st.booleans()):
        given_["no_such_param"] = 1.0
    # as the CLI passes them: strings (only for values that have a string form the CLI could type)
    as_cli = data.draw(st.booleans())
    if as_cli:
        given_ = {k: (",".join(map(str, v)) if isinstance(v, tuple) else str(v)) for k, v in given_.items()}
    STATS["validation cases"] += 1
    try:
        values = spec.resolve(given_)
    except ParameterError as e:
        STATS["validation: ParameterError"] += 1
        check_error(spec, e, set(given_))
        return
    STATS["validation: accepted"] += 1
    assert "no_such_param" not in given_
    check_valid_values(spec, values)
    check_cost(spec, values, set(given_))


def check_cost(spec, values, fuzzed):
    """Any valid values have a cost (no exception, nothing negative or NaN; inf for an absurd
    step), and the budget check passes them or refuses them in one line naming a parameter."""
    from theoria.physics.errors import BudgetExceeded

    cost = spec.cost_of(values)
    for x in (cost.steps, cost.samples, cost.bytes):
        assert x >= 0, (spec.name, values, cost)  # False for NaN too
    try:
        spec.check_budget(values)
    except BudgetExceeded as e:
        STATS["validation: over budget"] += 1
        check_error(spec, e, fuzzed | {"parameters"})
    return cost


# ---- 2. simulation of valid values -------------------------------------------------------------

# Caps on how long / how finely a fuzzed run goes (the physical parameters keep full ranges).
CAPS: dict[str, tuple[float | None, float | None]] = {
    "duration": (None, 5.0), "step": (2e-3, None), "probe_time": (None, 1.0),
    "duration_yr": (None, 1.5), "step_days": (0.05, None), "sample_days": (0.5, None),
    "years": (None, 1.0), "sample_years": (0.01, None), "turns": (None, 2.0),
    "duration_turns": (None, 4.0), "steps_per_turn": (None, 400), "orbits": (None, 10.0),
    "steps_per_orbit": (None, 200), "periods": (None, 4.0), "steps_per_period": (None, 400),
    "n_starts": (None, 4), "n_orbits": (None, 20), "probe_orbits": (None, 3.0), "n_points": (None, 12),
}
PER_SCENARIO_CAPS = {
    "earth": {"years": (None, 2.0), "step_days": (0.25, None)},
    "earth-long-view": {"years": (None, 300.0), "step_days": (1.0, None), "sample_years": (1.0, None)},
    # libration-eccentric roams its whole range of e again: the forced-libration search that took
    # two minutes at e = 0.5, (B−A)/C = −0.45 (found by this file) now refuses in seconds
}


def capped(spec, p):
    lo, hi = PER_SCENARIO_CAPS.get(spec.name, {}).get(p.name, CAPS.get(p.name, (None, None)))
    if lo is None and hi is None:
        return p
    import dataclasses

    new_lo = p.minimum if lo is None else max(lo, p.minimum if p.minimum is not None else lo)
    new_hi = p.maximum if hi is None else min(hi, p.maximum if p.maximum is not None else hi)
    return dataclasses.replace(p, minimum=new_lo, maximum=new_hi,
                               exclusive_min=p.exclusive_min and new_lo == p.minimum)


class RecordingScene:
    """A viser scene API that records every number the scene code sends."""

    def __init__(self):
        self.numbers: list[tuple[str, np.ndarray]] = []
        self.calls = 0

    def _keep(self, where, v):
        if isinstance(v, (bool, np.bool_, str)) or v is None:
            return
        try:
            a = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            return
        self.numbers.append((where, a))

    def __getattr__(self, method):
        scene = self

        class Handle:
            def __init__(self, name):
                object.__setattr__(self, "name", name)
                object.__setattr__(self, "visible", True)

            def __setattr__(self, key, value):
                scene._keep(f"{self.name}.{key}", value)
                object.__setattr__(self, key, value)

            def remove(self):
                pass

        def call(*args, **kw):
            scene.calls += 1
            name = args[0] if args and isinstance(args[0], str) else method
            for i, a in enumerate(args):
                scene._keep(f"{method}({name}) arg{i}", a)
            for k, v in kw.items():
                scene._keep(f"{method}({name}) {k}", v)
            return Handle(name)

        return call


def scene_numbers_finite(spec, result):
    from theoria.app.scene import SceneView

    scene = RecordingScene()
    view = SceneView(scene)
    drawing = spec.drawing(result)
    view.show(drawing, overlays={k: True for k in drawing.overlays})  # every group drawn, also those off by default
    n = drawing.n_frames
    for i in sorted({0, n // 3, n // 2, n - 1}):
        view.set_frame(i)
    bad = [(w, a) for w, a in scene.numbers if a.size and not np.all(np.isfinite(a))]
    assert not bad, f"{spec.name}: non-finite numbers sent to the scene: {[w for w, _ in bad][:5]}"
    return scene.calls


# scenarios whose single run takes seconds even when capped (shooting, surfaces of section)
SLOW = {"hyperion", "libration-eccentric", "lunar-perturbation", "earth", "earth-long-view"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in LONG_SIMULATION else n
                                  for n in NAMES if n not in SLOW])
@settings(max_examples=15, deadline=None, database=None, derandomize=DERANDOMIZE, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_simulation_fuzz(name, data):
    simulate_fuzzed(name, data)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(SLOW & set(NAMES)))
@settings(max_examples=4, deadline=None, database=None, derandomize=DERANDOMIZE, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_simulation_fuzz_slow(name, data):
    simulate_fuzzed(name, data)


def simulate_fuzzed(name, data):
    spec = next(s for s in SCENARIOS if s.name == name)
    given_ = {p.name: data.draw(in_range(capped(spec, p), _floats), label=p.name) for p in spec.params}
    try:
        values = spec.resolve(given_)
    except ParameterError as e:  # a cross-parameter check refusing the combination
        STATS["simulation: refused by check"] += 1
        check_error(spec, e, set(given_))
        return
    STATS["simulation cases"] += 1
    cost = check_cost(spec, values, set(given_))
    try:
        result = spec.simulate_fn(values)
    except ParameterError as e:  # e.g. Diverged: no finite sample at all
        STATS["simulation: ParameterError"] += 1
        FOUND.append(f"{name}: {e}")
        check_error(spec, e, set(given_) | {"parameters"})
        return
    out = result.to_dict()
    json.dumps(out, allow_nan=False)  # strict JSON: no NaN / Infinity
    tr = result.trajectory
    if tr is None:
        return
    for label, arr in (("t", tr.t), ("quat", tr.quat_wxyz), ("L", tr.L_body), ("omega", tr.omega_body),
                       ("omega_inertial", tr.omega_inertial), ("rotation_axis", tr.rotation_axis),
                       ("figure_axis", tr.figure_axis), ("energy", tr.energy),
                       *((f"body {k}", v) for k, v in tr.bodies.items()),
                       *((f"series {k}", v) for k, v in tr.series.items()),
                       *((f"plot {k}", v) for k, v in result.plot_series.items())):
        assert np.all(np.isfinite(np.asarray(arr, float))), f"{name}: non-finite {label} with {values}"
    # the estimate made before the run (scenarios/budget.py) holds for these values too
    from theoria.scenarios.budget import held_bytes

    assert len(tr.t) <= cost.samples, (name, values, cost, len(tr.t))
    if result.status == "ok":
        assert held_bytes(result) <= 1.25 * cost.bytes, (name, values, cost, held_bytes(result))
    if result.status == "diverged":
        STATS["simulation: diverged (reported)"] += 1
        FOUND.append(f"{name}: {result.warnings[0]} with {values}")
        assert any("diverged at t=" in w for w in result.warnings) and out["status"] == "diverged"
    else:
        assert result.status in ("ok", "tumbles")  # tumbles: no libration (libration-eccentric), said in warnings
        if result.status == "tumbles":
            assert result.warnings and out["metrics"]["forced_amplitude_rad"] is None
        STATS[f"simulation: {result.status}"] += 1
    scene_numbers_finite(spec, result)


def test_zz_report_counts():
    """Prints how many cases ran (pytest -s)."""
    print("\nfuzz counts:", dict(STATS))
    for f in FOUND:
        print("  ", f[:300])


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW | LONG_SIMULATION else n
                                  for n in NAMES])
def test_the_least_value_above_an_open_minimum_runs_or_is_refused(name):
    """Each parameter whose minimum is open (a step, a duration, a time > 0) at 1e-300 above it,
    the others at their defaults: refused with the parameter's message, or a run without a warning
    from inside numpy and with strict JSON (probe_time = 1e-300 s gave the initial axis as 0/0,
    a tidal body with ω₀ = 1e-300 its resonance depth as 0 in a division). A metric not measured
    in so short a run is NaN by design (the flip interval with fewer than two flips)."""
    import warnings

    spec = next(s for s in SCENARIOS if s.name == name)
    for p in spec.params:
        if not p.exclusive_min or p.kind not in ("float", "int"):
            continue
        v = float(p.minimum) + max(abs(float(p.minimum)), 1.0) * 1e-300
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")  # nothing printed from inside numpy either
                values = spec.resolve({p.name: v})
                spec.check_budget(values)  # as every run is checked before it starts
                result = spec.simulate_fn(values)
        except ParameterError as e:
            check_error(spec, e, {p.name, "parameters"})
            continue
        json.dumps(result.to_dict(), allow_nan=False)
