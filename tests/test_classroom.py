"""Many browsers (issue 7 item 3): clients that leave — even in the middle of a long
simulation — leave nothing running, over repeated connect/disconnect cycles.

The clients are `app.bench_classroom.ViserProtocolClient`: viser's own websocket protocol (the
camera handshake that makes the server build a ClientSession, GUI updates as msgpack), so the
server side runs exactly as with a browser."""
from __future__ import annotations

import asyncio
import contextlib
import io
import threading
import time

import pytest

from app.bench_classroom import ViserProtocolClient, _free_port
from app.server import make_server

CYCLES = 6


def _session_threads():
    return [t for t in threading.enumerate() if t.name.startswith(("sim-", "play-")) and t.is_alive()]


def _wait(cond, limit=120.0):
    t0 = time.time()
    while not cond():
        if time.time() - t0 > limit:
            return False
        time.sleep(0.05)
    return True


@pytest.fixture()
def server():
    with contextlib.redirect_stdout(io.StringIO()):
        srv, sessions = make_server(port=_free_port(), host="127.0.0.1", scenario="middle-axis-flip", verbose=False)
    yield srv, sessions
    with contextlib.redirect_stdout(io.StringIO()):
        srv.stop()


def test_disconnect_mid_simulation_leaves_nothing_running(server):
    srv, sessions = server
    url = f"ws://127.0.0.1:{srv.get_port()}"
    base_threads = threading.active_count()
    seen_threads = set()

    async def cycle(k):
        c = ViserProtocolClient(url)
        await c.connect()
        assert await c.wait_for(lambda: c.update_no >= 1, 120), "no first scene"
        seen_threads.update(t.name for t in _session_threads())
        # a long run (duration 3000 s at step 0.005: 6e5 steps, seconds of work), then leave at once
        await c.send_gui(c.uuid_of("duration"), 3000.0)
        await asyncio.sleep(0.3 if k % 2 else 0.0)
        await c.close()

    for k in range(CYCLES):
        asyncio.run(cycle(k))
    assert len(seen_threads) >= 2 * CYCLES  # each browser had its own worker and player
    # every session is closed and its worker and player threads end (the running integration is
    # abandoned from its progress callback, not finished)
    assert _wait(lambda: not sessions and not _session_threads()), [t.name for t in _session_threads()]
    assert _wait(lambda: threading.active_count() <= base_threads + 2), threading.enumerate()


def test_concurrent_clients_each_get_their_own_redraw(server):
    """Five clients moving the same slider at once: each gets its own scene back, with its own value."""
    srv, sessions = server
    url = f"ws://127.0.0.1:{srv.get_port()}"

    async def main():
        cs = [ViserProtocolClient(url) for _ in range(5)]
        for c in cs:
            await c.connect()
        for c in cs:
            assert await c.wait_for(lambda c=c: c.update_no >= 1, 120)
        lat = await asyncio.gather(*(c.move_slider("perturbation", 0.02 * (i + 1), timeout=300) for i, c in enumerate(cs)))
        for c in cs:
            await c.close()
        return lat

    lat = asyncio.run(main())
    assert all(x is not None for x in lat), lat
    assert _wait(lambda: not sessions and not _session_threads())
