"""The `theoria` command (design.md, "Command line").

Exit status 2 with one line naming the key, the value and the allowed range for any bad input,
including a run beyond the step or memory limit (refused before it starts; `--max-steps`,
`--max-memory` raise the limits). A file that cannot be written: exit 1, one line, nothing
changed. Ctrl-C: exit 130, SIGTERM: exit 143, one line each, never a traceback.
"""
from __future__ import annotations

import argparse
import json
import re
import sys
import time

from theoria.app.files import WriteError
from theoria.app.interrupt import (EXIT_INTERRUPTED, EXIT_TERMINATED, Terminated, cli_signals,
                                   forget_interrupts_in_source_text)
from theoria.physics.params import ParameterError, whole_number

from .format import human_size, number


def _terminal() -> bool:
    """stderr is a terminal: a progress line rewritten in place (\r) is for a person watching;
    in a file or a pipe (a log, `2>&1`) the rewrites would be kept as fragments."""
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class Progress:
    """Progress on stderr for runs that take longer than a second (throttled), on a terminal only."""

    showing: "Progress | None" = None  # the progress line on the terminal now, if any

    def __init__(self, label: str, quiet: bool = False):
        self.label = label
        self.t0 = time.perf_counter()
        self.last = 0.0
        self.quiet = quiet or not _terminal()
        self.shown = False

    def __call__(self, fraction: float) -> None:
        now = time.perf_counter()
        if self.quiet or now - self.t0 < 1.0 or (now - self.last < 0.5 and fraction < 1):
            return
        self.last = now
        self.shown = True
        Progress.showing = self
        sys.stderr.write(f"\r{self.label}: {100 * fraction:5.1f}%  ({now - self.t0:.1f} s)")
        sys.stderr.flush()

    def done(self) -> None:
        if self.shown:
            sys.stderr.write("\n")
        Progress.showing = None

    @staticmethod
    def clear() -> None:
        """Blank the progress line (a message follows on the same line)."""
        if Progress.showing is not None:
            sys.stderr.write("\r" + " " * 72 + "\r")
            Progress.showing = None


# ---- limits ------------------------------------------------------------------------------------

def _limits(args) -> dict:
    from theoria.scenarios.budget import MAX_MEMORY, MAX_STEPS, memory_limit, steps_limit

    steps = MAX_STEPS if args.max_steps is None else steps_limit(args.max_steps, "--max-steps")
    memory = MAX_MEMORY if args.max_memory is None else memory_limit(args.max_memory, "--max-memory")
    return {"max_steps": steps, "max_memory": memory}


def _parse_sets(items: list[str] | None, spec=None) -> dict[str, str]:
    """`--set key=value` items; a parameter given twice with two values (as `spec` reads them, when
    given) is refused: the last one silently won."""
    def same(k, a, b):
        if a == b:
            return True
        try:
            return spec is not None and spec.param(k).parse(a) == spec.param(k).parse(b)
        except (ParameterError, KeyError):
            return False

    out = {}
    for item in items or []:
        if "=" not in item:
            raise ParameterError("--set", item, "key=value")
        k, v = (x.strip() for x in item.split("=", 1))
        if k in out and not same(k, out[k], v):
            raise ParameterError("--set", item, f"each parameter once ({k} is also given as {k}={out[k]})")
        out[k] = v
    return out


def _scenario_values(name: str, sets: list[str] | None, duration: str | None, preset: str | None = None):
    """The scenario, its values from --preset, --set and --duration (text, parsed as a --set
    value is: an error shows what was typed, not what a float made of it), and a sentence for each
    value given that these values leave unused (`Scenario.unused`)."""
    from theoria.scenarios import get

    sc = get(name)
    given = {}
    if preset is not None:  # the preset's values first; --set and --duration override them
        try:
            given.update(sc.presets[sc.preset_name(preset)])
        except ParameterError as e:
            raise ParameterError("--preset", preset, e.allowed) from None
    sets = _parse_sets(sets, sc)
    given.update(sets)
    if duration is not None:
        if not any(p.name == "duration" for p in sc.params):
            lengths = [p.name for p in sc.params if re.match(r"(duration|years|orbits|periods|.*turns)", p.name)]
            raise ParameterError("--duration", duration, f"not a parameter of {sc.name}" + (
                f"; its length is --set {lengths[0]}=…" if lengths else ""))
        if "duration" in sets and sc.param("duration").parse(sets["duration"]) != sc.param("duration").parse(duration):
            raise ParameterError("--duration", duration, f"the same as --set duration={sets['duration']}, "
                                 "or one of the two")
        given["duration"] = duration
    values = sc.resolve(given)
    return sc, values, sc.unused(values, given)


