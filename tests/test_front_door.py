"""`import theoria as th`: the front door a notebook uses, held against the command line and against
what it promises (the same numbers as `theoria run --json`, the same one-line error)."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT
from conftest import run_theoria as _cli

import theoria as th


@pytest.mark.slow
def test_scenarios_in_gallery_order_and_each_one_described():
    names = th.scenarios()
    assert len(names) == len(set(names)) >= 16
    assert names[0] == "free-tumble" and names[-1] == "lunar-perturbation"  # ch. 15 first, the 1768 paper last
    listed = json.loads(_cli("list", "--json").stdout)["scenarios"]
    assert [s["name"] for s in listed] == names
    for n in names:
        sc = th.scenario(n)
        assert isinstance(sc, th.Scenario) and sc.name == n
        assert list(sc.parameters) == [p.name for p in sc.params]
        for name, values in sc.presets.items():
            assert set(values) <= set(sc.parameters), (n, name)


@pytest.mark.slow
def test_metrics_equal_the_command_lines_for_the_same_parameters():
    sc = th.scenario("middle-axis-flip")
    run = sc.simulate(spin=1, perturbation=0.01, duration=200)
    p = _cli("run", "middle-axis-flip", "--set", "spin=1", "--set", "perturbation=0.01", "--set", "duration=200",
             "--json")
    assert p.returncode == 0, p.stderr
    cli = json.loads(p.stdout)
    assert cli == json.loads(run.to_json()) == json.loads(json.dumps(run.to_dict()))
    assert p.stdout.strip() == run.to_json()  # the same text
    assert cli["metrics"] == pytest.approx(run.metrics, rel=0, abs=0)
    # a preset by (part of) its name, overridden by keywords, as `--preset` and `--set`
    tiny = sc.simulate(preset="tiny nudge", duration=50)
    p = _cli("run", "middle-axis-flip", "--preset", "tiny nudge", "--set", "duration=50", "--json")
    assert json.loads(p.stdout)["metrics"] == json.loads(tiny.to_json())["metrics"]
    assert tiny.params["perturbation"] == 1e-6


@pytest.mark.slow
@pytest.mark.parametrize("kwargs, cli", [
    ({"spin": 1e9}, ["--set", "spin=1e9"]),
    ({"perturbation": "nan"}, ["--set", "perturbation=nan"]),
    ({"wobble": 1}, ["--set", "wobble=1"]),
    ({"step": 0}, ["--set", "step=0"]),
])
def test_a_bad_value_is_one_parameter_error_with_the_clis_line(kwargs, cli):
    with pytest.raises(th.ParameterError) as e:
        th.scenario("middle-axis-flip").simulate(**kwargs)
    assert isinstance(e.value, ValueError) and e.value.name == next(iter(kwargs))
    p = _cli("run", "middle-axis-flip", *cli)
    assert p.returncode == 2 and p.stdout == ""
    # one line, the same words (the value as each typed it: 1e9 on the command line, 1e+09 a float)
    line = p.stderr.strip()
    assert "\n" not in line and line.startswith(f"theoria: error: {e.value.name}=")
    assert line.endswith(f": {e.value.allowed}")


def test_unknown_scenario_and_preset_name_what_there_is():
    with pytest.raises(th.ParameterError, match="free-tumble"):
        th.scenario("free-tumbel")
    with pytest.raises(th.ParameterError, match="Brick: the flip"):
        th.scenario("middle-axis-flip").simulate(preset="no such preset")


def test_wrong_kinds_of_argument_name_the_argument_and_what_is_allowed(tmp_path):
    """What a notebook user mistypes raised TypeError or AttributeError from deep inside (a
    scenario passed where its name goes, a number for the values, bytes for a path)."""
    sc = th.scenario("middle-axis-flip")
    assert th.scenario(sc) is sc
    with pytest.raises(th.ParameterError, match=r"^scenario=3: one of free-tumble"):
        th.scenario(3)
    with pytest.raises(th.ParameterError, match=r"^given=1: a mapping"):
        sc.simulate(1)
    run = sc.simulate(duration=2)
    with pytest.raises(th.ParameterError, match=r"^path=b'x.rrd': a file name"):
        run.record(b"x.rrd")
    assert not list(tmp_path.iterdir())
    assert th.WriteError.__module__.startswith("theoria")


def test_a_run_is_one_line_in_a_notebook():
    """repr(run) was every array of the trajectory (~37 KB for a 2-s run)."""
    run = th.scenario("middle-axis-flip").simulate(duration=2)
    text = repr(run)
    assert "\n" not in text and len(text) < 200, text
    assert text == (f"<theoria run of 'middle-axis-flip', ok: {len(run.trajectory.t):,} states, "
                    f"{len(run.metrics)} metrics, 1 comparison>"), text


def test_the_run_carries_its_trajectory_and_a_table_per_sample():
    run = th.scenario("free-tumble").simulate(duration=5)
    tr = run.trajectory
    n = len(tr.t)
    assert tr.quat_wxyz.shape == (n, 4) and tr.omega_body.shape == (n, 3) and tr.L_body.shape == (n, 3)
    assert np.allclose(np.linalg.norm(tr.quat_wxyz, axis=1), 1.0, atol=1e-12)
    df = run.to_dataframe()
    assert len(df) == n and np.allclose(df["t_s"], tr.t) and np.allclose(df["omega_body_y"], tr.omega_body[:, 1])
    assert run.warnings == [] and run.status == "ok"
    assert {c.label for c in run.comparisons} >= {"polhode period"}
    orbit = th.scenario("collinear").simulate()
    cols = orbit.to_dataframe().columns
    assert "q_w" not in cols and any(c.endswith("_x") for c in cols)  # bodies, no attitude


def test_check_rows_from_python():
    rows = th.check("E2")  # the group: E2 and its sub-rows (E2.aliasing, E2.separatrix)
    assert rows[0].id == "E2" and all(r.id.split(".")[0] == "E2" for r in rows) and len(rows) >= 2
    assert all(r.passed for r in rows) and rows[0].rel_error <= rows[0].tolerance
    with pytest.raises(th.ParameterError, match="E99"):
        th.check("E99")
    # a list, as the command line's `theoria check E1 E2` reads in Python (a TypeError before)
    assert [r.id for r in th.check(["E1", "E3"])] == [r.id for r in th.check("E1", "E3")]
    with pytest.raises(th.ParameterError, match="^check=3: one of E1, "):
        th.check(3)


@pytest.mark.slow
def test_the_example_runs_and_writes_its_files(tmp_path):
    """examples/first_five_minutes.py, as a student runs it, from a directory of their own."""
    p = subprocess.run([sys.executable, str(ROOT / "examples" / "first_five_minutes.py"), str(tmp_path)],
                       capture_output=True, text=True, timeout=1800, cwd=tmp_path)
    assert p.returncode == 0, p.stderr[-2000:]
    assert "refused: spin=1e+09: allowed range [-50, 50] rad/s" in p.stdout
    assert "interval between flips: Euler" in p.stdout
    import re

    m = re.search(r"with a nudge of \S+: ([\d.]+) s between flips, against ([\d.]+) s", p.stdout)
    assert m and float(m[1]) > float(m[2]), p.stdout  # as its comment says (it printed the opposite)
    from theoria.app.replay import check

    assert check(str(tmp_path / "flip.rrd"))["kind"] == "rrd"
    html = check(str(tmp_path / "flip.html"))
    assert html["scenario"] == "middle-axis-flip"
    assert "Brick: the flip about the middle axis" in (tmp_path / "flip.html").read_text()


def test_show_serves_the_run_in_the_app():
    """`run.show()` in a notebook: returns at once, the app answers, every browser starts from this run."""
    import urllib.request

    from theoria.app.server import show_run

    run = th.scenario("free-tumble").simulate(duration=3)
    shown = show_run(run, port=0, block=False)
    try:
        with urllib.request.urlopen(shown.url, timeout=30) as r:
            assert r.status == 200 and b"<html" in r.read(2000).lower()
    finally:
        shown.stop()


@pytest.mark.parametrize("sig,status,after", [("SIGTERM", 143, False), ("SIGINT", 0, True)])
def test_a_script_blocked_in_show_ends_on_sigterm_and_carries_on_after_ctrl_c(tmp_path, sig, status, after):
    """A batch job's kill (SIGTERM) returned from show() and ran the rest of the script, exit 0."""
    import signal
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    script = tmp_path / "s.py"
    script.write_text("import theoria as th\n"
                      f"th.scenario('free-tumble').simulate(duration=2).show(port={port})\n"
                      "print('after show')\n")
    # as from a terminal: SIGINT at its default (a child inherits an ignored one, as the suite's
    # process may have it after an in-process command, and Python then never raises Ctrl-C)
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        first = p.stdout.readline()  # the URL: the signal comes at once (a Ctrl-C there was a traceback)
        assert "open http" in first, (first, p.stderr.read() if p.poll() is not None else "")
        p.send_signal(getattr(signal, sig))
        out, err = p.communicate(timeout=60)
        out = first + out
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == status, err
    assert ("after show" in out) == after and "Traceback" not in err


