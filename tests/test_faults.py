"""Faults: foreign or damaged files given to `theoria replay`, diverging simulations reported as
such."""
from __future__ import annotations

import json

import numpy as np
import pytest

from theoria.app.replay import ReplayError, check
from theoria.physics.params import Param, ParameterError
from theoria.scenarios import get
from theoria.scenarios.base import Diverged, Run, Scenario
from theoria.physics.trajectory import Trajectory


# ---- theoria replay ------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from theoria.app.export_html import export
    from theoria.app.record import record

    d = tmp_path_factory.mktemp("replay")
    rrd, html = d / "tumble.rrd", d / "tumble.html"
    record("free-tumble", str(rrd), {"duration": "2"})
    export("free-tumble", str(html), {"duration": "2"})
    return d, rrd, html


def test_replay_accepts_own_files(files, cli):
    d, rrd, html = files
    code, out, err = cli("replay", str(rrd), "--check")
    assert code == 0 and "ok" in out and err == ""
    code, out, err = cli("replay", str(html), "--check")
    assert code == 0 and out.strip().endswith(html.resolve().as_uri()) and "free-tumble" in out
    assert check(str(rrd))["rows"] > 3 * 201  # the whole run is read back: body, ω and L at each of 201 frames


def _bad_cases(d, rrd, html):
    import rerun as rr

    data_rrd, data_html = rrd.read_bytes(), html.read_bytes()
    cases = {
        "truncated.rrd": data_rrd[: len(data_rrd) // 2],
        "tiny.rrd": data_rrd[:40],
        "empty.rrd": b"",
        "text.rrd": b"hello, not a recording\n",
        "bitflip.rrd": data_rrd[:200] + bytes(b ^ 0xFF for b in data_rrd[200:400]) + data_rrd[400:],
        "truncated.html": data_html[: len(data_html) // 2],
        # whole in form (marker, scene, closing tag) but damaged: a piece of the middle cut out, one
        # byte changed; each passed the check before the export wrote its digest
        "cut.html": data_html[: len(data_html) // 3] + data_html[len(data_html) // 3 + 199_000:],
        "changed.html": data_html[:len(data_html) // 2] + bytes([data_html[len(data_html) // 2] ^ 1]) +
        data_html[len(data_html) // 2 + 1:],
        "foreign.html": b"<!doctype html><html><head><title>x</title></head><body>hi</body></html>\n",
        "binary.html": bytes(range(256)) * 10,
        "empty.html": b"",
        "notes.txt": b"theoria",
    }
    for name, blob in cases.items():
        (d / name).write_bytes(blob)
    # a complete rerun recording from another application
    rec = rr.RecordingStream("someone-else", recording_id="foreign")
    rec.save(str(d / "foreign.rrd"))
    rec.log("/points", rr.Points3D(np.zeros((3, 3))))
    rec.disconnect()
    # theoria's application id but none of theoria's entities
    rec = rr.RecordingStream("theoria", recording_id="impostor")
    rec.save(str(d / "impostor.rrd"))
    rec.log("/points", rr.Points3D(np.zeros((3, 3))))
    rec.disconnect()
    return sorted(list(cases) + ["foreign.rrd", "impostor.rrd", "missing.rrd", "."])


def test_replay_refuses_corrupt_truncated_foreign(files, cli):
    d, rrd, html = files
    for name in _bad_cases(d, rrd, html):
        path = str(d / name)
        with pytest.raises(ReplayError) as ei:
            check(path)
        assert "\n" not in str(ei.value) and path in str(ei.value)
        code, out, err = cli("replay", path, "--check")
        assert code == 2, name
        assert out == "" and err.startswith("theoria: error: ") and err.count("\n") == 1, (name, err)
    # what the messages say
    msg = {n: str(pytest.raises(ReplayError, check, str(d / n)).value)
           for n in ("truncated.rrd", "foreign.rrd", "impostor.rrd", "truncated.html", "foreign.html")}
    assert "no footer" in msg["truncated.rrd"]
    assert "not theoria's" in msg["foreign.rrd"] and "someone-else" in msg["foreign.rrd"]
    assert "no /world" in msg["impostor.rrd"]
    assert "truncated" in msg["truncated.html"]
    assert "no theoria marker" in msg["foreign.html"]


def test_replay_cli_subprocess_exit_code(files, cli_process):
    """The installed entry point path: `python -m theoria.app.cli replay` exits 2 with one line."""
    d, rrd, _ = files
    bad = d / "half.rrd"
    bad.write_bytes(rrd.read_bytes()[:5000])
    code, out, err = cli_process("replay", bad, "--check")
    assert code == 2 and out == "" and err.count("\n") == 1 and "half.rrd" in err


def _flipped(data: bytes, at: int) -> bytes:
    return data[:at] + bytes([data[at] ^ 0x10]) + data[at + 1:]


def _last_chunk(data: bytes) -> tuple[int, int]:
    """Where the last data message's payload lies in an .rrd: rerun's stream is a 12-byte header,
    then messages, each a 16-byte header (kind, length: little-endian u64) and its payload; kind 2
    is a chunk, kind 0 the end, whose payload is the footer (under rerun's CRC)."""
    import struct

    at, last = 12, None
    while at + 16 <= len(data):
        kind, n = struct.unpack_from("<QQ", data, at)
        if kind == 0:
            return last
        if kind == 2:
            last = (at + 16, at + 16 + n)
        at += 16 + n
    raise AssertionError("no end message")


def test_one_changed_byte_anywhere_in_a_recording_is_seen(tmp_path, cli_process):
    """A recording made by `theoria record`, then one byte changed on disk: in the middle and in
    the last chunk (inside chunks, which rerun's reader reads without complaint: `--check` passed
    them) and near the end of the file (rerun's footer, under its own CRC). `theoria replay --check`
    (a child process, as a user runs it) refuses each copy in one line naming it, exit 2; the
    untouched file passes, and rerun's own reader streams it whole."""
    rec = tmp_path / "tumble.rrd"
    code, out, err = cli_process("record", "free-tumble", "--duration", "2", "--out", rec)
    assert code == 0, err
    data = rec.read_bytes()
    code, out, err = cli_process("replay", rec, "--check")
    assert code == 0 and err == "" and out.strip().endswith("— ok"), (out, err)
    start, stop = _last_chunk(data)
    for name, at in (("middle", len(data) // 2), ("last-chunk", (start + stop) // 2), ("end", len(data) - 200)):
        bad = tmp_path / f"{name}.rrd"
        bad.write_bytes(_flipped(data, at))
        code, out, err = cli_process("replay", bad, "--check")
        assert code == 2 and out == "" and err.count("\n") == 1, (name, code, out, err)
        assert err.startswith(f"theoria: error: {bad}: "), (name, err)
        if name != "end":
            assert "damaged (its bytes do not match the blake2b digest" in err, (name, err)
    # every part of the file, one byte at a time (in this process: the same check)
    for at in range(0, len(data), max(1, len(data) // 97)):
        bad = tmp_path / "flip.rrd"
        bad.write_bytes(_flipped(data, at))
        with pytest.raises(ReplayError):
            check(str(bad))
    # rerun's own reader: every chunk, with the "no footer" warning taken as an error
    import warnings

    from rerun.chunk import RrdReader

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        chunks = RrdReader(str(rec)).stream().to_chunks()
    assert {"/world", "/text", "/theoria/digest"} <= {str(c.entity_path) for c in chunks}
    # and rerun's own command: "can be loaded and correctly interpreted"
    import subprocess

    from theoria.app.replay import rerun_binary, viewer_env

    r = subprocess.run([rerun_binary(), "rrd", "verify", str(rec)], capture_output=True, text=True, timeout=120,
                       env=viewer_env())
    assert r.returncode == 0 and "1 file verified without error" in r.stdout + r.stderr, r.stdout + r.stderr


def test_a_recording_without_a_digest_is_read_and_said_to_have_none(tmp_path, cli_process):
    """A theoria recording as theoria wrote them before it carried a digest (its entities, no
    digest): `--check` reads it whole, says in one line that it has no digest, exit 3."""
    import rerun as rr

    old = tmp_path / "old.rrd"
    rec = rr.RecordingStream("theoria", recording_id="older")
    rec.save(str(old))
    rec.log("/world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    rec.log("/text", rr.TextDocument("# an older recording"), static=True)
    rec.disconnect()
    code, out, err = cli_process("replay", old, "--check")
    assert code == 3 and err == "" and out.count("\n") == 1 and "no digest" in out, (code, out, err)


def test_an_export_without_a_digest_is_said_to_have_none_as_a_recording_is(files, tmp_path, cli_process):
    """An HTML export as theoria wrote them before it carried a digest (its marker without
    data-sha256): `--check` reads it, says in one line that it has none and exits 3, as it does for
    a recording without one; opened without `--check` its URL is printed (exit 0). An export with
    its digest: exit 0, the digest named."""
    import re

    _, _, html = files
    old = tmp_path / "old.html"
    old.write_text(re.sub(r' data-sha256="[0-9a-f]{64}"', "", html.read_text(encoding="utf-8"), count=1),
                   encoding="utf-8")
    assert "data-sha256" not in old.read_text(encoding="utf-8")[:4096]
    code, out, err = cli_process("replay", old, "--check")
    assert code == 3 and err == "" and out.count("\n") == 1 and "no digest" in out and "export it again" in out, \
        (code, out, err)
    code, out, err = cli_process("replay", old)
    assert code == 0 and out.strip().endswith(old.resolve().as_uri()), (code, out, err)
    code, out, err = cli_process("replay", html, "--check")
    assert code == 0 and "sha256 " in out and "ok" in out and out.strip().endswith(html.resolve().as_uri()), out


# ---- divergence ------------------------------------------------------------------------------------

def _blowup_scenario(nan_at: float | None = 3.0, kind: str = "rotation"):
    """A test scenario whose spin becomes NaN at t = nan_at (as an overflowing integration would)."""

    def simulate(values, progress=None):
        t = np.linspace(0.0, 5.0, 51)
        L = np.tile([1.0, 0.5, 0.2], (len(t), 1)) * (1 + t[:, None])
        if nan_at is not None:
            L[t >= nan_at] = np.nan
        q = np.tile([1.0, 0.0, 0.0, 0.0], (len(t), 1))
        traj = Trajectory(t, q, L, np.array([1.0, 2.0, 3.0]), bodies={"moon": np.c_[np.cos(t), np.sin(t), 0 * t]})
        return Run("blowup", dict(values), traj, {"final_spin": float(np.linalg.norm(L[-1]))},
                      plot_series={"spin": np.linalg.norm(L, axis=1)})

    return Scenario("blowup", "blow-up", "§0", "ch. 15", "test", (Param("x", 1.0, 0.0, 2.0),), simulate, kind=kind)


def test_diverged_run_is_cut_and_reported():
    spec = _blowup_scenario(3.0)
    res = spec.simulate({"x": 1.0})
    assert res.status == "diverged" and res.diverged
    t = res.trajectory.t
    assert t[-1] < 3.0 and len(t) == 30  # 0, 0.1, ..., 2.9: the finite part, nothing after
    assert np.all(np.isfinite(res.trajectory.L_body)) and np.all(np.isfinite(res.trajectory.omega_inertial))
    assert len(res.plot_series["spin"]) == 30 and res.trajectory.bodies["moon"].shape == (30, 3)
    assert len(res.warnings) == 1 and res.warnings[0].startswith("diverged at t=3 s") and "angular momentum" in res.warnings[0]
    out = res.to_dict()
    assert out["status"] == "diverged" and out["warnings"] == res.warnings
    assert out["metrics"]["final_spin"] is None  # NaN metric → null, never NaN in the JSON
    json.dumps(out, allow_nan=False)
    # the app shows the notes beside the scene
    from theoria.app.server import comparison_markdown

    assert "diverged at t=3" in comparison_markdown(res)


def test_ok_run_untouched_and_no_finite_sample_refused():
    ok = _blowup_scenario(None).simulate({})
    assert ok.status == "ok" and ok.warnings == [] and len(ok.trajectory.t) == 51
    assert ok.to_dict()["status"] == "ok"
    with pytest.raises(Diverged) as ei:
        _blowup_scenario(0.0).simulate({})
    assert isinstance(ei.value, ParameterError) and "diverged at the start" in str(ei.value)


def test_overflow_without_nan_is_divergence():
    spec = _blowup_scenario(None)
    inner = spec.simulate_fn.__wrapped__

    def huge(values, progress=None):
        r = inner(values)
        r.trajectory.bodies["moon"][40:] = 1e200  # thrown out beyond any physical scale
        return r

    res = Scenario("huge", "h", "§0", "ch. 15", "t", spec.params, huge).simulate({})
    assert res.status == "diverged" and len(res.trajectory.t) == 40 and "position of moon" in res.warnings[0]


def test_cli_json_reports_divergence(cli, monkeypatch):
    """`theoria run --json` on a diverging scenario: status and warning in the JSON, exit 0."""
    from theoria.scenarios import base

    spec = _blowup_scenario(3.0)
    monkeypatch.setitem(base.REGISTRY, "blowup", spec)
    code, out, err = cli("run", "blowup", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["status"] == "diverged" and data["warnings"][0].startswith("diverged at t=3")


def test_real_scenarios_default_runs_are_ok():
    """The central check does not flag healthy runs (two quick scenarios of different kinds)."""
    for name, given in (("free-tumble", {"duration": 2.0}), ("collinear", {})):
        res = get(name).simulate(given)
        assert res.status == "ok", (name, res.warnings)


