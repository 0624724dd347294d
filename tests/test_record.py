"""Rerun recordings read back with rerun's own reader (rerun.chunk.RrdReader)."""
from __future__ import annotations

import warnings

import numpy as np
from rerun.chunk import RrdReader

from theoria.app.record import record, record_run
from theoria.scenarios import get


def _read(path):
    """entity path → (rows on the time lines, static rows, timeline names, chunks)."""
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # "RRD file has no footer" is a warning: make it fail
        chunks = RrdReader(str(path)).stream().to_chunks()
    for c in chunks:
        e = out.setdefault(str(c.entity_path), {"rows": 0, "static": 0, "timelines": set(), "chunks": []})
        if c.is_static:
            e["static"] += c.num_rows
        else:
            e["rows"] += c.num_rows
            e["timelines"] |= set(c.timeline_names)
        e["chunks"].append(c)
    return out


def test_recording_holds_the_drawing_every_frame_and_every_sample(tmp_path):
    spec = get("middle-axis-flip")
    values = spec.resolve({"duration": "10", "step": "0.02"})
    out = tmp_path / "flip.rrd"
    info = record("middle-axis-flip", str(out), values)
    n = 501  # 10 s / 0.02 s steps + the initial state: every sample is a frame
    assert info["steps"] == n and info["frames"] == n
    ents = _read(out)
    for e in ("/world/body", "/world/omega", "/world/L"):  # what moves: one row per frame
        assert ents[e]["rows"] == n, (e, ents[e]["rows"])
        assert {"frame", "t"} <= ents[e]["timelines"], e
    for e in ("/series/energy", "/series/momentum_norm"):  # the run's series: one row per sample
        assert ents[e]["rows"] == n and {"step", "t"} <= ents[e]["timelines"], e
    for e in ("/world/body/mesh/0", "/world/body/axes", "/world/body/polhode", "/world/herpolhode",
              "/world/axis_trail", "/text"):
        assert ents[e]["static"] >= 1, e
    for m in ("flip_interval", "flip_interval_exact", "energy_rel_drift"):
        assert ents[f"/metrics/{m}"]["rows"] == 2
    # the quaternions in the file are the trajectory's, in rerun's (x, y, z, w) order
    res = spec.simulate_fn(values)
    rows = []
    for c in ents["/world/body"]["chunks"]:
        if c.is_static:
            continue
        rb = c.to_record_batch()
        rows += list(zip(rb.column("frame").to_pylist(), (x[0] for x in rb.column("Transform3D:quaternion").to_pylist())))
    rows.sort()
    assert [r[0] for r in rows] == list(range(n))
    q = np.array([r[1] for r in rows])
    qw = res.trajectory.quat_wxyz
    assert np.allclose(q, np.c_[qw[:, 1:], qw[:, :1]], atol=1e-6)  # float32 in the file
    text = [c for c in ents["/text"]["chunks"]][0].to_record_batch().to_pylist()
    assert "§808" in str(text)


def test_orbit_like_bodies_are_recorded(tmp_path):
    """A trajectory with Trajectory.bodies (as the orbit scenarios produce) gets a position per frame."""
    from theoria.physics.trajectory import Trajectory
    from theoria.scenarios.base import Run, Scenario

    n = 50
    t = np.linspace(0, 1, n)
    pos = np.stack([np.cos(t), np.sin(t), 0 * t], 1)
    traj = Trajectory(t, np.tile([1.0, 0, 0, 0], (n, 1)), np.zeros((n, 3)), (1.0, 1.0, 1.0),
                      bodies={"moon": pos, "sun": -pos})
    spec = Scenario("demo-orbit", "demo", "§0", "three bodies", "demo", (), lambda v, progress=None: None, kind="orbit")
    out = tmp_path / "orbit.rrd"
    record_run(Run("demo-orbit", {}, traj, {"x_m": 1.0}, spec=spec), out)
    ents = _read(out)
    assert ents["/world/bodies/moon"]["rows"] == n and ents["/world/bodies/sun"]["rows"] == n
    assert ents["/world/body_trails/moon"]["static"] == 1
    assert "/world/body" not in ents


def test_a_digest_field_not_stored_as_logged_is_encoded_again(tmp_path, monkeypatch):
    """rerun's LZ4 may store a few of the digest field's random bytes as a reference to earlier
    bytes of its chunk: the field is then not found as logged, and the recording is encoded again
    (other random bytes) rather than written without a digest or refused."""
    import theoria.app.record as R
    from theoria.app.replay import check

    seal, calls = R.seal, []

    def not_found_once(data, field):
        calls.append(field)
        return None if len(calls) == 1 else seal(data, field)

    monkeypatch.setattr(R, "seal", not_found_once)
    out = tmp_path / "again.rrd"
    record("free-tumble", str(out), {"duration": "1"})
    assert len(calls) == 2 and calls[0] != calls[1]
    assert check(str(out))["digest"] is not None


def test_replay_without_a_display_says_to_use_the_web_viewer(tmp_path, monkeypatch, capsys):
    """On a machine with no screen (a server, CI, SSH) `theoria replay run.rrd` ended with rerun's
    own winit error, exit 1: it says where the viewer can go instead, one line, exit 2."""
    import theoria as th
    from theoria.app.cli import main

    rrd = tmp_path / "run.rrd"
    th.scenario("free-tumble").simulate(duration=1).record(str(rrd))
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")
    code = main(["replay", str(rrd)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "no display" in err and "--web-viewer" in err, err