def test_a_preset_cannot_be_changed_for_the_whole_process():
    """sc.presets is read-only, and so is each preset: a notebook that assigned into one changed
    what every later run with that preset (and the app in the same process) started from."""
    sc = th.scenario("free-tumble")
    name = next(iter(sc.presets))
    before = sc.preset(name)
    with pytest.raises(TypeError):
        sc.presets[name]["omega0"] = (9.0, 9.0, 9.0)
    assert th.scenario("free-tumble").preset(name) == before


def test_record_and_export_from_python_check_what_they_write(tmp_path):
    """From a notebook: the file's kind is the method's (record() wrote .rrd bytes into an .html
    file, which `theoria replay` then refused), force=False keeps an existing file, and a bad
    number of frames, frame rate or view is refused by name (ZeroDivisionError, TypeError...)."""
    run = th.scenario("free-tumble").simulate(duration=2)
    page = tmp_path / "a.html"
    assert run.export_html(page)["bytes"] > 10_000
    kept = page.read_bytes()
    for call, needle in ((lambda: run.record(page), "^path=.*: a file name ending in .rrd"),
                         (lambda: run.export_html(tmp_path / "a.txt"), "a file name ending in .html"),
                         (lambda: run.export_html(page, force=False), "it exists; force=True replaces it"),
                         (lambda: run.export_html(tmp_path / "b.html", frames=-5), "^frames=-5: a whole number"),
                         (lambda: run.export_html(tmp_path / "b.html", fps=0), "^fps=0: frames a second"),
                         (lambda: run.export_html(tmp_path / "b.html", view="x"), "^view=x: None or a theoria View")):
        with pytest.raises(th.ParameterError, match=needle):
            call()
    assert page.read_bytes() == kept
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.html"]
    assert run.record(tmp_path / "a.rrd")["bytes"] > 0
    # .htm as `theoria export` takes it (it was refused from Python only)
    assert run.export_html(tmp_path / "a.htm")["bytes"] > 10_000
    assert _cli("replay", str(tmp_path / "a.htm"), "--check").returncode == 0


