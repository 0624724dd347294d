"""`theoria replay FILE`: open a recording or an export that theoria wrote, and refuse anything
else with one clear line (exit 2).

- ``.rrd`` (from `theoria record`): rerun's own reader (`rerun.chunk.RrdReader`) must read the
  whole file with its footer (a file cut short has none: rerun then warns "no footer", taken here
  as an error), hold a recording whose application id is "theoria", and hold theoria's entities
  (`/world` and the `/text` document with the Euler table); its bytes must match the blake2b
  digest it carries (app/record.py: one byte changed inside a chunk reads without complaint).
  A recording written before theoria wrote digests carries none: it is opened, and ``--check``
  says so and exits 3 (EXIT_NO_DIGEST). Then the rerun viewer opens it:
  the native viewer, or with ``--web-viewer`` rerun's web viewer served on 127.0.0.1 (``--host``
  to change it), its URL printed and a browser opened only with ``--open``. The viewer runs as
  a child that stops with this command: Ctrl-C or SIGTERM stop it, and the kernel stops it if
  this process dies (PR_SET_PDEATHSIG); it sends no analytics.
- ``.html`` (from `theoria export`): must carry the marker `app.export_html.MARKER`, the embedded
  viser scene, end with ``</html>`` (a truncated file does not) and match the sha256 digest the
  export wrote into its marker (a piece cut out of the middle, or a changed byte, does not); an
  export made before theoria wrote that digest is read, and ``--check`` says it has none and exits
  3, as for a recording. Then its ``file://`` URL is printed (the file plays in any browser with
  no server).

``--check`` validates only (tests, scripts) and prints what was found.
"""
from __future__ import annotations

import ctypes
import os
import re
import shutil
import signal
import socket
import stat
import subprocess
import sys
import warnings
from pathlib import Path
from urllib.parse import quote

APPLICATION_ID = "theoria"  # app/record.py: rr.RecordingStream("theoria", ...)
REQUIRED_ENTITIES = ("/world", "/text")
# an export inlines viser's client (~1 MB) and a run's frames: tens of MB at most; a bigger .html
# is not one (read whole to be checked, a link to /dev/zero would never end)
MAX_HTML_BYTES = 512e6
# the export's own digest (sha256 of the page with these 64 characters as zeros): a page with a
# piece of its scene cut out, or bytes changed, still ends with </html> but no longer matches it
HTML_DIGEST_RE = re.compile(r'data-sha256="([0-9a-f]{64})"')
HTML_DIGEST_BLANK = "0" * 64
HTML_MARKER_RE = re.compile(r'<meta name="generator" content="theoria export_html" data-theoria-scenario="([^"]*)"')


# `--check` of a recording or an export that carries no digest (written before theoria wrote one):
# it reads whole, but a changed byte inside it could not be seen; neither ok (0) nor refused (2)
EXIT_NO_DIGEST = 3


class ReplayError(Exception):
    """The file cannot be replayed here: not a complete theoria recording / export, or no display
    for the native viewer. Message: one line."""


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
    digest = check_rrd_digest(path)
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
    from .record import DIGEST_ENTITY

    if digest is None and DIGEST_ENTITY in entities:  # the field is there, its marker is not: changed
        raise ReplayError(f"{path}: theoria recording is damaged (its digest field was changed)")
    rows = sum(c.num_rows for c in chunks)
    return {"kind": "rrd", "path": str(path), "recording_id": ours[0].recording_id,
            "entities": len(entities), "rows": rows, "digest": digest}


def check_rrd_digest(path: str) -> str | None:
    """The hex blake2b the recording carries, checked against its bytes (app/record.py: the
    digest's field); None for a recording written before theoria wrote one. ReplayError when the
    bytes do not match it."""
    import mmap

    from .record import DIGEST_MARKER, DIGEST_SIZE, file_digest

    try:
        with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as m:
            at = m.find(DIGEST_MARKER)
            if at < 0:
                return None
            if m.find(DIGEST_MARKER, at + 1) >= 0:
                raise ReplayError(f"{path}: theoria recording is damaged (its digest field appears twice)")
            at += len(DIGEST_MARKER)
            stored = m[at:at + DIGEST_SIZE]
            if len(stored) != DIGEST_SIZE or file_digest(m, at) != stored:
                raise ReplayError(f"{path}: theoria recording is damaged (its bytes do not match the blake2b "
                                  "digest written with it)")
            return stored.hex()
    except (OSError, ValueError) as e:  # ValueError: an empty file cannot be mapped (refused before this)
        raise ReplayError(f"{path}: cannot read ({getattr(e, 'strerror', None) or _one_line(e)})") from None


def html_digest(text: str) -> str:
    """sha256 of an export's page with its digest field blank (the value written into that field)."""
    import hashlib

    blank = HTML_DIGEST_RE.sub(f'data-sha256="{HTML_DIGEST_BLANK}"', text, count=1)
    return hashlib.sha256(blank.encode("utf-8")).hexdigest()


def check_html(path: str) -> dict:
    """The scenario of a theoria HTML export, or ReplayError."""
    try:
        if os.path.getsize(path) > MAX_HTML_BYTES:
            raise ReplayError(f"{path}: larger than any theoria export ({os.path.getsize(path) / 1e6:.0f} MB; "
                              f"at most {MAX_HTML_BYTES / 1e6:.0f} MB)")
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
    d = HTML_DIGEST_RE.search(text[:4096])
    if d is not None and html_digest(text) != d.group(1):  # an export written before the digest has none
        raise ReplayError(f"{path}: theoria HTML export is damaged (its content does not match the digest "
                          "written when it was exported)")
    return {"kind": "html", "path": str(path), "scenario": m.group(1),
            "url": Path(os.path.abspath(path)).as_uri(), "bytes": len(data), "digest": d and d.group(1)}


