"""The app opens a sweep result (`theoria serve --sweep result.zarr`): a map in a Sweep tab with axes
and colour bar in words, and a click on a pixel replays that run in the scene.

The server is spoken to as a browser would (`ViserProtocolClient`: viser's websocket protocol, no
browser): the click is the control value the page's script sends (app/browser.py reads the row,
column and view from the map's image), so it passes the server's gate like any typed value.
"""
from __future__ import annotations

import asyncio
import contextlib
import html
import io
import re
import subprocess
import sys

import numpy as np
import pytest

import theoria as th
from theoria.app import sweep as sw
from theoria.app.server import make_server
from theoria.app.sweep_map import SweepMaps, map_html, metric_words, parse_click
from theoria.benchmarks.classroom import ViserProtocolClient, _free_port

from conftest import ROOT

FIXED = dict(n_starts=4, n_orbits=100, probe_orbits=1)
GRID = {"eccentricity": (0.0, 0.2, 3), "probe_rate": [0.5, 1.0, 1.45, 2.5]}


@pytest.fixture(scope="module")
def tiny_sweep(tmp_path_factory):
    """Hyperion over 3 eccentricities × 4 starting spins (quick: 100 orbits, 4 section starts)."""
    from distributed import Client, LocalCluster

    out = tmp_path_factory.mktemp("map") / "h.zarr"
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc, \
            Client(lc) as c:
        th.scenario("hyperion").sweep(grid=GRID, out=out, cluster=c, **FIXED)
    return out


def test_map_words_and_pixels(tiny_sweep):
    maps = SweepMaps(tiny_sweep)
    assert maps.scenario.name == "hyperion" and maps.metrics[0] == "lyapunov_probe_per_orbit"
    view = maps.default_view(maps.metrics[0])
    assert view == "each run"
    pic = maps.picture(maps.metrics[0], view)
    assert pic.rows == 3 and pic.cols == 4
    ref = sw.open_map(tiny_sweep, "lyapunov_probe_per_orbit")
    assert np.array_equal(pic.map.values, ref.values, equal_nan=True)
    # the PNG: one pixel per run, the lowest eccentricity in the bottom row
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(pic.png)))
    assert img.shape == (3, 4, 3)
    v = (pic.map.values - pic.lo) / (pic.hi - pic.lo)
    assert np.argmax(img[::-1].sum(-1)) == np.argmax(np.nan_to_num(v))  # brightest pixel = largest exponent
    text = html.unescape(map_html(maps, pic, "u1", mark=(2, 2)))
    # axes and colour bar in words (Param.label and units), not keys
    assert "Orbital eccentricity" in text and "× the mean motion n" in text
    assert "Largest Lyapunov exponent of the drawn body (per orbit)" in text
    assert "probe_rate" not in re.sub(r"data-key='[^']*'", "", text)
    assert metric_words("captured_3_2") == ("Captured into the 3:2 resonance", "1 yes, 0 no")
    # a click's value: only for the view shown, only in range
    assert parse_click(f"2,3,{pic.key},1", pic) == (2, 3)
    assert parse_click(f"3,0,{pic.key},1", pic) is None and parse_click("1,1,other,1", pic) is None
    assert parse_click("x,1," + pic.key, pic) is None
    # a profile: the eccentricity summarised, against the starting spin
    prof = [lab for lab, v in maps.views(maps.metrics[0]) if v.y is None and v.x == "probe_rate"][0]
    p2 = maps.picture(maps.metrics[0], prof)
    assert p2.rows == 1 and np.allclose(p2.map.values[0], np.nanmean(ref.values, axis=0))


def _map_attrs(content: str) -> dict:
    return dict(re.findall(r"data-(uuid|rows|cols|key)='([^']*)'", content))