SECTION_COLUMN = 26  # `theoria list`: the width of the § column


def _param_json(p) -> dict:
    """A parameter as `list --json` gives it: what a script needs to pass a value that is taken
    (the choices, whether the minimum itself is allowed, where it applies)."""
    out = {"name": p.name, "label": p.display(), "default": p.default, "min": p.minimum, "max": p.maximum,
           "exclusive_min": p.exclusive_min, "allowed": p.allowed(), "unit": p.unit, "kind": p.kind, "help": p.help}
    if p.kind == "choice":
        out["choices"] = list(p.choices)
    if p.applies:  # one set of conditions, or a list of sets of which any one will do
        alts = [{k: list(v) for k, v in alt} for alt in p.applies]
        out["applies"] = alts[0] if len(alts) == 1 else alts
    return out


def cmd_list(args) -> int:
    from theoria.scenarios import all_scenarios

    items = all_scenarios()
    if args.json:
        print(json.dumps({"scenarios": [
            {"name": s.name, "title": s.title, "section": s.section, "group": s.group, "kind": s.kind,
             "summary": s.summary, "presets": [n for n in s.presets],
             "params": [_param_json(p) for p in s.params]}
            for s in items]}, indent=2))
        return 0
    w = max(len(s.name) for s in items)
    group = None
    for s in items:
        if s.group != group:
            group = s.group
            print(f"{'' if s is items[0] else chr(10)}{group}")
        if len(s.section) <= SECTION_COLUMN:
            print(f"  {s.name:<{w}}  {s.section:<{SECTION_COLUMN}} {s.title}")
        else:  # a long section (a modern source beside Euler's §) has the line to itself
            print(f"  {s.name:<{w}}  {s.section}")
            print(f"  {'':<{w}}  {'':<{SECTION_COLUMN}} {s.title}")
        for n in s.presets:
            print(f"  {'':<{w}}    --preset \"{n}\"")
    return 0


def _check_table_out(path: str | None, force: bool) -> str | None:
    """`theoria run --out FILE`: .parquet or .csv, a new file (or --force) in a writable folder,
    checked before the run."""
    if path is None:
        return None
    from theoria.app.files import check_out

    check_out(path, (".parquet", ".csv"), force=force, reader="")
    return path


def write_table(run, path: str) -> int:
    """The run's samples (Run.to_dataframe: one row per sample) as Parquet or CSV, whole or absent
    (app/files.py `write_whole`: a full disk or a file-size limit is one line naming the file,
    which stays as it was). Parquet keeps every column's unit as a sweep's table does (the schema's
    "units", JSON; pandas reads them back into `df.attrs["units"]`). Returns rows written."""
    import io

    import pyarrow as pa
    import pyarrow.parquet as pq

    from theoria.app.files import write_whole

    df = run.to_dataframe()
    if path.lower().endswith(".parquet"):
        table = pa.Table.from_pandas(df, preserve_index=False)
        table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                               b"units": json.dumps(df.attrs["units"]).encode()})
        buf = io.BytesIO()
        pq.write_table(table, buf)
        data = buf.getvalue()
    else:
        data = df.to_csv(index=False).encode()
    write_whole(path, data)
    return len(df)


