"""The panel's words and numbers (app/panel.py), the controls' parsing (app/controls.py), the view
as a link (app/link.py), the session's playback controls and the page's first bytes (app/page.py),
without a browser."""
from __future__ import annotations

import contextlib
import math
import json
import os
import re
import threading
import time
from html.parser import HTMLParser

import numpy as np
import pytest

from theoria.app import link as linkmod
from theoria.app.controls import format_value, slider_range
from theoria.app.format import human_number
from theoria.app.panel import metric_label, verdict
from theoria.physics.params import Param, pretty_unit
from theoria.scenarios import all_scenarios, get
from theoria.scenarios.base import Comparison


def test_numbers_read_as_a_person_writes_them():
    assert human_number(0.0147721) == "0.01477"
    assert human_number(-2.79613e-11) == "−2.796 × 10⁻¹¹"
    assert human_number(2.5e6) == "2.5 × 10⁶"
    assert human_number(123456.7) == "123457"
    assert human_number(None) == "–" and human_number(float("nan")) == "–"
    assert human_number(0) == "0"
    assert human_number((1.0, -0.5)) == "1, −0.5"


def test_verdicts_say_how_far_euler_is_from_the_simulation():
    assert verdict(Comparison("x", 1.0, 1.0 + 1e-12))[1] == "good"
    assert "0.5 %" in verdict(Comparison("x", 1.0, 1.005))[0] and verdict(Comparison("x", 1.0, 1.005))[1] == "close"
    assert verdict(Comparison("x", 1.0, 1.5))[1] == "far" and "33 %" in verdict(Comparison("x", 1.0, 1.5))[0]
    assert verdict(Comparison("x", None, 2.0))[1] == ""
    words, tone = verdict(Comparison("x", 0.0, -2.8e-11))
    assert tone == "" and "exactly 0" in words  # no percentage of a zero
    # no Euler value: the simulated one against the modern one, also when both are exactly 0 (a
    # tidal run's capture outcome beside a probability of 0 divided by zero)
    assert verdict(Comparison("x", None, 0.0, 0.0)) == ("The simulation and the modern value agree exactly", "good")
    # one side exactly 0: both values, no percentage (the Moon's attitude 1.21″ from DE421's, whose
    # residual is 0 by definition, "differed by 100 %"; so did a run's outcome 0 beside a probability)
    assert verdict(Comparison("x", None, 1.2137, 0.0)) == ("The modern value: exactly 0; the simulation: 1.214", "")
    assert verdict(Comparison("x", None, 0.0, 0.5)) == ("The simulation: exactly 0; the modern value: 0.5", "")
    assert verdict(Comparison("x", 2.0, 1.0, 9.0))[0] == "Euler and the simulation differ by 50 %"
    # a run's outcome (captured: 1) beside a probability over many starts "differed by 12 %"
    words, tone = verdict(Comparison("probability of ending in 1:1", None, 1.0, 0.8751))
    assert tone == "" and "%" not in words and words.startswith("This run: yes")
    assert verdict(Comparison("probability of capture into 3:2", None, 0.0, 0.13))[0].startswith("This run: no")


def test_metric_keys_become_words_with_units():
    assert metric_label("flip_interval_s") == "Flip interval (s)"
    assert metric_label("precession_rate_arcsec_per_yr") == "Precession rate (″/yr)"
    assert metric_label("energy_rel_drift") == "Energy relative drift"
    assert metric_label("polhode_period_euler_808_s") == "Polhode period Euler's §808 (s)"
    assert metric_label("nutation_longitude_18_6yr_iau2000_arcsec") == "Nutation longitude 18.6-year IAU 2000 (″)"
    assert metric_label("captured_3_2") == "Captured 3:2" and metric_label("resonance_1_1") == "Resonance 1:1"
    assert metric_label("physical_libration_mprime_arcsec") == "Physical libration M′ term (″)"
    assert metric_label("precession_rate_iau2006_psi_a_arcsec_per_yr") == "Precession rate IAU 2006 ψA (″/yr)"


def test_a_label_that_starts_with_a_greek_letter_keeps_it():
    """ω (the rotation) and Ω (the node's longitude) are different quantities: "ω and L arrows"
    was shown as "Ω and L arrows" in every scenario's list of what is drawn."""
    from theoria.app.format import capitalised
    from theoria.scenarios.drawing import OVERLAYS
    from test_gallery import _session

    assert capitalised("ω and L arrows") == "ω and L arrows" and capitalised("polhode") == "Polhode"
    with _session("free-tumble") as (s, client):
        shown = {h.label for h in client.gui.handles if h.kind == "checkbox"}
    assert "ω and L arrows" in shown and not any(label.startswith("Ω") for label in shown)
    assert len(shown) >= len(OVERLAYS)


def test_a_comparison_whose_label_says_its_unit_shows_it_once():
    """"optical libration in longitude, max (°) (°)" (the Moon, Cassini, the long view)."""
    import types
    from theoria.app.panel import compare_html, comparison_markdown

    said = Comparison("optical libration in longitude, max (°)", None, 7.9, 7.9, "deg", "")
    unsaid = Comparison("obliquity", None, 23.4, 23.4, "deg", "")
    result = types.SimpleNamespace(comparisons=[said, unsaid], warnings=[], notes=[])
    for text in (compare_html(result), comparison_markdown(result)):
        assert text.count("(°)") == 2, text  # once in each row


def test_units_in_words():
    assert pretty_unit("kg m^2") == "kg·m²" and pretty_unit("m^3/s^2") == "m³/s²" and pretty_unit("1") == ""
    assert pretty_unit("deg") == "°"


def test_every_parameter_has_a_human_label_and_every_choice_its_words():
    for s in all_scenarios():
        for p in s.params:
            assert p.label and "_" not in p.display(), (s.name, p.name)
            assert p.display() != p.name, (s.name, p.name)
            if p.kind == "choice" and p.choice_labels:
                assert len(p.choice_labels) == len(p.choices), (s.name, p.name)
                for c in p.choices:
                    assert p.choice_of(p.choice_text(c)) == str(c)


@pytest.mark.parametrize("text,value", [("1e9", 1e9), ("2.5e6", 2.5e6), ("1e-3", 1e-3), ("-0.5", -0.5),
                                        ("0.001", 0.001)])
def test_typed_numbers_are_taken_exactly(text, value):
    p = Param("x", 1000.0, -1e12, 1e12, "m")
    assert p.parse(text) == value
    assert p.parse(format_value(p, value)) == value  # what a field shows reads back to the same value


