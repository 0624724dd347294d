"""REBOUND's integrate, with Python's Ctrl-C handler given back after every call.

REBOUND's C library installs its own SIGINT handler at the start of every integration
(`signal(SIGINT, reb_sigint_handler)`: a flag it reads between its steps) and never restores
the one it replaced. After the first REBOUND run of a process Ctrl-C then only sets that flag,
which the next call clears: the rest of the command (every `earth` run, recording or export)
ignores Ctrl-C and runs to its end. `integrate_to` restores the handler Python had before the
call. During the call REBOUND's own handler stops the integration and its Python wrapper raises
KeyboardInterrupt, so Ctrl-C works there too.

Python can set a signal handler only in the main thread: elsewhere (a worker thread of the app)
the call is made as it is and REBOUND keeps the handler it installed.
"""
from __future__ import annotations

import signal
import threading


def integrate_to(sim, t: float, exact_finish_time: int = 1) -> None:
    """`sim.integrate(t, exact_finish_time)`, then Python's SIGINT handler back in place."""
    if threading.current_thread() is not threading.main_thread():
        sim.integrate(t, exact_finish_time=exact_finish_time)
        return
    handler = signal.getsignal(signal.SIGINT)
    try:
        sim.integrate(t, exact_finish_time=exact_finish_time)
    finally:
        if handler is not None:  # None: a handler not installed from Python, nothing to restore
            signal.signal(signal.SIGINT, handler)
