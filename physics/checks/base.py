"""The check registry. A check is a function returning Euler's value, the simulated value, the
modern reference, the relative error and the tolerance it must meet (with why)."""
from __future__ import annotations

import math
import traceback
from dataclasses import dataclass
from typing import Callable


@dataclass
class CheckResult:
    id: str
    title: str
    section: str
    euler: float | None
    simulated: float | None
    modern: float | None
    rel_error: float | None
    tolerance: float
    passed: bool
    unit: str = ""
    note: str = ""

    def to_json(self) -> dict:
        def f(x):
            if x is None:
                return None
            x = float(x)
            return x if math.isfinite(x) else None

        return {
            "id": self.id,
            "title": self.title,
            "section": self.section,
            "euler": f(self.euler),
            "simulated": f(self.simulated),
            "modern": f(self.modern),
            "rel_error": f(self.rel_error),
            "tolerance": self.tolerance,
            "pass": bool(self.passed),
            "unit": self.unit,
            "note": self.note,
        }


@dataclass(frozen=True)
class Check:
    id: str
    title: str
    section: str
    fn: Callable[[], dict]


CHECKS: list[Check] = []


def register_check(id: str, title: str, section: str):
    """Decorator. The function returns a dict with keys euler, simulated, modern, rel_error,
    tolerance, and optionally unit, note, passed (default: rel_error <= tolerance)."""

    def deco(fn):
        CHECKS.append(Check(id, title, section, fn))
        return fn

    return deco


def _sort_key(c: Check):
    head = c.id.split(".")[0].lstrip("E")
    return (int(head) if head.isdigit() else 999, c.id)


def run_checks(ids: list[str] | None = None, progress: Callable[[str], None] | None = None) -> list[CheckResult]:
    from . import _load_all  # noqa: F401

    out = []
    for c in sorted(CHECKS, key=_sort_key):
        if ids and c.id not in ids and c.id.split(".")[0] not in ids:
            continue
        if progress:
            progress(c.id)
        try:
            r = c.fn()
            rel = r.get("rel_error")
            passed = r.get("passed", rel is not None and math.isfinite(rel) and rel <= r["tolerance"])
            out.append(
                CheckResult(
                    c.id, c.title, c.section, r.get("euler"), r.get("simulated"), r.get("modern"),
                    rel, r["tolerance"], bool(passed), r.get("unit", ""), r.get("note", ""),
                )
            )
        except Exception as e:  # a failing check is a row that fails, not a crash
            out.append(
                CheckResult(c.id, c.title, c.section, None, None, None, None, 0.0, False,
                            note=f"error: {type(e).__name__}: {e}; " + traceback.format_exc(limit=1).strip().splitlines()[-1])
            )
    return out