def test_a_field_shows_ten_digits_and_keeps_the_value_whole_when_left_as_shown():
    """The Earth's obliquity (84381.406″) filled its field as 23.439279444444445; shown to ten
    digits, a field left as shown (a blur, Enter) keeps the exact value and runs nothing."""
    from theoria.app.controls import ParamControls
    from test_gallery import FakeGui

    spec = get("earth")
    changes = []
    ctl = ParamControls(FakeGui(), spec, on_change=lambda name, debounce: changes.append(name))
    assert ctl.kinds["obliquity_deg"] == "text"
    assert ctl.handles["obliquity_deg"].value == "23.43927944"
    ctl.enter("obliquity_deg", "23.43927944")
    assert changes == [] and ctl.values()["obliquity_deg"] == spec.param("obliquity_deg").default
    ctl.enter("obliquity_deg", "23.5")
    assert changes == ["obliquity_deg"] and ctl.values()["obliquity_deg"] == 23.5


def test_a_slider_only_when_it_holds_the_default_and_every_preset_on_its_grid():
    p = Param("perturbation", 0.01, 1e-9, 0.5, "1", step=0.001)
    assert slider_range(p) is not None
    assert slider_range(p, presets=[1e-6]) is None  # 10⁻⁶ is not on a 0.001 grid: a text field
    flip = get("middle-axis-flip")
    from theoria.app.controls import ParamControls  # noqa: F401

    presets = [g["perturbation"] for g in flip.presets.values() if "perturbation" in g]
    assert slider_range(flip.param("perturbation"), presets) is None


def test_a_link_holds_the_view_and_reads_back():
    spec = get("middle-axis-flip")
    values = spec.resolve({"perturbation": 1e-3, "spin": -0.5})
    st = linkmod.LinkState(scenario=spec.name, params={p.name: linkmod.param_text(p, values[p.name]) for p in spec.params},
                           time=12.5, playing=False, camera=(3.0, 2.3, 1.8, 0.0, 0.0, 0.0),
                           options={}, overlays={"axes": False}, present=True)
    q = linkmod.to_query(st, spec)
    back = linkmod.from_address("http://h:1/?" + q)
    assert back.scenario == spec.name and back.time == 12.5 and not back.playing and back.present
    assert back.camera == st.camera and back.overlays == {"axes": False}
    got, errors = linkmod.link_values(spec, back)
    assert errors == [] and got == values


def test_a_bad_link_keeps_the_defaults_and_says_which_value():
    spec = get("middle-axis-flip")
    got, errors = linkmod.link_values(spec, linkmod.from_address("?s=middle-axis-flip&p.spin=1e9&p.nope=3"))
    assert got == spec.defaults and {e.name for e in errors} == {"spin", "nope"}
    assert linkmod.from_address("?cam=1,2,nan").camera is None or not all(
        math.isfinite(x) for x in linkmod.from_address("?cam=1,2,nan").camera) is False


def test_words_for_numbers_in_a_link_are_dropped():
    """float() reads "nan" and "inf": a link's time, speed and camera take finite numbers only."""
    for word in ("nan", "NaN", "inf", "-inf", "infinity"):
        st = linkmod.from_address(f"?s=free-tumble&t={word}&speed={word}&cam=1,2,3,0,0,{word}")
        assert st.scenario == "free-tumble" and st.time is None and st.speed is None and st.camera is None, (word, st)
    for cam in ("0,0,0,0,0,0", "1,2,3,1,2,3", "3,2,1,0,0,0,0,0,0"):  # no distance, no up: viser raised
        assert linkmod.from_address(f"?cam={cam}").camera is None, cam
    st = linkmod.from_address("?t=12.5&speed=2&cam=1,2,3,0,0,0")
    assert (st.time, st.speed, st.camera) == (12.5, 2.0, (1.0, 2.0, 3.0, 0.0, 0.0, 0.0))


def test_a_link_with_nan_for_the_time_and_speed_leaves_the_clock_moving(monkeypatch):
    """A shared link (or its QR code) with t=nan&speed=nan put the page's clock at NaN: playback
    stood on the last frame for everyone who opened it, until Reset."""
    from theoria.app import browser
    from test_gallery import _session, _wait

    monkeypatch.setattr(browser, "read_address",
                        lambda client, timeout=3.0: "http://127.0.0.1:1/?s=free-tumble&t=nan&speed=nan")
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        assert s.playing and s.speed.value == 1.0
        start = s.clock
        assert math.isfinite(start)
        _wait(lambda: math.isfinite(s.clock) and s.clock != start, 30)


@pytest.mark.parametrize("speed,used,told", [("100", 1.0, True), ("0.01", 1.0, True), ("2.5", 2.5, False)])
def test_a_link_with_a_speed_out_of_range_says_so(monkeypatch, speed, used, told):
    """speed=100 became 10 without a word, unlike every other value a link holds that is refused."""
    from theoria.app import browser
    from test_gallery import _session, _wait

    monkeypatch.setattr(browser, "read_address",
                        lambda client, timeout=3.0: f"http://127.0.0.1:1/?s=free-tumble&speed={speed}")
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        assert s.speed.value == used
        notes = [(t, b) for t, b in client.notes if t == "Not allowed: Playback speed"]
        assert bool(notes) == told and all("[0.1, 10]" in b and "default" in b for _, b in notes), client.notes


@pytest.mark.parametrize("cam", ["0,0,0,0,0,0", "3,2,1,0,0,0,0,0,0"])
def test_a_link_with_a_camera_the_view_cannot_take_still_shows_the_scene(monkeypatch, cam):
    """A camera at the point it looks at, or with no up direction: viser raised while the link was
    restored, and the page stayed on "preparing…" with an empty panel."""
    from theoria.app import browser
    from test_gallery import _session, _wait

    monkeypatch.setattr(browser, "read_address",
                        lambda client, timeout=3.0: f"http://127.0.0.1:1/?s=middle-axis-flip&play=0&cam={cam}")
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        assert s.spec.name == "middle-axis-flip" and not s.playing
        assert np.linalg.norm(np.subtract(client.camera.position, client.camera.look_at)) > 0.1
        assert any(n[0] == "Not allowed: Camera" and "six numbers" in n[1] for n in client.notes)  # and it is said


def test_a_link_whose_values_together_go_over_the_budget_still_shows_its_scene(monkeypatch):
    """A duration and a step each in range, together 10¹⁰ steps: the link's run was refused at
    its start and the page showed no scene at all ("simulation failed"), the duration field
    showing 20 while nothing was drawn. The value named by the refusal goes back to its default,
    the class is told, and the scene is drawn with it."""
    from theoria.app import browser
    from test_gallery import _session, _wait

    monkeypatch.setattr(browser, "read_address", lambda client, timeout=3.0:
                        "http://127.0.0.1:1/?s=free-tumble&p.duration=1000000&p.step=0.0001")
    spec = get("free-tumble")
    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        assert s.drawing_spec == "free-tumble" and s.spec.name == "free-tumble"
        refused = [e for e in ("duration", "step") if s.good_values[e] == spec.resolve(None)[e]]
        kept = {"duration": 1e6, "step": 1e-4}
        assert len(refused) == 1 and all(s.good_values[k] == v for k, v in kept.items() if k not in refused)
        assert s.controls.values()[refused[0]] == spec.resolve(None)[refused[0]]
        assert any(t.startswith("Not allowed") and "default" in b for t, b in client.notes), client.notes