@pytest.mark.parametrize("kw, says", [
    (dict(wrkers=2), "wrkers=2: unknown parameter 'wrkers'"),  # a misspelt keyword: a parameter to the scenario
    (dict(out=None), "out=None: a file name ending in .zarr or .parquet"),
    (dict(out=3), "out=3: a file name ending in .zarr or .parquet"),  # was a TypeError from os.fspath
    (dict(resume=True, force=True), "resume=True, force=True: one of the two: resume completes the sweep at out"),
    (dict(max_memory="lots"), "max_memory=lots: bytes with an optional unit (e.g. 4GB, 500MB, 2GiB), or None"),
    (dict(max_steps=2.5), "max_steps=2.5: a whole number of integrator steps ≥ 1, or None"),
    # counts that are not whole were cut (2.5 workers ran 2) or read in other scripts' digits
    (dict(workers=2.5), "workers=2.5: a whole number from 1 to 256"),
    (dict(workers="２"), "workers=２: a whole number from 1 to 256"),
    (dict(chunk=1.5), "chunk=1.5: a whole number of runs ≥ 1"),
    (dict(chunk=True), "chunk=True: a whole number of runs ≥ 1"),
])
def test_a_sweep_from_python_names_its_keywords_not_the_command_lines_flags(tmp_path, kw, says):
    """Errors read "--set=wrkers=2", "--out=None", "--resume=--force" (the command line's flags),
    and out=3 raised a bare TypeError; all before any worker starts and with nothing written."""
    given = {"grid": {"step": (0.01, 0.02, 2)}, "out": str(tmp_path / "s.zarr"), **kw}
    with pytest.raises(th.ParameterError) as e:
        th.scenario("free-tumble").sweep(**given)
    assert str(e.value).startswith(says), str(e.value)
    assert list(tmp_path.iterdir()) == []


