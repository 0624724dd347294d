"""`theoria check`: every result of design.md's table, Euler's value against the simulated one
and the modern reference.

Each scenario module registers the rows about it with `@register_check(id, title, section)`. The
function returns a dict with keys euler, simulated, modern, rel_error, tolerance, and optionally
unit, note, passed (default: rel_error ≤ tolerance). A row is a `Comparison` with its id,
section, relative error, tolerance and verdict; a row whose computation raises is a failing row
with the error in its note, never a crash.
"""
from __future__ import annotations

import math
import re
import traceback
from dataclasses import dataclass
from typing import Callable

from ..physics.errors import ParameterError
from .base import Comparison, load_all

CheckResult = Comparison  # a check row is a comparison row with its verdict


@dataclass(frozen=True)
class Check:
    id: str
    title: str
    section: str
    fn: Callable[[], dict]


CHECKS: list[Check] = []


def register_check(id: str, title: str, section: str):
    """Decorator: the function computes one row of `theoria check` (see the module docstring)."""

    def deco(fn):
        CHECKS.append(Check(id, title, section, fn))
        return fn

    return deco


def _sort_key(c: Check):
    head = c.id.split(".")[0].lstrip("E")
    return (int(head) if head.isdigit() else 999, c.id)


def all_checks() -> list[Check]:
    load_all()
    return sorted(CHECKS, key=_sort_key)


def select(ids: list[str] | None) -> list[Check]:
    """The checks named by `ids` (an id such as "E8.moon", or a group such as "E8"); an id that
    names none raises ParameterError listing the ids there are."""
    checks = all_checks()
    if not ids:
        return checks
    known = {c.id for c in checks} | {c.id.split(".")[0] for c in checks}
    spelt = {k.lower(): k for k in known}  # "e2", "e8.Moon": as the ids are written
    wanted = []
    for i in ids:
        if not isinstance(i, str) or i.strip().lower() not in spelt:
            raise ParameterError("check", i, "one of " + ", ".join(sorted(known, key=_in_order)))
        wanted.append(spelt[i.strip().lower()])
    return [c for c in checks if c.id in wanted or c.id.split(".")[0] in wanted]


def run_check(c: Check) -> Comparison:
    try:
        r = c.fn()
        rel = r.get("rel_error")
        passed = r.get("passed", rel is not None and math.isfinite(rel) and rel <= r["tolerance"])
        return Comparison(c.title, r.get("euler"), r.get("simulated"), r.get("modern"), r.get("unit", ""),
                          r.get("note", ""), id=c.id, section=c.section, rel_error=rel,
                          tolerance=r["tolerance"], passed=bool(passed))
    except Exception as e:  # a failing check is a row that fails, not a crash
        where = traceback.format_exc(limit=1).strip().splitlines()[-1]
        return Comparison(c.title, None, None, None, note=f"error: {type(e).__name__}: {e}; {where}",
                          id=c.id, section=c.section, tolerance=0.0, passed=False)


def _in_order(check_id: str) -> tuple:
    """E1, E1.x, E2, …, E13, then the others: as the table reads (not E1, E10, E11, …, E2)."""
    m = re.match(r"E(\d+)(.*)", check_id)
    return (0, int(m.group(1)), m.group(2)) if m else (1, 0, check_id)


def run_checks(ids: list[str] | None = None, progress: Callable[[str], None] | None = None) -> list[Comparison]:
    out = []
    for c in select(ids):
        if progress:
            progress(c.id)
        out.append(run_check(c))
    return out
