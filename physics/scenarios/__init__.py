"""Scenarios: the units users pick. Each module registers its scenarios on import."""
from .base import Comparison, Result, Scenario, all_scenarios, get, register  # noqa: F401
