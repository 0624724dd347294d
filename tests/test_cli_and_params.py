"""The command line and parameter validation: bad input exits 2 with one clear line."""
import json

import numpy as np
import pytest

from theoria.physics.inertia import validate_moments
from theoria.physics.params import Param, ParameterError


@pytest.mark.parametrize("moments,needle", [((-1, 2, 3), "> 0"), ((0, 2, 3), "> 0"), ((1, 2, 5), "A+B >= C"),
                                            ((1, np.nan, 3), "finite"), ((10, 2, 3), "B+C >= A")])
def test_impossible_moments_rejected(moments, needle):
    with pytest.raises(ParameterError) as e:
        validate_moments(moments)
    assert needle in str(e.value) and "inertia" in str(e.value)


def test_flat_disc_is_a_real_body():
    validate_moments((1, 1, 2))


def test_param_parse_errors():
    p = Param("step", 0.01, 0.0, 10.0, "s", exclusive_min=True)
    for bad in ["nan", "inf", "abc", "0", "-1", "11"]:
        with pytest.raises(ParameterError) as e:
            p.parse(bad)
        msg = str(e.value)
        assert msg.startswith("step=") and "(0, 10] s" in msg and "\n" not in msg
    v = Param("omega0", (1, 2, 3), -50, 50, "rad/s", kind="vec3")
    assert v.parse("1,2,3") == (1.0, 2.0, 3.0)
    for bad in ["1,2", "1,2,x", "1,2,99"]:
        with pytest.raises(ParameterError):
            v.parse(bad)


