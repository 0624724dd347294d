"""`theoria sweep` and `Scenario.sweep`: the grid spec refused before any work, a sweep killed midway
and resumed without recomputing its finished chunks, the same sweep on a separately started Dask
scheduler with two workers (loopback only), Parquet out, the map a class clicks, `run --out`."""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import theoria as th
from theoria.app import sweep as sw

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
THEORIA = [sys.executable, "-m", "theoria.app.cli"]
# libration-eccentric made cheap: one orbit at 50 steps (the forced-solution search dominates)
CHEAP = ["--set", "orbits=1", "--set", "steps_per_orbit=50", "--set", "free_zeta0_deg=1"]


def cli(*args, timeout=600, **kw):
    return subprocess.run([*THEORIA, *args], capture_output=True, text=True, timeout=timeout, cwd=ROOT, **kw)


# ----------------------------------------------------------------------- refused before any work

@pytest.mark.slow  # a theoria process per case (the sweep's imports take seconds each)
@pytest.mark.parametrize("spec, names", [
    ("nonsense=0:1:3", ["nonsense", "unknown parameter", "eccentricity"]),
    ("eccentricity=0:0.9:3", ["eccentricity", "0.9", "[0, 0.5]"]),
    ("eccentricity=0:0.5:0", ["--grid", "count must be at least 1"]),
    ("eccentricity=0:0.5:1", ["--grid", "both ends only when they are equal"]),  # it kept 0 and dropped 0.5
    ("eccentricity=0:0.5", ["--grid", "name=start:stop:count"]),
    ("eccentricity=a:b:3", ["--grid", "name=start:stop:count"]),
    ("eccentricity=0:0.5:2.5", ["--grid", "whole number"]),
    ("eccentricity", ["--grid", "name=start:stop:count"]),
    ("steps_per_orbit=50:60:4", ["steps_per_orbit", "whole numbers"]),
])
def test_bad_grid_exits_2_with_one_line_before_any_work(tmp_path, spec, names):
    out = tmp_path / "m.zarr"
    r = cli("sweep", "libration-eccentric", "--grid", spec, "--out", str(out), timeout=120)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("theoria: error: "), r.stderr
    for n in names:
        assert n in lines[0], (n, lines[0])
    assert not out.exists()  # nothing was written: no work began


def test_grid_and_random_bounds_are_read_as_a_person_writes_them():
    """A count written "1e1" was refused as not a whole number, and bounds copied from the panel
    ("−0.5" with a true minus, "2.5 × 10⁻¹") as not matching the form; they are the same numbers
    as "10", "-0.5" and "0.25" (numpy's own linspace and the parameter's range decide the rest)."""
    from theoria.app.sweep import parse_grid, parse_random
    from theoria.physics.errors import ParameterError
    from theoria.scenarios import get

    sc = get("libration-eccentric")
    a = parse_grid(sc, "eccentricity=0:2.5 × 10⁻¹:1e1")
    assert np.array_equal(a.values, np.linspace(0.0, 0.25, 10))
    b = parse_grid(sc, "free_zeta0_deg=−0.5:0.5:3")
    assert np.array_equal(b.values, [-0.5, 0.0, 0.5])
    assert len(parse_grid(sc, "eccentricity=0:0.5:1.5e1").values) == 15
    r = parse_random(sc, "free_zeta0_deg=−0.5:0.5", 200, np.random.default_rng(0))
    assert r.values.min() >= -0.5 and r.values.max() <= 0.5 and r.values.min() < 0
    for bad in ("eccentricity=0:0.5:1e9", "eccentricity=0:0.5:1.25e1", "eccentricity=0:0.5:2.5"):
        with pytest.raises(ParameterError) as e:
            parse_grid(sc, bad)
        assert "--grid" in str(e.value)


@pytest.mark.parametrize("spec, says", [
    ("eccentricity=0.1,0.2,0.1", "each value once (0.1 given more than once)"),
    ("eccentricity=0.1,0.2,0.20", "each value once (0.2 given more than once)"),  # the same number
    ("eccentricity=0.1:0.1:3", "start and stop that differ"),
    ("eccentricity=0:0.5:1_0", "count must be a whole number"),  # Python's float() reads 10
    ("eccentricity=0,٠.٢", "eccentricity=٠.٢: a number"),  # Arabic-Indic digits: float() reads 0.2
])
def test_a_grid_runs_each_value_once_and_reads_ascii_numbers_only(spec, says):
    """A grid with a value twice ran it twice and gave the store a coordinate that xarray's .sel
    cannot select by; "1_0" and other scripts' digits were read as numbers by Python's float()."""
    from theoria.app.sweep import parse_grid
    from theoria.physics.errors import ParameterError
    from theoria.scenarios import get

    with pytest.raises(ParameterError) as e:
        parse_grid(get("libration-eccentric"), spec)
    assert says in str(e.value), str(e.value)


@pytest.mark.parametrize("name, metric, said", [
    ("free-tumble", "nope", "--metrics=nope: not a metric of free-tumble (`theoria run free-tumble --json` lists them)"),
    ("libration-eccentric", "free_perod", "did you mean 'free_period'?"),
])
def test_a_name_no_metric_could_have_is_refused_before_any_work(tmp_path, monkeypatch, name, metric, said):
    """`--metrics nope` showed five seconds of a progress bar (a local cluster starting, the first
    runs) before the error. Every metric has a unit, declared or in its name: a name with neither
    is refused at once, before a cluster is asked for, and nothing is written."""
    def no_cluster(*a, **kw):
        raise AssertionError("a cluster was started")

    monkeypatch.setattr(sw, "_client", no_cluster)
    with pytest.raises(th.ParameterError) as e:
        sw.run_sweep(th.scenario(name), grid={"orbits" if name != "free-tumble" else "duration": (1, 2, 2)},
                     metrics=metric, out=str(tmp_path / "m.zarr"), progress=False)
    assert said in str(e.value)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow  # a local cluster starts before the first runs say which metrics there are
@pytest.mark.parametrize("suffix", ["zarr", "parquet"])
def test_a_metric_no_run_reports_names_the_metrics_and_leaves_nothing(tmp_path, suffix):
    """`--metrics` with a name the scenario's runs do not report: known only once the first runs
    are back; one line naming the metrics they do report (the list was empty: it held only the
    asked-for ones), exit 2, and nothing of the sweep on disk (a partial result was left)."""
    out = tmp_path / f"m.{suffix}"
    # (a name that could be a metric, a time in seconds: a name no metric could have is refused
    # before the cluster starts, test_a_name_no_metric_could_have_is_refused_before_any_work)
    r = cli("sweep", "free-tumble", "--grid", "duration=1:2:3", "--workers", "1", "--metrics", "nosuch_s",
            "--out", str(out), "--quiet", timeout=300)
    assert r.returncode == 2, r.stderr
    line = r.stderr.strip().splitlines()[-1]
    assert line.startswith("theoria: error: --metrics=nosuch_s: not a metric of free-tumble; its metrics: "), line
    assert "energy_rel_drift" in line and "polhode_period_s" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.slow  # three sweeps, each with its local cluster
def test_a_finished_sweep_is_not_replaced_by_a_repeated_command(tmp_path):
    """The same command again (up-arrow, Enter) replaced hours of results without a word: it is
    refused, the result untouched, unless --resume (complete it) or --force (replace it)."""
    out = tmp_path / "s.zarr"
    args = ["sweep", "free-tumble", "--grid", "duration=1:2:3", "--workers", "1", "--out", str(out), "--quiet"]
    assert cli(*args).returncode == 0
    stamp = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    r = cli(*args)
    assert r.returncode == 2 and "add --resume to complete it or --force to replace it" in r.stderr, r.stderr
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == stamp
    assert cli(*args, "--force").returncode == 0