@pytest.mark.parametrize("n", [3000, 90000])
def test_a_link_of_thousands_of_unknown_values_gives_a_few_notices(monkeypatch, n):
    """A hand-made link with 3,000 unknown `p.` keys made the server send 3,000 notifications; one
    of 90,000 cost 1.7 s of the server's CPU each time a page opened it (a refusal made for every
    key), and five tabs reopening it held the class's redraws at 1-4 s. Three notices and a count;
    the parts beyond MAX_LINK_PARTS are counted, not read."""
    from theoria.app import browser, link
    from test_gallery import _session, _wait

    keys = "&".join(f"p.x{k}=1" for k in range(n))
    address = f"http://127.0.0.1:1/?s=free-tumble&p.duration=7&{keys}"
    monkeypatch.setattr(browser, "read_address", lambda client, timeout=3.0: address)
    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        assert s.good_values["duration"] == 7.0
        assert len(client.notes) == 4 and client.notes[-1][1] == f"{n - 3} more parts of the link were not used", \
            client.notes[-2:]
    st = link.from_address(address)
    assert len(st.params) == link.MAX_LINK_PARTS - 1 and st.unread == n + 2 - link.MAX_LINK_PARTS


def test_the_class_link_only_on_a_network_address():
    assert linkmod.class_link("127.0.0.1", 8080) is None
    assert linkmod.class_link("192.168.1.5", 8080) == "http://192.168.1.5:8080/"
    assert linkmod.class_link("0.0.0.0", 8080, "http://10.0.0.7:8080/?s=moon") == "http://10.0.0.7:8080/"
    uri = linkmod.qr_svg_uri("http://10.0.0.7:8080/?s=moon")
    assert uri.startswith("data:image/svg+xml")


# ---- the session's controls with a fake browser ------------------------------------------------

def test_session_typed_values_reset_step_and_presenter_mode(monkeypatch):
    from test_gallery import _session, _wait

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        n = s.updates
        s.controls.enter("perturbation", "1e-3")
        _wait(lambda: s.updates > n, 300)
        assert s.good_values["perturbation"] == 1e-3
        # a value out of range is refused with the allowed range; the field shows the last good value
        s.controls.enter("perturbation", "7")
        assert client.notes and "0.5" in client.notes[-1][1]
        assert s.controls.handles["perturbation"].value == "0.001"
        assert s.controls.values()["perturbation"] == 1e-3
        # Reset while paused puts the clock at the start and the read-out follows
        s._toggle_play()
        assert not s.playing
        s.clock = 0.5
        s._reset()
        assert s.clock == 0.0 and s.scrub.value == 0.0 and s.time_md.content.startswith("t = 0 ")
        assert not s.playing
        s._step(1)
        assert s.clock == pytest.approx(0.01) and not s.playing and s.view.frame > 0
        s._set_present(True)
        assert s.view.label_scale > 1 and all(not h.visible for h in s.controls._containers)
        # projected: the server's limits (--host, steps, memory) are the teacher's, not the class's
        assert not s.limits_md.visible and s.present_cb.visible
        assert not s.class_html.visible  # "started with --host 0.0.0.0": the teacher's note, not the class's
        s._set_present(False)
        assert all(h.visible for h in s.controls._containers) and s.limits_md.visible and s.class_html.visible


def test_presenter_mode_keeps_labels_apart_at_its_size_and_through_a_scenario_switch():
    """Presenter mode's larger type (1.6× on a screen 1.35× taller) put libration-circular's L on
    "C = 1" all run long and the Cassini scene's note on the normals: labels are placed for their
    size there, and stay so on the next scene."""
    from theoria.app.session import APP_ROWS, PRESENT_LABEL_SCALE, PRESENT_ROWS
    from theoria.scenarios.drawing import View
    from test_gallery import _session, _wait

    def anchors(d):
        return {it.name: (getattr(it, "anchor", None), getattr(it, "label_anchors", None)) for it in d.items}

    scale = PRESENT_LABEL_SCALE * APP_ROWS / PRESENT_ROWS
    with _session("cassini") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        normal = anchors(s.drawing)
        s._set_present(True)
        assert s.view_opts.text_scale == pytest.approx(scale)
        # placed afresh for presenter size (not the session's cached drawing compared with itself)
        assert anchors(s.drawing) == anchors(s.spec.drawing(s.result, View(text_scale=scale))) != normal
        n = s.updates
        s._switch_scenario("libration-circular")
        s.request()
        _wait(lambda: s.updates > n and s.drawing_spec == "libration-circular", 300)
        assert s.view_opts.text_scale == pytest.approx(scale)
        s._set_present(False)
        assert s.view_opts.text_scale == 1.0


def test_session_restores_a_link(monkeypatch):
    from theoria.app import browser
    from test_gallery import _session, _wait

    spec = get("middle-axis-flip")
    q = "s=middle-axis-flip&p.spin=4.5&p.perturbation=0.002&t=10&play=0&cam=4,1,2,0,0,0&v.axes=0&exag=3.5"
    monkeypatch.setattr(browser, "read_address", lambda client, timeout=3.0: "http://127.0.0.1:1/?" + q)
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        assert s.spec.name == spec.name and s.good_values["spin"] == 4.5 and s.good_values["perturbation"] == 0.002
        assert not s.playing and client.camera.position == (4.0, 1.0, 2.0)
        t = s.drawing.times[s.view.frame]
        assert abs(t - 10.0) <= np.diff(s.drawing.times).max()
        assert s.toggles["axes"].value is False
        st = s.link_state()
        assert st.params["spin"] == "4.5" and st.camera[:3] == (4.0, 1.0, 2.0) and st.overlays == {"axes": False}
        # the shape as exaggerated when the link was copied: drawn so, and the slider says so
        assert s.view_opts.exaggerate == 3.5 and s.exag.value == 3.5 and "exag=3.5" in s.link_query()
        s.exag.value = 2.0
        _wait(lambda: s.view_opts.exaggerate == 2.0, 60)
        assert "exag=2&" in s.link_query() + "&"


