"""`theoria record NAME --out FILE.rrd`: a rerun recording of a run's drawing.

The rerun renderer of a scenario's `Drawing` (theoria.scenarios.drawing): each item becomes the
entity "/world/<its name>" (rerun composes transforms along entity paths as viser does along node
names, so "body/polhode" turns with the body), with the same colours and scale as the app.
What moves is sent column-wise (`rr.send_columns`, one call per entity for the whole run) on the
`frame` timeline and the `t` timeline (the run's time in seconds, or `t_milli` = 1000 × t in the
run's own unit when that is not a time or does not fit rerun's durations). The run's series
(energy, the scenario's plot) and its metrics go to time series views on the run's own samples.

The blueprint opens the 3D view where the app's camera is, looking at the same point, beside the
plots and a text panel with the title, §, what to look for, Euler's formula, the parameters, the
Euler / simulated / modern table and the warnings. Overlays that are off by default in the app are
left out of the view's contents (present in the file, one click away in rerun).

Differences that rerun imposes: paths are drawn whole (rerun has no "appear at frame" for points
of one strip), lights are not recorded (rerun lights the scene itself), and a camera that follows
the run (the Moon seen from the Earth) is recorded as the starting view only.

The file carries a digest of its own bytes: the static entity "/theoria/digest" holds a fixed
16-byte marker and the 32-byte blake2b of the whole file with those 32 bytes as zeros (as the HTML
export carries its sha256). rerun copies short runs of random bytes into its (LZ4) chunks as they
are, so the field is logged with random bytes, found in the encoded stream and overwritten there:
the file stays a plain rerun recording (rerun's viewer and reader open it), and `theoria replay
--check` recomputes the digest, so that one byte changed anywhere in the file is seen.

The file is whole or absent: rerun encodes the recording into memory (a binary stream, footer
included) and `app.files.write_whole` writes it beside the target and renames it over the target
only when every byte is on disk. A recording interrupted (Ctrl-C, SIGTERM) or refused by the disk
leaves no file and an older one as it was. rerun's own file sink is not used: it writes the footer
however early the stream is closed (a cut-short file passed every check), and on a full disk its
flush blocks forever.

Replay: `rerun FILE.rrd`, or `theoria replay FILE.rrd --web-viewer`.
"""
from __future__ import annotations

import hashlib
import os
import uuid

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from theoria.physics.constants import JULIAN_YEAR_DAYS, SECONDS_PER_DAY
from theoria.physics.quaternion import to_xyzw
from theoria.scenarios.drawing import Arrows, Frame, Label, Light, Mesh, Path, Points, Segments, Sphere

from .files import write_whole
from .format import comparison_rows
from .interrupt import signals_held

_YEAR_S = JULIAN_YEAR_DAYS * SECONDS_PER_DAY
SECONDS = {"s": 1.0, "min": 60.0, "h": 3600.0, "day": SECONDS_PER_DAY, "days": SECONDS_PER_DAY, "d": SECONDS_PER_DAY,
           "yr": _YEAR_S, "year": _YEAR_S, "years": _YEAR_S}  # seconds in each time unit a run may carry
APPLICATION_ID = "theoria"
DIGEST_ENTITY = "/theoria/digest"
DIGEST_MARKER = bytes.fromhex("dc04f4d982420f87075d28b0c7f814b5")  # random: in no other chunk of any file
DIGEST_SIZE = 32  # blake2b-256


def file_digest(data, at: int) -> bytes:
    """blake2b-256 of the recording `data` (bytes, a memoryview, an mmap) with its DIGEST_SIZE bytes
    at `at` read as zeros: the value written there."""
    view = memoryview(data)
    h = hashlib.blake2b(digest_size=DIGEST_SIZE)
    h.update(view[:at])
    h.update(bytes(DIGEST_SIZE))
    h.update(view[at + DIGEST_SIZE:])
    return h.digest()


def _log_digest_field(rec) -> bytes:
    """Log the digest's field, holding random bytes for now; returns the field as logged."""
    field = DIGEST_MARKER + os.urandom(DIGEST_SIZE)
    rec.log(DIGEST_ENTITY, rr.AnyValues(blake2b=np.frombuffer(field, np.uint8)), static=True)
    return field


