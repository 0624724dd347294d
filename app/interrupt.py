"""Ctrl-C and SIGTERM in the command line: one line, the usual exit status (130, 143), never a
traceback or a SystemError.

Python raises KeyboardInterrupt in whatever Python code runs when the signal is handled. When a
compiled (numba) function returns arrays, numba runs a little Python code of its own to build
them (`numba.core.serialize._numba_unpickle`); a Ctrl-C that arrived during the compiled loop is
raised *there*, numba cannot pass it on, and the command dies with "SystemError: CPUDispatcher(...)
returned a result with an exception set" and two tracebacks (5 of 5 Ctrl-C at step=1e-5 before
this). The same holds for an exception raised in a `__del__`, which Python only prints. So the
handlers here do not raise in such a frame: they ask for the signal again 20 ms later
(`_thread.interrupt_main`), by when the interpreter is back in theoria's own code (the integrator
checks between chunks of steps) and the interrupt is raised where it can propagate.

SIGTERM (`kill`, a service manager, a closed session) becomes `Terminated`, so that the same
clean-up runs as for Ctrl-C (a recording's temporary file is removed, the target left as it was).
"""
from __future__ import annotations

import contextlib
import os
import signal
import threading
import _thread

EXIT_INTERRUPTED = 128 + signal.SIGINT  # 130
EXIT_TERMINATED = 128 + signal.SIGTERM  # 143
RETRY_S = 0.02


class Terminated(BaseException):
    """SIGTERM: the command was asked to stop (a BaseException, like KeyboardInterrupt, so that no
    `except Exception` swallows it)."""


_state = {"active": 0, "retry_pending": False}


def _unsafe(frame) -> bool:
    """Is `frame`, or any frame that called it, code from which an exception cannot propagate:
    numba building a compiled function's result, or a finaliser. (The whole chain: a second
    signal handled while the first is being deferred runs inside the first handler, itself
    inside numba's code.)"""
    while frame is not None:
        code = frame.f_code
        if code.co_name == "__del__" or (code.co_name == "_numba_unpickle" and "numba" in code.co_filename):
            return True
        frame = frame.f_back
    return False


def _fire(signum: int) -> None:
    _state["retry_pending"] = False
    if _state["active"]:  # not once the command has returned: the signal would land after it
        _thread.interrupt_main(signum)


def _again(signum: int) -> None:
    """Ask for the signal again in RETRY_S (once: a retry already pending covers this one)."""
    if _state["retry_pending"]:
        return
    _state["retry_pending"] = True
    t = threading.Timer(RETRY_S, _fire, (signum,))
    t.daemon = True
    t.start()


def _on_sigint(signum, frame):
    if _unsafe(frame):
        _again(signum)
        return
    raise KeyboardInterrupt


def _on_sigterm(signum, frame):
    if _unsafe(frame):
        _again(signum)
        return
    raise Terminated


@contextlib.contextmanager
def cli_signals():
    """While the block runs (main thread only): Ctrl-C raises KeyboardInterrupt and SIGTERM
    raises Terminated, each only where the exception can propagate. The previous handlers are
    restored after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    signal.signal(signal.SIGINT, _on_sigint)
    signal.signal(signal.SIGTERM, _on_sigterm)
    _state["active"] += 1
    try:
        yield
    finally:
        _state["active"] -= 1
        for s, h in old.items():
            if h is not None:
                signal.signal(s, h)


@contextlib.contextmanager
def sigterm_raises():
    """SIGTERM raises Terminated while the block runs, if nothing else handles it (a script or a
    notebook calling `Run.record`): the block's clean-up runs, then the process ends by SIGTERM
    as it would have, instead of dying half-way. Main thread only; a handler already installed
    (the command line's) is kept."""
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL):
        yield
        return
    signal.signal(signal.SIGTERM, _on_sigterm)
    _state["active"] += 1
    try:
        yield
    except Terminated:  # the block has cleaned up: now end as SIGTERM would have ended the process
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)
        raise
    finally:
        _state["active"] -= 1
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