@pytest.mark.parametrize("t, end", [("999", True), ("-5", False)])
def test_a_linked_time_outside_the_run_is_shown_at_its_end_and_said(monkeypatch, t, end):
    from theoria.app import browser
    from test_gallery import _session, _wait

    q = f"s=middle-axis-flip&p.duration=30&t={t}&play=0"
    monkeypatch.setattr(browser, "read_address", lambda client, timeout=3.0: "http://127.0.0.1:1/?" + q)
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1 and s.spec.name == "middle-axis-flip", 300)
        _wait(lambda: any(n[0] == "Not allowed: Time" for n in client.notes), 30)
        text = next(n[1] for n in client.notes if n[0] == "Not allowed: Time")
        assert text.startswith(f"“{t}”: outside the run (t = 0 to 30 s)") and ("its end" if end else "its start") in text
        assert s.view.frame == (s.drawing.n_frames - 1 if end else 0)


def test_a_link_to_a_scene_that_does_not_exist_says_so(monkeypatch):
    """`?s=nonexistent` opened the first scene without a word: the student thought the link was it."""
    from theoria.app import browser
    from test_gallery import _session, _wait

    monkeypatch.setattr(browser, "read_address", lambda client, timeout=3.0: "http://127.0.0.1:1/?s=nonexistent")
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        assert s.spec.name == "free-tumble"
        assert any(t == "Not allowed: Scene" and "“nonexistent”" in b and s.spec.title in b for t, b in client.notes), \
            client.notes


@pytest.mark.parametrize("query", ["scenario=moon", "scene=moon", "moon", "s=moon&zoom=3", "s=moon&" + "&".join(
    f"utm{k}=x" for k in range(40)), "s=moon&fixedDpr=1&darkMode=1"])  # (the last two: viser's own settings)
def test_a_link_typed_by_hand_opens_its_scene_and_names_what_it_did_not_use(monkeypatch, query):
    """A teacher writing the link on the board typed `?scenario=moon` (or `?scene=moon`, `?moon`):
    the first scene opened, without a word; a key of no theoria link (`zoom`, a mailer's `utm_…`)
    was ignored silently. The scene is opened, and each key not used is named, a few at most."""
    from theoria.app import browser
    from test_gallery import _session, _wait

    monkeypatch.setattr(browser, "read_address", lambda client, timeout=3.0: f"http://127.0.0.1:1/?{query}")
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        assert s.spec.name == "moon"
        unused = [b for t, b in client.notes if t.startswith("Not allowed")]
        if "zoom" in query:
            assert len(unused) == 1 and unused[0].startswith("“3”") and "not a key of a theoria link" in unused[0]
        elif "utm" in query:
            assert len(unused) == 4 and unused[-1] == "37 more parts of the link were not used", unused
        else:
            assert unused == []


