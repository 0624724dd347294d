"""The scenarios: the units users pick, one module each.

A scenario module registers itself with `register(Scenario(...))` when it is imported; `_load_all`
imports every module of this package, so a new scenario is one new file here (and its test),
with no list to edit elsewhere (docs/adding-a-scenario.md).
"""
from .base import Comparison, Run, Scenario, all_scenarios, get, register  # noqa: F401