def check(path: str) -> dict:
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise ReplayError(f"{path}: no such file") from None
    except OSError as e:  # a name too long for the file system, a loop of links
        raise ReplayError(f"{path}: cannot read ({e.strerror or type(e).__name__})") from None
    if stat.S_ISDIR(st.st_mode):
        raise ReplayError(f"{path}: a directory, not a file")
    if not stat.S_ISREG(st.st_mode):  # a pipe would block the reader for ever, /dev/zero never end
        raise ReplayError(f"{path}: not a regular file (a device, a pipe or a socket)")
    suffix = p.suffix.lower()
    if suffix == ".rrd":
        return check_rrd(path)
    if suffix in (".html", ".htm"):
        return check_html(path)
    raise ReplayError(f"{path}: unknown kind of file; theoria replays .rrd (theoria record) and .html (theoria export)")


def replay(path: str, check_only: bool = False, web_viewer: bool = False, open_browser: bool = False,
           host: str = "127.0.0.1") -> int:
    """Validate `path`, then open it (rerun viewer for .rrd; print the file:// URL for .html)."""
    info = check(path)
    html = info["kind"] == "html"
    if check_only:
        if html:
            head, hash_name, made = f"theoria export of {info['scenario']}", "sha256", ("exported", "export")
        else:
            head = f"theoria recording {info['recording_id']}: {info['entities']} entities, {info['rows']} rows"
            hash_name, made = "blake2b", ("recorded", "record")
        if info["digest"] is None:
            print(f"{head} — no digest ({made[0]} before theoria wrote one): read whole, but its bytes cannot be "
                  f"verified; {made[1]} it again to get one")
            return EXIT_NO_DIGEST
        print(f"{head}, {hash_name} {info['digest'][:16]}… — ok" + (f": open {info['url']}" if html else ""))
        return 0
    if html:
        print(f"theoria export of {info['scenario']}: open {info['url']}")
        return 0
    if not web_viewer and sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                                     or os.environ.get("WAYLAND_DISPLAY")):
        # the native viewer needs a screen (rerun's own error is winit's, in its words)
        raise ReplayError(f"{path}: no display to open rerun's viewer on here; add --web-viewer to serve it "
                          "to a browser (on this machine or, with --host, another)")
    cmd, url = viewer_command(path, web_viewer, open_browser, host)
    if url is not None:
        print(f"rerun web viewer for {path}: {url}", flush=True)
    return run_child(cmd, viewer_env())


def _free_port(host: str) -> int:
    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as s:
        s.bind((host, 0))
        return s.getsockname()[1]


def rerun_binary() -> str:
    """The rerun viewer binary itself. The `rerun` on PATH is a Python wrapper (rerun_cli) that
    runs the binary as *its* child: stopping the wrapper left the viewer running on its own (at
    ~95 % CPU), so theoria starts the binary directly and stops exactly the process it started."""
    if os.environ.get("RERUN_CLI_PATH"):
        return os.environ["RERUN_CLI_PATH"]
    try:
        import rerun_cli

        here = Path(rerun_cli.__file__).parent
        for cand in (here / "Rerun.app" / "Contents" / "MacOS" / "Rerun", here / "rerun", here / "rerun.exe"):
            if cand.is_file():
                return str(cand)
    except ImportError:
        pass
    return shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))


def viewer_command(path, web_viewer: bool, open_browser: bool, host: str) -> tuple[list[str], str | None]:
    """The rerun command line for `path` and the URL of the web viewer (None for the native one).
    rerun's own defaults listen on 0.0.0.0 and its `--web-viewer` opens a browser: here it binds
    `host`, and serves (`--serve-web`) without opening anything unless `open_browser`."""
    exe = rerun_binary()
    if not web_viewer:
        return [exe, str(path), "--bind", host], None
    web, grpc = _free_port(host), _free_port(host)
    shown = f"[{host}]" if ":" in host else host
    url = f"http://{shown}:{web}?url=" + quote(f"rerun+http://{shown}:{grpc}/proxy", safe="")
    mode = "--web-viewer" if open_browser else "--serve-web"
    return [exe, str(path), mode, "--bind", host, "--web-viewer-port", str(web), "--port", str(grpc)], url


def viewer_env() -> dict:
    """rerun's analytics are off when `CI` is set (no first-run notice, no config written, nothing
    sent); its INFO log lines are left out (theoria prints the URL itself)."""
    return dict(os.environ, CI=os.environ.get("CI", "1"), RUST_LOG=os.environ.get("RUST_LOG", "warn"))


PR_SET_PDEATHSIG = 1  # linux/prctl.h


def _die_with_parent() -> None:  # runs in the child between fork and exec
    try:
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    except (OSError, AttributeError):  # not Linux: the parent's own clean-up still stops it
        pass


STOP_GRACE_S = 3.0


def run_child(cmd: list[str], env: dict | None = None) -> int:
    """Run the viewer until it exits. If this command is stopped (Ctrl-C, SIGTERM, any error) the
    viewer is stopped too: SIGTERM, then SIGKILL after STOP_GRACE_S; if this process is killed
    outright, the kernel sends the viewer SIGTERM (PR_SET_PDEATHSIG)."""
    proc = subprocess.Popen(cmd, env=env, preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None)
    try:
        return proc.wait()
    finally:
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=STOP_GRACE_S)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