def cmd_run(args) -> int:
    table_out = _check_table_out(getattr(args, "out", None), getattr(args, "force", False))
    sc, values, unused = _scenario_values(args.name, args.set, args.duration, args.preset)
    sc.check_budget(values, **_limits(args))  # before the run: a run of hours is refused at once
    prog = Progress(f"run {sc.name}", quiet=False)
    result = sc.simulate_fn(values, progress=prog)
    result.warnings.extend(unused)
    prog.done()
    if table_out is not None:
        n = _put_in_place(table_out, lambda: write_table(result, table_out))
        sys.stderr.write(f"wrote {'the' if n is None else n} samples × {len(result.columns())} columns to {table_out}\n")
    out = result.to_dict()
    if args.json:
        print(result.to_json())
        return 0
    print(f"{sc.title} ({sc.name}, {sc.section})")
    print("parameters:")
    for p in sc.params:
        print(f"  {p.name:<24} {number(values[p.name], 10)} {p.unit if p.unit != '1' else ''}".rstrip())
    print("metrics:")
    for k, v in out["metrics"].items():
        print(f"  {k:<40} {number(v, 10)} {out['metric_units'][k] or ''}".rstrip())
    if result.comparisons:
        print("Euler / simulated / modern:")
        for c in result.comparisons:
            print(f"  {c.label}: Euler {number(c.euler, 10)}  simulated {number(c.simulated, 10)}  "
                  f"modern {number(c.modern, 10)} {c.unit}"
                  + (f"  ({c.note})" if c.note else ""))
    for n in result.notes:
        print("note:", n)
    if result.status != "ok":
        print("status:", result.status)
    for w in result.warnings:
        if w not in result.notes:  # a divergence is said in both
            print("warning:", w)
    if "final_state" in out:
        fs = out["final_state"]
        print(f"final state at t={number(fs['t'], 10)}: q_wxyz={number(fs['quaternion_wxyz'], 10)} "
              f"omega_body={number(fs['omega_body'], 10)}")
    return 0


def check_table(rows) -> str:
    head = f"{'id':<22} {'section':<16} {'Euler':>14} {'simulated':>14} {'modern':>14} {'rel.error':>10} {'tol':>8}  verdict"
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r.id:<22} {r.section:<16} {number(r.euler, 9):>14} {number(r.simulated, 9):>14} {number(r.modern, 9):>14} "
            f"{number(r.rel_error, 2):>10} {r.tolerance:>8.2g}  {'pass' if r.passed else 'FAIL'}  {r.title}"
            + (f" [{r.unit}]" if r.unit else "")
        )
    return "\n".join(lines)


def cmd_check(args) -> int:
    from theoria.scenarios.checks import run_checks

    t0 = time.perf_counter()

    def progress(cid):
        sys.stderr.write(f"\rcheck {cid:<24} ({time.perf_counter() - t0:.0f} s)")
        sys.stderr.flush()

    shown = not args.json and _terminal()
    rows = run_checks(args.ids or None, progress=progress if shown else None)
    if shown:
        sys.stderr.write("\r" + " " * 50 + "\r")
    if args.json:
        print(json.dumps({"results": [r.to_dict() for r in rows]}, indent=2))
    else:
        print(check_table(rows))
        for r in rows:
            if r.note:
                print(f"  {r.id}: {r.note}")
        print(f"{sum(r.passed for r in rows)} passed, {sum(not r.passed for r in rows)} failed")
    return 0 if all(r.passed for r in rows) else 1


def cmd_bench(args) -> int:
    from theoria.benchmarks import format_table, run_benches

    rows = run_benches(args.names or None, progress=None if args.json else (lambda n: sys.stderr.write(f"bench {n}\n")))
    if args.json:
        print(json.dumps({"benchmarks": rows}, indent=2, default=float))
    else:
        print(format_table(rows))
    return 0


def cmd_sweep(args) -> int:
    from theoria.app.files import written_whole
    from theoria.app.interrupt import finishing
    from theoria.app.sweep import SWEEP_PRESETS, SweepError, preset_kwargs, run_sweep
    from theoria.scenarios import get

    kw = {"grid": args.grid, "random": args.random, "samples": args.samples, "fixed": _parse_sets(args.set)}
    name = args.name
    if name in SWEEP_PRESETS:  # a named sweep: its scenario, grid and fixed values (the flags add or override)
        kw = preset_kwargs(name, **kw)
        name = SWEEP_PRESETS[name].scenario
    sc = get(name)
    try:
        summary, _ = run_sweep(sc, out=args.out, cluster=args.cluster, resume=args.resume, force=args.force,
                               metrics=args.metrics, limits=_limits(args),
                               preset=args.preset, seed=args.seed, chunk=args.chunk, workers=args.workers,
                               progress=not args.quiet, **kw)
    except SweepError as e:
        sys.stderr.write(f"theoria: error: {e}\n")
        return 1
    except (KeyboardInterrupt, Terminated):
        if not written_whole(args.out):
            raise
        finishing()  # stopped on its way out, with the whole result in place
        sys.stderr.write(f"sweep: done → {args.out}\n")
        return 0
    if not summary.interrupted:
        finishing()  # the result is in place: a stop from here changes nothing, so none is reported
    sys.stderr.write(summary.line() + "\n")
    if args.json:
        import dataclasses

        print(json.dumps(dataclasses.asdict(summary), indent=2))
    if summary.interrupted:
        return 143 if summary.signal == "SIGTERM" else 130
    return 0