def seal(data: bytes, field: bytes) -> bytearray | None:
    """The encoded recording with its digest written into the field logged by `_log_digest_field`;
    None when the field is not in the stream once as logged (LZ4 met 4 of its random bytes earlier
    in the same chunk and stored a reference to them instead: rare, the chunk holds little else)."""
    at = data.find(field)
    if at < 0 or data.find(field, at + 1) >= 0:
        return None
    at += len(DIGEST_MARKER)
    out = bytearray(data)
    out[at:at + DIGEST_SIZE] = file_digest(out, at)
    return out


def blueprint(drawing) -> rrb.Blueprint:
    cam = drawing.camera
    hidden = sorted({f"- /world/{it.name}/**" for it in drawing.items if not drawing.shown(it)} |
                    {f"- /world/{it.name}" for it in drawing.items if not drawing.shown(it)})
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(origin="/world", name=drawing.title or "scene", contents=["$origin/**", *hidden],
                              eye_controls=rrb.EyeControls3D(position=cam.position, look_target=cam.look_at,
                                                             eye_up=cam.up)),
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


def text_of(drawing, run) -> str:
    """The scenario's text as markdown: what the app's panel says."""
    lines = [f"# {drawing.title}", f"**{drawing.section}** · `{run.scenario}`", "", drawing.summary, ""]
    if drawing.formula:
        lines += ["**Euler:**", ""] + [f"> {ln.strip()}  " for ln in drawing.formula.splitlines() if ln.strip()] + [""]
    lines += [f"Time: timeline `t` (seconds), or `t_milli` = 1000 × t in {drawing.time_unit} when the unit is "
              "not a time or the run is longer than rerun's durations allow; `frame` steps through the drawing.", "",
              "## Parameters", ""]
    spec = run._spec()
    for p in spec.params:
        lines.append(f"- {p.name} = {run.params.get(p.name)} {p.unit}".rstrip())
    rows = comparison_rows(run.comparisons)
    if rows:
        lines += ["", "## Euler says / simulated / modern", "", "| | Euler says | simulated | modern | unit |",
                  "|---|---|---|---|---|"]
        lines += ["| " + " | ".join(c.replace("|", "\\|") for c in r) + " |" for r in rows]
    if run.warnings:
        lines += ["", "## Warnings", ""] + [f"- {w}" for w in run.warnings]
    if run.notes:
        lines += [""] + [f"*{n}*" for n in run.notes]
    return "\n".join(lines)


def _time_columns(t, unit_name, index_name, index) -> list:
    """`index_name` as a sequence, and `t` as a duration in seconds when the unit is known and fits
    rerun's int64 nanoseconds (±292 years), else `t_milli` = 1000 × t in the run's own unit."""
    t = np.asarray(t, float)
    cols = [rr.TimeColumn(index_name, sequence=np.asarray(index, np.int64))]
    unit = SECONDS.get(unit_name)
    if unit is not None and np.all(np.abs(t * unit) < 9e9):
        return cols + [rr.TimeColumn("t", duration=t * unit)]
    return cols + [rr.TimeColumn("t_milli", sequence=np.round(1000.0 * t).astype(np.int64))]


def _rgb(c):
    a = np.asarray(c, np.uint8)
    return a.reshape(-1, 3)


