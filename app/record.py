"""`theoria record NAME --out FILE.rrd`: a rerun recording of one run.

Everything is sent column-wise (`rr.send_columns`), one call per entity for the whole run, on
two timelines: `t` (a duration, in seconds of the run's time unit converted to seconds) and
`step` (the sample index). The file always gets its footer: `rec.disconnect()` runs in a
`finally`, and SIGTERM is turned into an exception while recording so that the `finally` runs
(SIGINT already raises KeyboardInterrupt).

Replay: `rerun FILE.rrd` (native viewer) or `rerun FILE.rrd --web-viewer` (the wheel carries
the web viewer).
"""
from __future__ import annotations

import contextlib
import signal
import threading
import uuid

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from theoria.physics.quaternion import to_xyzw

from .scene import shape_semi_axes, AXIS_COLORS, L_COLOR, OMEGA_COLOR, POLHODE_COLOR, TRAIL_COLOR, HERPOLHODE_COLOR, palette

SECONDS = {"s": 1.0, "min": 60.0, "h": 3600.0, "day": 86400.0, "days": 86400.0, "d": 86400.0,
           "yr": 365.25 * 86400.0, "year": 365.25 * 86400.0, "years": 365.25 * 86400.0}
MAX_TRAIL_POINTS = 100_000


def blueprint(series_paths: list[str]) -> rrb.Blueprint:
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(origin="/world", name="scene"),
            rrb.Vertical(
                rrb.TimeSeriesView(origin="/series", name="key quantities"),
                rrb.TimeSeriesView(origin="/metrics", name="metrics"),
                rrb.TextDocumentView(origin="/text", name="Euler"),
                row_shares=[3, 1, 2],
            ),
            column_shares=[3, 2],
        ),
        collapse_panels=False,
    )


def text_of(spec, result) -> str:
    from .server import comparison_markdown

    lines = [f"# {spec.title}", f"**{spec.section}** · {spec.group} · `{spec.name}`", "", spec.summary, ""]
    if spec.euler_formula:
        lines += ["**Euler:** " + spec.euler_formula, ""]
    lines += [f"Time: timeline `t` (seconds), or `t_milli` = 1000 × t in {result.trajectory.time_unit} "
              "when the unit is not a time or the run is longer than rerun's durations allow.", "",
              "## Parameters", ""]
    for p in spec.params:
        lines.append(f"- `{p.name}` = {result.params.get(p.name)} {p.unit}")
    lines += ["", "## Euler says / simulated / modern", "", comparison_markdown(result)]
    return "\n".join(lines)


