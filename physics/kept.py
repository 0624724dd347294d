"""Pieces of a run kept for the next run that shares their numbers.

A slider moved in class usually changes one number. A piece of a run that depends on other numbers
only (Hyperion's resonance branches, the forced libration on an eccentric orbit, the precession's
resonance table, the ellipsoid's quadrature rule, the syzygy's measured swing) is made once per
process and reused: `@kept(n)` keeps the last n results of a pure function of hashable numbers,
results that are never written to. A `progress` keyword is not part of the key (it only reports,
and may stop the work by raising: nothing is kept then). `forget()` drops everything kept so (a
cost measured on a run made afresh); the older per-scenario tables made with functools.lru_cache
(earth-long-view's secular calibration, the ephemerides) are not among them.
"""
from __future__ import annotations

import functools
import threading
from collections import OrderedDict

_KEPT: list[OrderedDict] = []
_LOCK = threading.Lock()
_reuses = 0  # pieces handed out again in this process: a run that reused one says little of the next


def reused() -> int:
    """How many times a kept piece has been handed out again in this process so far."""
    return _reuses


def note_reuse() -> None:
    """Count a piece kept by a rule of its own (`new_store`) handed out again."""
    global _reuses
    with _LOCK:
        _reuses += 1


def kept(maxsize: int):
    def wrap(fn):
        store: OrderedDict = OrderedDict()
        _KEPT.append(store)

        @functools.wraps(fn)
        def call(*args, progress=None, **kwargs):
            key = (args, tuple(sorted(kwargs.items())))
            global _reuses
            with _LOCK:
                if key in store:
                    store.move_to_end(key)
                    _reuses += 1
                    return store[key]
            out = fn(*args, **kwargs) if progress is None else fn(*args, progress=progress, **kwargs)
            with _LOCK:
                store[key] = out
                while len(store) > maxsize:
                    store.popitem(last=False)
            return out

        call.cache_clear = store.clear
        return call
    return wrap


def new_store() -> OrderedDict:
    """An empty store for a piece kept by a rule of its own (a longer run answering a shorter one);
    `forget()` clears it with the rest."""
    store: OrderedDict = OrderedDict()
    with _LOCK:
        _KEPT.append(store)
    return store


def forget() -> None:
    with _LOCK:
        for store in _KEPT:
            store.clear()
