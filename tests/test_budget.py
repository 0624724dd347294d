"""Budgets checked before a run starts (scenarios/budget.py).

Every scenario states what a run costs from its parameter values alone (`Scenario.cost`); the
estimate is checked against the real run of every scenario's defaults and presets: the samples
kept (exactly, or as an upper bound where a run may stop early), the bytes the finished Run
holds, and the integrator steps counted inside every integrator theoria uses
(tests/step_counter.py). Runs beyond the limits — the probes of a student who asks for hours of
CPU or tens of gigabytes — are refused before any step is taken, with a message that names the
parameter driving the cost and a value that fits.
"""
from __future__ import annotations

import pytest

import theoria as th
from theoria.app.cli import main
from theoria.physics import integrator
from theoria.physics.errors import BudgetExceeded, ParameterError
from theoria.physics.kept import forget
from theoria.scenarios.base import all_scenarios, get
from theoria.scenarios.budget import MAX_MEMORY, MAX_STEPS, held_bytes

from conftest import run_theoria
from step_counter import count_steps

# stated accuracy of the estimates (docs/robustness.md)
UNDER = 1.25  # an estimate is never below the real value divided by this
OVER_FIXED = 1.1  # fixed-step integrators only: the count is known before the run
OVER_ADAPTIVE = 8.0  # with DOP853 or REBOUND: steps by a measured rate, runs that may stop early
BYTES_PER_SAMPLE = 1.02  # bytes per kept state: the estimate counts each array the Run keeps
EARLY_STOP = {"syzygy": "the run ends when the Moon leaves its syzygy"}
HEAVY = {"earth-long-view", "earth", "lunar-perturbation", "hyperion", "libration-eccentric", "moon"}
# values beyond the presets whose cost has a term of its own (label → given)
EXTRA = {"earth-long-view": {"zoom, secular": {"zoom_years": 2.0, "step_days": 2.0, "sample_years": 50.0},
                             "zoom, full": {"model": "full", "years": 300.0, "sample_years": 50.0,
                                            "zoom_years": 1.0, "step_days": 0.5}},
         # the turning line breaks up after a turn or two: each later turn costs five times more
         "collinear": {"15 turns": {"turns": 15.0}, "20 turns, light middle body": {"turns": 20.0,
                                                                                  "masses": (1.0, 1e-3, 1.0)}}}


def _cases():
    out = []
    for sc in all_scenarios():
        seen = []
        for label, given in [("defaults", {})] + [(n, dict(v)) for n, v in sc.presets.items()] + \
                list(EXTRA.get(sc.name, {}).items()):
            values = sc.resolve(given)
            if values in seen:  # a preset equal to the defaults is run once
                continue
            seen.append(values)
            marks = [pytest.mark.slow] if sc.name in HEAVY else []
            out.append(pytest.param(sc.name, label, id=f"{sc.name}:{label}", marks=marks))
    return out


def test_every_scenario_states_its_cost():
    missing = [s.name for s in all_scenarios() if s.cost_fn is None]
    assert missing == []


def test_defaults_and_presets_pass_the_default_limits():
    for sc in all_scenarios():
        for given in [{}] + [dict(v) for v in sc.presets.values()]:
            cost = sc.cost(given)
            assert cost.within(MAX_STEPS, MAX_MEMORY), (sc.name, given, cost)
            assert cost.steps < MAX_STEPS / 4 and cost.bytes < MAX_MEMORY / 50, (sc.name, cost)  # room to spare


@pytest.mark.parametrize("name,label", _cases())
def test_cost_estimate_against_the_real_run(name, label):
    sc = get(name)
    given = {} if label == "defaults" else EXTRA[name][label] if label in EXTRA.get(name, {}) else sc.presets[label]
    values = sc.resolve(given)
    est = sc.cost_of(values)
    forget()  # the estimate is for a run made afresh, without pieces kept from an earlier run
    with count_steps() as counted:
        run = sc.simulate_fn(values)
    samples = len(run.trajectory.t)
    held = held_bytes(run)
    # samples: exact, or an upper bound for a run that may stop early
    if name in EARLY_STOP:
        assert samples <= est.samples
    else:
        assert est.samples == samples, (est.samples, samples)
    # bytes: per kept state as the run holds them, and never under by more than UNDER in total
    per_est, per_run = est.bytes / est.samples, held / samples
    assert per_run / BYTES_PER_SAMPLE <= per_est <= per_run * BYTES_PER_SAMPLE, (per_est, per_run)
    assert est.bytes >= held / UNDER
    # steps: every integrator counted
    steps = sum(counted.values())
    adaptive = counted["scipy"] + counted["rebound"] > 0
    if steps == 0:
        assert est.steps == 0  # no integrator at all (gravity-gradient-accuracy: quadratures)
        return
    ratio = est.steps / steps
    assert 1 / UNDER <= ratio <= (OVER_ADAPTIVE if adaptive else OVER_FIXED), (ratio, dict(counted), est)


