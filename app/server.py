"""`theoria serve`: the viser web app, one `ClientSession` (app/session.py) per browser."""
from __future__ import annotations

import time
import traceback

import viser

from theoria.scenarios import get

from .gallery import camera_view  # noqa: F401  (the scenario's view, as the app frames it)
from .panel import comparison_markdown, info_markdown  # noqa: F401
from .session import ClientSession


def make_server(port: int = 8080, host: str = "127.0.0.1", scenario: str | None = None, verbose: bool = True,
                run=None):
    """A running viser server with one ClientSession per browser; returns (server, sessions).
    `run`: a finished Run every new browser is shown first (its scenario and parameters)."""
    if run is not None:
        scenario = run.scenario
    if scenario is not None:
        get(scenario)  # a bad name raises ParameterError before the server starts
    if verbose:
        server = viser.ViserServer(host=host, port=port, verbose=True)
    else:
        import contextlib
        import io

        with contextlib.redirect_stdout(io.StringIO()):  # viser prints its banner even when not verbose
            server = viser.ViserServer(host=host, port=port, verbose=False)
    sessions: dict[int, ClientSession] = {}

    @server.on_client_connect
    def _(client: viser.ClientHandle) -> None:
        try:
            sessions[client.client_id] = ClientSession(server, client, scenario, run=run)
        except Exception as e:
            traceback.print_exc()
            try:
                client.add_notification("Error", f"{type(e).__name__}: {e}", color="red")
            except Exception:
                pass

    @server.on_client_disconnect
    def _(client: viser.ClientHandle) -> None:
        s = sessions.pop(client.client_id, None)
        if s is not None:
            s.close()

    return server, sessions


def serve(port: int = 8080, host: str = "127.0.0.1", scenario: str | None = None, run=None) -> None:
    """Run the web app until interrupted, printing the URL to open."""
    server, _ = make_server(port=port, host=host, scenario=scenario, verbose=False, run=run)
    port = server.get_port()
    if host in ("0.0.0.0", "::", ""):
        import socket

        print(f"theoria: listening on all interfaces, port {port}; open http://{socket.gethostname()}:{port}/ "
              f"(or http://127.0.0.1:{port}/ on this machine). Ctrl-C to stop.", flush=True)
    else:
        print(f"theoria: open http://{host}:{port}/ in a browser (Ctrl-C to stop)", flush=True)
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()


class Shown:
    """A server showing one run in the background (`Run.show()` in a notebook): `.url`, `.stop()`."""

    def __init__(self, server):
        self.server = server
        self.url = f"http://127.0.0.1:{server.get_port()}/"

    def stop(self) -> None:
        self.server.stop()

    def __repr__(self) -> str:
        return f"<theoria app showing a run at {self.url}>"


def _interactive() -> bool:
    import sys

    return hasattr(sys, "ps1") or bool(sys.flags.interactive) or "ipykernel" in sys.modules


def show_run(run, port: int = 8080, host: str = "127.0.0.1", block: bool | None = None):
    """Serve `run` in the app. Blocks until Ctrl-C in a script; in an interactive session (a
    notebook, the REPL) returns a `Shown` handle at once and serves in the background."""
    block = (not _interactive()) if block is None else block
    if block:
        serve(port=port, host=host, run=run)
        return None
    server, _ = make_server(port=port, host=host, verbose=False, run=run)
    shown = Shown(server)
    print(f"theoria: open {shown.url} in a browser (.stop() to stop)", flush=True)
    return shown