def test_serve_sweep_click_replays_the_run(tiny_sweep):
    """A browser opens the server started with a sweep: the Sweep tab's map; a click on a pixel
    switches the session to the sweep's scenario with that run's parameters, drawn by the worker."""
    with contextlib.redirect_stdout(io.StringIO()):
        srv, sessions = make_server(port=_free_port(), host="127.0.0.1", scenario="middle-axis-flip",
                                    verbose=False, sweep=tiny_sweep)
    try:
        async def go():
            c = ViserProtocolClient(f"ws://127.0.0.1:{srv.get_port()}")
            await c.connect()
            assert await c.wait_for(lambda: c.update_no >= 1, 180)
            def map_content():  # the HTML the page shows (created, then updated when rendered)
                return next((str(x["props"].get("content")) for x in c.components.values()
                             if "data-theoria-map" in str(x["props"].get("content"))), None)

            assert await c.wait_for(lambda: map_content() is not None, 120)
            content = map_content()
            a = _map_attrs(content)
            assert (a["rows"], a["cols"]) == ("3", "4")
            assert "Colour shows" in c.labels
            session = next(iter(sessions.values()))
            assert session.spec.name == "middle-axis-flip"  # the scenario asked for comes first
            want = sw.open_map(tiny_sweep, "lyapunov_probe_per_orbit").run_values(2, 2)
            # what the page's script would never send: outside the map, another view, not a pixel at
            # all, longer than a control value may be (the gate drops that one) — nothing is replayed
            for bad in (f"3,0,{a['key']},1", f"0,4,{a['key']},2", "0,0,some other view,3", "x,y", "0," * 150):
                await c.send_gui(a["uuid"], bad)
            await asyncio.sleep(1.5)
            assert session._sweep_mark is None and session.spec.name == "middle-axis-flip"
            await c.send_gui(a["uuid"], f"2,2,{a['key']},1")  # row 2 (e = 0.2), column 2 (θ̇/n = 1.45)
            # the worker may show a quick preview first (fewer orbits); then the run itself
            ok = await c.wait_for(lambda: session.good_values == want, 240)
            assert ok, (c.status, session.good_values)
            words = [m for m in c.markdown.values() if m.startswith("**In the scene:**")]
            await c.wait_for(lambda: "the run shown in the scene" in map_content(), 30)
            marked = map_content()  # the map as the page now has it: the pixel marked
            await c.close()
            return session, words, marked

        session, words, marked = asyncio.run(go())
        m = sw.open_map(tiny_sweep, "lyapunov_probe_per_orbit")
        want = m.run_values(2, 2)
        assert session.good_values == want
        # the same run, drawn (to the last digits: numba's code compiled afresh and loaded from its
        # cache differ in the last bit, 1.076340449845408 against 1.0763404498454086, measured)
        assert session.result.metrics["lyapunov_probe_per_orbit"] == pytest.approx(m.values[2, 2], rel=1e-12, abs=0)
        assert session.drawing is not None and session.drawing_spec == "hyperion"
        assert words and "Orbital eccentricity = 0.2" in words[0] and "1.45" in words[0]
        assert "the run shown in the scene" in marked
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            srv.stop()


@pytest.mark.parametrize("what", ["missing", "not-zarr", "foreign-zarr"])
def test_serve_refuses_what_is_not_a_sweep(tmp_path, what):
    path = tmp_path / "x.zarr"
    if what == "not-zarr":
        path.mkdir()
        (path / "readme.txt").write_text("hello")
    elif what == "foreign-zarr":
        import xarray as xr

        xr.Dataset({"a": ("x", np.arange(3.0))}).to_zarr(path)
    r = subprocess.run([sys.executable, "-m", "theoria.app.cli", "serve", "--sweep", str(path), "--port", "0",
                        "--no-precompute"], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert r.returncode == 2, (r.stdout, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("theoria: error: ") and "--sweep" in lines[0], r.stderr
    assert "theoria sweep" in lines[0]


def test_a_sweep_written_again_while_served_does_not_mix_into_the_map(tiny_sweep, tmp_path):
    """The server shows the sweep as it was when it opened it. A researcher who writes another
    sweep to the same folder meanwhile (`--force`: a new store renamed over the old) used to get
    the old panel (metrics, axes) over the new store's numbers: a map of another size, and a click
    that replayed a run the map did not show. Views not drawn before and the clicked run's values
    still come from the store as it was opened."""
    import shutil

    from distributed import Client, LocalCluster

    out = tmp_path / "served.zarr"
    shutil.copytree(tiny_sweep, out)
    maps = SweepMaps(out)
    metric = maps.metrics[0]
    views = [label for label, _ in maps.views(metric)]
    first = maps.picture(metric, views[0])
    before = first.map.values.copy()
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc, \
            Client(lc) as c:
        th.scenario("hyperion").sweep(grid={"eccentricity": (0.05, 0.15, 2), "probe_rate": [0.7, 1.2, 3.0]},
                                      out=out, cluster=c, force=True, **FIXED)
    assert sw.open_map(out, metric).values.shape == (2, 3)  # the folder now holds the other sweep
    axes = {"eccentricity": [0.0, 0.1, 0.2], "probe_rate": GRID["probe_rate"]}  # the sweep as opened
    for label in views:
        pic = maps.picture(metric, label)
        assert pic.map.x_values.tolist() == pytest.approx(axes[pic.map.x]), label
        if pic.map.y:
            assert pic.map.y_values.tolist() == pytest.approx(axes[pic.map.y]), label
    maps._cache.clear()
    again = maps.picture(metric, views[0])
    assert np.array_equal(again.map.values, before, equal_nan=True)
    row, col = 2, 3
    assert again.map.run_values(row, col)["probe_rate"] == GRID["probe_rate"][col]
    assert again.map.run_values(row, col)["eccentricity"] == pytest.approx(0.2)


def test_a_parquet_sweep_given_to_serve_is_named_as_such(tmp_path):
    """`serve --sweep e.parquet` said "no such folder" of a file that is there: a Parquet sweep has
    no grid to draw, and the message says to sweep to .zarr."""
    from theoria.app.sweep_map import SweepMaps
    from theoria.physics.errors import ParameterError

    f = tmp_path / "e.parquet"
    f.write_bytes(b"PAR1")
    with pytest.raises(ParameterError, match="a Parquet sweep is a flat table with no grid to draw"):
        SweepMaps(f)
    with pytest.raises(ParameterError, match="no such folder"):
        SweepMaps(tmp_path / "missing.zarr")