def test_simulate_takes_a_memory_limit_as_the_command_line_writes_it():
    """`sweep(max_memory="4GB")` was taken (and then refused every run: each run's check took
    numbers only) while `simulate(max_memory="4GB")` was refused: one reading for both, as
    `--max-memory` reads it."""
    sc = th.scenario("free-tumble")
    assert sc.simulate(duration=2, max_memory="4GB").status == "ok"
    assert sc.simulate(duration=2, max_memory="none").status == "ok"
    with pytest.raises(th.BudgetExceeded, match="over the limit of 1 kB"):
        sc.simulate(duration=2, max_memory="1KB")
    with pytest.raises(th.ParameterError, match="max_memory=-1: a size of at least one byte"):
        sc.simulate(duration=2, max_memory=-1)


def test_what_dir_shows_is_the_front_door():
    """Tab completion on `th.` showed `annotations` (a __future__ import), a name that is nothing of
    theoria's: every public name is in __all__, besides the subpackages that are reachable."""
    import types

    def subpackage(n):  # theoria.app, .physics, … once something imported them
        m = getattr(th, n)
        return isinstance(m, types.ModuleType) and m.__name__ == f"theoria.{n}"

    stray = [n for n in dir(th) if not n.startswith("_") and n not in th.__all__ and not subpackage(n)]
    assert stray == []


def test_a_busy_sweeps_own_message_reaches_python_whole():
    """The keywords-for-flags rewording replaced a SweepBusy's message ("another sweep (PID …) is
    writing …; wait for it to end, or give another --out") by a bare "out=…: a result no other
    sweep is writing": the PID and the advice were lost."""
    from theoria.app.sweep import SweepBusy
    from theoria.scenarios.base import in_python_words

    e = in_python_words(SweepBusy("/tmp/x.zarr", 1234))
    assert isinstance(e, SweepBusy) and e.name == "out" and "1234" in str(e), str(e)


@pytest.mark.parametrize("limit", [10 ** 400, np.array(1e400), float("inf")])
def test_a_limit_too_large_for_a_float_is_no_limit(limit):
    """10**400 raised OverflowError where "1e400" meant no limit; a 0-d numpy array was refused."""
    from theoria.scenarios.budget import memory_limit, steps_limit

    assert steps_limit(limit) is None and memory_limit(limit) is None
    assert steps_limit(np.array(2e7)) == 2e7 and memory_limit(np.array(4e9)) == 4e9


def test_a_path_with_a_nul_character_is_refused_by_name(tmp_path):
    """pathlib raised "ValueError: embedded null byte" from record and export."""
    run = th.scenario("free-tumble").simulate(duration=1)
    for call, name in ((lambda p: run.record(p + ".rrd"), "path"), (lambda p: run.export_html(p + ".html"), "path"),
                       (lambda p: th.scenario("free-tumble").sweep(grid={"duration": (1, 2, 2)}, out=p + ".zarr"),
                        "out")):
        with pytest.raises(th.ParameterError, match="a file name without a NUL character") as e:
            call(str(tmp_path / "a\0b"))
        assert e.value.name == name
    assert list(tmp_path.iterdir()) == []


def _free_tumble_run(duration):
    return th.scenario("free-tumble").simulate(duration=duration)