def cmd_serve(args) -> int:
    from theoria.app.server import check_address, serve

    check_address(args.host, args.port, flag="--")
    if args.scenario is not None:
        from theoria.scenarios import get

        get(args.scenario)  # unknown name: exit 2 before the server starts
    from theoria.app.server import Limits

    for flag, v in (("--max-clients", args.max_clients), ("--max-per-address", args.max_per_address)):
        if v < 1:
            raise ParameterError(flag, v, "a whole number ≥ 1")
    sweep = None
    if args.sweep is not None:
        from theoria.app.sweep_map import SweepMaps

        sweep = SweepMaps(args.sweep)  # not a theoria sweep: one line, exit 2, before the server starts
    ended = serve(port=args.port, host=args.host, scenario=args.scenario,
                  limits=Limits(max_connections=args.max_clients, max_per_address=args.max_per_address),
                  precompute=not args.no_precompute, sweep=sweep)
    # stopped as every command is (the server and its simulation processes are gone by now)
    return _fail("terminated", EXIT_TERMINATED) if ended == "SIGTERM" else _fail("interrupted", EXIT_INTERRUPTED)


def _write_command(args, suffixes, write, what: str, how: str) -> int:
    """record / export: the values, the limits and the target checked before the run; then the
    file written whole or not at all (app/files.py), and where it went said."""
    from theoria.app.files import check_out

    sc, values, unused = _scenario_values(args.name, args.set, args.duration, args.preset)
    sc.check_budget(values, **_limits(args))
    check_out(args.out, suffixes, force=args.force)
    for sentence in unused:
        sys.stderr.write(f"note: {sentence}\n")
    _put_in_place(args.out, lambda: write(sc.name, args.out, values))
    _wrote(args.out, f"{what} of {sc.name}", how)
    return 0


def _put_in_place(path: str, write):
    """`write()`, which puts a whole file at `path` (app/files.py); once the file is there, a stop
    is too late to undo it: it is not reported as one (exit 130 beside a new file), the command
    goes on to say what it wrote. Returns what `write` returns (None if it was stopped after)."""
    from theoria.app.files import written_whole
    from theoria.app.interrupt import finishing

    try:
        out = write()
    except (KeyboardInterrupt, Terminated):
        if not written_whole(path):
            raise
        out = None
    finishing()
    return out


def cmd_record(args) -> int:
    from theoria.app.record import record

    return _write_command(args, (".rrd",), record, "a rerun recording", "theoria replay")


def cmd_export(args) -> int:
    from theoria.app.export_html import export

    return _write_command(args, (".html", ".htm"), export, "an HTML replay", "open it in a browser, or theoria replay")


def _wrote(path: str, what: str, how: str) -> None:
    """Say where the file went and how big it is (a silent success looked like a failure)."""
    import os

    full = os.path.abspath(path)
    size = os.path.getsize(full)
    print(f"theoria: wrote {what} to {full} ({human_size(size)}); {how} {path}", flush=True)