def test_bad_specs_from_python_and_the_names_the_scenario_uses():
    sc = th.scenario("libration-eccentric")
    # the issue's `e=` is accepted as the unique beginning of the scenario's `eccentricity`
    plan = sw.make_plan(sc, grid=["e=0:0.5:64", "asymmetry=0.01:0.3:64"])
    assert plan.dims == ("eccentricity", "asymmetry") and plan.shape == (64, 64)
    assert np.allclose(plan.grid[0].values, np.linspace(0, 0.5, 64))
    assert plan.batched  # both may vary across one batch of libration-eccentric
    with pytest.raises(th.ParameterError, match="more than one parameter begins with .o."):
        sw.make_plan(sc, grid=["o=1:2:2"])  # orbital_rate or orbits
    with pytest.raises(th.ParameterError, match="swept twice"):
        sw.make_plan(sc, grid=["e=0:0.1:2", "eccentricity=0:0.2:2"])
    with pytest.raises(th.ParameterError, match="is swept"):
        sw.make_plan(sc, grid={"eccentricity": (0, 0.1, 2)}, fixed={"eccentricity": 0.2})
    with pytest.raises(th.ParameterError, match="--samples"):
        sw.make_plan(sc, random={"free_zeta0_deg": (-5, 5)})
    with pytest.raises(th.ParameterError, match="free_zeta0_deg"):
        sw.make_plan(sc, random={"free_zeta0_deg": (-5, 500)}, samples=4)
    with pytest.raises(th.ParameterError, match="^out=x.nc: a name ending in .zarr"):  # the keyword, from Python
        sc.sweep(grid={"eccentricity": (0, 0.1, 2)}, out="x.nc")
    # grid × random: a sample dimension with the same draws at every grid point
    plan = sw.make_plan(sc, grid={"eccentricity": (0, 0.1, 3)}, random={"free_zeta0_deg": (-5, 5)}, samples=10, seed=3)
    assert plan.dims == ("eccentricity", "sample") and plan.shape == (3, 10)
    z = plan.random[0].values
    assert np.all((z >= -5) & (z <= 5)) and len(np.unique(z)) == 10
    pts = plan.points((slice(1, 3), slice(0, 10)))
    assert np.allclose(pts["free_zeta0_deg"], np.tile(z, 2)) and np.allclose(pts["eccentricity"], np.repeat([0.05, 0.1], 10))


# ----------------------------------------------------------------------------- the done criteria