@pytest.mark.parametrize("args,needle", [
    (["run", "free-tumble", "--set", "inertia=1,2,5"], "inertia=1,2,5"),
    (["run", "free-tumble", "--set", "inertia=-1,2,3"], "inertia="),
    (["run", "free-tumble", "--set", "omega0=0,0,0"], "omega0=0,0,0"),
    (["run", "free-tumble", "--set", "step=nan"], "step=nan"),
    (["run", "free-tumble", "--set", "nosuchkey=1"], "nosuchkey=1"),
    (["run", "free-tumble", "--set", "duration=-5"], "duration=-5"),
    (["run", "free-tumble", "--set", "inertia"], "key=value"),
    # one parameter given two values: refused, not the last one silently taken
    (["run", "free-tumble", "--set", "duration=3", "--set", "duration=4"],
     "--set=duration=4: each parameter once (duration is also given as duration=3)"),
    (["run", "free-tumble", "--set", "duration=3", "--duration", "5"], "--duration=5: the same as --set duration=3"),
    # --duration as typed, not as a float made it (400 nines were reported as inf)
    (["run", "free-tumble", "--duration", "9" * 400], "duration=" + "9" * 20),
    (["run", "free-tumble", "--duration", "abc"], "duration=abc: a number, allowed range (0, 1e+06] s"),
    # what Python's float() reads and no one types meaning that number
    (["run", "free-tumble", "--set", "duration=1_0"], "duration=1_0: a number, allowed range"),
    (["run", "free-tumble", "--duration", "١٠"], "duration=١٠: a number, allowed range"),
    (["run", "free-tumble", "--set", "omega0=0,１,2"], "omega0=0,１,2: a number"),
    (["run", "free-tumble", "--duration", "0." + "0" * 300 + "1"], "a value of at most 200 characters"),
    (["run", "no-such-scenario"], "scenario=no-such-scenario"),
    (["run", "middle-axis-flip", "--set", "inertia=1,1,2"], "three different moments"),
    # a rate too slow to compute with (its square underflows): named as given, not as "omega0"
    (["run", "middle-axis-flip", "--set", "spin=1e-200"], "spin=1e-200: a rate other than 0 (a body at rest does not move), from -50 to 50 rad/s and at least 1e-100 rad/s in size"),
    (["run", "middle-axis-flip", "--set", "spin=0"], "spin=0: a rate other than 0 (a body at rest does not move), from -50 to 50 rad/s and at least 1e-100 rad/s in size"),
    (["run", "free-tumble", "--set", "omega0=1e-200,0,0"], "omega0=1e-200,0,0: a rate other than 0 (a body at rest does not move)"),
    (["run", "initial-axis", "--set", "torque=0,0,0"], "torque=0,0,0"),
    (["run", "middle-axis-flip", "--preset", "no such preset"], '--preset=no such preset: one of "Brick: the flip"'),
    (["run", "middle-axis-flip", "--preset", "brick"], "more than one matches"),
    # a server that cannot listen: refused before it starts (it printed viser's traceback and hung)
    (["serve", "--port", "99999"], "--port=99999: a whole number from 0 to 65535"),
    (["serve", "--port", "-1"], "--port=-1"),
    (["serve", "--host", "999.1.1.1"], "--host=999.1.1.1: an address of this machine"),
    (["serve", "--host", "192.0.2.1"], "--host=192.0.2.1: an address of this machine"),  # TEST-NET: not ours
    (["bench", "nosuch"], "name=nosuch: one of "),  # printed an empty table, exit 0
    # no torque at the start (§815): the value that makes it so is named (it always blamed the direction)
    (["run", "gravity-start", "--set", "gm=1e-200"], "gm=1e-200: an attraction large enough"),
    (["run", "gravity-start", "--set", "inertia=1,1,1"], "inertia=1,1,1: moments not all equal"),
    (["run", "gravity-start", "--set", "direction=0,1,0"], "direction=0,1,0: a direction off this body's principal axes"),
    (["run", "gravity-start", "--set", "inertia=2,2,4", "--set", "direction=0.6,0.8,0"], "direction=0.6,0.8,0: a direction off"),
    # a name longer than the file system takes: the parameter message, not an OSError's traceback
    (["run", "free-tumble", "--out", "a" * 300 + ".csv"], "a path this system takes (File name too long)"),
    (["record", "free-tumble", "--out", "a" * 300 + ".rrd"], "a path this system takes (File name too long)"),
    (["export", "free-tumble", "--out", "a" * 300 + ".html"], "a path this system takes (File name too long)"),
    (["replay", "a" * 300 + ".rrd", "--check"], "cannot read (File name too long)"),
    # a sweep's counts: the range it takes, and no "None" for a flag not given
    (["sweep", "free-tumble", "--random", "step=0.001:0.002", "--samples", "1e12", "--out", "x.parquet"],
     "--samples=1e12: a whole number from 1 to 10,000,000"),
    (["sweep", "free-tumble", "--out", "x.parquet"], "--grid=(none given): at least one --grid"),
    # counts as a person writes them, in ASCII digits (int() read "２" and "1_0", and cut 1.5 to 1)
    (["sweep", "free-tumble", "--random", "step=0.001:0.002", "--samples", "２", "--out", "x.parquet"],
     "--samples=２: a whole number from 1 to 10,000,000"),
    (["sweep", "free-tumble", "--grid", "duration=1:2:2", "--chunk", "1.5", "--out", "x.parquet"],
     "--chunk=1.5: a whole number of runs ≥ 1"),
    (["sweep", "free-tumble", "--grid", "duration=1:2:2", "--chunk", "1_0", "--out", "x.parquet"], "--chunk=1_0"),
    (["sweep", "free-tumble", "--grid", "duration=1:2:2", "--workers", "２", "--out", "x.parquet"],
     "argument --workers: invalid whole number value: '２'"),
    (["sweep", "free-tumble", "--grid", "duration=1:2:2", "--seed", "1.5", "--out", "x.parquet"],
     "argument --seed: invalid whole number value: '1.5'"),
    (["serve", "--port", "８０８０"], "argument --port: invalid whole number value: '８０８０'"),
    (["serve", "--max-clients", "٣"], "argument --max-clients: invalid whole number value"),
    # a parameter name typed by hand is cut like a value (a 3,000-character name was echoed whole)
    (["run", "free-tumble", "--set", "é" * 3000 + "=1"], "éééé…=1: unknown parameter"),
])
def test_bad_set_exits_2_with_one_line(args, needle, cli):
    code, _, err = cli(*args)
    assert code == 2
    err = err.strip()
    assert len(err.splitlines()) == 1 and needle in err, err


