"""The pure-Python simulation process: on a fresh install the server starts one child with numba's
JIT off, and it draws the first scenes while the other children compile (app/worker.py). It runs
with an empty numba cache, so nothing may need compiling for it to import or run: it once died
at import on every fresh install (numba compiled a ufunc with the JIT off and could not type the
plain-Python function it calls), so a fresh install's first scene waited for the compiler, and
the tracebacks reached the teacher's terminal."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.slow  # every scenario's preview in pure Python (~70 s)

EVERY_PREVIEW = """
import json, sys
import numpy as np
import theoria as th
out = {}
for name in th.scenarios():
    sc = th.scenario(name)
    try:
        run = sc.simulate(**sc.preview)
        out[name] = {"status": run.status}
        if name == "free-tumble":
            out[name]["last"] = np.asarray(run.trajectory.omega_body[-1], float).tolist()
    except Exception as e:
        out[name] = {"status": f"{type(e).__name__}: {e}"}
print(json.dumps(out))
"""


def _previews(tmp_path, jit: bool) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_DISABLE_JIT",)}
    env["NUMBA_CACHE_DIR"] = str(tmp_path / ("numba-jit" if jit else "numba"))  # empty: nothing compiled yet
    if not jit:
        env["NUMBA_DISABLE_JIT"] = "1"
    p = subprocess.run([sys.executable, "-c", EVERY_PREVIEW], capture_output=True, text=True, env=env,
                       cwd=tmp_path, timeout=1800)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout.strip().splitlines()[-1])


def test_every_scenario_imports_and_runs_its_preview_without_the_jit_on_an_empty_cache(tmp_path):
    plain = _previews(tmp_path, jit=False)
    assert len(plain) >= 16
    assert {n: r["status"] for n, r in plain.items() if r["status"] != "ok"} == {}
    # the same numbers as the compiled code (the free body is not chaotic: round-off only), so the
    # first scene and the refined one agree
    from theoria.scenarios import get

    spec = get("free-tumble")
    compiled = spec.simulate_fn(spec.resolve(dict(spec.preview)))
    assert plain["free-tumble"]["last"] == pytest.approx(list(compiled.trajectory.omega_body[-1]), rel=1e-9, abs=1e-12)


def test_a_chaotic_scene_is_computed_by_the_compiled_code_on_a_fresh_install(tmp_path, monkeypatch):
    """Hyperion's numbers hang on the last bit of every step: the pure-Python child (which would
    answer first on a fresh install) gave a Lyapunov probe of 0.47 per orbit where the compiled
    code, the command line and a sweep give 0.96. A browser's first Hyperion scene waits for the
    compiled code and shows its numbers."""
    import threading

    from theoria.app import worker as worker_mod
    from theoria.scenarios import get

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))  # a fresh install: nothing compiled
    spec = get("hyperion")
    values = dict(spec.preview)
    want = spec.simulate_fn(spec.resolve(values)).metrics  # compiled, in this process
    pool = worker_mod.SimPool(slots=2, store=False)
    got, done = {}, threading.Event()
    try:
        assert "hyperion" not in pool.warm
        w = worker_mod.SimulationWorker("browser", lambda req, run, s: (got.update(run=run), done.set()),
                                        lambda req, e: (got.update(run=e), done.set()), lambda *a: None, pool=pool)
        w.submit(spec, values)
        assert done.wait(600)
        run = got["run"]
        assert not isinstance(run, Exception), run
        for k in ("lyapunov_probe_per_orbit", "lyapunov_max_per_orbit"):
            assert run.metrics[k] == pytest.approx(want[k], rel=1e-9), (k, run.metrics[k], want[k])
        assert pool.nojit is None or pool.nojit.runs == 0
    finally:
        pool.close()
