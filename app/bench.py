"""`theoria bench`: each benchmark is a ratio against a baseline measured in the same run.

Modules register benchmarks with `register_bench(name)`; the function returns a dict with
theoria_s, baseline_s, theoria_error, baseline_error (and optional extra fields). The ratio
printed is baseline_s / theoria_s (> 1: theoria is faster).
"""
from __future__ import annotations

import math
from typing import Callable

BENCHES: dict[str, Callable[[], dict]] = {}


def register_bench(name: str):
    def deco(fn):
        BENCHES[name] = fn
        return fn

    return deco


def run_benches(names: list[str] | None = None, progress: Callable[[str], None] | None = None) -> list[dict]:
    from . import bench_all  # noqa: F401  (registers every benchmark module)

    out = []
    for name, fn in BENCHES.items():
        if names and name not in names:
            continue
        if progress:
            progress(name)
        try:
            r = dict(fn())
        except Exception as e:  # a broken benchmark is reported, not fatal
            r = {"error": f"{type(e).__name__}: {e}", "theoria_s": None, "baseline_s": None,
                 "theoria_error": None, "baseline_error": None}
        ts, bs = r.get("theoria_s"), r.get("baseline_s")
        r["ratio"] = r.get("ratio", (bs / ts) if ts and bs else None)
        out.append({"name": name, **r})
    return out


def _fmt(x):
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.3g}" if math.isfinite(x) else str(x)
    return str(x)


def format_table(rows: list[dict]) -> str:
    cols = ["name", "ratio", "theoria_s", "baseline_s", "theoria_error", "baseline_error"]
    lines = ["  ".join(f"{c:>14}" if i else f"{c:<28}" for i, c in enumerate(cols))]
    for r in rows:
        lines.append("  ".join(f"{_fmt(r.get(c)):>14}" if i else f"{r['name']:<28}" for i, c in enumerate(cols)))
        extra = {k: v for k, v in r.items() if k not in cols}
        if extra:
            lines.append("      " + ", ".join(f"{k}={_fmt(v)}" for k, v in extra.items()))
    return "\n".join(lines)