@contextlib.contextmanager
def _sigterm_raises():
    """While recording, SIGTERM raises SystemExit so that `finally` writes the footer."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        raise SystemExit(128 + signum)

    old = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def _decimate(n: int, m: int) -> np.ndarray:
    return np.arange(n) if n <= m else np.unique(np.linspace(0, n - 1, m).round().astype(int))


def record_result(result, spec, out: str, application_id: str = "theoria") -> dict:
    """Write `result` (physics.scenarios.Result of `spec`) to the .rrd file `out`."""
    traj = result.trajectory
    n = len(traj.t)
    unit = SECONDS.get(traj.time_unit, None)
    rec = rr.RecordingStream(application_id, recording_id=str(uuid.uuid4()))
    with _sigterm_raises():
        try:
            rec.save(out, default_blueprint=blueprint([]))
            _write(rec, result, spec, traj, n, unit)
        finally:
            rec.disconnect()  # writes the footer; a file without it is refused by the reader
    return {"path": out, "steps": n}


def _write(rec, result, spec, traj, n, unit):
    tcols = [rr.TimeColumn("step", sequence=np.arange(n))] + _time_columns(traj.t, unit, traj.time_unit)
    rec.log("/world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    rec.log("/text", rr.TextDocument(text_of(spec, result), media_type=rr.MediaType.MARKDOWN), static=True)
    idx = _decimate(n, MAX_TRAIL_POINTS)
    rotation = spec.kind == "rotation"
    if rotation:
        semi = shape_semi_axes(traj.inertia)  # true proportions, a flat body given a little thickness
        q = to_xyzw(np.asarray(traj.quat_wxyz, float))
        rec.send_columns("/world/body", indexes=tcols,
                         columns=rr.Transform3D.columns(quaternion=q))
        rec.log("/world/body/ellipsoid", rr.Ellipsoids3D(half_sizes=[semi], colors=[(200, 190, 170)],
                                                         fill_mode=rr.components.FillMode.Solid), static=True)
        rec.log("/world/body/axes", rr.Arrows3D(vectors=np.diag(semi * 1.35), colors=list(AXIS_COLORS),
                                                labels=[f"A={traj.inertia[0]:.4g}", f"B={traj.inertia[1]:.4g}",
                                                        f"C={traj.inertia[2]:.4g}"]), static=True)
        rec.log("/world/body", rr.TransformAxes3D(axis_length=0.6), static=True)
        E0, L0 = float(traj.energy[0]), float(traj.momentum_norm[0])
        if E0 > 0:  # the scale of the energy ellipsoid, as in the app
            k_w = 1.3 / np.sqrt(2 * E0 / traj.inertia).max()
        else:  # starts at rest: the largest ω of the run is drawn 1.3 long
            wmax = float(np.max(np.linalg.norm(traj.omega_body, axis=1)))
            k_w = 1.3 / wmax if wmax > 0 else 1.0
        w = k_w * np.asarray(traj.omega_inertial, float)
        Lv = 1.3 * np.asarray(traj.L_inertial, float) / L0 if L0 > 0 else np.zeros((n, 3))
        rec.send_columns("/world/omega", indexes=tcols, columns=rr.Arrows3D.columns(vectors=w))
        rec.log("/world/omega", rr.Arrows3D.from_fields(colors=[OMEGA_COLOR], labels=["ω"]), static=True)
        rec.send_columns("/world/L", indexes=tcols, columns=rr.Arrows3D.columns(vectors=Lv))
        rec.log("/world/L", rr.Arrows3D.from_fields(colors=[L_COLOR], labels=["L"]), static=True)
        # paths (static, whole run): polhode on the body, herpolhode and rotation-axis trail in space
        wb = np.asarray(traj.omega_body, float)[idx]
        nw = np.linalg.norm(wb, axis=1, keepdims=True)
        ok = nw[:, 0] > 0
        if ok.sum() >= 2:
            u = wb[ok] / nw[ok]
            s = 1.0 / np.sqrt(np.sum((u / semi) ** 2, axis=1, keepdims=True))
            rec.log("/world/body/polhode", rr.LineStrips3D([1.01 * s * u], colors=[POLHODE_COLOR]), static=True)
        rec.log("/world/herpolhode", rr.LineStrips3D([w[idx]], colors=[HERPOLHODE_COLOR]), static=True)
        rec.log("/world/axis_trail", rr.LineStrips3D([1.6 * np.asarray(traj.rotation_axis)[idx]],
                                                     colors=[TRAIL_COLOR]), static=True)
        rec.log("/world/figure_axis_trail", rr.LineStrips3D([2.4 * np.asarray(traj.figure_axis)[idx]],
                                                            colors=[AXIS_COLORS[2]]), static=True)
        series = {"energy": traj.energy, "momentum_norm": traj.momentum_norm,
                  "omega/x": traj.omega_body[:, 0], "omega/y": traj.omega_body[:, 1],
                  "omega/z": traj.omega_body[:, 2]}
    else:
        series = {}
    # other bodies: positions per step, trails static
    if traj.bodies:
        allpos = np.concatenate([np.asarray(p, float) for p in traj.bodies.values()])
        span = float(np.max(np.linalg.norm(allpos, axis=1))) or 1.0
        for k, (name, pos) in enumerate(traj.bodies.items()):
            pos = np.asarray(pos, float)
            if rotation:  # a distant attractor is drawn by its direction
                pos = 3.0 * pos / np.maximum(np.linalg.norm(pos, axis=1, keepdims=True), 1e-300)
            else:
                pos = 3.0 * pos / span
            rec.send_columns(f"/world/bodies/{name}", indexes=tcols, columns=rr.Points3D.columns(positions=pos))
            rec.log(f"/world/bodies/{name}", rr.Points3D.from_fields(colors=[palette(k)], radii=[0.08],
                                                                     labels=[name]), static=True)
            rec.log(f"/world/trails/{name}", rr.LineStrips3D([pos[idx]], colors=[palette(k)]), static=True)
    for name, v in traj.series.items():
        series[f"trajectory/{name}"] = v
    for name, v in result.plot_series.items():
        series[f"plot/{name}"] = v
    for name, v in series.items():
        v = np.asarray(v, float)
        if v.shape != (n,):
            continue
        rec.send_columns(f"/series/{_safe(name)}", indexes=tcols, columns=rr.Scalars.columns(scalars=v))
    # the metrics, as constant lines over the run (so they show beside the series)
    ends = [0, n - 1]
    mcols = [rr.TimeColumn("step", sequence=ends)] + _time_columns(np.asarray(traj.t)[ends], unit, traj.time_unit)
    for name, v in result.metrics.items():
        try:
            v = float(v)
        except (TypeError, ValueError):
            continue
        if np.isfinite(v):
            rec.send_columns(f"/metrics/{_safe(name)}", indexes=mcols, columns=rr.Scalars.columns(scalars=[v, v]))


def _time_columns(t, unit, unit_name) -> list:
    """The `t` timeline: a duration in seconds when the unit is known and fits rerun's int64
    nanoseconds (±292 years); otherwise `t_milli`, a sequence of 1000 × t in the run's own unit."""
    t = np.asarray(t, float)
    if unit is not None and np.all(np.abs(t * unit) < 9e9):
        return [rr.TimeColumn("t", duration=t * unit)]
    return [rr.TimeColumn("t_milli", sequence=np.round(1000.0 * t).astype(np.int64))]


def _safe(name: str) -> str:
    return "".join(c if (c.isalnum() or c in "_/-") else "_" for c in name).strip("_") or "x"


def record(name: str, out: str, values: dict | None = None) -> dict:
    """Simulate scenario `name` with resolved parameter `values` and write a recording to `out`."""
    from theoria.scenarios import get

    spec = get(name)
    values = spec.resolve(values) if values is not None else spec.resolve(None)
    result = spec.simulate_fn(values)
    return record_result(result, spec, out)