# ---- the probes: refused before any step is taken ------------------------------------------------

@pytest.fixture
def no_integration(monkeypatch):
    """Fails the test if the rigid-body integrator is entered."""
    def refuse(*a, **k):
        raise AssertionError("the run started")

    monkeypatch.setattr(integrator, "_run", refuse)


def _fits(sc, values, e: BudgetExceeded, max_steps=MAX_STEPS, max_memory=MAX_MEMORY) -> bool:
    fixed = {**values, **e.reset}
    if e.fit is not None:
        fixed[e.fit[0]] = e.fit[1]
    return sc.cost(fixed).within(max_steps, max_memory)


PROBES = [
    # a free body at a fine step over a long time: ~1e11 steps, hours of CPU
    ("free-tumble", {"step": 1e-5, "duration": 1e6}, "duration", "integrator steps"),
    ("free-tumble", {"step": 1e-5, "duration": 1e4}, "step", "integrator steps"),
    # earth-long-view with a tiny step and tiny samples: ~56 GB and 1.9e8 steps
    ("earth-long-view", {"model": "full", "step_days": 0.05, "sample_years": 1e-4}, "step_days", "GB"),
    # the same at its own step: only the memory is over
    ("earth-long-view", {"sample_years": 1e-3}, "sample_years", "GB of arrays"),
    ("pole-near-axis", {"steps_per_turn": 100000, "duration_turns": 10000}, "duration_turns", "1e+09"),
    ("hyperion", {"n_starts": 400, "n_orbits": 3000, "steps_per_orbit": 2048}, "steps_per_orbit", "2.46e+09"),  # 400·3000·2048 = 2.458e9 member-steps and the rest
    ("lunar-perturbation", {"duration_yr": 200, "step_days": 0.005, "sample_days": 0.05}, "step_days", "steps"),
    # a zoom window of the full torque at a tiny step: 2.9e7 steps (the window was not counted once)
    ("earth-long-view", {"zoom_years": 40.0, "step_days": 0.0005}, "zoom_years", "integrator steps"),
    # a sampling interval so small that counting the samples overflows (OverflowError before)
    ("earth-long-view", {"sample_years": 5e-324}, "sample_years", "unbounded memory"),
]


@pytest.mark.parametrize("name,given,driver,needle", PROBES, ids=[f"{p[0]}:{','.join(p[1])}" for p in PROBES])
def test_probe_refused_before_it_runs(name, given, driver, needle, no_integration):
    sc = th.scenario(name)
    with pytest.raises(BudgetExceeded) as ei:
        sc.simulate(given)
    e = ei.value
    msg = str(e)
    assert isinstance(e, ParameterError) and "\n" not in msg
    assert e.name == driver and msg.startswith(f"{driver}=") and needle in msg, msg
    assert " fits" in msg
    assert _fits(sc, sc.resolve(given), e), msg  # what the message offers really fits


# the scenarios' values under which every step-like parameter is used (the secular model of the long
# view takes no step)
STEPPED = {"earth-long-view": {"model": "full"}}


@pytest.mark.parametrize("bad", [1e-300, 5e-324, 0.0, -1.0, float("nan")])
def test_absurd_steps_anywhere_get_the_parameter_message(bad, no_integration):
    """Every step-like or sampling parameter of every scenario, at 1e-300, the smallest float, 0, a
    negative value or NaN: one ParameterError naming it (a range error, or a budget refusal),
    never a traceback."""
    seen = 0
    for sc in all_scenarios():
        for p in sc.params:
            if "step" not in p.name and "sample" not in p.name:
                continue
            seen += 1
            with pytest.raises(ParameterError) as ei:
                sc.simulate({**STEPPED.get(sc.name, {}), p.name: bad})
            assert ei.value.name == p.name and "\n" not in str(ei.value), (sc.name, str(ei.value))
    assert seen >= 10


def test_the_front_door_limits_can_be_set_and_lifted():
    sc = th.scenario("free-tumble")
    with pytest.raises(BudgetExceeded) as ei:
        sc.simulate(duration=2, max_steps=100)
    assert "200 integrator steps" in str(ei.value) and "100" in str(ei.value)
    assert len(sc.simulate(duration=2, max_steps=None).trajectory.t) == 201
    with pytest.raises(BudgetExceeded, match="kB of arrays"):
        sc.simulate(duration=2, max_memory=10_000)
    assert sc.cost(duration=2) == th.Cost(200.0, 201.0, 201 * 200.0)


def test_cli_refuses_naming_the_steps(capsys, no_integration):
    code = main(["run", "free-tumble", "--set", "step=1e-5", "--duration", "1e6"])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("theoria: error: duration=") and "1e+11 integrator steps" in err and "--max-steps" in err