def _log_item(rec, it, path, tcols, n_frames) -> None:
    anim = it.animated()
    if isinstance(it, Light):
        return  # rerun lights the scene itself
    if isinstance(it, (Frame, Mesh)):
        if anim and ("wxyz" in anim or "position" in anim):
            kw = {}
            if "wxyz" in anim:
                kw["quaternion"] = to_xyzw(np.asarray(it.wxyz, float))
            if "position" in anim:
                kw["translation"] = np.asarray(it.position, float)
            rec.send_columns(path, indexes=tcols, columns=rr.Transform3D.columns(**kw))
        static = {}
        if "wxyz" not in anim:
            static["quaternion"] = rr.Quaternion(xyzw=to_xyzw(np.asarray(it.wxyz, float)))
        if "position" not in anim:
            static["translation"] = np.asarray(it.position, float)
        if isinstance(it, Mesh):
            static["scale"] = np.asarray(it.scale, float)
        rec.log(path, rr.Transform3D(**static), static=True)
        if isinstance(it, Mesh):
            rgba = list(_rgb(it.color)[0]) + [int(255 * it.opacity)]
            rec.log(path, rr.Mesh3D(vertex_positions=np.asarray(it.vertices, np.float32),
                                    triangle_indices=np.asarray(it.faces, np.uint32), albedo_factor=rgba), static=True)
        return
    if isinstance(it, Sphere):
        if "position" in anim:
            rec.send_columns(path, indexes=tcols, columns=rr.Transform3D.columns(translation=np.asarray(it.position, float)))
        else:
            rec.log(path, rr.Transform3D(translation=np.asarray(it.position, float)), static=True)
        rec.log(path, rr.Ellipsoids3D(half_sizes=[[it.radius] * 3], colors=_rgb(it.color),
                                      fill_mode=rr.components.FillMode.Solid), static=True)
        return
    if isinstance(it, Path):
        rec.log(path, rr.LineStrips3D([np.asarray(it.points, np.float32)], colors=_rgb(it.color),
                                      radii=[0.5 * it.thickness]), static=True)
        return
    if isinstance(it, Points):
        cols = _rgb(it.colors)
        rec.log(path, rr.Points3D(np.asarray(it.points, np.float32), colors=cols if len(cols) > 1 else cols[0],
                                  radii=[0.5 * it.size]), static=True)
        return
    if isinstance(it, Segments):
        cols = _rgb(np.asarray(it.colors)[..., 0, :] if np.ndim(it.colors) == 3 else it.colors)
        if "points" in anim:
            segs = np.asarray(it.points, np.float32)  # (F, K, 2, 3)
            F, K = segs.shape[:2]
            rec.send_columns(path, indexes=tcols,
                             columns=rr.LineStrips3D.columns(strips=list(segs.reshape(F * K, 2, 3))).partition([K] * F))
            rec.log(path, rr.LineStrips3D.from_fields(colors=cols, radii=[0.5 * it.thickness]), static=True)
        else:
            rec.log(path, rr.LineStrips3D(list(np.asarray(it.points, np.float32)), colors=cols,
                                          radii=[0.5 * it.thickness]), static=True)
        return
    if isinstance(it, Arrows):
        origins = np.asarray(it.origins, np.float32).reshape(-1, 3)
        cols = _rgb(it.colors)
        labels = [str(x) for x in it.labels] or None
        if "vectors" in anim:
            v = np.asarray(it.vectors, np.float32)  # (F, K, 3)
            F, K = v.shape[:2]
            rec.send_columns(path, indexes=tcols, columns=rr.Arrows3D.columns(
                vectors=v.reshape(F * K, 3), origins=np.tile(origins, (F, 1))).partition([K] * F))
            rec.log(path, rr.Arrows3D.from_fields(colors=cols, labels=labels, radii=[it.shaft_radius]), static=True)
        else:
            rec.log(path, rr.Arrows3D(origins=origins, vectors=np.asarray(it.vectors, np.float32), colors=cols,
                                      labels=labels, radii=[it.shaft_radius]), static=True)
        return
    if isinstance(it, Label):
        if "position" in anim:
            rec.send_columns(path, indexes=tcols, columns=rr.Transform3D.columns(translation=np.asarray(it.position, float)))
            pos = np.zeros(3)
        else:
            pos = np.asarray(it.position, float)
        if "text" in anim:
            rec.send_columns(path, indexes=tcols, columns=rr.Points3D.columns(
                positions=np.tile(pos, (n_frames, 1)), labels=[str(x) for x in it.text]))
            rec.log(path, rr.Points3D.from_fields(radii=[0.004], show_labels=True), static=True)
        else:
            rec.log(path, rr.Points3D([pos], labels=[str(it.text)], radii=[0.004], show_labels=True), static=True)