def test_runs_and_refusals_cross_a_process_boundary_whole():
    """A researcher's pool (multiprocessing, joblib, Dask) sends runs and errors between processes
    by pickling them: no run could be pickled (a scenario's wrapped simulate function), a refusal
    came back without its parameter, and `run == run` raised on its arrays."""
    import copy
    import pickle
    from concurrent.futures import ProcessPoolExecutor
    from multiprocessing import get_context

    from theoria.physics.errors import BudgetExceeded
    from theoria.scenarios.base import all_scenarios

    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
        run = pool.submit(_free_tumble_run, 20.0).result()
        with pytest.raises(th.ParameterError) as refused:
            pool.submit(_free_tumble_run, -1.0).result()
    assert run.spec is th.scenario("free-tumble") and run.status == "ok"
    assert run.metrics == th.scenario("free-tumble").simulate(duration=20.0).metrics
    assert (refused.value.name, refused.value.value) == ("duration", -1.0) and "duration=-1" in str(refused.value)
    assert run == run and run != copy.copy(run)
    for sc in all_scenarios():  # every scenario's run, at its quick preview's values
        r = sc.simulate(**dict(sc.preview))
        back = pickle.loads(pickle.dumps(r))
        assert back.spec is sc and back.metrics.keys() == r.metrics.keys() and back.warnings == r.warnings
        assert np.array_equal(back.trajectory.t, r.trajectory.t) and back.to_dataframe().shape == r.to_dataframe().shape
        assert copy.deepcopy(sc) is sc
    e = pickle.loads(pickle.dumps(BudgetExceeded("step", 1e-9, "at least 0.01 fits", fit=("step", 0.01))))
    assert type(e) is BudgetExceeded and e.fit == ("step", 0.01) and str(e) == "step=1e-09: at least 0.01 fits"


def test_a_refused_value_is_shown_as_given_not_rounded_into_the_range():
    with pytest.raises(th.ParameterError, match=r"spin=50\.0000001: allowed range"):
        th.scenario("middle-axis-flip").simulate(spin=50.0000001)


def test_a_name_written_another_way_is_found_and_a_misspelt_one_gets_a_suggestion():
    """A researcher's `th.scenario("Middle-Axis-Flip")`, `simulate(spn=1)` or `th.check("e2")` got the
    whole list and no hint."""
    assert th.scenario("Middle-Axis-Flip").name == th.scenario("middle_axis_flip").name == "middle-axis-flip"
    with pytest.raises(th.ParameterError, match="did you mean 'hyperion'"):
        th.scenario("hyperon")
    with pytest.raises(th.ParameterError, match="did you mean 'middle-axis-flip'"):
        th.scenario("middle")
    with pytest.raises(th.ParameterError, match=r"spn=1: unknown parameter \(did you mean 'spin'\?\); known: inertia"):
        th.scenario("middle-axis-flip").simulate(spn=1)
    with pytest.raises(th.ParameterError) as e:
        th.scenario("middle-axis-flip").simulate(xyz=1)
    assert "did you mean" not in str(e.value)  # nothing near: no guess
    assert [r.id for r in th.check("e2")] == [r.id for r in th.check("E2")]
    r = _cli("run", "hyperon")
    assert r.returncode == 2 and "did you mean 'hyperion'" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_a_trajectory_is_one_line_and_the_listed_range_is_the_refused_one():
    """repr(run.trajectory) printed every array; precession-circular listed its length as (0, 10⁵]
    revolutions and refused 0.0001 with "allowed range [0.5, …]"."""
    tr = th.scenario("moon").simulate(years=1).trajectory
    text = repr(tr)
    assert "\n" not in text and len(text) < 200 and f"{len(tr):,} samples" in text and "earth" in text, text
    orbits = th.scenario("precession-circular").parameters["orbits"]
    assert orbits.minimum == 0.5 and not orbits.exclusive_min
    with pytest.raises(th.ParameterError, match=r"^orbits=0\.0001: .*0\.5"):
        th.scenario("precession-circular").simulate(orbits=0.0001)
    assert th.scenario("precession-circular").simulate(orbits=0.5, steps_per_orbit=50).status == "ok"