def _finished_chunks(path):
    import zarr

    try:
        st = zarr.open_group(str(path), mode="r")["status"]
    except Exception:  # noqa: BLE001 — not created yet
        return None, None
    plan_chunks = st.chunks
    a = st[...]
    done = 0
    for idx in np.ndindex(*[-(-n // c) for n, c in zip(a.shape, plan_chunks)]):
        reg = tuple(slice(i * c, (i + 1) * c) for i, c in zip(idx, plan_chunks))
        done += bool(np.all(a[reg] != 0))
    return done, int(np.prod([-(-n // c) for n, c in zip(a.shape, plan_chunks)]))


@pytest.mark.slow
def test_ctrl_c_while_the_local_cluster_starts_stops_the_sweep(tmp_path):
    """The first seconds of a sweep start its local cluster; a terminal's Ctrl-C (to the whole
    process group) in that time used to be ignored and the sweep ran to its end, exit 0. Sent at
    several moments: exit 130 each time, and no worker process left behind."""
    import psutil

    for delay in (0.8, 1.2, 1.6, 2.2):
        out = tmp_path / f"s{delay}.parquet"
        p = subprocess.Popen([*THEORIA, "sweep", "free-tumble", "--grid", "step=0.001:0.002:20", "--set", "duration=1000",
                              "--out", str(out), "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             cwd=ROOT, start_new_session=True)
        time.sleep(delay)
        kids = psutil.Process(p.pid).children(recursive=True)
        os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate(timeout=120)
        gone, alive = psutil.wait_procs(kids, timeout=30)
        assert not alive, (delay, [q.pid for q in alive])
        assert p.returncode == 130 and "Traceback" not in err, (delay, p.returncode, err[-500:])


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, "ctrl-c"])
def test_sweep_killed_midway_resumes_without_recomputing_finished_chunks(tmp_path, sig):
    """SIGINT or SIGTERM to the sweep, or SIGINT to its whole process group as a terminal's Ctrl-C
    sends it (the local cluster's workers too: they ignore it, the sweep stops them)."""
    out = tmp_path / "m.zarr"
    # (B − A)/C = 0.333 is refused at once (Euler's resonance A² = 2N): a column of refused runs
    args = ["sweep", "libration-eccentric", "--grid", "e=0:0.2:12", "--grid", "asymmetry=0.01,0.1,0.2,0.333",
            "--out", str(out), "--chunk", "2", "--workers", "2", *CHEAP]
    p = subprocess.Popen([*THEORIA, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
                         start_new_session=True)
    t_end = time.monotonic() + 400
    done = None
    while time.monotonic() < t_end and p.poll() is None:
        done, total = _finished_chunks(out)
        if done is not None and done >= 2:
            break
        time.sleep(0.2)
    assert p.poll() is None, "the sweep finished before it could be interrupted: " + p.stderr.read()
    # the local cluster (scheduler, nannies, workers, their HTTP servers) listens on loopback only
    import psutil

    for q in [psutil.Process(p.pid), *psutil.Process(p.pid).children(recursive=True)]:
        for c in q.net_connections(kind="inet"):
            if c.status == psutil.CONN_LISTEN:
                assert c.laddr.ip in ("127.0.0.1", "::1"), (q.cmdline()[:3], c.laddr)
    if sig == "ctrl-c":
        os.killpg(p.pid, signal.SIGINT)
    else:
        p.send_signal(sig)
    _, err = p.communicate(timeout=120)
    assert p.returncode == (143 if sig == signal.SIGTERM else 130), err
    # stderr is a pipe here: the summary alone, no frame of the progress bar (a terminal's)
    assert "Traceback" not in err and "runs/s" not in err and "interrupted" in err, err
    done, total = _finished_chunks(out)
    assert total == 24 and 2 <= done < total, (done, total)
    import xarray as xr

    before = xr.open_zarr(out, consolidated=False).load()
    kept = before["status"].values != 0
    # resume: only the unfinished chunks are computed (counted by the sweep and recorded in the store)
    r = cli(*args, "--resume", "--json", "--quiet")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["chunks_done_before"] == done and s["chunks_computed"] == total - done, s
    assert s["complete"] and not s["found_complete"] and not s["interrupted"] and s["kept"] == "", s
    ds = xr.open_zarr(out, consolidated=False)
    sessions = ds.attrs["sessions"]
    assert [x["chunks_computed"] for x in sessions] == [done, total - done]
    assert sessions[0]["interrupted"] and not sessions[1]["interrupted"]
    # the finished chunks are untouched, the rest filled
    for name in ("forced_amplitude_rad", "status"):
        assert np.array_equal(ds[name].values[kept], before[name].values[kept], equal_nan=True)
    st = ds["status"].values
    # every run finished: ok, and refused (with why) where (B − A)/C = 0.333
    assert np.all(st[:, :3] == sw.STATUS["ok"]) and np.all(st[:, 3] == sw.STATUS["refused"])
    for i in range(4):
        assert "1/3" in ds.attrs["messages"][f"{i},3"] and np.isnan(ds["forced_amplitude_rad"].values[i, 3])
    # named dimensions, units, the fixed parameters and the version
    assert ds["forced_amplitude_rad"].dims == ("eccentricity", "asymmetry")
    assert ds["eccentricity"].attrs["units"] == "1" and "eccentricity" in ds["eccentricity"].attrs["long_name"]
    assert ds.attrs["fixed_parameters"]["orbital_rate"] == {"value": 1.0, "unit": "rad/unit"}
    assert ds.attrs["theoria_version"] == th.__version__
    # a resume of a complete sweep computes nothing
    r = cli(*args, "--resume", "--json", "--quiet")
    s = json.loads(r.stdout)
    assert s["chunks_computed"] == 0 and s["complete"] and s["found_complete"], s
    # the values are the scenario's own, run by run (one point, recomputed here)
    sc = th.scenario("libration-eccentric")
    i, j = 1, 2
    m = sc.simulate(eccentricity=float(ds.eccentricity[i]), asymmetry=float(ds.asymmetry[j]), orbits=1,
                    steps_per_orbit=50, free_zeta0_deg=1).metrics
    assert ds["forced_amplitude_rad"].values[i, j] == pytest.approx(m["forced_amplitude_rad"], rel=1e-9)
    # a resume of another sweep into the same file is refused, naming what differs
    r = cli("sweep", "libration-eccentric", "--grid", "e=0:0.3:4", "--grid", "asymmetry=0.01,0.1,0.2,0.333",
            "--out", str(out), "--resume", *CHEAP)
    assert r.returncode == 2 and "different sweep" in r.stderr and "grid" in r.stderr


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_the_same_sweep_on_a_separately_started_scheduler_with_two_workers(tmp_path):
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    loop = ["--dashboard-address", "127.0.0.1:0"]  # every server of the cluster on loopback only
    procs = [subprocess.Popen([str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", str(port), *loop],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)]
    try:
        for _ in range(2):
            procs.append(subprocess.Popen([str(BIN / "dask"), "worker", addr, "--nthreads", "1", "--host", "127.0.0.1",
                                           *loop, "--name", f"w{len(procs)}"],
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env))
        from distributed import Client

        t_end = time.monotonic() + 120
        while True:
            try:
                with Client(addr, timeout=5) as c:
                    if len(c.scheduler_info()["workers"]) == 2:
                        break
            except OSError:
                pass
            assert time.monotonic() < t_end, "the scheduler and two workers did not come up"
            time.sleep(1)
        out = tmp_path / "m.zarr"
        r = cli("sweep", "libration-eccentric", "--grid", "e=0:0.2:3", "--grid", "asymmetry=0.01:0.2:2",
                "--out", str(out), "--cluster", addr, "--chunk", "2", "--json", "--quiet", *CHEAP)
        assert r.returncode == 0, r.stderr
        s = json.loads(r.stdout)
        assert s["cluster"] == f"scheduler {addr}" and s["chunks_computed"] == 3
        assert s["complete"] and s["kept"] == "", s  # a finished sweep keeps no parts aside
        import xarray as xr

        ds = xr.open_zarr(out, consolidated=False)
        assert np.all(ds.status.values == sw.STATUS["ok"])
        # both workers took part (each chunk records nothing about its worker; the scheduler does)
        with Client(addr, timeout=5) as c:
            assert len(c.scheduler_info()["workers"]) == 2
        # the same numbers as a local single run
        m = th.scenario("libration-eccentric").simulate(eccentricity=0.1, asymmetry=0.2, orbits=1, steps_per_orbit=50,
                                                        free_zeta0_deg=1).metrics
        assert float(ds.forced_amplitude_rad.sel(eccentricity=0.1, asymmetry=0.2)) == pytest.approx(
            m["forced_amplitude_rad"], rel=1e-9)
        # nothing of the cluster listens beyond loopback
        import psutil

        for p in procs:
            for q in [psutil.Process(p.pid), *psutil.Process(p.pid).children(recursive=True)]:
                for c in q.net_connections(kind="inet"):
                    if c.status == psutil.CONN_LISTEN:
                        assert c.laddr.ip in ("127.0.0.1", "::1"), (q.cmdline()[:3], c.laddr)
        # and a bad address is one line, exit 2
        r = cli("sweep", "libration-eccentric", "--grid", "e=0:0.2:2", "--out", str(tmp_path / "x.zarr"),
                "--cluster", "tcp://127.0.0.1:1", *CHEAP, timeout=120)
        assert r.returncode == 2 and "--cluster" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()


# ------------------------------------------------------------------ Python, Parquet, the map

@pytest.mark.slow
def test_python_sweep_batched_to_zarr_and_parquet_and_the_map_replays_a_pixel(tmp_path):
    from distributed import Client, LocalCluster

    sc = th.scenario("hyperion")
    fixed = dict(n_starts=4, n_orbits=100, probe_orbits=1)
    grid = {"eccentricity": (0.0, 0.2, 3), "probe_rate": [0.5, 1.0, 1.45, 2.5]}
    import datetime

    with LocalCluster(n_workers=1, threads_per_worker=1, host="127.0.0.1", dashboard_address=None) as lc, Client(lc) as c:
        before = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0)
        ds = sc.sweep(grid=grid, out=tmp_path / "h.zarr", cluster=c, **fixed)
        after = datetime.datetime.now(datetime.timezone.utc)
        df = sc.sweep(grid=grid, out=tmp_path / "h.parquet", cluster=c, **fixed)
    assert ds.attrs["sessions"][0]["path"] == "batched"
    # when it started (it was when it ended): no later than the sweep's own length before the end
    started = datetime.datetime.fromisoformat(ds.attrs["sessions"][0]["started"])
    assert before <= started <= after - datetime.timedelta(seconds=ds.attrs["sessions"][0]["seconds"]) \
        + datetime.timedelta(seconds=1)
    assert ds["lyapunov_probe_per_orbit"].dims == ("eccentricity", "probe_rate")
    assert ds["probe_rate"].attrs["units"] == "n"
    # every metric with the scenario's unit ("1" for a pure number), in both stores
    import pyarrow.parquet as pq
    table_units = json.loads(pq.read_schema(tmp_path / "h.parquet").metadata[b"units"])
    metrics = [v for v in ds.data_vars if v != "status"]
    assert "lyapunov_probe_per_unit_time" in metrics
    for name in metrics:
        assert ds[name].attrs["units"] == table_units[name] == (sc.metric_unit(name) or "1"), name
    assert table_units["lyapunov_probe_per_orbit"] == "1/orbit" and table_units["lyapunov_probe_per_unit_time"] == "n"
    assert table_units["probe_rate"] == "n"
    import pandas as pd
    # as `run --out F.parquet` gives them: pandas reads the units into the frame's attrs
    assert pd.read_parquet(tmp_path / "h.parquet").attrs["units"] == table_units
    # the flat table: one row per run, the same numbers
    assert len(df) == 12 and set(df.columns) >= {"eccentricity", "probe_rate", "status", "lyapunov_probe_per_orbit"}
    for _, row in df.iterrows():
        v = float(ds["lyapunov_probe_per_orbit"].sel(eccentricity=row.eccentricity, probe_rate=row.probe_rate))
        assert v == row.lyapunov_probe_per_orbit
    assert not (tmp_path / "h.parquet.parts").exists()
    # the map: 2-D over the two swept parameters, axes with names and units, any pixel replayable
    m = sw.open_map(tmp_path / "h.zarr", "lyapunov_probe_per_orbit")
    assert m.values.shape == (3, 4) and (m.y, m.x) == ("eccentricity", "probe_rate")
    assert m.x_unit == "n" and m.metric_unit == "1/orbit" and np.allclose(m.y_values, [0, 0.1, 0.2])
    vals = m.run_values(2, 2)
    assert vals["eccentricity"] == 0.2 and vals["probe_rate"] == 1.45 and vals["n_orbits"] == 100
    r = sc.simulate(**vals)
    # the same run to the last digits, not bit for bit: numba's code compiled afresh and the same
    # code loaded from its cache differ in the last bit here (1.076340449845408 against
    # 1.0763404498454086, measured), and on a fresh install (CI) one process compiles, another loads
    assert r.metrics["lyapunov_probe_per_orbit"] == pytest.approx(m.values[2, 2], rel=1e-12, abs=0)
    # e = 0: no chaos anywhere; e = 0.2 between the 1:1 and 3:2 islands: chaotic (WPM 1984)
    assert np.all(m.values[0] < 0.05) and m.values[2, 2] > 0.1
    with pytest.raises(th.ParameterError, match="metric"):
        sw.open_map(tmp_path / "h.zarr", "nonsense")


@pytest.mark.slow
def test_run_out_writes_the_samples_as_parquet_and_csv(tmp_path):
    import pandas as pd

    for ext in ("parquet", "csv"):
        out = tmp_path / f"r.{ext}"
        r = cli("run", "libration-circular", "--set", "periods=1", "--set", "steps_per_period=100", "--out", str(out),
                timeout=300)
        assert r.returncode == 0, r.stderr
        df = pd.read_parquet(out) if ext == "parquet" else pd.read_csv(out)
        ref = th.scenario("libration-circular").simulate(periods=1, steps_per_period=100).to_dataframe()
        assert list(df.columns) == list(ref.columns) and len(df) == len(ref)
        assert np.allclose(df["zeta_rad"], ref["zeta_rad"], rtol=1e-15, atol=1e-15)
        if ext == "parquet":  # every column's unit, as a sweep's table keeps them (pandas: df.attrs)
            import pyarrow.parquet as pq

            assert json.loads(pq.read_schema(out).metadata[b"units"]) == ref.attrs["units"] == df.attrs["units"]
            assert ref.attrs["units"]["zeta_dot"] == "rad/unit" and len(ref.attrs["units"]) == len(ref.columns)
    r = cli("run", "libration-circular", "--out", str(tmp_path / "r.txt"), timeout=120)
    assert r.returncode == 2 and "--out" in r.stderr and ".parquet or .csv" in r.stderr


def _tree(path):
    """A file's bytes, or a folder's files' bytes by relative path."""
    if path.is_file():
        return path.read_bytes()
    return {str(f.relative_to(path)): f.read_bytes() for f in sorted(path.rglob("*")) if f.is_file()}


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["parquet", "zarr"])
def test_a_new_sweep_stopped_before_its_first_chunk_leaves_nothing(tmp_path, kind):
    """Ctrl-C once the new sweep's store was made but before any chunk finished: the store stayed,
    "finished chunks kept in a.zarr (--resume continues)" was printed with none finished, and the
    same command run again was refused ("add --resume … or --force"). Now nothing is left, the
    line says so, and the command run again just runs."""
    out = tmp_path / f"a.{kind}"
    made = tmp_path / ("a.parquet.parts" if kind == "parquet" else "a.zarr")
    args = ["sweep", "free-tumble", "--grid", "step=0.001:0.002:2", "--set", "duration=1e5", "--workers", "1",
            "--max-steps", "none", "--out", str(out), "--quiet"]
    p = subprocess.Popen([*THEORIA, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    t_end = time.monotonic() + 300
    while time.monotonic() < t_end and p.poll() is None and not made.exists():
        time.sleep(0.05)
    time.sleep(0.5)  # the chunks are sent: each takes minutes
    assert p.poll() is None, p.stderr.read()
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert err.strip().endswith("interrupted before any chunk finished: nothing written"), err
    assert sorted(f.name for f in tmp_path.iterdir()) == [], err
    r = cli(*args[:4], "--set", "duration=2", "--out", str(out), "--quiet")
    assert r.returncode == 0 and "2 ok" in r.stderr, r.stderr


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["parquet", "zarr"])
def test_an_interrupted_sweep_with_force_leaves_the_older_result_as_it_was(tmp_path, kind):
    """--force replaces an older table or store only once the new one is whole: interrupted
    half-way, the older one is byte for byte as it was (it used to be deleted at the start); --resume
    then completes the new sweep and replaces it."""
    out = tmp_path / f"a.{kind}"
    r = cli("sweep", "free-tumble", "--grid", "step=0.01:0.02:2", "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    old = _tree(out)
    args = ["sweep", "free-tumble", "--grid", "step=0.001:0.002:40", "--set", "duration=600", "--chunk", "1",
            "--workers", "2", "--out", str(out), "--quiet"]
    p = subprocess.Popen([*THEORIA, *args, "--force"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         cwd=ROOT)
    # where the new sweep's finished chunks go meanwhile
    kept = tmp_path / ("a.parquet.parts" if kind == "parquet" else "a.zarr.new")

    def chunks_done():
        if kind == "parquet":
            return len(list(kept.glob("part-*.parquet")))
        return len([f for f in (kept / "status").rglob("*") if f.is_file() and f.name != "zarr.json"])

    t_end = time.monotonic() + 300
    while time.monotonic() < t_end and p.poll() is None:
        if kept.is_dir() and chunks_done() >= 2:
            break
        time.sleep(0.1)
    assert p.poll() is None, "finished before it could be interrupted: " + p.stderr.read()
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert _tree(out) == old
    r = cli(*args, "--resume")
    assert r.returncode == 0, r.stderr
    if kind == "parquet":
        import pandas as pd

        assert len(pd.read_parquet(out)) == 40
    else:
        import xarray as xr

        with xr.open_zarr(out, consolidated=False) as ds:
            assert ds.sizes["step"] == 40 and bool((ds["status"] != 0).all())
    assert not kept.exists() and sorted(q.name for q in tmp_path.iterdir()) == [out.name]


@pytest.mark.slow  # a sweep per case, each with its local cluster
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("kind,moment", [("parquet", "in place"), ("zarr", "in place"), ("parquet", "saying so")])
def test_a_stop_once_the_sweep_is_in_place_reports_it_done(tmp_path, sig, kind, moment):
    """Ctrl-C or SIGTERM once the finished sweep has taken the place of --out (replacing an older
    one), or while its last line is written: the result is whole and new, so the sweep says so and
    exits 0. It said "interrupted" (130, 143: the status of a stop that changed nothing) beside the
    new result; a stop in the middle of the parquet join left a half table beside the parts."""
    out = tmp_path / f"a.{kind}"
    r = cli("sweep", "free-tumble", "--grid", "step=0.01:0.02:2", "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    patch = ("import theoria.app.sweep as S\n"
             f"cls = S.{'ParquetWriter' if kind == 'parquet' else 'ZarrWriter'}\n"
             "real = cls.finish\n"
             "def finish(self):\n"
             "    real(self)\n"
             "    print('ready', flush=True)\n"
             "    time.sleep(2)\n"
             "cls.finish = finish\n") if moment == "in place" else (
             "import theoria.app.sweep as S\n"
             "real = S.Summary.line\n"
             "def line(self):\n"
             "    print('ready', flush=True)\n"
             "    time.sleep(2)\n"
             "    return real(self)\n"
             "S.Summary.line = line\n")
    code = ("import sys, time\n" + patch + "from theoria.app.cli import main\n"
            f"sys.exit(main(['sweep', 'free-tumble', '--grid', 'step=0.01:0.02:3', '--out', {str(out)!r}, "
            "'--force', '--workers', '1', '--quiet']))\n")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         cwd=ROOT, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert p.stdout.readline().strip() == "ready"
    p.send_signal(sig)
    _, err = p.communicate(timeout=300)
    assert p.returncode == 0 and "3 ok" in err and "interrupted" not in err, (p.returncode, err[-500:])
    if kind == "parquet":
        import pandas as pd

        assert len(pd.read_parquet(out)) == 3
    else:
        import xarray as xr

        with xr.open_zarr(out, consolidated=False) as ds:
            assert ds.sizes["step"] == 3 and bool((ds["status"] != 0).all())
    assert sorted(q.name for q in tmp_path.iterdir()) == [out.name]


@pytest.mark.parametrize("out,why", [("d.parquet", "a file name: this is a directory"),
                                     ("a" * 300 + ".zarr", "a path this system takes (File name too long)")])
def test_an_out_path_the_sweep_cannot_write_is_refused_before_it_runs(tmp_path, out, why):
    (tmp_path / "d.parquet").mkdir()
    r = cli("sweep", "free-tumble", "--grid", "step=0.01:0.02:2", "--out", str(tmp_path / out), "--force")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and why in r.stderr, r.stderr
    assert sorted(q.name for q in tmp_path.iterdir()) == ["d.parquet"] and not any((tmp_path / "d.parquet").iterdir())


@pytest.mark.slow  # sweeps, each with its local cluster
def test_resume_and_force_keep_every_finished_result(tmp_path):
    """Found by probing --resume and --force: a Parquet table was replaced by another sweep's
    with --resume (no --force); a Zarr sweep finished in OUT.new/ while OUT was gone crashed
    (FileNotFoundError) on every --resume; a user's own OUT.old was deleted by --force."""
    small = ["sweep", "free-tumble", "--grid", "step=0.01:0.02:2", "--quiet"]
    other = ["sweep", "free-tumble", "--grid", "step=0.05:0.07:3", "--quiet"]
    p = tmp_path / "p.parquet"
    assert cli(*small, "--out", str(p)).returncode == 0
    table = p.read_bytes()
    r = cli(*other, "--out", str(p), "--resume")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "a different sweep" in r.stderr, r.stderr
    r = cli(*small, "--out", str(p), "--resume")  # the same sweep: done, nothing run, nothing written
    assert r.returncode == 0 and "computed 0 chunks now, 2 were done before" in r.stderr, r.stdout + r.stderr
    assert p.read_bytes() == table
    z = tmp_path / "a.zarr"
    backup = tmp_path / "a.zarr.old"
    backup.mkdir()
    (backup / "mine.txt").write_text("a user's own copy")
    assert cli(*small, "--out", str(z)).returncode == 0
    assert cli(*other, "--out", str(z), "--force").returncode == 0
    assert (backup / "mine.txt").read_text() == "a user's own copy"
    z.rename(tmp_path / "a.zarr.new")  # a finished replacing sweep whose OUT is gone
    r = cli(*other, "--out", str(z), "--resume")
    assert r.returncode == 0, r.stderr
    import xarray as xr

    with xr.open_zarr(z, consolidated=False) as ds:
        assert ds.sizes["step"] == 3 and bool((ds["status"] != 0).all())
    assert sorted(q.name for q in tmp_path.iterdir()) == ["a.zarr", "a.zarr.old", "p.parquet"]


def test_a_zarr_store_cut_short_while_created_is_left_nowhere(tmp_path, monkeypatch):
    """A sweep interrupted while its store was being created left a store without its
    coordinates, which --resume took for one to complete, and swapped in place of a finished sweep
    (its step coordinate all NaN). The store is now made beside its place and renamed there whole."""
    import xarray as xr

    plan = sw.make_plan(th.scenario("free-tumble"), grid=["step=0.01:0.02:2"])
    made = xr.Dataset.to_zarr

    def cut_short(self, store, *a, **k):
        if k.get("mode") == "w":
            made(self[["status"]].drop_vars(list(self.coords)), store, *a, **k)  # the status only, then a Ctrl-C
            raise KeyboardInterrupt
        return made(self, store, *a, **k)

    monkeypatch.setattr(xr.Dataset, "to_zarr", cut_short)
    with pytest.raises(KeyboardInterrupt):
        sw.ZarrWriter(str(tmp_path / "a.zarr"), plan, resume=False)
    assert list(tmp_path.iterdir()) == []


def _wait_for(cond, timeout, p=None):
    t_end = time.monotonic() + timeout
    while time.monotonic() < t_end:
        if cond():
            return True
        if p is not None and p.poll() is not None:
            return False
        time.sleep(0.05)
    return False


@pytest.mark.slow  # five theoria processes and a local cluster
def test_a_second_sweep_on_the_same_out_is_refused_while_the_first_writes(tmp_path):
    """Two sweeps on one OUT at once: a second --force removed the first's OUT.new/ under it and
    wrote its own. While the first runs, a second one — --force, --resume or plain — is refused at
    once, exit 2, one line naming the first's PID and OUT; the first goes on untouched (here until
    Ctrl-C: exit 130, its finished chunks kept for --resume, its lock file gone)."""
    out = tmp_path / "a.zarr"
    assert cli("sweep", "free-tumble", "--grid", "step=0.01:0.02:2", "--out", str(out), "--quiet").returncode == 0
    first = subprocess.Popen([*THEORIA, "sweep", "free-tumble", "--grid", "step=0.001:0.002:40", "--set",
                              "duration=600", "--chunk", "1", "--workers", "1", "--out", str(out), "--force",
                              "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    staging = tmp_path / "a.zarr.new"
    try:
        assert _wait_for(staging.is_dir, 120, first), first.communicate()[1]
        made = staging.stat().st_ino
        for how in (["--force"], ["--resume"], []):
            r = cli("sweep", "free-tumble", "--grid", "step=0.01:0.02:2", "--out", str(out), "--quiet", *how)
            assert r.returncode == 2 and r.stderr.count("\n") == 1, (how, r.returncode, r.stderr)
            assert r.stderr.startswith(f"theoria: error: another sweep (PID {first.pid}) is writing {out}; "), r.stderr
            assert staging.stat().st_ino == made and first.poll() is None, how  # the first's store, the first running
    finally:
        first.send_signal(signal.SIGINT)
        _, err = first.communicate(timeout=120)
    assert first.returncode == 130 and "Traceback" not in err, err
    assert (staging / "status").is_dir()  # its own store, for its --resume
    assert sorted(q.name for q in tmp_path.iterdir()) == ["a.zarr", "a.zarr.new"]  # no lock file left


@pytest.mark.slow  # two sweeps, each with its local cluster
def test_a_sweep_killed_outright_leaves_no_lock(tmp_path):
    """SIGKILL to a sweep and its workers (nothing of it runs its clean-up): the kernel lets its lock
    go, so the next sweep on that OUT runs; the lock file it left is taken over and removed."""
    out = tmp_path / "a.parquet"
    first = subprocess.Popen([*THEORIA, "sweep", "free-tumble", "--grid", "step=0.001:0.002:40", "--set",
                              "duration=600", "--chunk", "1", "--workers", "1", "--out", str(out), "--quiet"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, cwd=ROOT,
                             start_new_session=True)
    lock = Path(sw._lock_path(str(out)))
    try:
        assert _wait_for(lambda: lock.exists() and lock.read_text().strip() == str(first.pid), 120, first)
    finally:
        os.killpg(first.pid, signal.SIGKILL)
        first.wait(timeout=60)
    assert lock.exists()  # left by the killed sweep: a file, no longer a lock
    r = cli("sweep", "free-tumble", "--grid", "step=0.01:0.02:2", "--out", str(out), "--force", "--quiet")
    assert r.returncode == 0, r.stderr
    assert sorted(q.name for q in tmp_path.iterdir()) == [out.name]


@pytest.mark.slow  # a theoria process per moment
def test_ctrl_c_while_the_store_is_created_is_one_line(tmp_path):
    """Ctrl-C while a Zarr sweep writes its new store (zarr writes it from a thread of its own): the
    command printed thousands of lines of zarr's and asyncio's RuntimeError tracebacks after
    'theoria: interrupted'. A grid of 5000 one-run chunks makes the store's creation last about a
    second; Ctrl-C (to the process group, as a terminal sends it) at several moments from the
    moment the store appears on disk: exit 130, the one line, and no half-made store left."""
    for k, delay in enumerate((0.0, 0.1, 0.2, 0.4, 0.6)):
        out = tmp_path / f"s{k}.zarr"
        p = subprocess.Popen([*THEORIA, "sweep", "free-tumble", "--grid", "step=0.001:0.002:5000", "--chunk", "1",
                              "--set", "duration=100", "--out", str(out), "--quiet"], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, cwd=ROOT, start_new_session=True)
        assert _wait_for(lambda: any(tmp_path.glob(f"s{k}.zarr*")), 120, p), p.communicate()[1]
        time.sleep(delay)
        os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate(timeout=120)
        assert p.returncode == 130, (delay, p.returncode, err[-2000:])
        assert "Traceback" not in err and "RuntimeError" not in err, (delay, err[-2000:])
        assert err == "theoria: interrupted\n", (delay, err[-2000:])
        assert not [q.name for q in tmp_path.iterdir() if ".making-" in q.name], delay


def test_a_run_over_the_budget_is_refused_in_a_sweep_not_run():
    """Each run of a sweep is held to the budget every run is (a probe's sweep of free-tumble at
    durations 1e5 and 1e6 s ran 1e8 and 1e9 integrator steps, 859 s of CPU, and wrote them "ok"):
    over it, the run is not run and its status is 'refused' with the budget's message; the
    command's --max-steps / --max-memory set the limits."""
    points = {"duration": np.array([2.0, 1e6])}
    task = {"scenario": "free-tumble", "fixed": {}, "points": points, "metrics": None, "batched": False,
            "threads": None, "limits": {}}
    res = sw.run_chunk(task)
    assert list(res["status"]) == [sw.STATUS["ok"], sw.STATUS["refused"]]
    assert "1e+08 integrator steps" in res["messages"][1] and "max_steps" in res["messages"][1]
    res = sw.run_chunk({**task, "points": {"duration": np.array([2.0])}, "limits": {"max_steps": 100}})
    assert list(res["status"]) == [sw.STATUS["refused"]] and "over the limit of 100" in res["messages"][0]


@pytest.mark.parametrize("name, over, limits", [("libration-eccentric", {"orbits": 200.0}, {"max_steps": 20000}),
                                                 ("tidal-capture", {"orbits": 200000.0, "steps_per_orbit": 512.0}, {})])
def test_the_batched_path_holds_each_run_to_the_same_budget(name, over, limits):
    """Scenarios that advance many bodies together ran every point, however many steps it took: a
    tidal capture of 10⁸ steps that `simulate` refuses was written "ok" (27.7 s), and --max-steps
    changed nothing. Each point is held to its own budget first: the refused one gets status 3 and
    the message `simulate` gives, the others their metrics as before."""
    sc = th.scenario(name)
    assert sc.batch is not None
    fixed = {k: v for k, v in sc.resolve({}).items() if k not in over}  # as a plan fixes what is not swept
    points = {k: np.array([float(sc.resolve({})[k]) if k != "orbits" else 20.0, v]) for k, v in over.items()}
    assert set(points) <= set(sc.batch.sweepable), sc.batch.sweepable
    task = {"scenario": name, "fixed": fixed, "points": points, "metrics": None, "batched": True, "threads": None,
            "limits": limits}
    res = sw.run_chunk(task)
    assert list(res["status"]) == [sw.STATUS["ok"], sw.STATUS["refused"]], res["messages"]
    with pytest.raises(th.BudgetExceeded) as e:
        sc.simulate(**{k: v[1] for k, v in points.items()}, **limits)
    assert res["messages"][1] == str(e.value)
    one = sc.simulate(**{k: v[0] for k, v in points.items()})
    for k, v in res["metrics"].items():
        assert np.isnan(v[1]) and np.allclose(v[0], one.metrics[k], rtol=1e-9, atol=1e-15, equal_nan=True), k
    # the command's limit applies too
    res = sw.run_chunk({**task, "limits": {"max_steps": 10}})
    assert list(res["status"]) == [sw.STATUS["refused"]] * 2 and "over the limit of 10 " in res["messages"][0]


def test_a_sweep_description_left_empty_is_one_line_on_resume(tmp_path):
    """A full disk cut the sweep's description (OUT.parts/_sweep.json) to 0 bytes; --resume then
    ended in a JSONDecodeError traceback. It is written whole now, and one that cannot be read is
    refused in one line naming it (written whole: app/files.py, tested in test_safety.py)."""
    sc = th.scenario("free-tumble")
    out = str(tmp_path / "s.parquet")
    plan = sw.make_plan(sc, grid={"step": (0.001, 0.01, 2)})
    sw.ParquetWriter(out, plan, resume=False)
    spec = tmp_path / "s.parquet.parts" / "_sweep.json"
    assert json.loads(spec.read_text())["scenario"] == "free-tumble"
    spec.write_text("")
    with pytest.raises(th.ParameterError) as e:
        sw.ParquetWriter(out, sw.make_plan(sc, grid={"step": (0.001, 0.01, 2)}), resume=True)
    assert "_sweep.json" in str(e.value) and "--force" in str(e.value)


@pytest.mark.parametrize("kind", ["parquet", "zarr"])
def test_a_sweep_resumed_with_another_budget_is_refused(tmp_path, kind):
    """Each run's budget (--max-steps, --max-memory) decides which runs are refused (status 3):
    resumed with another, a sweep mixed runs refused under one with runs made under the other, and
    nothing in the store told them apart. The budget is part of what identifies a sweep; a store
    written before it was recorded resumes as before."""
    sc = th.scenario("free-tumble")
    out = str(tmp_path / f"s.{kind}")
    writer = sw.ZarrWriter if kind == "zarr" else sw.ParquetWriter

    def plan(**limits):
        p = sw.make_plan(sc, grid={"step": (0.001, 0.01, 2)})
        p.limits = limits
        return p

    writer(out, plan(), resume=False)
    writer(out, plan(max_steps=sw.MAX_STEPS, max_memory=sw.MAX_MEMORY), resume=True)  # the defaults, said
    for limits, named in (({"max_steps": 1e8}, "max_steps"), ({"max_memory": None}, "max_memory")):
        with pytest.raises(th.ParameterError) as e:
            writer(out, plan(**limits), resume=True)
        assert f"it differs in: {named})" in str(e.value)
    # a store from before budgets were recorded
    if kind == "zarr":
        import zarr

        g = zarr.open_group(out, mode="r+")
        old = dict(g.attrs["theoria_sweep"])
        g.attrs["theoria_sweep"] = {k: v for k, v in old.items() if k not in sw.BUDGET_KEYS}
    else:
        spec = tmp_path / "s.parquet.parts" / "_sweep.json"
        old = json.loads(spec.read_text())
        spec.write_text(json.dumps({k: v for k, v in old.items() if k not in sw.BUDGET_KEYS}))
    writer(out, plan(max_steps=1e8), resume=True)


def test_a_table_that_cannot_be_joined_leaves_no_half_file_and_keeps_the_chunks(tmp_path, monkeypatch):
    """The last step of a Parquet sweep joins its finished chunks into one table; on a full disk it
    left a half-written OUT.tmp beside them, and a traceback. Now: one line naming the file, no
    OUT.tmp, the chunks kept for --resume."""
    import errno

    import pyarrow.parquet as pq

    sc = th.scenario("free-tumble")
    out = str(tmp_path / "s.parquet")
    plan = sw.make_plan(sc, grid={"step": (0.01, 0.02, 2)})
    writer = sw.ParquetWriter(out, plan, resume=False)
    regions = plan.chunk_regions()
    for i, reg in enumerate(regions):
        writer.write(i, reg, sw.run_chunk({"scenario": sc.name, "fixed": plan.fixed, "points": plan.points(reg),
                                           "metrics": None, "batched": plan.batched, "threads": 1, "limits": {}}))

    def full_disk(table, where, **kw):
        with open(where, "wb") as f:
            f.write(b"PAR1 half a table")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(pq, "write_table", full_disk)
    with pytest.raises(sw.WriteError) as e:
        writer.finish()
    assert "s.parquet" in str(e.value) and "No space left" in str(e.value) and "\n" not in str(e.value)
    assert sorted(q.name for q in tmp_path.iterdir()) == ["s.parquet.parts"]
    assert len(list((tmp_path / "s.parquet.parts").glob("part-*.parquet"))) == len(regions)


@pytest.mark.slow
def test_python_sweep_takes_the_budget_as_simulate_does(tmp_path):
    """`Scenario.sweep` held every run to the default budget with no way to change it (the command
    has --max-steps): `max_steps` / `max_memory` as `simulate` takes them. Free body at its 0.01 s
    step: 2 s is 200 steps, 4 s is 400."""
    from distributed import Client, LocalCluster

    sc = th.scenario("free-tumble")
    with LocalCluster(n_workers=1, threads_per_worker=1, host="127.0.0.1", dashboard_address=None) as lc, Client(lc) as c:
        df = sc.sweep(grid={"duration": [2.0, 4.0]}, out=tmp_path / "b.parquet", cluster=c, max_steps=300)
        assert list(df.sort_values("duration")["status"]) == [sw.STATUS["ok"], sw.STATUS["refused"]]
        df = sc.sweep(grid={"duration": [2.0, 4.0]}, out=tmp_path / "b.parquet", cluster=c, force=True, max_steps=None)
        assert list(df["status"]) == [sw.STATUS["ok"]] * 2


# ------------------------------------------------- a refused or failed sweep leaves --out as it was

TINY = {"grid": ["step=0.01:0.02:2"], "fixed": {"duration": 2.0}}


@pytest.fixture(scope="module")
def in_process_client():
    """One Dask worker thread in this process: the sweeps below need a cluster, not its start-up."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc, \
            Client(lc) as c:
        yield c


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("suffix", ["zarr", "parquet"])
def test_a_sweep_refused_for_its_cluster_writes_nothing_at_out(tmp_path, suffix):
    """`--cluster nonsense` was refused (exit 2, the right line) only after the store was made:
    OUT/zarr.json (or OUT.parts/_sweep.json) stayed, and the corrected command was then refused
    as "it holds a sweep"; with --force over a finished sweep, an OUT.new/ stayed beside it."""
    sc = th.scenario("free-tumble")
    out = tmp_path / f"e.{suffix}"
    with pytest.raises(th.ParameterError) as e:
        sw.run_sweep(sc, out=out, cluster="nonsense", progress=False, **TINY)
    assert "--cluster" in str(e.value) and "tcp://" in str(e.value)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(th.ParameterError) as e:  # not a client at all: was an AttributeError ('submit')
        sw.run_sweep(sc, out=out, cluster=42, progress=False, **TINY)
    assert "cluster=42" in str(e.value) and "Client" in str(e.value)
    assert list(tmp_path.iterdir()) == []
    # a finished sweep there, replaced with --force through the same wrong --cluster: left as it was
    plan = sw.make_plan(sc, **TINY)
    (sw.ZarrWriter if suffix == "zarr" else sw.ParquetWriter)(str(out), plan, resume=False)
    before = _files(tmp_path)
    with pytest.raises(th.ParameterError):
        sw.run_sweep(sc, out=out, cluster="nonsense", force=True, progress=False, **TINY)
    assert _files(tmp_path) == before


@pytest.mark.slow  # a theoria process waiting on a port nobody answers, then a sweep on a local cluster
def test_a_sweep_whose_scheduler_does_not_answer_leaves_nothing_and_the_corrected_command_runs(tmp_path):
    out = tmp_path / "e.zarr"
    args = ["sweep", "free-tumble", "--grid", "step=0.01:0.02:2", "--set", "duration=2", "--quiet", "--out", str(out)]
    r = cli(*args, "--cluster", "tcp://127.0.0.1:1", timeout=120)
    assert r.returncode == 2 and "--cluster" in r.stderr and "no Dask scheduler answers" in r.stderr, r.stderr
    assert list(tmp_path.iterdir()) == []
    r = cli(*args, "--workers", "1", timeout=300)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e.zarr"]


@pytest.mark.parametrize("suffix, where", [("parquet", "description"), ("parquet", "chunk"), ("zarr", "chunk")])
def test_a_new_sweep_that_fails_on_a_full_disk_leaves_nothing_behind(tmp_path, monkeypatch, in_process_client,
                                                                      suffix, where):
    """A new sweep on a full disk said it could not write, and left an empty OUT.parts/ (or a store
    of no finished chunk) that made the next sweep on the same --out "hold a sweep"."""
    import errno

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    if where == "description":
        monkeypatch.setattr(sw, "write_whole", full)
    else:
        monkeypatch.setattr(sw.ZarrWriter if suffix == "zarr" else sw.ParquetWriter, "write", full)
    with pytest.raises(OSError) as e:
        sw.run_sweep(th.scenario("free-tumble"), out=tmp_path / f"b.{suffix}", cluster=in_process_client,
                     progress=False, **TINY)
    assert e.value.errno == errno.ENOSPC
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("suffix", ["zarr", "parquet"])
def test_resuming_a_finished_sweep_leaves_it_byte_for_byte_and_says_it_is_complete(tmp_path, in_process_client,
                                                                                    suffix):
    """--resume of a finished Zarr sweep rewrote it: a new `sessions` entry in zarr.json each time."""
    sc = th.scenario("free-tumble")
    out = tmp_path / f"f.{suffix}"
    summary, _ = sw.run_sweep(sc, out=out, cluster=in_process_client, progress=False, **TINY)
    # what `--json` prints of a sweep just finished: whole, nothing kept aside for a resume
    assert summary.complete and not summary.found_complete and summary.kept == "", summary
    before = _files(tmp_path)
    for _ in range(2):
        summary, result = sw.run_sweep(sc, out=out, cluster=in_process_client, resume=True, progress=False, **TINY)
        assert summary.found_complete and summary.complete and summary.chunks_computed == 0
        assert "complete" in summary.line() and "left as it is" in summary.line()
        assert len(result["status"]) == 2 if suffix == "parquet" else result.sizes["step"] == 2
        del result
        assert _files(tmp_path) == before


def test_resume_and_force_together_are_refused_naming_both(tmp_path, capsys):
    """`--resume --force` was taken, and silently resumed."""
    from theoria.app.cli import main

    out = tmp_path / "r.zarr"
    plan = sw.make_plan(th.scenario("free-tumble"), **TINY)
    sw.ZarrWriter(str(out), plan, resume=False)
    before = _files(tmp_path)
    code = main(["sweep", "free-tumble", "--grid", "step=0.01:0.02:2", "--set", "duration=2", "--out", str(out),
                 "--resume", "--force", "--cluster", "nonsense", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "--resume" in err and "--force" in err and err.count("\n") == 1, err
    assert _files(tmp_path) == before
    with pytest.raises(th.ParameterError) as e:
        th.scenario("free-tumble").sweep(grid={"step": (0.01, 0.02, 2)}, out=out, resume=True, force=True)
    assert str(e.value).startswith("resume=True, force=True: one of the two")  # the keywords, from Python


def test_a_finished_store_opened_as_the_docs_show_it_warns_nothing(tmp_path, in_process_client):
    """`xarray.open_zarr("F.zarr")` as the docs showed it warned, on every store, that it found no
    consolidated metadata (a multi-line RuntimeWarning)."""
    import re
    import warnings

    import xarray

    doc = (ROOT / "docs" / "sweeps.md").read_text()
    shown = re.search(r"open with `(xarray\.open_zarr\(\"F\.zarr\"[^`]*\))`", doc)
    assert shown, "docs/sweeps.md shows how to open a sweep's Zarr store"
    out = tmp_path / "F.zarr"
    sw.run_sweep(th.scenario("free-tumble"), out=out, cluster=in_process_client, progress=False, **TINY)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ds = eval(shown.group(1).replace('"F.zarr"', repr(str(out))), {"xarray": xarray})
        assert ds.sizes["step"] == 2 and bool((ds["status"] == sw.STATUS["ok"]).all())
        ds.close()
        m = sw.open_map(out, "final_energy_J" if "final_energy_J" in ds.data_vars else
                        next(v for v in ds.data_vars if v != "status"), x="step", y=False)
        assert m.values.size == 2


GUARDLESS = """\
import theoria as th
th.scenario("free-tumble").sweep(grid={{"step": (0.01, 0.02, 2)}}, duration=2.0, out={out!r}, workers=1)
print("swept")
"""


@pytest.mark.slow  # a script and its local cluster's worker, in processes of their own
def test_a_script_without_the_main_guard_is_told_to_add_it_and_leaves_no_half_store(tmp_path):
    """The documented `sc.sweep(...)` saved as a script and run with `python script.py`: the local
    cluster's worker process re-imports the script (as __mp_main__) and started a sweep of its
    own (RuntimeError: Nanny failed to start; SweepBusy), leaving a half-made store. A script
    with the guard runs."""
    out = tmp_path / "g.zarr"
    script = tmp_path / "guardless.py"
    script.write_text(GUARDLESS.format(out=str(out)))
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    # said before any worker starts, as the traceback's last line (it ended "RuntimeError: Nanny
    # failed to start." after ~100 lines of the workers' tracebacks, the advice buried in them)
    last = r.stderr.strip().splitlines()[-1]
    assert r.returncode == 1 and last.startswith("RuntimeError: ") and 'if __name__ == "__main__":' in last, r.stderr
    assert "Nanny" not in r.stderr and "swept" not in r.stdout
    assert not out.exists() and not (tmp_path / "g.zarr.new").exists()
    assert sorted(p.name for p in tmp_path.iterdir() if p.name != "g.zarr") == ["guardless.py"]
    # the script put right runs
    guarded = "if __name__ == \"__main__\":\n" + "".join("    " + ln + "\n" for ln in GUARDLESS.format(
        out=str(tmp_path / "h.zarr")).splitlines()[1:])
    script.write_text("import theoria as th\n" + guarded)
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 0 and "swept" in r.stdout, r.stderr[-3000:]


@pytest.mark.slow  # a program and its local cluster's worker, in processes of their own
def test_a_sweep_read_from_standard_input_runs(tmp_path):
    """`python - <<EOF` (a program piped in, as a notebook's %%bash or a heredoc in a shell does):
    its __main__ is named "<stdin>", and the workers tried to run that file again on their way in:
    FileNotFoundError, "Nanny failed to start", three tracebacks. It sweeps, and the program's own
    __main__ keeps its name."""
    out = tmp_path / "i.zarr"
    program = GUARDLESS.format(out=str(out)) + "import __main__; print(__main__.__file__)\n"
    r = subprocess.run([sys.executable, "-"], input=program, capture_output=True, text=True, timeout=300,
                       cwd=tmp_path)
    assert r.returncode == 0 and r.stdout.split() == ["swept", "<stdin>"], r.stderr[-3000:]
    assert "Traceback" not in r.stderr
    import xarray as xr
    assert xr.open_zarr(out, consolidated=False)["status"].values.tolist() == [1, 1]  # 1: ok


def test_a_sweep_started_by_a_workers_reimport_is_refused_there(tmp_path, monkeypatch):
    """Where the script's guard is missing but the check above cannot tell (a sweep at the top
    level of a script that also has a guard), the worker re-importing it refuses to sweep."""
    import multiprocessing

    from theoria.app.sweep import run_sweep
    from theoria.scenarios import get

    monkeypatch.setattr(multiprocessing.current_process(), "_inheriting", True, raising=False)
    with pytest.raises(RuntimeError, match='if __name__ == "__main__":'):
        run_sweep(get("free-tumble"), grid=["step=0.01:0.02:2"], out=str(tmp_path / "w.zarr"))
    assert list(tmp_path.iterdir()) == []


def test_which_scripts_are_told_to_add_the_guard(tmp_path, monkeypatch):
    """The file of __main__ is read: a script with the guard at its top level (either way round),
    `python -m theoria` (whose module ran the command again in each worker), a console or a
    notebook (no .py file) pass; a script without it is named."""
    import types

    import theoria.__main__ as theoria_main  # the module only: the guard keeps it from running the command
    from theoria.app import sweep as sw

    def main_file(path):
        m = types.ModuleType("__main__")
        if path is not None:
            m.__file__ = str(path)
        monkeypatch.setitem(sys.modules, "__main__", m)
        return sw._unguarded_script()

    bare, guarded, reversed_, anded, in_try, bom = (tmp_path / n for n in (
        "bare.py", "guarded.py", "reversed.py", "anded.py", "in_try.py", "bom.py"))
    bare.write_text("import theoria as th\nth.scenario('free-tumble').sweep(out='x.zarr')\n")
    guarded.write_text("import theoria as th\n\nif __name__ == '__main__':\n    th.scenario('free-tumble')\n")
    reversed_.write_text("if '__main__' == __name__:\n    pass\n")
    anded.write_text("import sys\nif __name__ == '__main__' and len(sys.argv) < 9:\n    pass\n")
    in_try.write_text("try:\n    if __name__ == '__main__':\n        pass\nexcept KeyboardInterrupt:\n    pass\n")
    bom.write_bytes(b"\xef\xbb\xbfx = 1  # \xc3\xa9\n")  # a BOM, no guard: read, and named
    assert main_file(bare) == str(bare) and main_file(bom) == str(bom)
    for ok in (guarded, reversed_, anded, in_try):
        assert main_file(ok) is None, ok.name
    assert main_file(theoria_main.__file__) is None
    assert main_file(None) is None and main_file(tmp_path / "missing.py") is None
    # `python -m pkg` with no guard in its __main__.py: spawn never runs such a module again
    m = types.ModuleType("__main__")
    m.__file__ = str(bare)
    m.__spec__ = types.SimpleNamespace(name="pkg.__main__")
    monkeypatch.setitem(sys.modules, "__main__", m)
    assert sw._unguarded_script() is None


STOP_DURING_SHUTDOWN = """
import os, signal, sys

import distributed

close = distributed.LocalCluster.close


def stopped_while_closing(self, *args, **kwargs):  # Ctrl-C or SIGTERM as the cluster shuts down
    os.kill(os.getpid(), getattr(signal, os.environ["STOP_WITH"]))
    return close(self, *args, **kwargs)


if __name__ == "__main__":
    distributed.LocalCluster.close = stopped_while_closing
    from theoria.app.cli import main

    sys.argv = ["theoria", *sys.argv[1:]]
    sys.exit(main())
"""


@pytest.mark.slow  # two sweeps, each with its local cluster
@pytest.mark.parametrize("stop", ["SIGINT", "SIGTERM"])
def test_a_stop_while_a_finished_sweep_shuts_down_is_too_late_and_the_sweep_is_recorded(tmp_path, stop):
    """Every chunk written, then Ctrl-C or SIGTERM while the local cluster shut down: the sweep
    exited 130/143 "interrupted" with no summary, and the invocation that computed every chunk was
    never written in the store's `sessions` (not by --resume either). A stop then is too late: the
    sweep says it is done and exits 0, its session recorded."""
    import xarray as xr

    script = tmp_path / "stop_during_shutdown.py"
    script.write_text(STOP_DURING_SHUTDOWN)
    out = tmp_path / "s.zarr"
    r = subprocess.run([sys.executable, str(script), "sweep", "free-tumble", "--grid", "step=0.01:0.02:2",
                        "--chunk", "1", "--workers", "1", "--out", str(out)], capture_output=True, text=True,
                       timeout=600, cwd=ROOT, env={**os.environ, "STOP_WITH": stop})
    assert r.returncode == 0, (r.returncode, r.stderr[-2000:])
    assert "interrupted" not in r.stderr and "terminated" not in r.stderr and str(out) in r.stderr, r.stderr
    ds = xr.open_zarr(out)
    assert (ds["status"].values == sw.STATUS["ok"]).all()
    assert [(x["chunks_computed"], x["interrupted"]) for x in ds.attrs["sessions"]] == [(2, False)]


def test_a_stop_during_the_last_chunks_write_is_too_late_to_interrupt(monkeypatch):
    """A Ctrl-C held while the last chunk was written (a store's write waits for the signal) reached
    the sweep's loop once every chunk was in: the sweep said "interrupted", exit 130, and the new
    store was never put in place. Every chunk written, the sweep is done."""
    import types

    import distributed

    from theoria.app import sweep as sw

    class Finished:
        def result(self):
            return {"metrics": {}, "status": np.zeros(1, int)}

        def done(self):
            return True

    class InOrder:
        def __init__(self, futures):
            self.futures = list(futures)

        def is_empty(self):
            return not self.futures

        def has_ready(self):
            return bool(self.futures)

        def __next__(self):
            return self.futures.pop(0)

    monkeypatch.setattr(distributed, "as_completed", InOrder)
    monkeypatch.setattr(sw, "_nruns", lambda region: 1)
    todo, stop = [0, 1, 2], sw._Stop()

    class Writer:
        new, kept = True, "OUT"

        def write(self, i, region, res):
            if i == todo[-1]:  # the signal held through the last write, delivered as it ends
                stop.flag, stop.signum = True, signal.SIGINT

    client = types.SimpleNamespace(submit=lambda *a, **k: Finished())
    plan = types.SimpleNamespace(scenario=types.SimpleNamespace(name="free-tumble"), fixed={}, metrics=None,
                                 batched=False, limits={}, points=lambda region: [])
    summary = types.SimpleNamespace(chunks_computed=0)
    interrupted = sw._drive(client, plan, {i: None for i in todo}, todo, Writer(), stop, lambda n: None,
                            {k: 0 for k in sw.STATUS}, summary, 1, None)
    assert (interrupted, summary.chunks_computed) == (False, 3)


def test_a_grid_of_a_million_is_checked_in_a_moment_and_every_bad_point_still_found():
    """The scenario's cross-parameter check ran at each of a million points before any work (27 s
    for the flip, whose check reads the spin only); it is run once per combination of what it
    reads, falling back to every point when a call reads another swept value, so a check whose
    branch reads the nudge only at high spin still finds the one bad corner."""
    sc = th.scenario("middle-axis-flip")
    plan = sw.make_plan(sc, grid={"spin": (1, 8, 1000), "perturbation": (1e-3, 1e-1, 1000)})
    calls = []

    def reads_spin(v):
        calls.append(v["spin"])
        if v["spin"] == 8.0:
            raise th.ParameterError("spin", v["spin"], "a bad corner")

    with pytest.raises(th.ParameterError, match="bad corner"):
        sw._check_every_point(reads_spin, plan)
    assert len(calls) == 1001  # the first point, then each spin once

    def branch(v):
        calls.append(1)
        if v["spin"] > 5 and v["perturbation"] == 0.1 and v["spin"] == 8.0:
            raise th.ParameterError("perturbation", 0.1, "a bad corner behind a branch")

    calls.clear()
    with pytest.raises(th.ParameterError, match="behind a branch"):
        sw._check_every_point(branch, plan)
    ok = sw.make_plan(sc, grid={"spin": (1, 7, 50), "perturbation": (1e-3, 1e-1, 50)})
    calls.clear()
    sw._check_every_point(branch, ok)  # no bad point: every point was looked at once the branch read the nudge
    assert 2500 <= len(calls) <= 2500 + 51


def test_a_metric_a_run_could_not_measure_says_why_in_the_sweep():
    """libration-circular over one period: its libration period is NaN (two swings are needed) and
    the run said nothing, nor did the sweep (status ok, no message). The run warns, and the sweep
    keeps an ok run's warnings in its messages."""
    task = {"scenario": "libration-circular", "fixed": {}, "points": {"periods": np.array([1.0, 3.0])},
            "metrics": ["libration_period"], "batched": False, "threads": None, "limits": {}}
    res = sw.run_chunk(task)
    assert list(res["status"]) == [sw.STATUS["ok"]] * 2
    period = res["metrics"]["libration_period"]
    assert np.isnan(period[0]) and np.isfinite(period[1])
    assert set(res["messages"]) == {0} and "periods ≥ 2" in res["messages"][0], res["messages"]
    # against the exact pendulum period: three periods measure it, so the warning's advice holds
    exact = th.scenario("libration-circular").simulate(periods=3).metrics["libration_period_exact"]
    assert period[1] == pytest.approx(exact, rel=1e-3)


def test_a_metric_asked_for_is_in_the_store_even_where_every_run_was_refused(tmp_path, in_process_client):
    """With every run over the budget the store held `status` only, and code reading the metric
    asked for broke (the Parquet table had no column either): it is there, NaN, in both."""
    import xarray as xr
    import pyarrow.parquet as pq

    sc = th.scenario("libration-circular")
    kw = dict(grid={"asymmetry": [0.01, 0.2]}, metrics="libration_period", progress=False, limits={"max_steps": 1},
              cluster=in_process_client)
    sw.run_sweep(sc, out=tmp_path / "r.zarr", **kw)
    sw.run_sweep(sc, out=tmp_path / "r.parquet", **kw)
    ds = xr.open_zarr(tmp_path / "r.zarr", consolidated=False)
    assert list(ds["status"].values) == [sw.STATUS["refused"]] * 2
    assert np.all(np.isnan(ds["libration_period"].values))
    table = pq.read_table(tmp_path / "r.parquet")
    assert "libration_period" in table.column_names


@pytest.mark.parametrize("what", ["empty folder", "text file", "text file.parquet", "run table.parquet"])
def test_a_path_that_is_not_a_sweep_is_not_called_one(tmp_path, what):
    """An empty folder or a text file named like the output was refused as "it holds a sweep; add
    --resume": it says what it is. Any file named F.parquet was said to hold a sweep, and --force
    then overwrote it (a run's own table, say); a Zarr refusal offered --force, which was then
    refused. A sweep replaces only a sweep: refused with and without --force, the file untouched."""
    out = tmp_path / ("x.parquet" if what.endswith(".parquet") else "x.zarr")
    if what == "empty folder":
        out.mkdir()
    elif what == "run table.parquet":
        th.scenario("free-tumble").simulate(duration=1).to_dataframe().to_parquet(out)
    else:
        out.write_text("hi")
    before = out.read_bytes() if out.is_file() else None
    for force in (False, True):
        with pytest.raises(th.ParameterError) as e:
            sw.run_sweep(th.scenario("free-tumble"), out=out, force=force, progress=False, **TINY)
        assert "is not a theoria sweep" in str(e.value) and "holds a sweep" not in str(e.value), str(e.value)
        assert "--force" not in str(e.value)
    assert (out.read_bytes() if out.is_file() else None) == before
