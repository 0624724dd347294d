"""`theoria bench`: each benchmark is a ratio against a baseline measured in the same run.

Every module of this package registers its rows with `register_bench(name, needs=...)`; the
function returns a dict with theoria_s, baseline_s, theoria_error, baseline_error (and optional
extra fields). The ratio printed is baseline_s / theoria_s (> 1: theoria is faster).

`needs` names the modules a row imports beyond a plain install (Playwright drives Chromium,
psutil reads a server's memory): without them the row says which extra to install
(`pip install "theoria-motus[bench]"`) instead of failing.
"""
from __future__ import annotations

import importlib
import importlib.util
import pkgutil
from typing import Callable

from theoria.app.format import number

BENCHES: dict[str, Callable[[], dict]] = {}
NEEDS: dict[str, tuple[str, ...]] = {}
EXTRA = "bench"


def register_bench(name: str, needs: tuple[str, ...] = ()):
    def deco(fn):
        BENCHES[name] = fn
        NEEDS[name] = tuple(needs)
        return fn

    return deco


def _load_all() -> None:
    """Import every module of this package: each registers its rows (no list to keep)."""
    for m in pkgutil.iter_modules(__path__):
        importlib.import_module(f"{__name__}.{m.name}")


def missing(name: str) -> list[str]:
    """The modules row `name` needs that this installation lacks."""
    return [m for m in NEEDS.get(name, ()) if importlib.util.find_spec(m) is None]


def run_benches(names: list[str] | None = None, progress: Callable[[str], None] | None = None) -> list[dict]:
    _load_all()
    unknown = [n for n in names or () if n not in BENCHES]
    if unknown:
        from theoria.physics.errors import ParameterError

        raise ParameterError("name", unknown[0], "one of " + ", ".join(BENCHES))
    out = []
    for name, fn in BENCHES.items():
        if names and name not in names:
            continue
        if progress:
            progress(name)
        lacking = missing(name)
        if lacking:
            out.append({"name": name, "skipped": f"needs {', '.join(lacking)}: pip install "
                        f"\"theoria-motus[{EXTRA}]\"", "theoria_s": None, "baseline_s": None,
                        "theoria_error": None, "baseline_error": None, "ratio": None})
            continue
        try:
            r = dict(fn())
        except Exception as e:  # a broken benchmark is reported, not fatal
            r = {"error": f"{type(e).__name__}: {e}", "theoria_s": None, "baseline_s": None,
                 "theoria_error": None, "baseline_error": None}
        ts, bs = r.get("theoria_s"), r.get("baseline_s")
        r["ratio"] = r.get("ratio", (bs / ts) if ts and bs else None)
        out.append({"name": name, **r})
    return out


def format_table(rows: list[dict]) -> str:
    cols = ["name", "ratio", "theoria_s", "baseline_s", "theoria_error", "baseline_error"]
    lines = ["  ".join(f"{c:>14}" if i else f"{c:<28}" for i, c in enumerate(cols))]
    for r in rows:
        lines.append("  ".join(f"{number(r.get(c), 3):>14}" if i else f"{r['name']:<28}" for i, c in enumerate(cols)))
        extra = {k: v for k, v in r.items() if k not in cols}
        if extra:
            lines.append("      " + ", ".join(f"{k}={number(v, 3)}" for k, v in extra.items()))
    return "\n".join(lines)
