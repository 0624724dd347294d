"""`theoria check`: every result of design.md's table, Euler's value against the simulated one
and the modern reference. Each module under physics/checks registers its rows with
`register_check`; `_load_all` lists the modules."""
from .base import CHECKS, CheckResult, register_check, run_checks  # noqa: F401
