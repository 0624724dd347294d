"""`theoria replay FILE`: open a recording or an export that theoria wrote, and refuse anything
else with one clear line (exit 2).

- ``.rrd`` (from `theoria record`): rerun's own reader (`rerun.chunk.RrdReader`) must read the
  whole file with its footer (a file cut short has none: rerun then warns "no footer", taken here
  as an error), hold a recording whose application id is "theoria", and hold theoria's entities
  (`/world` and the `/text` document with the Euler table). Then the rerun viewer opens it
  (`rerun FILE`, or `rerun FILE --web-viewer` with ``--web-viewer``).
- ``.html`` (from `theoria export`): must carry the marker `app.export_html.MARKER`, the embedded
  viser scene, and end with ``</html>`` (a truncated file does not). Then its ``file://`` URL is
  printed (the file plays in any browser with no server).

``--check`` validates only (tests, scripts) and prints what was found.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

APPLICATION_ID = "theoria"  # app/record.py: rr.RecordingStream("theoria", ...)
REQUIRED_ENTITIES = ("/world", "/text")
HTML_MARKER_RE = re.compile(r'<meta name="generator" content="theoria export_html" data-theoria-scenario="([^"]*)"')


class ReplayError(Exception):
    """The file is not a complete theoria recording / export. Message: one line."""


def _one_line(e: BaseException) -> str:
    text = " ".join(str(e).split())
    return (text[:157] + "…") if len(text) > 160 else text


def check_rrd(path: str) -> dict:
    """What the .rrd holds, or ReplayError when it is not a complete theoria recording."""
    from rerun.chunk import RrdReader

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # "RRD file has no footer" (cut short) is only a warning
            reader = RrdReader(str(path))
            recs = reader.recordings()
    except Exception as e:
        if "footer" in str(e):
            raise ReplayError(f"{path}: incomplete rerun recording (no footer: cut short while being written, "
                              "or not written by theoria)") from None
        raise ReplayError(f"{path}: not a readable rerun recording ({_one_line(e) or type(e).__name__})") from None
    ours = [r for r in recs if r.application_id == APPLICATION_ID]
    if not ours:
        apps = ", ".join(sorted({r.application_id for r in recs})) or "none"
        raise ReplayError(f"{path}: a rerun recording, but not theoria's (application id: {apps})")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            chunks = reader.stream(store=ours[0]).to_chunks()
    except Exception as e:
        raise ReplayError(f"{path}: theoria recording is damaged or incomplete ({_one_line(e) or type(e).__name__})") from None
    entities = {str(c.entity_path) for c in chunks}
    missing = [e for e in REQUIRED_ENTITIES if e not in entities]
    if missing:
        raise ReplayError(f"{path}: not a theoria recording (no {', '.join(missing)} entity)")
    rows = sum(c.num_rows for c in chunks)
    return {"kind": "rrd", "path": str(path), "recording_id": ours[0].recording_id,
            "entities": len(entities), "rows": rows}


def check_html(path: str) -> dict:
    """The scenario of a theoria HTML export, or ReplayError."""
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        raise ReplayError(f"{path}: cannot read ({e.strerror or type(e).__name__})") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise ReplayError(f"{path}: not a theoria HTML export (not UTF-8 text)") from None
    m = HTML_MARKER_RE.search(text[:4096])
    if m is None:
        raise ReplayError(f"{path}: not a theoria HTML export (no theoria marker in <head>)")
    if "__VISER_EMBED" not in text and "viser" not in text:
        raise ReplayError(f"{path}: theoria HTML export without its embedded scene")
    if not text.rstrip().endswith("</html>"):
        raise ReplayError(f"{path}: theoria HTML export is truncated (no closing </html>)")
    return {"kind": "html", "path": str(path), "scenario": m.group(1),
            "url": Path(os.path.abspath(path)).as_uri(), "bytes": len(data)}


def check(path: str) -> dict:
    p = Path(path)
    if not p.exists():
        raise ReplayError(f"{path}: no such file")
    if p.is_dir():
        raise ReplayError(f"{path}: a directory, not a file")
    suffix = p.suffix.lower()
    if suffix == ".rrd":
        return check_rrd(path)
    if suffix in (".html", ".htm"):
        return check_html(path)
    raise ReplayError(f"{path}: unknown kind of file; theoria replays .rrd (theoria record) and .html (theoria export)")


def replay(path: str, check_only: bool = False, web_viewer: bool = False) -> int:
    """Validate `path`, then open it (rerun viewer for .rrd; print the file:// URL for .html)."""
    info = check(path)
    if info["kind"] == "html":
        print(f"theoria export of {info['scenario']}: open {info['url']}")
        return 0
    if check_only:
        print(f"theoria recording {info['recording_id']}: {info['entities']} entities, {info['rows']} rows — ok")
        return 0
    exe = shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))
    cmd = [exe, str(path)] + (["--web-viewer"] if web_viewer else [])
    return subprocess.call(cmd)
