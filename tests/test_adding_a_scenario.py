"""docs/adding-a-scenario.md: the worked example's module and test, taken from the page and run, so
the page cannot go stale and "one module and one test" stays true: the module alone makes the
scenario appear in the front door, the command line, the app's session and the replays."""
from __future__ import annotations

import importlib.util
import re
import sys

import pytest
from conftest import ROOT

import theoria as th
from theoria.scenarios import base

PAGE = ROOT / "docs" / "adding-a-scenario.md"


def _blocks():
    return re.findall(r"```python\n(.*?)```", PAGE.read_text(encoding="utf-8"), re.S)


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    """The page's module, loaded as theoria.scenarios.axis_stability (as if it were a file there)."""
    module_src, test_src = _blocks()[-2:]
    d = tmp_path_factory.mktemp("example")
    path = d / "axis_stability.py"
    path.write_text(module_src)
    name = "theoria.scenarios.axis_stability"
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    yield test_src
    base.REGISTRY.pop("axis-stability", None)
    sys.modules.pop(name, None)


def test_the_worked_example_is_a_scenario_everywhere(example, tmp_path):
    assert "axis-stability" in th.scenarios()
    names = th.scenarios()
    assert names.index("axis-stability") == names.index("free-tumble") - 1  # ch. 15, by its § (803 < 805)
    run = th.scenario("axis-stability").simulate(preset="about A")
    assert run.status == "ok" and run.metrics["wobble_period_s"] > 0
    from theoria.app.cli import main

    assert main(["run", "axis-stability", "--preset", "about B", "--json"]) == 0
    run.record(tmp_path / "x.rrd")
    run.export_html(tmp_path / "x.html")
    from theoria.app.replay import check

    assert check(str(tmp_path / "x.rrd"))["kind"] == "rrd"
    assert "Spinning about a principal axis" in (tmp_path / "x.html").read_text()


def test_the_worked_examples_own_test_passes(example):
    ns: dict = {}
    exec(compile(example, "adding-a-scenario.md", "exec"), ns)
    tests = [f for k, f in ns.items() if k.startswith("test_")]
    assert len(tests) == 2
    for t in tests:
        t()
