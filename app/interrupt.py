"""Ctrl-C and SIGTERM in the command line: one line, the usual exit status (130, 143), never a
traceback or a SystemError.

Python raises KeyboardInterrupt in whatever Python code runs when the signal is handled. When a
compiled (numba) function returns arrays, numba runs a little Python code of its own to build
them (`numba.core.serialize._numba_unpickle`); a Ctrl-C that arrived during the compiled loop is
raised *there*, numba cannot pass it on, and the command dies with "SystemError: CPUDispatcher(...)
returned a result with an exception set" and two tracebacks (5 of 5 Ctrl-C at step=1e-5 before
this). The same holds for an exception raised in a `__del__`, which Python only prints.

So a handler that finds itself in such a frame does not raise: it marks the signal pending and
installs a trace function that raises it on the first line of Python executed in a frame from
which it can propagate (the integrator's loop between two compiled chunks, a script's own loop).
Asking for the signal again later instead (a timer and `_thread.interrupt_main`) is not enough: a
compiled function that releases the GIL picks up a pending signal at its next Python frame, which
is numba's boxing again, and on a loaded machine 29 of 40 Ctrl-C were deferred for ever. A slow
backstop timer still re-asks, for a main thread that goes on to block in a C call (a sleep, a
lock) where no line of Python runs.

SIGTERM (`kill`, a service manager, a closed session) becomes `Terminated`, so that the same
clean-up runs as for Ctrl-C (a recording's temporary file is removed, the target left as it was).
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
import _thread

EXIT_INTERRUPTED = 128 + signal.SIGINT  # 130
EXIT_TERMINATED = 128 + signal.SIGTERM  # 143


class Terminated(BaseException):
    """SIGTERM: the command was asked to stop (a BaseException, like KeyboardInterrupt, so that no
    `except Exception` swallows it)."""


_state = {"active": 0, "pending": None, "previous_trace": None, "traced": [], "backstop": None, "finishing": False}
BACKSTOP_S = 0.5
# the backstop's look at the pending signal and its delivery, against the main thread taking it:
# between the two, the main thread could raise the signal, print "interrupted" and put Python's
# handlers back, and the copy then ended the process by SIGINT (exit -2) on its way out
_lock = threading.RLock()


def _unsafe(frame) -> bool:
    """Is `frame`, or any frame that called it, code from which an exception cannot propagate:
    numba building a compiled function's result, a finaliser, llvmlite's Python called back by
    LLVM through ctypes while numba compiles or loads compiled code (its object cache: an
    exception raised there is printed as "Exception ignored on calling ctypes callback function"
    and lost, and the command ran on to the end and exited 0), or a descriptor's `__set_name__`
    (Python 3.11 turns its exception into a RuntimeError), or a module being imported (the
    commands import scipy, numba and the scenarios as they need them: a KeyboardInterrupt inside
    a compiled module's initialisation comes back as "ImportError: initialization failed", a
    traceback, and code that imports something optionally swallows it, so the command ran on and
    exited 0). (The whole chain: a signal handled inside another handler, itself inside numba's
    code, is as unsafe.)"""
    while frame is not None:
        code = frame.f_code
        if (code.co_name in ("__del__", "__set_name__") or "llvmlite" in code.co_filename
                or code.co_filename.startswith("<frozen importlib")
                or (code.co_name == "_numba_unpickle" and "numba" in code.co_filename)):
            return True
        frame = frame.f_back
    return False


def _raise(signum: int):
    raise Terminated if signum == signal.SIGTERM else KeyboardInterrupt


def _take_pending() -> int | None:
    """The deferred signal, if any, with the trace function removed."""
    with _lock:
        signum = _state["pending"]
        _state["pending"] = None
    if signum is None:
        return None
    sys.settrace(_state["previous_trace"])
    for f in _state["traced"]:
        f.f_trace = None
    _state["traced"] = []
    return signum


def _trace_line(frame, event, arg):
    if _state["pending"] is not None and event == "line" and not _unsafe(frame):
        _raise(_take_pending())
    return _trace_line


def _trace_call(frame, event, arg):
    return None if _unsafe(frame) else _trace_line


def _backstop(signum: int) -> None:
    """A deferred signal still pending after BACKSTOP_S (no Python line ran where it could be
    raised): delivered to the main thread again. The trace may raise it meanwhile: `_handler` then
    drops this copy (delivered too, the one Ctrl-C was raised twice: the command printed
    "interrupted", then died by SIGINT on its way out)."""
    with _lock:
        if _state["pending"] == signum and _state["active"]:
            _state["backstop"] = time.monotonic()
            _thread.interrupt_main(signum)


def _defer(signum: int, frame) -> None:
    """Raise `signum` at the next line of Python that runs in a frame where it can propagate."""
    if _state["pending"] is None:
        _state["previous_trace"] = sys.gettrace()
    _state["pending"] = signum
    sys.settrace(_trace_call)  # frames called from now on
    f = frame
    while f is not None:  # and the frames already running, once the unsafe ones return to them
        if not _unsafe(f):
            f.f_trace = _trace_line
            _state["traced"].append(f)
        f = f.f_back
    t = threading.Timer(BACKSTOP_S, _backstop, (signum,))
    t.daemon = True
    t.start()


def _handler(signum, frame):
    sent, _state["backstop"] = _state["backstop"], None
    if sent is not None and _state["pending"] is None and time.monotonic() - sent < 1.0:
        return  # the backstop's copy of a signal already raised (a later Ctrl-C is raised)
    if _unsafe(frame):
        _defer(signum, frame)
        return
    _take_pending()
    _raise(signum)


@contextlib.contextmanager
def cli_signals(process: bool = False):
    """While the block runs (main thread only): Ctrl-C raises KeyboardInterrupt and SIGTERM
    raises Terminated, each only where the exception can propagate. The previous handlers are
    restored after, unless the command is `finishing` and the block is the whole `process` (the
    `theoria` command itself, which exits right after: there a late Ctrl-C stays ignored)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    signal.signal(signal.SIGINT, _handler)
    signal.signal(signal.SIGTERM, _handler)
    _state["active"] += 1
    try:
        yield
    finally:
        with _lock:
            _state["active"] -= 1
        pending = _take_pending() if not _state["active"] else None
        if not (process and _state["finishing"]):
            _state["finishing"] = False
            for s, h in old.items():
                if h is not None:
                    signal.signal(s, h)
            if pending is not None:  # deferred and never raised (the block ended first): not lost
                _raise(pending)


