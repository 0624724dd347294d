"""What a user gets: the wheel, installed (not editable) in a fresh virtual environment, run from a
directory of their own that holds files called physics.py and app.py."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from conftest import ROOT

pytestmark = pytest.mark.slow  # builds a wheel and installs it with its dependencies (minutes)

EVERY_SCENARIO = textwrap.dedent("""
    import json, sys
    import theoria as th
    out = {"file": th.__file__, "version": th.__version__, "runs": {}}
    for name in th.scenarios():
        sc = th.scenario(name)
        run = sc.simulate(**sc.preview)
        d = sc.drawing(run)
        out["runs"][name] = {"status": run.status, "items": len(d.items), "frames": d.n_frames}
    run = th.scenario("earth").simulate(years=1)
    out["html"] = run.export_html("earth.html")["bytes"]
    out["rrd"] = run.record("earth.rrd")["frames"]
    print(json.dumps(out))
""")


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    d = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(d / "dist"), str(ROOT)],
                   check=True, capture_output=True, timeout=1800)
    wheel, = (d / "dist").glob("theoria_motus-*.whl")
    subprocess.run([sys.executable, "-m", "venv", str(d / "venv")], check=True, timeout=600)
    py = d / "venv" / "bin" / "python"
    p = subprocess.run([str(py), "-m", "pip", "install", "-q", str(wheel)], capture_output=True, text=True,
                       timeout=3600)
    assert p.returncode == 0, p.stderr[-3000:]
    return d, py


def _student_dir(d: Path) -> Path:
    work = d / "notebook"
    work.mkdir(exist_ok=True)
    # a student's own files with the names of theoria's folders: importing them would fail loudly
    (work / "physics.py").write_text("raise SystemExit('the student physics.py was imported')\n")
    (work / "app.py").write_text("raise SystemExit('the student app.py was imported')\n")
    return work


def test_nothing_named_physics_or_app_at_the_top_of_site_packages(venv):
    d, py = venv
    site = Path(subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    top = {p.name for p in site.iterdir()}
    assert "theoria" in top
    assert not top & {"physics", "app", "scenarios", "benchmarks", "assets", "tests"}, sorted(top)
    assert (site / "theoria" / "assets" / "bright_stars.csv").is_file()


def test_every_scenario_runs_from_a_students_directory(venv):
    d, py = venv
    work = _student_dir(d)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    p = subprocess.run([str(py), "-c", EVERY_SCENARIO], capture_output=True, text=True, timeout=3600, cwd=work,
                       env=env)
    assert p.returncode == 0, p.stderr[-3000:]
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert str(d / "venv") in out["file"]  # the installed copy, not the checkout
    assert set(out["runs"]) >= {"earth", "free-tumble", "earth-long-view", "moon"} and len(out["runs"]) >= 16
    assert all(r["status"] == "ok" and r["items"] > 0 for r in out["runs"].values()), out["runs"]
    assert out["html"] > 10_000 and out["rrd"] > 0
    # the command line from the same directory: earth (stars, REBOUND) and free-tumble
    theoria = d / "venv" / "bin" / "theoria"
    for args in (["run", "earth", "--set", "years=1", "--json"], ["run", "free-tumble", "--json"]):
        q = subprocess.run([str(theoria), *args], capture_output=True, text=True, timeout=1800, cwd=work, env=env)
        assert q.returncode == 0, q.stderr[-2000:]
        assert json.loads(q.stdout)["status"] == "ok"


def test_bench_rows_needing_an_extra_say_so_in_a_plain_install(venv):
    d, py = venv
    theoria = d / "venv" / "bin" / "theoria"
    p = subprocess.run([str(theoria), "bench", "app-slider-latency", "--json"],
                       capture_output=True, text=True, timeout=600, cwd=_student_dir(d))
    assert p.returncode == 0, p.stderr[-2000:]
    rows = {r["name"]: r for r in json.loads(p.stdout)["benchmarks"]}
    assert "playwright" in rows["app-slider-latency"]["skipped"] and "[bench]" in rows["app-slider-latency"]["skipped"]


def test_serve_from_the_checkout_folder_draws_the_first_scene(venv):
    """README's first command installs theoria and starts `theoria serve` from the checkout: there
    the folder theoria/ (the front door only) sits in the working folder. The server's simulation
    processes must still import the installed package (they imported the checkout's and died)."""
    import asyncio
    import time

    from theoria.benchmarks.classroom import ViserProtocolClient, _free_port

    d, py = venv
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    port = _free_port()
    server = subprocess.Popen([str(d / "venv" / "bin" / "theoria"), "serve", "--port", str(port)], cwd=ROOT,
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        t0 = time.time()
        while "open http" not in server.stdout.readline():
            assert server.poll() is None and time.time() - t0 < 120, server.stderr.read()[-2000:]

        async def first_scene():
            c = ViserProtocolClient(f"ws://127.0.0.1:{port}")
            await c.connect()
            try:
                return await c.wait_for(lambda: c.update_no >= 1, 300), c.status
            finally:
                await c.close()

        drawn, status = asyncio.run(first_scene())
        assert drawn, status
    finally:
        server.terminate()
        _, err = server.communicate(timeout=30)
    assert "Traceback" not in err and "ModuleNotFoundError" not in err, err[-2000:]
