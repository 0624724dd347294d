"""Ctrl-C and SIGTERM while the `theoria` command starts and while it exits.

The command line's own handlers (app/interrupt.py: one line, exit 130 or 143, the target file
left as it was) are in place while `main` runs. Before it, the imports take 0.15–0.45 s (numpy,
the scenarios), and a Ctrl-C there printed a traceback of importlib's frames and a SIGTERM ended
the process silently (exit −15); after it, while the interpreter exits (threads joined, rerun's
stream flushed), the same. Nothing is written in either phase that a stop could leave half done
(every file is written whole inside `main`), so the stop is immediate: the one line and the exit
status, without unwinding.
"""
import atexit
import os
import signal
import sys
import threading

_LINE = {signal.SIGINT: b"theoria: interrupted\n", signal.SIGTERM: b"theoria: terminated\n"}


def _stop(signum, frame):
    os.write(2, _LINE[signum])
    os._exit(128 + signum)


def _is_the_command() -> bool:
    """The `theoria` console script, or `python -m theoria` (not a notebook importing theoria, and
    not a process multiprocessing started for it: a sweep's Dask workers re-import the script with
    its argv, and each printed "theoria: terminated" when the sweep stopped them)."""
    if "--multiprocessing-fork" in getattr(sys, "orig_argv", ()):  # how multiprocessing starts a child
        return False
    argv = getattr(sys, "argv", None) or [""]
    orig = list(getattr(sys, "orig_argv", ()))
    by_m = any(a == "-m" and b in ("theoria", "theoria.app.cli") for a, b in zip(orig, orig[1:]))
    return os.path.basename(argv[0]) == "theoria" or by_m


def _last_at_exit() -> None:
    """After the last exit handler the interpreter puts the default actions back for signals with
    a Python handler (a SIGTERM there ended the process as killed, exit −15, after the command had
    said what it did). Ignored signals it leaves ignored: for those last steps the two are, and
    the exit status is the command's. (Blocking them would not do: other threads would take them.)"""
    for s in (signal.SIGINT, signal.SIGTERM):
        try:
            signal.signal(s, signal.SIG_IGN)
        except (OSError, ValueError):
            pass


def guard() -> None:
    """Stop at once on Ctrl-C or SIGTERM, where Python's own handling is still in place."""
    if not _is_the_command() or threading.current_thread() is not threading.main_thread():
        return
    atexit.register(_last_at_exit)  # registered first: run last
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _stop)
    if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _stop)
