"""Many browsers at once: clients that leave — even in the middle of a long
simulation — leave nothing running, over repeated connect/disconnect cycles.

The clients are `theoria.benchmarks.classroom.ViserProtocolClient`: viser's own websocket protocol (the
camera handshake that makes the server build a ClientSession, GUI updates as msgpack), so the
server side runs exactly as with a browser."""
from __future__ import annotations

import asyncio
import contextlib
import io
import threading
import time

import pytest

from theoria.benchmarks.classroom import ViserProtocolClient, _free_port
from theoria.app.server import make_server

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
        lat = await asyncio.gather(*(c.move_slider("Spin rate", 6.0 + 0.1 * (i + 1), timeout=300) for i, c in enumerate(cs)))
        for c in cs:
            await c.close()
        return lat

    lat = asyncio.run(main())
    assert all(x is not None for x in lat), lat
    assert _wait(lambda: not sessions and not _session_threads())


def test_app_reports_divergence_and_survives_a_raising_scenario():
    """In the app: a diverging run shows 'diverged at t=...' beside the scene (the finite part is
    drawn); a scenario that raises gives the browser a notification and the server keeps serving
    the next browser."""
    import numpy as np

    from theoria.physics.params import Param
    from theoria.scenarios import base
    from theoria.physics.trajectory import Trajectory

    def blowup(values, progress=None):
        t = np.linspace(0.0, 5.0, 51)
        L = np.tile([1.0, 0.5, 0.2], (51, 1)) * (1 + t[:, None])
        L[t >= 3.0] = np.inf
        traj = Trajectory(t, np.tile([1.0, 0, 0, 0], (51, 1)), L, np.array([1.0, 2.0, 3.0]))
        return base.Run("test-blowup", dict(values), traj, {})

    def boom(values, progress=None):
        raise RuntimeError("deliberate failure in a test scenario")

    specs = [base.Scenario("test-blowup", "blow-up", "§0", "ch. 15", "diverges", (Param("x", 1.0, 0.0, 2.0),), blowup),
             base.Scenario("test-broken", "broken", "§0", "ch. 15", "raises", (Param("x", 1.0, 0.0, 2.0),), boom)]
    for s in specs:
        base.REGISTRY[s.name] = s
    try:
        for name in ("test-blowup", "test-broken"):
            with contextlib.redirect_stdout(io.StringIO()):
                srv, sessions = make_server(port=_free_port(), host="127.0.0.1", scenario=name, verbose=False)
            try:
                url = f"ws://127.0.0.1:{srv.get_port()}"

                async def visit():
                    c = ViserProtocolClient(url)
                    await c.connect()
                    if name == "test-blowup":
                        ok = await c.wait_for(lambda: any("diverged at t=3" in v for v in c.markdown.values()), 120)
                        shown = c.update_no
                    else:
                        ok = await c.wait_for(lambda: any("deliberate failure" in b for _, b in c.notifications), 120)
                        shown = None
                    await c.close()
                    return ok, shown, c.notifications

                for _ in range(2):  # a second browser is served as well
                    ok, shown, notes = asyncio.run(visit())
                    assert ok, notes
                    if name == "test-blowup":
                        assert shown >= 1  # the finite part was drawn
                    else:
                        assert any(t.startswith("Error in test-broken") for t, _ in notes), notes
                assert _wait(lambda: not sessions and not _session_threads())
            finally:
                with contextlib.redirect_stdout(io.StringIO()):
                    srv.stop()
    finally:
        for s in specs:
            base.REGISTRY.pop(s.name, None)