def cmd_replay(args) -> int:
    from theoria.app.replay import ReplayError, replay

    try:
        return replay(args.file, check_only=args.check, web_viewer=args.web_viewer, open_browser=args.open,
                      host=args.host)
    except ReplayError as e:  # corrupt, truncated or foreign file: one line, exit 2
        sys.stderr.write(f"theoria: error: {e}\n")
        return 2


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # argparse's usage errors also exit 2, in one line
        sys.stderr.write(f"theoria: error: {message}\n")
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    import theoria

    p = _Parser(prog="theoria", description="A browser laboratory of Euler's rotational celestial mechanics.")
    p.add_argument("--version", action="version", version=f"theoria {theoria.__version__}")
    sub = p.add_subparsers(dest="cmd", required=True, parser_class=_Parser)

    s = sub.add_parser("serve", help="the web app")
    s.add_argument("--port", type=whole_number, default=8080, help="the port to serve on (default 8080; 0: any free one)")
    s.add_argument("--host", default="127.0.0.1", help="interface to bind (default 127.0.0.1; 0.0.0.0 for a classroom)")
    s.add_argument("--scenario", default=None, metavar="NAME",
                   help="the scenario a new browser opens on (default free-tumble; `theoria list` names them)")
    s.add_argument("--max-clients", type=whole_number, default=200, metavar="N",
                   help="browsers connected at once (default 200); more are refused")
    s.add_argument("--max-per-address", type=whole_number, default=10, metavar="N",
                   help="browsers from one network address (default 10)")
    s.add_argument("--no-precompute", action="store_true",
                   help="do not prepare every scenario's defaults and presets in the background")
    s.add_argument("--sweep", default=None, metavar="RESULT.zarr",
                   help="a sweep result (theoria sweep … --out RESULT.zarr) shown as a map in a Sweep tab; "
                        "click a pixel to replay that run")
    s.set_defaults(fn=cmd_serve)

    s = sub.add_parser("list", help="scenarios, one line each")
    s.add_argument("--json", action="store_true",
                   help="each scenario's parameters (range, unit, default) and presets as JSON (its metrics: "
                        "theoria run NAME --json)")
    s.set_defaults(fn=cmd_list)

    for name, fn, hlp in (("run", cmd_run, "headless run; prints metrics"),
                          ("record", cmd_record, "a rerun recording of the run"),
                          ("export", cmd_export, "a standalone HTML replay")):
        s = sub.add_parser(name, help=hlp)
        s.add_argument("name", help="the scenario (`theoria list` shows them)")
        s.add_argument("--set", action="append", metavar="KEY=VALUE",
                       help="a parameter's value, e.g. --set spin=2 --set inertia=1,2,3 (repeat for more)")
        s.add_argument("--duration", default=None, help="the run's length (its `duration`, where it has one)")
        s.add_argument("--preset", default=None, metavar="NAME",
                       help="start from a preset (its name or a unique part of it; `theoria list` shows them)")
        s.add_argument("--max-steps", default=None, metavar="N",
                       help="refuse a run of more integrator steps (default 2e7; none: no limit)")
        s.add_argument("--max-memory", default=None, metavar="SIZE",
                       help="refuse a run that keeps more memory (default 1GB; e.g. 4GB; none: no limit)")
        if name == "run":
            s.add_argument("--json", action="store_true", help="parameters, metrics and comparisons as JSON on stdout")
            s.add_argument("--out", default=None, metavar="FILE.parquet|FILE.csv",
                           help="also write the run's samples as a table (one row per sample)")
        else:
            s.add_argument("--out", required=True, metavar="FILE" + (".rrd" if name == "record" else ".html"),
                           help="the file to write (whole or not at all)")
        s.add_argument("--force", action="store_true", help="replace the --out file if it exists")
        s.set_defaults(fn=fn)

    s = sub.add_parser("replay", help="open a theoria .rrd (rerun viewer) or .html export; refuses other files")
    s.add_argument("file", help="a recording written by theoria record (.rrd) or a replay by theoria export (.html)")
    s.add_argument("--check", action="store_true", help="only validate the file: exit 0 if it is theoria's and whole, 2 if "
                   "not, 3 for a recording or export too old to carry a digest")
    s.add_argument("--web-viewer", action="store_true", help="rerun's web viewer instead of the native one "
                   "(prints its URL; stops with this command)")
    s.add_argument("--open", action="store_true", help="with --web-viewer: open the URL in a browser")
    s.add_argument("--host", default="127.0.0.1", help="interface the viewer binds (default 127.0.0.1)")
    s.set_defaults(fn=cmd_replay)

    s = sub.add_parser("sweep", help="many runs on Dask, written chunk by chunk to Zarr or Parquet (docs/sweeps.md)")
    s.add_argument("name", help="a scenario, or a named sweep (hyperion-chaos-map, mercury-capture)")
    s.add_argument("--grid", action="append", metavar="NAME=START:STOP:COUNT",
                   help="a swept parameter (COUNT values, both ends included), or NAME=V1,V2,…; repeat for more")
    s.add_argument("--random", action="append", metavar="NAME=LO:HI",
                   help="a parameter drawn uniformly in [LO, HI], --samples times (a 'sample' dimension)")
    s.add_argument("--samples", default=None, metavar="N", help="how many draws each --random parameter gets")
    s.add_argument("--seed", type=whole_number, default=0, help="seed of the random draws (default 0)")
    s.add_argument("--set", action="append", metavar="KEY=VALUE", help="a fixed parameter")
    s.add_argument("--preset", default=None, metavar="NAME", help="fixed parameters from a preset")
    s.add_argument("--out", required=True, metavar="FILE.zarr|FILE.parquet",
                   help="where the results go: a Zarr store (an xarray Dataset) or a Parquet table")
    s.add_argument("--cluster", default=None, metavar="ADDRESS",
                   help="an existing Dask scheduler (tcp://host:8786); default: a local cluster on this machine's cores")
    s.add_argument("--workers", default=None, type=whole_number, help="workers of the local cluster (default: one per core)")
    s.add_argument("--resume", action="store_true", help="keep the finished chunks of --out and compute the rest")
    s.add_argument("--force", action="store_true", help="replace what --out holds (an earlier sweep)")
    s.add_argument("--metrics", default=None, metavar="A,B", help="the metrics to keep (default: all)")
    s.add_argument("--max-steps", default=None, metavar="N",
                   help="a run of more integrator steps is not run, its status 'refused' (default 2e7; none: no limit)")
    s.add_argument("--max-memory", default=None, metavar="SIZE",
                   help="the same for a run that keeps more memory (default 1GB; none: no limit)")
    s.add_argument("--chunk", default=None, metavar="N", help="runs per chunk (default: chosen from the grid)")
    s.add_argument("--quiet", action="store_true", help="no progress bar")
    s.add_argument("--json", action="store_true", help="print a summary as JSON on stdout")
    s.set_defaults(fn=cmd_sweep)

    s = sub.add_parser("check", help="every result of Euler's: Euler / simulated / modern")
    s.add_argument("ids", nargs="*", help="rows to check, e.g. E1 E7 (default: every row, each printed with its id)")
    s.add_argument("--json", action="store_true", help="the rows as JSON on stdout")
    s.set_defaults(fn=cmd_check)

    s = sub.add_parser("bench", help="benchmarks as ratios against a baseline in the same run")
    s.add_argument("names", nargs="*", help="benchmarks to run (default: all; a wrong name lists them)")
    s.add_argument("--json", action="store_true", help="the rows as JSON on stdout")
    s.set_defaults(fn=cmd_bench)
    return p