@pytest.mark.parametrize("args,code,needle", [
    (["--max-steps", "1000"], 2, "2000 integrator steps"),
    (["--max-steps", "3000"], 0, ""),
    (["--max-memory", "100kB"], 2, "400 kB of arrays"),
    (["--max-memory", "1MB"], 0, ""),
    (["--max-steps", "none", "--max-memory", "none"], 0, ""),
    (["--max-steps", "abc"], 2, "--max-steps=abc"),
    (["--max-memory=-3GB"], 2, "--max-memory=-3GB"),
    (["--max-memory", "0"], 2, "a size of at least one byte"),
    (["--max-memory", "0.5"], 2, "--max-memory=0.5: a size of at least one byte"),  # was a limit of "0 bytes"
    (["--max-steps", "0.5"], 2, "--max-steps=0.5: a whole number of integrator steps ≥ 1"),
    (["--max-steps", "1.5"], 2, "--max-steps=1.5: a whole number of integrator steps ≥ 1"),
    (["--max-steps", "3e3"], 0, ""),
    (["--max-steps", "1e-300"], 2, "--max-steps=1e-300"),
])
def test_cli_limits_override(args, code, needle, capsys):
    got = main(["run", "free-tumble", "--json", *args])
    out, err = capsys.readouterr()
    assert got == code, err
    if code:
        assert needle in err and err.count("\n") == 1
    else:
        assert err == ""


@pytest.mark.parametrize("cmd,suffix", [("record", "rrd"), ("export", "html")])
def test_record_and_export_refuse_before_running(cmd, suffix, tmp_path, capsys, no_integration):
    out = tmp_path / f"x.{suffix}"
    code = main([cmd, "free-tumble", "--set", "step=1e-7", "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 2 and "integrator steps" in err and not out.exists()


@pytest.mark.slow
def test_cli_subprocess_refusal_is_one_line():
    """The installed path: exit 2, one line, the number of steps, nothing else on stderr."""
    p = run_theoria("run", "earth-long-view", "--set", "model=full", "--set", "step_days=0.01")
    assert p.returncode == 2 and p.stdout == "" and p.stderr.count("\n") == 1
    assert "step_days=0.01" in p.stderr and "9.42e+08 integrator steps" in p.stderr, p.stderr


@pytest.mark.parametrize("kw, allowed", [
    ({"max_steps": -1}, "a whole number of integrator steps ≥ 1, or None"),
    ({"max_steps": 0}, "a whole number of integrator steps ≥ 1, or None"),
    ({"max_steps": float("nan")}, "a whole number of integrator steps ≥ 1, or None"),
    ({"max_steps": True}, "a whole number of integrator steps ≥ 1, or None"),
    ({"max_steps": "lots"}, "a whole number of integrator steps ≥ 1, or None"),
    ({"max_memory": -1}, "a size of at least one byte (e.g. 4GB), or None"),
    ({"max_memory": "4 apples"}, "bytes with an optional unit (e.g. 4GB, 500MB, 2GiB), or None"),
])
def test_a_limit_that_is_not_a_positive_number_is_refused_by_name(kw, allowed):
    """A limit is a number, the command line's words for one ("1e7", "4GB", "none"), or None: a
    string ended in a TypeError, and -1, 0 or NaN were taken as limits ('over the limit of -1')."""
    name, v = next(iter(kw.items()))
    with pytest.raises(ParameterError) as e:
        get("free-tumble").simulate(duration=1, **kw)
    assert str(e.value).startswith(f"{name}=") and str(e.value).endswith(": " + allowed), str(e.value)
    for words in ("none", "1e7") if name == "max_steps" else ("none", "4GB", "1e9"):  # as the flags take them
        assert get("free-tumble").simulate(duration=1, **{name: words}).status == "ok"


def test_precession_circulars_longest_runs_are_held_to_the_budget_the_limits_lift():
    """precession-circular listed orbits up to 10⁵ but refused anything over 5e6 steps in all, by a
    cap of its own that named steps_per_orbit (left at its default) and that --max-steps none did
    not lift. Its runs are held to the budget as every scenario's are."""
    from theoria.scenarios import get

    sc = get("precession-circular")
    sc.check_budget(sc.resolve({"orbits": 60000}))  # 6e6 steps: within the default 2e7
    with pytest.raises(ParameterError) as e:
        sc.check_budget(sc.resolve({"orbits": 100000, "steps_per_orbit": 1000}))
    assert e.value.name in ("orbits", "steps_per_orbit") and "fits" in str(e.value)
    sc.check_budget(sc.resolve({"orbits": 100000, "steps_per_orbit": 1000}), max_steps=None, max_memory=None)
