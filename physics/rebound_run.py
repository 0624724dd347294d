"""REBOUND's integrate, with Python's Ctrl-C handler given back after every call.

REBOUND's C library installs its own SIGINT handler at the start of every integration
(`signal(SIGINT, reb_sigint_handler)`: a flag it reads between its steps) and never restores
the one it replaced. After the first REBOUND run of a process Ctrl-C then only sets that flag,
which the next call clears: the rest of the command (every `earth` run, recording or export)
ignores Ctrl-C and runs to its end. `integrate_to` restores the handler Python had before the
call. During the call REBOUND's own handler stops the integration and its Python wrapper raises
KeyboardInterrupt, so Ctrl-C works there too.

REBOUND looks at its flag after each step and clears it when the next call starts. A Ctrl-C that
came after the last look of a call, before Python's handler was back, only set the flag: lost
(1 of 10 Ctrl-C sent to a loop of half-day integrations, as the Earth's ephemeris is made).
`integrate_to` reads the flag once its handler is back and hands such a Ctrl-C to Python.

Python can set a signal handler only in the main thread: elsewhere (a worker thread of the app)
the call is made as it is and REBOUND keeps the handler it installed.
"""
from __future__ import annotations

import ctypes
import signal
import threading

import rebound


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
    flag = _rebound_sigint()  # read only after a call that ended as finished: a stopped one raised
    if flag.value and handler is not None:
        flag.value = 0
        signal.raise_signal(signal.SIGINT)  # handled as any Ctrl-C, by Python's handler


def _rebound_sigint() -> ctypes.c_int:
    """REBOUND's `volatile sig_atomic_t reb_sigint` (an int here): how many Ctrl-C its handler saw."""
    return ctypes.c_int.in_dll(rebound.clibrebound, "reb_sigint")