def forget_interrupts_in_source_text() -> None:
    """CPython remembers a KeyboardInterrupt that left any code it ran from source text (`exec`
    or `eval` of a string: `dataclasses` builds every `__init__` that way, `namedtuple` its
    `__new__`), even when the interrupt was caught later, and a process started with `python -m`
    that exits normally then ends by SIGINT after its last line (exit −2, not the command's 130).
    A Ctrl-C while a sweep's local cluster starts (Dask imports dozens of modules of dataclasses)
    did that 2 of 10 times. Running an empty string clears the record; call it once the command's
    handlers are gone, when no KeyboardInterrupt can come any more."""
    exec("")


def finishing() -> None:
    """The command's work is done and cannot be undone (its file is in place): Ctrl-C and SIGTERM
    are ignored from here to the end of the process, so that a stop in its last lines is not
    reported as one that changed nothing (exit 130 beside a new file). Main thread, inside
    `cli_signals`, which puts the handlers back at its end (unless it is the whole process)."""
    if threading.current_thread() is not threading.main_thread():
        return
    _state["finishing"] = True
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, signal.SIG_IGN)
    _take_pending()


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
    signal.signal(signal.SIGTERM, _handler)
    _state["active"] += 1
    try:
        yield
    except Terminated:  # the block has cleaned up: now end as SIGTERM would have ended the process
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)
        raise
    finally:
        _state["active"] -= 1
        if not _state["active"]:
            _take_pending()
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


class _Stopped(BaseException):
    """Leaves a `signals_held` block early (`Held.check`)."""


class Held:
    """The signals held by a `signals_held` block so far."""

    def __init__(self):
        self.signals: list[int] = []

    def check(self) -> None:
        """Leave the block here if a signal is held (a point the block chooses, between two calls
        that must not be cut): the signal then takes effect as at the block's end."""
        if self.signals:
            raise _Stopped

    def drop(self) -> None:
        """Forget the signals held so far: the block's work is done and cannot be undone (a new
        result is in place), so a stop that came during it is too late, and is not raised."""
        self.signals.clear()


_holding: list[Held] = []  # the `signals_held` blocks the main thread is in, outermost first


@contextlib.contextmanager
def signals_held():
    """Ctrl-C and SIGTERM wait for the end of the block (or its next `Held.check`), then take
    effect as they would have: the handlers in place before the block get them. For work that must
    not be cut in the middle: zarr writes a store from its own event-loop thread while this one
    waits, and stopped in the middle, this thread would leave that one writing, and the
    interpreter's exit would cut it off with tracebacks of its own; rerun's calls convert their
    arguments with pyarrow, which could turn a KeyboardInterrupt into an error that rerun only
    warns about (the Ctrl-C lost, the recording without an entity). The same signal a second time
    is not held (a block that hangs can still be stopped). Main thread only (elsewhere signals are
    not delivered); an ignored signal stays ignored."""
    held = Held()
    if threading.current_thread() is not threading.main_thread():
        yield held
        return
    if _holding:  # inside another such block: its handler holds the signals for both, and counts them
        held.signals = _holding[-1].signals  # (a second Ctrl-C stops both, as it stops one)
        _holding.append(held)
        try:
            yield held
        finally:
            _holding.pop()
        return
    old = {}
    stopped = False

    def note(signum, frame):
        if signum not in held.signals:
            held.signals.append(signum)
            return
        held.signals.remove(signum)  # the second: delivered now, and not again at the block's end
        if callable(old[signum]):  # to the handler it would have gone to
            old[signum](signum, frame)
        else:  # the default action (SIGTERM outside the command line: the process ends)
            signal.signal(signum, old[signum])
            signal.raise_signal(signum)

    try:
        for s in (signal.SIGINT, signal.SIGTERM):
            previous = signal.getsignal(s)
            if previous is not None and previous is not signal.SIG_IGN:  # one installed from C cannot be put back
                old[s] = signal.signal(s, note)
        _holding.append(held)
        yield held
    except _Stopped:
        stopped = True
    finally:
        if _holding and _holding[-1] is held:
            _holding.pop()
        for s, h in old.items():
            signal.signal(s, h)
        for s in dict.fromkeys(held.signals):  # each signal once, in the order it came
            signal.raise_signal(s)
    if stopped:  # the handler only took note (a sweep's, between two chunks): the block is not done
        raise KeyboardInterrupt