def test_a_value_given_for_a_part_the_run_does_not_use_is_said_not_lost():
    """collinear's turns mean nothing while the line collapses from rest: a run given them says so
    (Python and the command line alike), and the defaults and presets of every scenario set no
    value their own choices leave unused."""
    sc = th.scenario("collinear")
    run = sc.simulate(preset="collapse", turns=5, phi_max_deg=60)
    said = [w for w in run.warnings if "turns" in w]
    assert len(said) == 1 and "motion = rotating or restricted" in said[0]
    assert not any("phi_max_deg" in w for w in run.warnings)
    assert not any("is not used" in w for w in sc.simulate(turns=1).warnings)
    for s in map(th.scenario, th.scenarios()):
        for given in [{}, *s.presets.values()]:
            assert s.unused(s.resolve(given), given) == [], (s.name, given)
    out = subprocess.run([sys.executable, "-m", "theoria", "run", "collinear", "--json", "--set", "motion=expansion",
                          "--set", "lagrange_point=L4"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert any("lagrange_point = L4 is not used" in w for w in json.loads(out.stdout)["warnings"])


def test_a_parameter_can_only_depend_on_a_choice_that_exists():
    from theoria.physics.params import Param
    from theoria.scenarios.base import Scenario

    bad = Param("x", 1.0, 0, 2, applies={"mode": "fast"})
    with pytest.raises(ValueError, match="x applies with mode"):
        Scenario(name="t-bad", title="t", section="§0", group="ch. 15", summary="", params=(bad,), simulate_fn=lambda v, progress=None: None)


def test_a_full_disk_is_an_oserror_a_script_can_catch_and_the_old_file_stays(tmp_path, monkeypatch):
    """From Python a failed write is one line naming the file, catchable as the OSError it is
    (`except OSError`, errno ENOSPC), and the file that was there is left whole."""
    import errno

    from theoria.app import files

    run = th.scenario("free-tumble").simulate(duration=2)
    page = tmp_path / "a.html"
    run.export_html(page)
    kept = page.read_bytes()

    def full(fd, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(files, "_write_all", full)
    with pytest.raises(OSError) as e:
        run.export_html(page, force=True)
    assert isinstance(e.value, th.WriteError) and e.value.errno == errno.ENOSPC
    assert str(e.value).startswith(str(page)) and "No space left" in str(e.value) and "\n" not in str(e.value)
    assert page.read_bytes() == kept and sorted(p.name for p in tmp_path.iterdir()) == ["a.html"]


def test_a_long_free_tumble_says_its_states_are_too_sparse_not_its_run_too_short():
    """150,000 s are ~40,000 polhode periods, kept as 20,000 states 7.5 s apart: the comparison
    gives no simulated period because the states are too sparse, which is what it must say."""
    run = th.scenario("free-tumble").simulate(duration=150000)
    note = next(c.note for c in run.comparisons if c.label == "polhode period")
    assert "too far apart" in note and "too short" not in note
    assert "too short" in next(c.note for c in th.scenario("free-tumble").simulate(duration=0.5).comparisons
                               if c.label == "polhode period")


def test_every_metric_is_a_python_number():
    """Some metrics were numpy float64 and others float (flip_interval_euler_808 among them): a
    script's isinstance(x, float) holds for both, type(x) is float did not, and repr differed."""
    for name in ("middle-axis-flip", "free-tumble", "libration-circular"):
        run = th.scenario(name).simulate(**th.scenario(name).preview)
        assert {type(v) for v in run.metrics.values()} <= {float, int, bool, str}, name


def test_a_scene_named_by_a_part_of_its_name_gets_a_suggestion():
    """`th.scenario("flip")` listed every scene without a suggestion, though "flip" is a part of one
    name only; a beginning ("tumble" of nothing, "free" of "free-tumble") was already suggested."""
    for part, meant in (("flip", "middle-axis-flip"), ("tumble", "free-tumble"), ("long-view", "earth-long-view")):
        with pytest.raises(th.ParameterError) as e:
            th.scenario(part)
        assert str(e.value).endswith(f"did you mean '{meant}'?"), str(e.value)
    with pytest.raises(th.ParameterError) as e:
        th.scenario("axis")  # a part of two names: no guess
    assert "did you mean" not in str(e.value)


def test_a_runs_table_has_no_column_twice():
    """`to_dataframe()` held ω on each body axis twice: as `omega_body_x` and again as the plot's
    curve "ω on middle axis" (the same numbers, a name with spaces that changes per scene)."""
    df = th.scenario("middle-axis-flip").simulate(duration=5).to_dataframe()
    cols = [df[c].to_numpy() for c in df.columns]
    twice = [(a, b) for i, a in enumerate(df.columns) for j, b in enumerate(df.columns)
             if i < j and np.array_equal(cols[i], cols[j])]
    assert twice == [] and "omega_body_y" in df.columns
    assert "obliquity of date (deg)" in th.scenario("earth-long-view").simulate(years=2000).to_dataframe().columns


def test_earth_long_views_zoom_is_said_unused_where_it_is():
    """earth-long-view took `zoom_year=-5000` with no zoom, and a zoom with the full model, with
    `warnings == []` though neither was used (docs/python.md: an unused value is said in
    `run.warnings`). The zoom is the secular model's; its start needs a length above zero."""
    sc = th.scenario("earth-long-view")
    r = sc.simulate(zoom_year=-5000, years=1000)
    assert r.warnings == ["zoom_year = -5000 is not used here: it applies only with model = secular and with "
                          "zoom_years > 0"]
    r = sc.simulate(model="full", zoom_years=5, zoom_year=2010, years=100)
    assert [w.split(" is not used")[0] for w in r.warnings] == ["zoom_year = 2010", "zoom_years = 5"]
    assert sc.simulate(zoom_years=5, zoom_year=2010, years=100).warnings == []


def test_earth_long_views_step_is_said_unused_by_the_averaged_torque_alone():
    """The averaged (secular) torque takes no step: `step_days` is the full model's and the zoom's,
    either of two conditions, and was taken silently by the default secular run."""
    sc = th.scenario("earth-long-view")
    assert sc.simulate(step_days=1.0, years=200).warnings == [
        "step_days = 1 is not used here: it applies only with model = full, or with model = secular and with "
        "zoom_years > 0"]
    assert sc.simulate(step_days=1.0, years=200, zoom_years=1).warnings == []
    assert sc.simulate(step_days=1.0, years=200, model="full").warnings == []
    assert not sc.param("step_days").applies_to(sc.resolve({}))  # the panel hides it at the defaults


@pytest.mark.parametrize("name, given, says", [
    ("pole-near-axis", {"steps_per_turn": 4}, "Raise steps_per_turn."),
    ("precession-circular", {"steps_per_orbit": 8}, "Raise steps_per_orbit."),
    ("hyperion", {"steps_per_orbit": 16, "n_starts": 4, "n_orbits": 20}, "Raise steps_per_orbit."),
])
def test_a_coarse_step_warning_says_which_way_helps(name, given, says):
    """"Lower steps_per_turn" was the advice when a turn had 2 steps: a count of steps per turn,
    orbit or period is raised to make the step finer (a step itself is lowered: test_validity)."""
    r = th.scenario(name).simulate(**given)
    assert any("too coarse" in w and w.endswith(says) for w in r.warnings), r.warnings


def test_ids_and_counts_read_as_written():
    """`check("E99")` listed the ids by length (E1, E10, E11, …, E2); a one-point sweep said "1 runs
    in 1 chunks"."""
    from theoria.app import sweep as sw

    with pytest.raises(th.ParameterError) as e:
        th.check("E99")
    ids = str(e.value).split("one of ")[1].split(", ")
    assert ids[:4] == ["E1", "E2", "E2.aliasing", "E2.separatrix"] and ids.index("E9") < ids.index("E10")
    line = sw.Summary(out="x.zarr", runs=1, chunks=1, chunks_done_before=0, chunks_computed=1, path="single runs",
                      seconds=1.0).line()
    assert line.startswith("sweep: 1 run in 1 chunk (single runs); computed 1 chunk now"), line
