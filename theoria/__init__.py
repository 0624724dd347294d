"""theoria: a laboratory of Euler's rotational celestial mechanics.

One import gives what a notebook needs::

    import theoria as th
    th.scenarios()                          # names, in gallery order
    sc = th.scenario("middle-axis-flip")
    sc.parameters                           # name -> Param (unit, allowed range, default, help)
    sc.presets                              # name -> parameter values
    run = sc.simulate(spin=1, perturbation=0.01, duration=200)
    run.metrics, run.comparisons, run.warnings, run.trajectory
    run.to_dataframe(); run.record("x.rrd"); run.export_html("x.html"); run.show()
    th.check("E2")                          # rows of `theoria check`
    th.scenario("libration-eccentric").sweep(grid={"eccentricity": (0, 0.5, 16)}, out="m.zarr")

A bad value raises `th.ParameterError` (a ValueError) naming the parameter, the value and the
allowed range: the same line the command line prints with exit status 2. A run beyond the step
or memory limit (`sc.cost(**values)` says what it would take; `th.MAX_STEPS`, `th.MAX_MEMORY`) is
refused before it starts with `th.BudgetExceeded`; `simulate(..., max_steps=None,
max_memory=None)` lifts the limits. A file that cannot be written (a full disk) raises
`th.WriteError`, and the target is as it was. The physics
(`theoria.physics`), the scenarios (`theoria.scenarios`) and the app (`theoria.app`) are
reachable but not needed.
"""

from . import _console

_console.guard()  # the command line: a Ctrl-C while it imports is one line, not a traceback

from importlib import metadata as _metadata  # noqa: E402

from .physics.errors import BudgetExceeded, Cancelled, Diverged, ParameterError  # noqa: E402
from .physics.params import Param  # noqa: E402
from .physics.trajectory import Trajectory  # noqa: E402
from .scenarios.base import Comparison, Run, Scenario  # noqa: E402
from .scenarios.budget import MAX_MEMORY, MAX_STEPS, Cost  # noqa: E402
from .app.files import WriteError  # noqa: E402

try:
    __version__ = _metadata.version("theoria-motus")
except _metadata.PackageNotFoundError:  # imported from a checkout that was never installed
    __version__ = "0+unknown"

__all__ = ["scenarios", "scenario", "check", "Scenario", "Run", "Comparison", "Param", "Trajectory", "Cost",
           "ParameterError", "Diverged", "Cancelled", "BudgetExceeded", "WriteError", "MAX_STEPS", "MAX_MEMORY", "__version__"]


def scenarios() -> list[str]:
    """The names of every scenario, in gallery order (Euler's ch. 15, ch. 16, then the three-body
    papers, each in the order of the § it illustrates)."""
    from .scenarios.base import all_scenarios

    return [s.name for s in all_scenarios()]


def scenario(name: str) -> Scenario:
    """The scenario called `name` (one of `scenarios()`); ParameterError names the ones there are."""
    from .scenarios.base import get

    return get(name)


def check(*ids: str) -> list[Comparison]:
    """Rows of `theoria check` (every row when no id is given; "E8" selects E8, E8.free, ...;
    `check("E1", "E2")` or `check(["E1", "E2"])`): Euler's value, the simulated one, the modern
    reference, the relative error, the tolerance and the verdict (`.passed`)."""
    from .scenarios.checks import run_checks

    flat = [i for x in ids for i in (x if isinstance(x, (list, tuple)) else (x,))]
    return run_checks(flat or None)