def test_a_long_name_is_not_echoed_whole(cli):
    code, _, err = cli("run", "free-tumble", "--set", "é" * 3000 + "=1")
    assert code == 2 and len(err) < 600, len(err)


def test_replay_refuses_what_is_not_a_regular_file(cli, tmp_path):
    """A named pipe blocked the reader for ever (only SIGKILL stopped it); a link to /dev/zero was
    read until memory ran out."""
    import os

    fifo = tmp_path / "f.rrd"
    os.mkfifo(fifo)
    (tmp_path / "z.html").symlink_to("/dev/zero")
    for path in (fifo, tmp_path / "z.html"):
        code, _, err = cli("replay", path, "--check")
        assert code == 2 and err.strip().endswith("not a regular file (a device, a pipe or a socket)"), err


def test_the_same_value_given_twice_is_taken(cli):
    for args in (["--set", "duration=3", "--set", "duration=3.0"], ["--set", "duration=3", "--duration", "3"]):
        code, out, err = cli("run", "free-tumble", *args, "--json")
        assert code == 0, err
        assert json.loads(out)["params"]["duration"]["value"] == 3.0


@pytest.mark.slow
def test_run_json_shape(cli_process):
    code, out, err = cli_process("run", "middle-axis-flip", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["scenario"] == "middle-axis-flip"
    assert d["params"]["spin"] == {"value": 6.0, "unit": "rad/s"}
    for k in ("energy_rel_drift", "momentum_rel_drift", "flip_interval", "flip_interval_exact"):
        assert k in d["metrics"]
    assert abs(d["metrics"]["flip_interval"] / d["metrics"]["flip_interval_exact"] - 1) < 1e-9
    fs = d["final_state"]
    assert len(fs["quaternion_wxyz"]) == 4 and len(fs["omega_body"]) == 3
    assert abs(np.linalg.norm(fs["quaternion_wxyz"]) - 1) < 1e-12


@pytest.mark.slow
def test_run_duration_flag_and_final_state_matches_exact(cli_process):
    from theoria.physics.torque_free_exact import exact_free_motion
    code, out, err = cli_process("run", "free-tumble", "--duration", "7.5", "--json")
    assert code == 0, err
    d = json.loads(out)
    w, q = exact_free_motion((2, 3, 4), (1.0, 0.5, 1.5), [7.5])
    assert np.allclose(d["final_state"]["omega_body"], w[0], atol=1e-11)
    from theoria.physics.quaternion import angle_between
    assert angle_between(np.array(d["final_state"]["quaternion_wxyz"]), q[0]) < 1e-10  # q and −q: one attitude


def test_list_json_has_every_scenario(cli_process):
    code, out, _ = cli_process("list", "--json")
    names = {s["name"] for s in json.loads(out)["scenarios"]}
    assert {"free-tumble", "middle-axis-flip", "initial-axis"} <= names
    flip = next(s for s in json.loads(out)["scenarios"] if s["name"] == "middle-axis-flip")
    assert "Brick: the flip" in flip["presets"]
    # what a script needs to pass a value that is taken: a choice's choices, whether the minimum
    # itself is allowed (gravity-start's distance 0.001 was listed as the minimum and refused)
    from theoria.scenarios import all_scenarios

    listed = {s["name"]: {p["name"]: p for p in s["params"]} for s in json.loads(out)["scenarios"]}
    for spec in all_scenarios():
        for p in spec.params:
            got = listed[spec.name][p.name]
            assert got["exclusive_min"] == p.exclusive_min and got["allowed"] == p.allowed()
            assert got.get("choices") == (list(p.choices) if p.kind == "choice" else None)
    assert listed["gravity-start"]["distance"]["exclusive_min"] is True
    assert listed["collinear"]["energy"]["applies"] == {"motion": ["expansion"]}
    assert listed["earth-long-view"]["step_days"]["applies"] == [{"model": ["full"]},
                                                                 {"model": ["secular"], "zoom_years": [">0"]}]


def test_preset_flag_gives_the_preset_values_and_set_overrides_them(cli):
    from theoria.scenarios import get

    spec = get("free-tumble")
    want = spec.preset("Tumble: spin near the short axis, a small polhode")
    code, out, _ = cli("run", "free-tumble", "--preset", "SHORT axis", "--set", "duration=3", "--json")
    assert code == 0
    d = json.loads(out)
    assert d["params"]["omega0"]["value"] == list(want["omega0"]) and d["params"]["duration"]["value"] == 3.0
    code, text, _ = cli("list")
    assert code == 0
    assert text.index("ch. 15") < text.index("ch. 16") < text.index("three bodies")
    assert '--preset "Brick: the flip"' in text
    # every title starts in the same column, on the scenario's line or, after a long section, below it
    from theoria.scenarios import all_scenarios
    lines = text.splitlines()
    columns = set()
    for s in all_scenarios():
        at = next(i for i, line in enumerate(lines) if line.split()[:1] == [s.name])
        line = lines[at] if lines[at].endswith(s.title) else lines[at + 1]
        assert line.endswith(" " + s.title), (s.name, lines[at:at + 2])
        columns.add(len(line) - len(s.title))
    assert len(columns) == 1, columns


@pytest.mark.slow
def test_every_check_row_passes_and_covers_design_table(cli_process):
    """`theoria check`: every row of design.md's table E1–E13 exists and passes."""
    code, out, err = cli_process("check", "--json")
    rows = json.loads(out)["results"]
    failed = [(r["id"], r["rel_error"], r["tolerance"], r["note"]) for r in rows if not r["pass"]]
    assert not failed, failed
    for r in rows:
        assert set(r) >= {"id", "title", "section", "euler", "simulated", "modern", "rel_error", "pass"}
    assert [r["id"] for r in rows][:2] == ["E1", "E2"]
    heads = {r["id"].split(".")[0] for r in rows}
    assert heads >= {f"E{k}" for k in range(1, 14)}, sorted(heads)
    for r in rows:  # no NaN or infinity reaches the JSON: a missing value is null
        assert r["rel_error"] is not None and r["rel_error"] <= r["tolerance"], r
    assert code == 0


def test_show_on_an_address_it_cannot_listen_on_names_it():
    """`run.show(port=...)` in a notebook: refused by name at once (it printed viser's traceback
    and never returned)."""
    import theoria as th

    run = th.scenario("free-tumble").simulate(duration=1)
    with pytest.raises(ParameterError, match=r"^port=99999: a whole number from 0 to 65535$"):
        run.show(port=99999, block=False)
    with pytest.raises(ParameterError, match=r"^host=999\.1\.1\.1: an address of this machine"):
        run.show(host="999.1.1.1", block=False)


def test_a_negative_seed_is_refused_before_the_sweep(cli, tmp_path):
    out = tmp_path / "s.zarr"
    code, _, err = cli("sweep", "free-tumble", "--grid", "duration=1:2:3", "--seed", "-1", "--out", str(out))
    assert code == 2 and err.strip() == "theoria: error: --seed=-1: a whole number ≥ 0", err  # was numpy's traceback
    assert not out.exists()


def test_version_and_python_dash_m(cli_process):
    import theoria

    code, out, _ = cli_process("--version")
    assert code == 0 and out.strip() == f"theoria {theoria.__version__}"
    import subprocess
    import sys

    p = subprocess.run([sys.executable, "-m", "theoria", "--version"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and p.stdout.strip() == f"theoria {theoria.__version__}", p.stderr


def test_the_advertised_range_is_the_one_enforced():
    """`theoria list --json` and sc.parameters say what a value may be: the shortest run the
    Earth scenes accept is their parameter's minimum (they advertised (0, …] and refused below
    0.05 and 100 years)."""
    import theoria as th

    for name, lo in (("earth", 0.05), ("earth-long-view", 100.0)):
        p = th.scenario(name).param("years")
        assert p.minimum == lo and not p.exclusive_min
        with pytest.raises(ParameterError):
            th.scenario(name).resolve({"years": lo * 0.99})
        th.scenario(name).resolve({"years": lo})


def test_values_a_user_did_not_mean_as_numbers_are_refused():
    """From Python: a set has no order (omega0={3, 2, 1} ran as (1, 2, 3)) and True is not a step
    (it ran as 1.0): refused by name."""
    import theoria as th

    sc = th.scenario("free-tumble")
    for kw, needle in (({"omega0": {3.0, 2.0, 1.0}}, "in order"), ({"step": True}, "a number"),
                       ({"duration": False}, "a number"), ({"omega0": (1.0, True, 2.0)}, "a number")):
        with pytest.raises(ParameterError, match=needle):
            sc.resolve(kw)


def test_numpy_complex_numbers_and_bytes_are_read_as_a_python_value_would_be():
    """float() of a numpy complex dropped the imaginary part with only a warning (2+3j ran as 2,
    where Python's own 2+3j is refused); float() of b"1_0" read 10 where the text "1_0" is refused."""
    import warnings

    import numpy as np
    import theoria as th

    sc = th.scenario("middle-axis-flip")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning on the way to the refusal
        for kw in ({"spin": np.complex128(2 + 3j)}, {"spin": np.array(2 + 0j)}, {"spin": 2 + 3j},
                   {"inertia": np.array([5 + 1j, 10, 13])}, {"spin": b"1_0"}):
            with pytest.raises(ParameterError, match="a number"):
                sc.resolve(kw)
    assert sc.resolve({"spin": b"2.5", "inertia": np.array([5, 10, 13], np.int64)})["spin"] == 2.5


def test_numbers_as_people_and_the_panel_write_them_are_taken():
    """The panel writes "−0.5" (a true minus) and "2.5 × 10⁶"; copied back into a field, both were
    refused as not a number. Taken exactly, as the Python literals say; a comma is still not a
    decimal point (it separates a vector's components)."""
    from theoria.app.format import human_number

    p = Param("x", 0.0, -1e30, 1e30)
    for text, want in [("−0.5", -0.5), ("2.5 × 10⁶", 2.5e6), ("2.5×10^6", 2.5e6), ("1 x 10^-3", 1e-3),
                       ("−2.796 × 10⁻¹¹", -2.796e-11), ("10⁻³", 1e-3), (" 7 ", 7.0), ("1e-3", 1e-3)]:
        assert p.parse(text) == want, text
    for v in (2.5e6, -2.796e-11, 0.01477, -0.5, 1.234e-7):  # what the panel shows reads back
        assert p.parse(human_number(v)) == v
    assert Param("v", (0, 0, 0), -10, 10, kind="vec3").parse("1, −0.5, 2.5 × 10⁰") == (1.0, -0.5, 2.5)
    assert p.parse("10") == 10.0  # ten, not a power of it
    for text in ("1,5", "abc", "2.5 × 10", "× 10⁶"):
        with pytest.raises(ParameterError):
            p.parse(text)


def test_bare_theoria_lists_what_there_is_to_do(capsys):
    """`theoria` alone said "the following arguments are required: cmd" and nothing of the commands."""
    from theoria.app.cli import main

    assert main([]) == 2
    err = capsys.readouterr().err
    assert all(c in err for c in ("serve", "run", "record", "export", "replay", "sweep", "check", "bench")), err


def test_a_whole_number_given_as_text_is_read_exactly():
    """Counts and seeds typed as text went through a float: a twenty-digit seed came back as another
    number (…891 as …168), and bytes were read as text ("1_0" as 10)."""
    from theoria.physics.params import whole_number

    assert whole_number("12345678901234567891") == 12345678901234567891
    assert whole_number("9007199254740993") == 9007199254740993  # 2⁵³ + 1, which a float cannot hold
    assert whole_number(" +42 ") == 42 and whole_number("1e3") == 1000
    for bad in (b"1_0", bytearray(b"10"), "1_0", "２", "2.5", True):
        with pytest.raises(ValueError):
            whole_number(bad)


def test_a_choice_is_taken_in_any_case_and_duration_points_to_the_scenarios_own_length(cli):
    from theoria.scenarios import get

    assert get("moon").param("start").parse("DE421") == "de421"
    assert get("earth-long-view").param("model").parse(" Full ") == "full"
    with pytest.raises(ParameterError, match="did you mean 'de421'"):
        get("moon").param("start").parse("de42")
    code, _, err = cli("run", "syzygy", "--duration", "1")
    assert code == 2 and "its length is --set duration_yr=" in err