def record_drawing(rec, drawing, run, check=lambda: None) -> None:
    """Log `drawing` of `run` into the open recording stream `rec`; `check()` between two items
    (where the logging may stop)."""
    F = drawing.n_frames
    tcols = _time_columns(drawing.times, drawing.time_unit, "frame", np.arange(F))
    rec.log("/world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    rec.log("/text", rr.TextDocument(text_of(drawing, run), media_type=rr.MediaType.MARKDOWN), static=True)
    for it in drawing.items:
        check()
        _log_item(rec, it, f"/world/{it.name}", tcols, F)
    # the run's series on its own samples: the energy and |L| of a rotation, the scenario's plot
    tr = run.trajectory
    n = len(tr.t)
    scols = _time_columns(tr.t, tr.time_unit, "step", np.arange(n))
    series = {}
    if drawing.rotation:
        series.update({"energy": tr.energy, "momentum_norm": tr.momentum_norm})
    series.update({f"plot/{k}": v for k, v in drawing.plot.items()})
    for name, v in series.items():
        check()
        v = np.asarray(v, float)
        if v.shape == (n,):
            rec.send_columns(f"/series/{_safe(name)}", indexes=scols, columns=rr.Scalars.columns(scalars=v))
    ends = [0, n - 1]
    mcols = _time_columns(np.asarray(tr.t)[ends], tr.time_unit, "step", ends)
    check()
    for name, v in run.metrics.items():
        try:
            v = float(v)
        except (TypeError, ValueError):
            continue
        if np.isfinite(v):
            rec.send_columns(f"/metrics/{_safe(name)}", indexes=mcols, columns=rr.Scalars.columns(scalars=[v, v]))


def _safe(name: str) -> str:
    return "".join(c if (c.isalnum() or c in "_/-") else "_" for c in name).strip("_") or "x"


def record_run(run, out, view=None, application_id: str = APPLICATION_ID) -> dict:
    """Write the rerun recording of `run` (its drawing, camera and text) to the .rrd file `out`."""
    drawing = run._spec().drawing(run, view)
    for _ in range(3):  # a field rerun did not store as it was logged: encoded again, with other random bytes
        sealed = seal(*_encode(run, drawing, application_id))
        if sealed is not None:
            break
    else:
        raise RuntimeError("rerun did not store the recording's digest field as it was logged")
    nbytes = write_whole(out, sealed)
    return {"path": str(out), "steps": len(run.trajectory.t), "frames": drawing.n_frames, "bytes": nbytes}


def _encode(run, drawing, application_id) -> tuple[bytes, bytes]:
    """The whole rerun stream of `drawing` (every chunk and the footer) and its digest's field."""
    rec = stream = data = None
    try:
        # rerun's calls are not cut in the middle (`signals_held`): Ctrl-C or SIGTERM is taken
        # between two items of the drawing, or once the whole stream is read
        with signals_held() as held:
            layout = blueprint(drawing)
            rec = rr.RecordingStream(application_id, recording_id=str(uuid.uuid4()))
            stream = rec.binary_stream()  # in memory: the file is written whole by write_whole below
            rec.send_blueprint(layout, make_active=False, make_default=True)
            record_drawing(rec, drawing, run, held.check)
            field = _log_digest_field(rec)
            data = stream.read(flush=True)  # every chunk and the footer
    finally:
        if rec is not None:
            rec.disconnect()
        if data is None and stream is not None:  # stopped: what rerun encodes still is read and dropped
            _drain(stream)
    return data, field


DRAIN_S = 30.0  # a bound on the wait for rerun to encode what was logged before a Ctrl-C


def _drain(stream) -> None:
    """Read and drop everything the recording stream holds or rerun still encodes for it (on
    threads of its own): a stream dropped with bytes unread makes rerun print a coloured WARN
    ("Dropping data in BinaryStreamStorage") at exit, after 'theoria: interrupted'. A second
    Ctrl-C or SIGTERM waits for the end of this (the command stops just after)."""
    with signals_held():
        try:
            stream.read(flush=True, flush_timeout_sec=DRAIN_S)
        except Exception:  # noqa: BLE001 — nothing is written either way
            pass


def record(name: str, out: str, values: dict | None = None) -> dict:
    """Simulate scenario `name` with `values` and write its recording to `out`."""
    from theoria.scenarios import get

    spec = get(name)
    run = spec.simulate_fn(spec.resolve(values))
    return record_run(run, out)