def _fail(message: str, code: int) -> int:
    Progress.clear()
    sys.stderr.write(f"theoria: {message}\n")
    sys.stderr.flush()
    return code


def _drop_stdout() -> None:
    """Standard output can take nothing more (its reader went away, its disk is full): what is
    left in its buffer goes nowhere, so that Python's own flush at exit prints no traceback."""
    import os

    try:
        fd = os.open(os.devnull, os.O_WRONLY)
        os.dup2(fd, sys.stdout.fileno())
        os.close(fd)
    except (OSError, ValueError):
        pass


def main(argv: list[str] | None = None) -> int:
    try:
        return _main(argv)
    except KeyboardInterrupt:  # on the way out of the handlers' block, after the command's own
        return _fail("interrupted", EXIT_INTERRUPTED)
    except Terminated:
        return _fail("terminated", EXIT_TERMINATED)
    finally:
        forget_interrupts_in_source_text()


def _main(argv: list[str] | None) -> int:
    import errno

    with cli_signals(process=argv is None):  # argv None: the `theoria` command itself
        try:
            parser = build_parser()
            if not (sys.argv[1:] if argv is None else argv):  # bare `theoria`: what there is to do
                parser.print_help(sys.stderr)
                return 2
            args = parser.parse_args(argv)
            code = args.fn(args)
            sys.stdout.flush()  # a closed pipe or a full disk under stdout shows here, not at exit
            return code
        except BrokenPipeError:  # `theoria … | head`: the reader has what it wanted
            _drop_stdout()
            return 1
        except WriteError as e:  # an OSError whose message already says which file and why
            return _fail(f"error: {e}", 1)
        except OSError as e:
            if e.errno not in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO):
                raise
            _drop_stdout()  # files are written whole or not at all (WriteError): this is stdout
            return _fail(f"error: cannot write the output ({e.strerror})", 1)
        except ParameterError as e:
            return _fail(f"error: {e}", 2)
        except KeyboardInterrupt:
            return _fail("interrupted", EXIT_INTERRUPTED)
        except Terminated:
            return _fail("terminated", EXIT_TERMINATED)


if __name__ == "__main__":
    raise SystemExit(main())
