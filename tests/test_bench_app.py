"""The app's measurements run in CI (README's test command): `theoria bench` for the slider-to-redraw
latency and the playback frame rate in headless Chromium, and the 10⁵-step recording. The numbers
are printed by the command and checked here for what they are (finite, positive, measured on the
run they describe), never against a wall-clock limit."""
from __future__ import annotations

import json
import math
import os

import pytest

from theoria.app.scene import MAX_DRAW_POINTS
from theoria.scenarios.drawing import MAX_FRAMES

pytestmark = [pytest.mark.skipif(not os.path.exists("/usr/bin/chromium"), reason="needs Debian's chromium"),
              pytest.mark.slow]


def _bench(cli, *names):
    code, out, _ = cli("bench", *names, "--json")
    assert code == 0
    rows = {r["name"]: r for r in json.loads(out)["benchmarks"]}
    assert set(rows) == set(names)
    for r in rows.values():
        assert "error" not in r, r
        assert math.isfinite(r["theoria_s"]) and r["theoria_s"] > 0
        assert math.isfinite(r["baseline_s"]) and r["baseline_s"] > 0
    return rows


def test_app_benches_measure_what_they_say(cli):
    rows = _bench(cli, "app-slider-latency", "app-playback-fps", "record-1e5-steps")
    lat = rows["app-slider-latency"]
    assert lat["samples"] == 6001 and 0 < lat["server_ms_median"] <= lat["latency_ms_median"] * 1.5
    fps = rows["app-playback-fps"]
    assert fps["samples"] == 20_001 and fps["frames"] == MAX_FRAMES
    # the naive player re-sends the very paths theoria draws: each at most MAX_DRAW_POINTS, and the
    # rotation-axis trail of the flip (the longest) thousands of points
    pts = fps["path_points"]
    assert set(pts) == {"axis_trail", "body/polhode", "herpolhode"}
    assert all(0 < n <= MAX_DRAW_POINTS for n in pts.values()) and pts["axis_trail"] > 2000, pts
    for k in ("fps", "fps_one_10k_trail", "fps_body_only", "fps_at_960x600", "empty_viser_page_fps"):
        assert 0 < fps[k] < 250, k  # a real frame rate, not a count of something else
    # the paths are sent once: playback beats the player that re-sends them every frame
    assert fps["fps"] > fps["fps_naive_resend"]
    rec = rows["record-1e5-steps"]
    assert rec["steps"] == 100_001 and rec["frames"] == MAX_FRAMES and rec["size_MB"] > 1