def test_a_linked_time_is_the_full_runs_frame_after_a_quick_preview(monkeypatch):
    """A link to a heavy scene is first shown on its quick preview, whose frames are not the full
    run's: the link's time fell on the preview's frame, and the full run then showed the frame
    after it (libration-eccentric: 51.43 for 51.427872, twice)."""
    from theoria.app import browser, worker
    from theoria.app.link import _num
    from theoria.app.worker import drawing_of
    from test_gallery import _session, _wait

    spec = get("libration-eccentric")
    # values no cache holds (a server's background work keeps every scene's defaults), shown first
    # as a quick preview whatever the pool has measured of this scene's speed, then as the full run
    monkeypatch.setattr(worker, "PREVIEW_AFTER_S", -1.0)
    zeta = 1.0 + (time.time_ns() % 10**6) * 1e-7
    run = spec.simulate_fn(spec.resolve({"free_zeta0_deg": zeta}))
    full = drawing_of(spec, run).times
    want = float(_num(full[len(full) // 3 + 1], 8))  # as the address writes it
    q = f"s={spec.name}&p.free_zeta0_deg={linkmod.param_text(spec.param('free_zeta0_deg'), zeta)}&t={want}&play=0"
    monkeypatch.setattr(browser, "read_address", lambda client, timeout=3.0: "http://127.0.0.1:1/?" + q)
    with _session("free-tumble") as (s, client):
        _wait(lambda: s.drawing_spec == spec.name and s.result is not None
              and s.result.params["free_zeta0_deg"] == zeta and len(s.result.trajectory.t) == len(run.trajectory.t), 120)
        # the full run's drawing shown (a preview first, unless the full run came back before it),
        # its frame set: the session does both under the view lock
        _wait(lambda: s.drawing_spec == spec.name and np.array_equal(s.drawing.times, full), 10)
        with s._view_lock:
            shown = s.drawing.times[s.view.frame]
        assert abs(shown - want) < 1e-6 * want and not s.playing, (shown, want, s.updates, s.playing, s.clock)


def test_a_linked_time_is_the_frame_shown_even_when_the_page_was_playing():
    """A link opened while the first run plays: pausing brought the clock up to now *after* the
    link's time was set, and a copied link came back one frame later (3.93 for 3.92), now and then
    in a browser; here the last tick is put a second back so that it always would."""
    from theoria.app.link import LinkState
    from test_gallery import _session, _wait

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        times = s.drawing.times
        for want in (times[392], times[1], times[len(times) // 2]):
            s._set_playing(True)
            s._last_tick = time.perf_counter() - 1.0
            s._restore_view(LinkState(time=float(want), playing=False), s.drawing)
            assert not s.playing
            assert times[s._frame_index()] == want


def test_the_clock_set_while_playing_is_never_overwritten_by_the_playback_thread():
    """The playback thread reads the clock, adds the time since its last tick and writes it back;
    a scrub, a step or a link's time set in between was lost (with the scrubber's callback in place
    of `_set_clock`, 8 to 22 of 10,000 before the clock had its lock). Here the thread ticks without
    pause and the interpreter switches threads every microsecond, so that the two meet often."""
    import sys
    from test_gallery import _session, _wait

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        s._set_playing(True)
        stop = threading.Event()

        def play():
            while not stop.is_set():
                s._advance()

        lost, switch = [], sys.getswitchinterval()
        player = threading.Thread(target=play, daemon=True)
        sys.setswitchinterval(1e-6)
        player.start()
        try:
            for i in range(10000):
                want = 0.2 if i % 2 else 0.7
                s._set_clock(want)
                if abs(s.clock - want) > 0.05:  # a playing clock moves on, by far less than that
                    lost.append((want, s.clock))
        finally:
            stop.set()
            player.join()
            sys.setswitchinterval(switch)
        assert not lost, f"{len(lost)} of 10000 settings of the clock lost, e.g. {lost[:3]}"


@contextlib.contextmanager
def _raised_on_another_thread(owner):
    """`owner._guard` (the code's own change under way) raised by another thread meanwhile."""
    raised, done = threading.Event(), threading.Event()

    def hold():
        owner._guard = True
        raised.set()
        done.wait(10)
        owner._guard = False

    other = threading.Thread(target=hold)
    other.start()
    try:
        assert raised.wait(10)
        yield
    finally:
        done.set()
        other.join()


def _ticked_by_hand_only(s):
    """Take a session from the playback thread, whose ticks at the real time would move the clock
    of a test that ticks it at times of its own; a pass of that thread begun before is let end."""
    from theoria.app import playback

    playback.ticker().remove(s)
    time.sleep(1.5 / playback.PLAY_HZ_MIN)


def test_a_browsers_scrub_is_taken_though_playback_moved_the_scrubber_meanwhile():
    """viser sets a browser's value as its message arrives and runs the callback later, on a
    thread of its pool. Playback moving the scrubber to its own time in between (twice a second)
    replaced the student's value before the callback read it; and while the playback thread held
    the flag that marks the code's own changes, a browser's event on another thread was ignored."""
    from theoria.app import session as session_mod
    from test_gallery import _session, _wait

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        _ticked_by_hand_only(s)
        s._set_playing(True)
        s._set_clock(0.7)
        object.__setattr__(s.scrub, "value", 20.0)  # the browser's value, as viser sets it
        object.__setattr__(s.scrub, "update_timestamp", time.time() + 1.0)
        s._time_gui()  # playback's read-out comes first ...
        s._browser_event(s._on_scrub)  # ... then the callback
        assert s.clock == pytest.approx(0.2, abs=0.01) and s.scrub.value == 20.0
        # playing on, the scrubber is left to the hand that moved it for a while (its number field
        # sends each keystroke: rewritten, "90" typed became "9" and then the playing time) ...
        def tick():
            t = time.perf_counter()
            s._tick(t)
            s._last_gui = -1e9
            s._tick(t + 0.2)

        tick()
        assert s.scrub.value == 20.0 and s.clock > 0.2
        s._scrub_moved -= session_mod.SCRUB_HOLD_S  # ... then follows the clock again
        tick()
        assert s.scrub.value == round(100 * s.clock, 1) and s.scrub.value > 20.0

        # the flag raised by another thread (playback, moving the scrubber) meanwhile
        with _raised_on_another_thread(s):
            object.__setattr__(s.scrub, "value", 50.0)
            object.__setattr__(s.scrub, "update_timestamp", time.time() + 2.0)
            s._browser_event(s._on_scrub)
            assert s.clock == pytest.approx(0.5, abs=0.01)


def test_a_playing_clock_never_runs_backward_for_a_time_read_earlier_on_another_thread():
    """The playback thread reads the time once for a pass over every browser; a pause on a
    browser's thread meanwhile brings the clock up to a later time. The pass's older time then
    moved the clock back by the difference (a frame shown twice, a jump back of the read-out)."""
    from theoria.app.session import RUN_SECONDS
    from test_gallery import _session, _wait

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        _ticked_by_hand_only(s)
        s._set_playing(True)
        s._set_clock(0.25)
        t0 = time.perf_counter() + 100.0
        rate = float(s.speed.value) / RUN_SECONDS  # run fraction per second of real time
        s._advance(t0)
        assert s.clock == pytest.approx(0.25, abs=1e-12)
        s._advance(t0 + 0.5)
        assert s.clock == pytest.approx(0.25 + 0.5 * rate, abs=1e-12)
        s._advance(t0 + 0.3)  # read before the last one
        assert s.clock == pytest.approx(0.25 + 0.5 * rate, abs=1e-12)
        s._advance(t0 + 0.6)  # real time only counted once
        assert s.clock == pytest.approx(0.25 + 0.6 * rate, abs=1e-12)


def test_a_drawing_thread_setting_the_scrubber_never_waits_for_a_browsers_event():
    """A drawing thread shows a run holding the view lock and moves the scrubber; viser runs the
    scrubber's callback at once on that thread. That callback took the browser's event lock,
    held by a browser's step waiting for the view lock: both stuck for good, and with them every
    drawing thread of the server (found by a teacher's arrow keys on a slider: a second browser
    then never got its first scene)."""
    import threading
    from test_gallery import _session, _wait

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        entered, drawn = threading.Event(), threading.Event()

        def browser_steps():  # holds the event lock, then wants the view lock (to show the frame)
            entered.set()
            s._step(1)

        def drawing_thread():
            with s._view_lock:
                browser = threading.Thread(target=s._browser_event, args=(browser_steps,), daemon=True)
                browser.start()
                assert entered.wait(10)
                s.clock = 0.3  # the run shown: the scrubber follows its clock
                s._time_gui()
            drawn.set()
            browser.join(10)

        t = threading.Thread(target=drawing_thread, daemon=True)
        t.start()
        assert drawn.wait(10), "the drawing thread waits for the browser's event, which waits for it"
        t.join(10)
        assert not t.is_alive()


def test_a_browsers_change_is_taken_while_another_thread_puts_a_control_back():
    """A refused run puts its control back from a drawing thread (`set_values`, with the flag that
    makes the controls' own callbacks do nothing); a slider a student moved meanwhile, handled on
    another thread, was ignored while that flag was up."""
    from theoria.app.controls import ParamControls
    from test_gallery import FakeGui

    changes = []
    ctl = ParamControls(FakeGui(), get("middle-axis-flip"), on_change=lambda name, debounce: changes.append(name))
    with _raised_on_another_thread(ctl):
        ctl.handles["spin"].value = 4.0  # the browser's change; its callback runs on this thread
        assert ctl.values()["spin"] == 4.0 and changes == ["spin"]


def test_a_plots_y_axis_has_room_for_the_ticks_uplot_puts_beyond_the_data():
    """lunar-perturbation's node runs down to -680°: uPlot pads the range by a tenth of the span
    and rounds it out to a hundred, and labels its lowest tick "-1,000", whose minus sign was cut."""
    from theoria.app.panel import y_axis_px

    assert y_axis_px([np.array([-679.5, 1736.9])]) >= len("-1,000") * 7.2 + 15
    assert y_axis_px([np.array([0.2, 0.8])]) == 50  # "0.1" … "0.9": the narrowest axis


def test_a_run_over_the_budget_is_refused_in_the_panels_words_and_keeps_its_preset():
    """A class reads the refusal: the control's name for the key, the number as typed, no flag of
    the command line (the limits are the server's); the values are the preset's again, and so is
    the name shown under "Start from"."""
    from test_gallery import _session, _wait

    with _session("free-tumble") as (s, client):
        _wait(lambda: s.updates >= 1, 300)
        preset = s.presets.value
        s.controls.enter("duration", "1e6")
        _wait(lambda: client.notes and "Length of the run" in client.notes[-1][0], 60)
        title, text = client.notes[-1]
        assert text.startswith("“1000000”:") and "Length of the run ≤ 200000 s fits" in text, text
        assert not re.search(r"max_steps|--max|\bduration\b|e\+0", text + s.status.content), text
        assert s.presets.value == preset and s.controls.values()["duration"] == s.good_values["duration"]


def test_only_the_controls_the_chosen_motion_uses_are_shown_and_presenter_mode_hides_them_all():
    from theoria.app.controls import ParamControls
    from test_gallery import FakeGui

    spec = get("collinear")
    ctl = ParamControls(FakeGui(), spec)

    def shown():
        return {n for n in ("turns", "phi_max_deg", "energy", "lagrange_point", "masses")
                if ctl.forms.get(n, ctl.handles[n]).visible}

    assert shown() == {"turns", "masses"}  # the line turns
    ctl.handles["motion"].value = spec.param("motion").choice_text("collapse")  # the student's choice
    assert shown() == {"phi_max_deg", "masses"}
    ctl.set_values({"motion": "restricted"})  # a preset
    assert shown() == {"turns", "lagrange_point", "masses"}
    ctl.set_hidden(True)  # presenter mode
    ctl.set_values({"motion": "expansion"})  # its key for a preset
    assert shown() == set()
    ctl.set_hidden(False)
    assert shown() == {"energy", "masses"}


def test_export_says_where_the_file_went_and_its_size(tmp_path, capsys):
    from theoria.app.cli import main

    out = tmp_path / "flip.html"
    assert main(["export", "middle-axis-flip", "--set", "duration=2", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert str(out) in text and out.exists()
    size = out.stat().st_size
    assert f"{size / 1e6:.1f} MB" in text or f"{size / 1e3:.0f} KB" in text or f"{size / 1e6:.0f} MB" in text


def test_the_loading_line_is_parsed_before_viser_s_client_runs():
    """viser's client is an 800 kB script inlined in the page's head, which the browser runs before
    it parses on; on a loaded machine a page caught at that moment had its title and no body. The
    line must come before it (and before the client's root) to be there from the first bytes."""
    from theoria.app.page import LOADING, SOFTWARE_GL_JS, _viser_index, themed_index

    order = []

    class Tags(HTMLParser):
        def handle_starttag(self, tag, attrs):
            order.append((tag, dict(attrs).get("id")))

        def handle_data(self, data):
            if data.strip() == LOADING or data.strip() == SOFTWARE_GL_JS.strip():
                order.append(("text", data.strip()[:20]))

    Tags().feed(themed_index(_viser_index().read_text(encoding="utf-8")))
    line = order.index(("div", "theoria-loading"))
    assert order[line + 1] == ("text", LOADING[:20])
    scripts = [i for i, (tag, _) in enumerate(order) if tag == "script"]
    ours = order.index(("text", SOFTWARE_GL_JS.strip()[:20])) - 1
    assert [i for i in scripts if i != ours], "viser's client script not found"
    assert all(line < i for i in scripts if i != ours)
    assert line < order.index(("div", "root"))
    assert order.index(("title", None)) < line  # the tab is named before anything else


@pytest.mark.parametrize("name, values", [
    ("libration-eccentric", {"orbital_rate": 2.0, "orbits": 3.0}),
    ("precession-circular", {"orbits": 7.0}),
    ("tidal-capture", {"orbits": 40.0}),
])
def test_a_time_in_the_unit_of_an_orbital_rate_is_read_out_in_orbits(name, values):
    """The read-out said "t = 0 of 31.42 1/n·rad". A run asked for a number of orbits (at any
    mean motion n, in rad per time unit) is read out as that number of orbits, and so is its plot's
    time axis."""
    from theoria.app.format import human_number

    spec = get(name)
    run = spec.simulate(dict(spec.preview, **values))
    d = spec.drawing(run)
    assert d.clock.reading(d.times[-1], d.times[-1], human_number) == f"t = {values['orbits']:g} of {values['orbits']:g} orbits"
    assert d.clock.reading(0.0, d.times[-1], human_number).startswith("t = 0 of ")


def test_a_run_of_decades_in_days_is_read_out_in_years_as_its_span_is_set():
    """Cassini's span is set in years (74.4: four node cycles) and its run is counted in days: the
    read-out said "t = 8816 of 27175 days". Runs in days longer than 1000 days read in years; a
    month of the Moon stays in days."""
    from theoria.app.format import human_number
    from theoria.physics.constants import JULIAN_YEAR_DAYS

    run = get("cassini").simulate()
    d = get("cassini").drawing(run)
    years = (d.times[-1] - d.times[0]) / JULIAN_YEAR_DAYS
    assert 70 < years < 80 and d.clock.reading(d.times[-1], d.times[-1], human_number) == (
        f"t = {human_number(d.times[-1] / JULIAN_YEAR_DAYS)} of {human_number(d.times[-1] / JULIAN_YEAR_DAYS)} years")
    short = get("cassini").simulate(years=2)
    assert get("cassini").drawing(short).clock.words == "days"


def test_what_is_drawn_offers_only_what_the_scene_draws():
    """A three-body scene listed the rigid body's overlays (principal axes, polhode, Poinsot's
    ellipsoid …) and the shape's exaggeration, none of which it draws; a rotation scene offers
    them again."""
    from theoria.app import gallery
    from test_gallery import _session, _wait

    with _session("collinear") as (s, client):
        _wait(lambda: s.updates >= 1)
        shown = {k for k, cb in s.toggles.items() if cb.visible}
        assert shown == {"bodies", "scenario"} and not s.exag.visible
        n = s.updates
        s.dd.value = gallery.label(get("free-tumble"))
        _wait(lambda: s.updates > n and s.drawing_spec == "free-tumble")
        shown = {k for k, cb in s.toggles.items() if cb.visible}
        assert {"axes", "vectors", "polhode", "herpolhode", "energy_ellipsoid"} <= shown and s.exag.visible
        assert "bodies" not in shown  # a free body has no other body


def test_a_rate_of_change_is_not_named_as_the_quantity():
    """pole-near-axis listed dγ′/dt, in rad/s², as "Spin rate (rad/s²)": a spin rate in the wrong
    unit to a reader. It is the rate of change of the spin; Euler's value of it says so first."""
    from theoria.app.panel import metric_label

    assert metric_label("dspin_dt", "rad/s^2") == "Rate of change of spin (rad/s²)"
    assert metric_label("dspin_dt_euler", "rad/s^2") == "Euler's rate of change of spin (rad/s²)"
    assert metric_label("pole_speed_euler", "rad/s") == "Euler's pole speed (rad/s)"
    assert metric_label("forced_floquet_half_trace", "") == "Forced Floquet half trace"
    assert metric_label("axis_angle_from_euler_rad", "rad") == "Axis angle from Euler (rad)"


def test_a_short_runs_time_axis_is_in_a_unit_its_ticks_can_show():
    """uPlot labels ticks with at most three decimals: a run of 0.001 s read "0 0 0 0.001 0.001
    0.001" under its plot. Spans under 0.05 are shown in thousandths."""
    from theoria.app.panel import time_axis

    x, words = time_axis(np.linspace(0.0, 0.001, 11), "s")
    assert words == "ms" and x[-1] == pytest.approx(1.0) and len({f"{v:.3f}" for v in x}) == 11
    assert time_axis(np.linspace(0.0, 2e-7, 3), "s")[1] == "ns"
    assert time_axis(np.linspace(0.0, 0.01, 3), "days")[1] == "10⁻³ days"
    x, words = time_axis(np.linspace(0.0, 30.0, 3), "s")  # a span its ticks show already: as it is
    assert words == "s" and x[-1] == 30.0


def test_small_plotted_values_are_in_a_unit_their_ticks_can_show(monkeypatch):
    """The satellite leaving Earth–Moon L2 drifts from 10⁻¹² to 8 × 10⁻⁶ distances: its plot's ticks
    read "0" and "0" (uPlot writes at most three decimals). Such values are scaled by a power of
    ten that the axis names; values that are only rounding (a locked libration's 10⁻¹⁴) are not."""
    from theoria.app.panel import value_axis
    from test_gallery import _session, _wait

    drift = np.geomspace(1e-12, 8.4e-6, 50)
    (y,), e = value_axis([drift])
    assert e == -6 and y.max() == pytest.approx(8.4) and len({f"{v:.3f}" for v in np.linspace(0, y.max(), 6)}) == 6
    assert value_axis([np.array([-3e-4, 2e-4]), np.array([1e-5])])[1] == -6  # the largest in size decides
    assert value_axis([np.array([0.0, 0.02])])[1] == -3
    for as_given in ([np.array([1e-14, -3e-14])], [np.array([0.0, 0.5])], [np.array([np.nan, 0.0])]):
        assert value_axis(as_given)[1] == 0
    from theoria.app import browser
    monkeypatch.setattr(browser, "read_address", lambda client, timeout=3.0:
                        "http://127.0.0.1:1/?s=collinear&p.motion=restricted&p.lagrange_point=L2")
    with _session("free-tumble") as (s, client):
        # (a quick preview of a shorter run comes first, its drift ×10⁻¹²)
        _wait(lambda: s.plot is not None and s.plot.axes[1].get("label") == "×10⁻⁶", 300)
        drift = np.asarray(next(iter(s.drawing.plot.values())), float)
        assert 1.0 <= np.nanmax(np.abs(drift)) * 1e6 < 1000.0  # what the axis names: 10⁻⁶ of its values


def test_hyperions_table_and_tidal_captures_plot_are_in_words():
    """Hyperion's table said "(1966, to e^3)" and "−0.00%" beside the series' half-width;
    tidal-capture's legend read "Spin rate orbit mean", "Pseudo synchronous" (code names made
    words) and a note named the series "plot_series spin_rate_orbit_mean_n"."""
    import re

    spec = get("hyperion")
    run = spec.simulate(**{k: v for k, v in spec.preview.items() if not isinstance(v, str)})
    notes = [c.note for c in run.comparisons if "half-width" in c.label]
    assert notes and all("^" not in n and not re.search(r"[−-]0\.00\s?%", n) for n in notes), notes
    assert all(re.search(r"to e[²³⁴⁵⁶]", n) for n in notes), notes
    run = get("tidal-capture").simulate(orbits=200)
    assert "spin rate, mean over each orbit (n)" in run.plot_series
    assert not [k for k in run.plot_series if "_" in k], list(run.plot_series)
    assert not [n for n in run.notes if "plot_series" in n or "_n" in n], run.notes


def test_a_quick_previews_own_warnings_are_not_shown_as_the_runs():
    """The Moon's preview (one year) cannot measure its annual term and says so; the run the class
    asked for (six years) can. While the preview is on screen the Compare tab says it is a preview."""
    from theoria.app.panel import compare_html

    spec = get("moon")
    preview = spec.simulate(**spec.preview)
    assert any("cannot tell" in w for w in preview.warnings)
    shown = compare_html(preview, preview=True)
    assert "quick, shorter preview" in shown and "cannot tell" not in shown
    assert "cannot tell" in compare_html(preview)


PROGRAMMERS_NUMBER = re.compile(r"(?<![\w.])\d+(?:\.\d+)?[eE][+\-−]?\d+|(?<![\w)\]−-])-\d")


@pytest.mark.parametrize("name", [s.name for s in all_scenarios()])
def test_every_text_of_the_panel_writes_numbers_as_people_do(name):
    """What a class can unfold (how the numbers were made, the printed text's errors, every number
    of the run) and the controls' hover hints: a teacher found "631.0e-6", "+6.2e−06 %", "~1e-6"
    and "-8.5″" there (the browser test reads only what is unfolded)."""
    from test_gallery import _session, _wait

    full = get(name).resolve({})
    with _session(name) as (s, client):
        _wait(lambda: s.result is not None and dict(s.result.params) == full, 300)  # the full run, not its preview
        handles = [h for h in client.gui.handles if not h.removed]
        texts = [getattr(h, "content", "") or "" for h in handles] + [getattr(h, "hint", "") or "" for h in handles]
    bad = [t[max(0, m.start() - 40):m.end() + 10] for t in texts for m in PROGRAMMERS_NUMBER.finditer(t)]
    assert bad == [], bad


def test_a_sweep_on_a_log_scale_plays_one_distance_per_equal_share_of_the_run():
    """gravity-gradient-accuracy's run is a sweep of F's distance, its twelve sizes/distances on a
    log scale from 0.01 to 0.5. Played in proportion to that "time", the first nine flashed by in a
    quarter of the run and F stood still at 0.5 from 70 % to the end (a teacher saw 50, 60 and 65 %
    all read 0.3504). Each now has an equal share, on the server's clock and in the page's tracks;
    a time set from a link still lands on its own distance."""
    import base64

    from test_gallery import _session, _wait

    with _session("gravity-gradient-accuracy") as (s, client):
        _wait(lambda: s.result is not None and s.drawing is not None and s.drawing.n_frames == 12)
        d = s.drawing
        seen = []
        for c in np.linspace(0.0, 1.0, 101):
            s._set_clock(c)
            seen.append(s._frame_index())
        counts = np.bincount(seen, minlength=12)
        assert counts[0] >= 1 and counts[1:].min() >= 8 and counts.max() <= 10, counts  # each its share (100 / 11)
        times = np.frombuffer(base64.b64decode(json.loads(s.view.tracks_json())["times"]), "<f4")
        assert np.allclose(times, np.linspace(0, 1, 12), atol=1e-6)
        t = float(d.times[9])
        s._set_clock_at(t, d)
        assert s._frame_index() == 9 and d.times[s._frame_index()] == t


def test_a_row_without_a_simulated_value_says_why_beside_it():
    """A spin of −0.5 rad/s flips fewer than twice in 30 s: the Compare row read "no simulated
    value", its reason only in a folded section below."""
    from theoria.app.panel import compare_html

    run = get("middle-axis-flip").simulate(spin=-0.5)
    assert run.comparisons[0].simulated is None or np.isnan(run.comparisons[0].simulated)
    page = compare_html(run)
    assert "No simulated value: fewer than two flips in 30 s" in page, page
    run = get("libration-circular").simulate(periods=1)
    assert "No simulated value: the run holds fewer than two whole swings" in compare_html(run)
    assert run.to_dict()["comparisons"][0]["missing"].startswith("the run holds fewer")


def test_a_time_in_the_compare_tab_is_in_the_orbits_the_clock_reads():
    """libration-circular read "t = 1.871 of 10.65 orbits" above a libration period of "16.73 time
    units": the period is shown in orbits too (16.73 time units at δ = 1 rad per unit are 2.66
    orbits), and its verdict is unchanged."""
    import html

    from theoria.app.format import human_number
    from theoria.app.panel import compare_html, verdict
    from theoria.scenarios.drawing import clock_of

    run = get("libration-circular").simulate()
    c = run.comparisons[0]
    clock = clock_of(run)
    assert clock.words == "orbits"
    page = compare_html(run)
    for x in (c.euler, c.simulated, c.modern):
        assert human_number(x * clock.scale) in page, (x * clock.scale, page)
    assert human_number(c.simulated) not in page  # not in time units any more
    assert "(orbits)" in page and "time units" not in page
    assert html.escape(verdict(c)[0]) in page
    T = c.modern * clock.scale
    end = run.trajectory.t[-1] * clock.scale
    assert end / T == pytest.approx(run.params["periods"], rel=1e-9)  # the clock's orbits, in periods


def test_the_long_views_plot_shows_the_obliquitys_swing_on_its_own_scale():
    """earth-long-view's Read tab points to the obliquity's swing of a degree in the time plot, which
    put it on one axis with the pole's longitude and RA (−340° … 90°) and a difference in arcminutes:
    a flat line. The plot holds the obliquity of date and Vondrák's; the run keeps every series."""
    from theoria.scenarios.drawing import View

    spec = get("earth-long-view")
    run = spec.simulate()
    d = spec.draw(run, spec, View())
    assert set(d.plot) == {"obliquity of date (deg)", "obliquity, Vondrák 2011 (deg)"}
    lo, hi = min(np.min(v) for v in d.plot.values()), max(np.max(v) for v in d.plot.values())
    assert 0.5 < hi - lo < 2.0  # the swing fills the axis
    assert "pole RA J2000 (deg)" in run.plot_series


def test_the_scene_shown_is_saved_as_a_web_page_from_the_panel():
    """Record and export were only on the command line: a teacher found no way to keep a scene. The
    Read tab's button sends this browser the standalone replay of what it shows (the page `theoria
    export` writes, which `theoria replay --check` accepts), and says its name and size."""
    from test_gallery import _session, _wait

    from theoria.app import replay
    from theoria.app.session import SAVE_PAGE_LABEL

    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.result is not None and s.drawing is not None)
        saved = []
        client.send_file_download = lambda name, content, **kw: saved.append((name, content))
        client.gui.find("button", SAVE_PAGE_LABEL).value = True  # a click
        _wait(lambda: saved and any(t == "Saved" for t, b in client.notes))
    (name, content), = saved
    assert name == "theoria-middle-axis-flip.html" and content.startswith(b"<!")
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, name)
        with open(path, "wb") as f:
            f.write(content)
        got = replay.check(path)  # raises on a page that is not a whole theoria export
        assert got["scenario"] == "middle-axis-flip" and got["digest"], got
    body = next(b for t, b in client.notes if t == "Saved")
    assert name in body and ("MB" in body or "KB" in body), body


def test_a_link_holds_only_the_values_changed_from_the_scenes_defaults(monkeypatch):
    """The class link of the Moon's scene with two years was 230 characters (every parameter's key
    and value: `p.equator_inclination_deg=1.54242&p.core_fraction=0.0007…`), which no student types
    and whose QR code is too dense to read across a room. It holds the changed value only, and
    opened, gives the same values."""
    from theoria.app import browser
    from theoria.scenarios import get
    from test_gallery import _session, _wait

    monkeypatch.setattr(browser, "read_address", lambda client, timeout=3.0: "http://127.0.0.1:1/?s=moon&p.years=2")
    with _session("free-tumble") as (s, client):
        # a quick preview of one year stands in first: its link holds the two years asked for, not
        # the preview's one (a link copied then opened a one-year run)
        _wait(lambda: s.drawing_spec == "moon", 300)
        q = s.link_query()
        assert [k for k in q.split("&") if k.startswith("p.")] == ["p.years=2"], q
        _wait(lambda: s.good_values["years"] == 2, 300)
        q = s.link_query()
        assert [k for k in q.split("&") if k.startswith("p.")] == ["p.years=2"], q
        assert s.good_values == get("moon").resolve({"years": 2})


def test_one_browser_saves_one_page_at_a_time(monkeypatch):
    """A tab clicking Save twelve times a second and reading slowly took the server from 0.3 to
    0.7 GB in 30 s (each page, ~1 MB, is held for the browser until it reads it), and three such
    tabs kept a core busy making pages while the class's saves were refused. One browser gets a
    page at most every SAVE_PAGE_EVERY_S, and none while the one before is still being sent."""
    from test_gallery import _session, _wait

    from theoria.app import server as server_mod
    from theoria.app import session as session_mod

    class Gate:  # what the server has queued for this browser and what it has sent
        queued, sent_ = 10, -1

        def pushed(self):
            return self.queued

        def sent(self):
            return self.sent_

    gate = Gate()
    monkeypatch.setattr(server_mod, "gate_of", lambda server, cid: gate)
    with _session("middle-axis-flip") as (s, client):
        _wait(lambda: s.result is not None and s.drawing is not None)
        saved = []
        client.send_file_download = lambda name, content, **kw: saved.append(name)
        button = client.gui.find("button", session_mod.SAVE_PAGE_LABEL)
        for _ in range(5):  # five clicks at once
            button.value = True
        _wait(lambda: len([t for t, b in client.notes if t in ("Saved", "Not saved again yet")]) == 5)
        assert len(saved) == 1
        monkeypatch.setattr(session_mod, "SAVE_PAGE_EVERY_S", 0.0)
        n = len(client.notes)
        button.value = True  # the page before is not yet sent (sent -1 < queued 10)
        _wait(lambda: len(client.notes) > n)
        assert client.notes[-1][0] == "Not saved again yet" and len(saved) == 1
        gate.sent_ = 10  # the browser has read it
        button.value = True
        _wait(lambda: len(saved) == 2)
