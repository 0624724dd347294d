"""One browser's session: its own scenario, parameters, run, drawing, scene nodes and playback
clock, so two people on one server do not disturb each other.

The panel is laid out for a class, in the manner of PhET simulations: the scene picker on top,
then three tabs. **Explore**: the preset to start from, play / reset / step, time and speed, the
few parameters that matter (numerical settings folded away), what is drawn, the plot over time.
**Compare**: Euler / simulated / modern side by side with units and a verdict in words, and the
run's warnings as a visible note. **Read**: what to look for, Euler's own words and §, where the
printed text is wrong, and the class's link with its QR code and presenter mode. Everything is
named in words (`Param.display()`, `panel.metric_label`), never by the keys scripts use.

A parameter change posts a request to the session's `SimulationWorker` (app/worker.py: off the
event loop, the newest request wins, an older run is cancelled); a slider being dragged is
debounced (only its last value is simulated), a typed value is taken on Enter or when its field
loses focus. The run's drawing is shown in one `client.atomic()` batch, with the drawing's own
camera. Playback runs in its own thread and moves only what the drawing animates.

The browser's address holds the view (app/link.py): opening a copied address restores scenario,
parameters, time, camera, options and presenter mode. Keys (viser commands): space play/pause,
← → step, 1–9 presets, P presenter mode.

Bad input: the ParameterError is shown as a notification naming the control in words and the
allowed range, and the scene keeps the last good run. Any other exception in a scenario is
reported the same way and never reaches the server loop.
"""
from __future__ import annotations

import re
import threading
import time
import traceback
from collections import OrderedDict
from typing import Any

import numpy as np
import viser

from theoria.physics.errors import ParameterError, show_value
from theoria.scenarios import all_scenarios, get
from theoria.scenarios.drawing import OVERLAYS, View, palette

from . import browser, gallery, page, playback
from . import link as linkmod
from .controls import ParamControls, PerThread, format_value, number_param, on_typed
from .export_html import configure_scene
from .format import capitalised, human_number, human_size, readable, superscript
from .panel import (UPLOT_POINTS, compare_html, heading_markdown, metric_label, numbers_markdown,
                    read_markdown, time_axis, value_axis, y_axis_px)
from .scene import SceneView
from .worker import SimulationWorker, drawing_of, limits_text, timing_log

# Playback: one thread for every browser within a share of a core (app/playback.py); with many
# browsers each plays back at a lower rate and slider changes stay quick.
RUN_SECONDS = 20.0  # at speed 1 a whole run plays in this many seconds
# a teacher read speed 1 as real time (a 30-s run played 1.5x faster than that): the label says what 1 is
SPEED_LABEL = f"Playback speed (1: the run in {RUN_SECONDS:g} s)"
# A teacher found no way to keep a scene from the panel (record and export were the command line's):
# the scene shown, as the standalone web page `theoria export` writes (~1 MB, 0.1-0.2 s to make).
SAVE_PAGE_LABEL = "Save this scene as a web page"
SAVE_PAGES_AT_ONCE = threading.BoundedSemaphore(2)  # pages made at once for the whole class
# one browser's pages: at most one every SAVE_PAGE_EVERY_S, and none while the one before is still
# being sent (each is ~1 MB held for that browser until it reads it: a tab clicking Save twelve
# times a second and reading slowly took the server from 0.3 to 0.7 GB in 30 s, and three such
# tabs kept a core making pages while the class's saves were refused)
SAVE_PAGE_EVERY_S = 5.0
CLOCK_TEXT_EVERY = 0.5  # s between updates of the time read-out and the scrubber while playing
# s the scrubber is left to the browser after it moved it: its number field sends each keystroke,
# and the scrubber following playback rewrote the field under a teacher typing "90" (lost)
SCRUB_HOLD_S = 3.0
# a page that plays by itself needs the server's ticks only for the time read-out
PAGE_TICK_HZ = 1.0 / CLOCK_TEXT_EVERY
LINK_ERRORS_SHOWN = 3  # a link's refused values, each in a notification of its own; the rest counted
SLIDER_DEBOUNCE_S = 0.15  # slider moves closer than this are a drag: only its last value is simulated
EXAGGERATE_RANGE = (1.0, 20.0)  # the shape exaggeration: 1 is the body as it is
STEP_FRACTION = 0.01  # ← / → move the clock by this fraction of the run
LINK_EVERY_S = 0.5  # the address bar follows the view at most this often (1 s while playing)
PRESENT_LABEL_SCALE = 1.6  # labels in the scene in presenter mode
PRESENT_ROWS, APP_ROWS = 1080, 800  # a projector's screen, and the laptop's the labels are sized for
PANEL_PX = 384  # viser's "large" control panel: 24 em of 16 px
PRESENT_PANEL_SCALE = 1.45  # the panel's type in presenter mode (app/browser.py `present`)

PLAY, PAUSE, RESET, BACK, FORWARD = "Play", "Pause", "Reset", "◀ Step", "Step ▶"


def _where(e: BaseException) -> str:
    """file:line where an exception was raised (one log line per kind of failure)."""
    tb = e.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    return f"{tb.tb_frame.f_code.co_filename}:{tb.tb_lineno}" if tb is not None else "?"


def playback_hz(active_sessions: int) -> float:
    """Playback rate of each session when `active_sessions` browsers are playing."""
    return playback.ticker().rate(active_sessions)


_IDENT = re.compile(r"\b[A-Za-z][A-Za-z0-9]*(?:_[A-Za-z0-9.]+)+\b|extras\[|plot_series|\bJSON\b")
_ERRATUM = re.compile(r"^(Text:|The translation|Eqs?\.|§[\dIVXLC]+[^:]{0,40} prints|§7's)|translat|prints? ", re.I)


def split_notes(notes) -> tuple[list[str], list[str]]:
    """A run's notes for the panel: (the text's errata, other notes a class can read). Notes written
    for scripts (naming series keys, extras, JSON fields) are left out."""
    errata, other = [], []
    for n in notes:
        if _IDENT.search(n):
            continue
        (errata if _ERRATUM.search(n) else other).append(n)
    return errata, other


def series_label(key: str) -> str:
    """A plot series' name in words (a snake_case key of the run becomes "ζ, Euler (rad)")."""
    if "_" not in key or " " in key:  # written for people already; its unit as the panel writes units
        return re.sub(r"\((deg|arcsec|arcmin)\b", lambda m: "(" + {"deg": "°", "arcsec": "″", "arcmin": "′"}[m[1]], key)
    words = key.split("_")
    tail = ""
    for w in ("euler", "simulated", "exact", "forced", "free"):
        if w in words and words.index(w) > 0 and words[words.index(w) - 1] == "from":
            continue  # "angle from Euler's axis" is not a curve of Euler's
        if w in words[:-1] or (w == words[-1]):
            words.remove(w)
            tail = ", Euler" if w == "euler" else f", {w}"
    text = metric_label("_".join(words))
    m = re.match(r"(.*?)( \(.*\))?$", text)
    return f"{m.group(1)}{tail}{m.group(2) or ''}"


class ClientSession:
    """GUI, scene, worker and playback of one browser."""

    active = 0  # sessions open on this process (sets the playback rate)
    _guard = PerThread()  # set while the code itself moves the scrubber or the checkboxes
    _pguard = PerThread()  # set while the code itself sets the preset or the parameter controls
    _sguard = PerThread()  # set while the code itself changes the sweep map's dropdowns

    def __init__(self, server: viser.ViserServer, client: viser.ClientHandle, scenario: str | None,
                 run=None, sweep=None):
        """`run`: a finished Run to show first (`Run.show()`), with its scenario and parameters.
        `sweep`: a sweep result (app/sweep_map.SweepMaps) shown as a map in a Sweep tab."""
        self._flags = threading.local()  # _guard, _pguard and _sguard, one for each thread
        self.server, self.client = server, client
        self.sweep = sweep
        ClientSession.active += 1
        self.scenarios = {s.name: s for s in all_scenarios()}
        # the address the browser opened: a shared view to restore (not for a Run.show()); a page
        # that answers runs theoria's JavaScript, and plays the scene by itself (app/scene.py)
        address = browser.read_address(client)
        self.address = address if run is None else None
        self.page_plays = address is not None
        self.link = linkmod.from_address(self.address)
        unknown = self.link.scenario if self.link.scenario not in self.scenarios else None
        if unknown is not None:  # said once the panel is there
            self.link.scenario = None
        name = self.link.scenario or scenario
        self.spec = get(name) if name else self.scenarios.get("free-tumble") or next(iter(self.scenarios.values()))
        self.present = bool(self.link.present)
        # the scene's root, hidden while a newly chosen scenario computes (`_hide_previous_scene`)
        self._world = client.scene.add_frame("/world", show_axes=False)
        self.view = SceneView(client.scene, "/world")
        self.view.page_plays = self.page_plays
        self._server_moves = True  # the scene shown has something only the server can move
        self.view_opts = View(options=dict(self.link.options) if self.link.scenario else {})
        if self.link.exaggerate is not None and EXAGGERATE_RANGE[0] <= self.link.exaggerate <= EXAGGERATE_RANGE[1]:
            self.view_opts.exaggerate = float(self.link.exaggerate)
        self._restore = self.link if (self.link.scenario or self.link.params) else None
        self.drawing = None
        self.drawing_spec: str | None = None  # the scenario whose drawing is shown
        self.result = None
        self.good_values: dict[str, Any] | None = None
        self.playing = True
        self.clock = 0.0  # playback time as a fraction of the run, 0..1
        # the playback thread advances the clock while a browser's callback or a drawing thread
        # sets it: one lock, so that a scrub, a step or a link's time is never overwritten by an
        # advance that had read the clock before it
        self._clock_lock = threading.Lock()
        self._scrub_taken = 0.0  # the scrubber's update time when it last followed or set the clock
        self._scrub_moved = -1e9  # when a browser last moved the scrubber (perf_counter)
        self._linked_time = None  # a link's time, again on the full run after its quick preview
        self._view_lock = threading.RLock()  # the worker rebuilds while the player animates
        # a browser's own events, one at a time: viser runs each callback on its thread pool as it
        # comes, and twenty scene switches sent at once raced each other's panels (controls left
        # twice, or of another scenario)
        self._callback_lock = threading.RLock()
        # events waiting for the one before them to be handled, oldest first; a control's newer
        # value takes the place of its older one still waiting (`_browser_event`)
        self._waiting: OrderedDict = OrderedDict()
        self._waiting_lock = threading.Lock()
        self._handling = False  # a thread of viser's pool is handling this session's events
        self._closed = False
        self._settling: dict[str, threading.Timer] = {}  # a dragged slider's last value, when the drag pauses
        self._moved_at: dict[str, float] = {}  # when each slider last moved (perf_counter)
        self._link_sent = None
        self._defaults_of: dict[str, dict] = {}  # each scenario's default values (`_defaults`)
        self._saved_at, self._saved_upto = -1e9, -1  # the last page saved: when, and its last message
        self._preview_shown = False  # the run shown is a quick preview of a longer one
        self._link_time = 0.0
        self._class_key = None
        self.updates = 0  # scene rebuilds done (tests and bench read it)
        self._build_gui()
        page.set_loading(client, f"theoria — preparing {self.spec.title}…")
        self._add_keys()
        browser.run_js(client, browser.SETUP)
        self._set_title()
        if self.present:
            self._apply_present()
        self.worker = SimulationWorker(f"sim-{client.client_id}", self._apply, self._failed, self._show_progress)
        self._last_tick = None
        self._last_gui = 0.0
        playback.ticker().add(self)
        if unknown:
            self._notify_bad(ParameterError("scenario", unknown, "the name of one of the scenes (the list at the top "
                                                          f"of the panel); {self.spec.title} is shown"))
        for key, value, takes in self.link.dropped[:LINK_ERRORS_SHOWN]:
            self._notify_bad(ParameterError(key, value, takes), " (from the link: not used)")
        # what was not used beyond the notices shown: one count for the whole link, said last
        more = max(0, len(self.link.dropped) - LINK_ERRORS_SHOWN) + self.link.unread
        exag = self.link.exaggerate
        if exag is not None and not EXAGGERATE_RANGE[0] <= exag <= EXAGGERATE_RANGE[1]:
            self._notify_bad(ParameterError("exaggerate", exag, "allowed range [%g, %g]" % EXAGGERATE_RANGE),
                             " (from the link: the default is used)")
        speed = self._restore.speed if self._restore is not None else None
        if speed is not None and not self.speed.min <= speed <= self.speed.max:
            self._notify_bad(ParameterError("speed", speed, f"allowed range [{self.speed.min:g}, {self.speed.max:g}]"),
                             " (from the link: the default is used)")
            self._restore.speed = None
        if run is not None and run.scenario == self.spec.name:
            self.controls.set_values(run.params)
            self._apply(self.worker.adopt(self.spec, run.params), run, 0.0)
        elif self._restore is not None and self._restore.params:
            values, errors = linkmod.link_values(self.spec, self._restore)
            for e in errors[:LINK_ERRORS_SHOWN]:
                self._notify_bad(e, " (from the link: the default is used)")
            more += max(0, len(errors) - LINK_ERRORS_SHOWN)  # a link of thousands of keys: not thousands of notices
            self.controls.set_values(values)
            self._set_preset_for(values)
            self.request(values)
        else:
            self.request()
        if more:
            self.notify("Not allowed: more of the link", f"{more} more parts of the link were not used")

    # ---- GUI -------------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.client.gui
        client = self.client
        client.scene.set_up_direction("+z")
        configure_scene(client.scene)
        try:
            gui.configure_theme(control_width="large", show_share_button=False)
            gui.set_panel_label("theoria")
            # docked beside the scene, not floating over it: the canvas is only the part a class
            # sees, and in software WebGL a page with nothing over its canvas plays ~18 % faster
            gui.main_panel.dock_right()
        except AttributeError:  # a test's fake client
            pass
        order = gallery.ordered(self.scenarios.values())
        self._labels = {gallery.label(s): s.name for s in order}
        self.dd = gui.add_dropdown("Scene", list(self._labels), initial_value=gallery.label(self.spec),
                                   hint="Euler's ch. 15, ch. 16, then the three-body papers, in § order")
        self.dd.on_update(self._on(self._on_scenario))
        self.status = gui.add_markdown("*Computing the scene…*")
        self.progress = gui.add_progress_bar(0.0, visible=False, animated=True)
        # the update counter that protocol-level tools (benchmarks/classroom.py) follow; never shown
        self._tick_md = gui.add_markdown("*simulating…*", visible=False)
        self.tabs = gui.add_tab_group()
        if self.sweep is not None:  # the server was started for this map: its tab comes first
            with self.tabs.add_tab("Sweep"):
                self._build_sweep_tab()
        self._explore = self.tabs.add_tab("Explore")
        with self._explore:
            self.heading = gui.add_markdown(heading_markdown(self.spec))
            self.presets = gui.add_dropdown("Start from", self._preset_options(self.spec),
                                            initial_value=self._preset_options(self.spec)[0],
                                            hint="starting points named after what they show (keys 1–9)")
            self.presets.on_update(self._on(self._on_preset))
            self.playback = gui.add_button_group("Playback", [PAUSE, RESET, BACK, FORWARD],
                                                 hint="keys: space play/pause, ← → step")
            self.playback.on_click(self._clicked(self._on_playback))
            self.scrub = gui.add_slider("Time (% of the run)", min=0.0, max=100.0, step=0.1, initial_value=0.0)
            self._scrub_taken = getattr(self.scrub, "update_timestamp", 0.0)  # made, not moved by a browser
            self.scrub.on_update(self._on(self._on_scrub))
            on_typed(self.scrub, self._typed_into(self.scrub))
            self.time_md = gui.add_markdown("t = 0")
            self.speed = gui.add_slider(SPEED_LABEL, min=0.1, max=10.0, step=0.1, initial_value=1.0,
                                        hint=f"1 = the whole run in {RUN_SECONDS:g} s")
            self.speed.on_update(self._on(self._send_clock))
            on_typed(self.speed, self._typed_into(self.speed))
            self._controls_order = getattr(self.speed, "order", None)
            self.controls = self._make_controls_here()
            self.draw_folder = gui.add_folder("What is drawn", expand_by_default=False)
            with self.draw_folder:
                self.options_folder = gui.add_folder("This scene")
                self.toggles = {}
                for key, (label, _, _) in OVERLAYS.items():
                    cb = gui.add_checkbox(capitalised(label), initial_value=True)
                    cb.on_update(self._on(self._on_toggle, key))
                    self.toggles[key] = cb
                self.exag = gui.add_slider("Exaggerate the shape", min=EXAGGERATE_RANGE[0], max=EXAGGERATE_RANGE[1],
                                           step=0.5, initial_value=float(self.view_opts.exaggerate),
                                           hint="multiplies the departures of the semi-axes from their mean")
                self.exag.on_update(self._on(self._on_exaggerate))
                on_typed(self.exag, self._typed_into(self.exag))
            self._option_handles: list = []
            self._options_key = None
            self.plot_folder = gui.add_folder("Over time")
            self.plot = None
        with self.tabs.add_tab("Compare"):
            self.compare = gui.add_html(compare_html(None))
            # how the numbers were made: folded, so the table and its verdicts fit a screen
            with gui.add_folder("How these numbers were made", expand_by_default=False):
                self.notes_md = gui.add_markdown("")
            self.numbers_folder = gui.add_folder("All numbers of this run", expand_by_default=False)
            with self.numbers_folder:
                self.numbers = gui.add_markdown("")
        with self.tabs.add_tab("Read"):
            self.read = gui.add_markdown(read_markdown(self.spec))
            self.errata = gui.add_markdown("")
            with gui.add_folder("For the class"):
                self.present_cb = gui.add_checkbox("Presenter mode", initial_value=self.present,
                                                   hint="large type, controls hidden; keys: space, ← →, 1–9, P")
                self.present_cb.on_update(self._on(self._on_present_cb))
                self.save_btn = gui.add_button(SAVE_PAGE_LABEL, hint="a replay of this run, as shown, that plays in "
                                               "any browser without a network (the page theoria export writes)")
                self.save_btn.on_click(self._on(self._save_page, clicks=True))
                self.class_html = gui.add_html("")
                self.limits_md = gui.add_markdown(limits_text())
        # projected, the panel shows what the class reads: not the server's limits for the teacher
        self._present_hidden = [self.draw_folder, self.speed, self.scrub, self.limits_md, self.save_btn]

    def _make_controls(self) -> ParamControls:
        tab = getattr(self, "_explore", None)
        if tab is not None:
            with tab:
                return self._make_controls_here()
        return self._make_controls_here()

    def _make_controls_here(self) -> ParamControls:
        return ParamControls(self.client.gui, self.spec, on_change=self._on_param, wrap=self._on,
                             on_error=lambda e: self._notify_bad(e, " — keeping the last good value"),
                             order=self._controls_order)

    def _add_keys(self) -> None:
        """Keyboard for a projector (viser commands, also in the command palette)."""
        gui = self.client.gui
        keys = [("Play / pause", "space", self._toggle_play), ("Step back", "arrowleft", lambda: self._step(-1)),
                ("Step forward", "arrowright", lambda: self._step(1)),
                ("Presenter mode", "P", lambda: self._set_present(not self.present))]
        keys += [(f"Preset {k}", str(k), lambda k=k: self._preset_key(k)) for k in range(1, 10)]
        self._commands = []
        for label, key, fn in keys:
            try:
                cmd = gui.add_command(label, hotkey=key)
                cmd.on_trigger(self._on(fn, clicks=True))
                self._commands.append(cmd)
            except (AttributeError, TypeError, ValueError):  # a fake client, or a viser without commands
                return

    # ---- camera --------------------------------------------------------------------------------
    def _follow_camera(self) -> None:
        """Apply the drawing's moving camera (e.g. the Moon seen from the Earth) while it has one;
        give the drawing's own view back when it stops."""
        d = self.drawing
        follow = d.follow if d is not None else None
        cam = self.client.camera
        if follow is None:
            if getattr(self, "_following", False):
                self._following = False
                self._set_camera(d)
            return
        self._following = True
        if follow.fov_deg is not None and abs((getattr(cam, "fov", 0.0) or 0.0) - np.radians(follow.fov_deg)) > 1e-6:
            cam.fov = np.radians(follow.fov_deg)
        cam.up_direction = tuple(follow.up)
        cam.position = tuple(float(x) for x in follow.position[self.view.frame])
        cam.look_at = tuple(follow.look_at)

    def _set_camera(self, drawing) -> None:
        """The drawing's camera (the scenario's curated view, or the one an option asks for)."""
        if drawing is None:
            return
        c = drawing.camera
        cam = self.client.camera
        cam.up_direction = tuple(float(x) for x in c.up)
        cam.position = tuple(float(x) for x in c.position)
        cam.look_at = tuple(float(x) for x in c.look_at)
        fov = np.radians(c.fov_deg if c.fov_deg is not None else 75.0)  # viser's default is 75°
        if abs((getattr(cam, "fov", None) or 0.0) - fov) > 1e-6:
            try:
                cam.fov = float(fov)
            except Exception:
                pass
        self._camera_shown = c

    def _set_camera_from_link(self, c: tuple) -> None:
        cam = self.client.camera
        try:  # a camera viser does not take (up along the line of sight) leaves the scene's own
            if len(c) == 9:
                cam.up_direction = tuple(c[6:9])
            cam.position = tuple(c[0:3])
            cam.look_at = tuple(c[3:6])
        except (ValueError, AssertionError):
            pass

    # ---- presets -----------------------------------------------------------------------------
    @staticmethod
    def _preset_options(spec) -> list[str]:
        return gallery.preset_names(spec) + [gallery.CUSTOM]

    def _set_preset_for(self, values: dict) -> None:
        """Show the preset whose values these are, else "(your own values)"."""
        name = gallery.CUSTOM
        for n in self.spec.presets:
            try:
                if self.spec.preset(n) == values:
                    name = n
                    break
            except ParameterError:
                continue
        self._pguard = True
        try:
            self.presets.value = name
        finally:
            self._pguard = False

    def _on_preset(self) -> None:
        """A preset chosen: its values (validated by Scenario.resolve) go into the controls and
        are simulated at once."""
        if self._pguard or self.presets.value == gallery.CUSTOM:
            return
        try:
            values = self.spec.preset(self.presets.value)
        except ParameterError as e:  # not one of the list's presets (only a hand-made message sends that)
            self._notify_bad(e)
            self._pguard = True
            try:
                self.presets.value = gallery.CUSTOM
            finally:
                self._pguard = False
            return
        self._pguard = True
        try:
            self.controls.set_values(values)
        finally:
            self._pguard = False
        self.request(dict(values))

    def _preset_key(self, k: int) -> None:
        names = gallery.preset_names(self.spec)
        if 1 <= k <= len(names):
            self.presets.value = names[k - 1]

    def _on_param(self, name: str, debounce: bool = False) -> None:
        """A parameter moved by hand: the preset no longer describes the values."""
        if self._pguard:
            return
        if self.presets.value != gallery.CUSTOM:
            self._pguard = True
            try:
                self.presets.value = gallery.CUSTOM
            finally:
                self._pguard = False
        if debounce and self._settles("parameters", self.request):
            return
        self._unsettle("parameters")  # a typed value runs at once, with the values of every control
        self.request()

    def _settles(self, key: str, fn) -> bool:
        """A slider being dragged (moves closer than SLIDER_DEBOUNCE_S): its first value was taken
        at once; the values in between are dropped and `fn` runs for the last one when the drag
        pauses (the last value wins, nothing queues). True when this move waits."""
        self._unsettle(key)
        now = time.perf_counter()
        dragged = now - self._moved_at.get(key, -1e9) < SLIDER_DEBOUNCE_S
        self._moved_at[key] = now
        if dragged:
            timer = threading.Timer(SLIDER_DEBOUNCE_S, lambda: self._browser_event(fn, key=("settled", key)))
            timer.daemon = True
            self._settling[key] = timer
            timer.start()
        return dragged

    def _unsettle(self, key: str) -> None:
        timer = self._settling.pop(key, None)
        if timer is not None:
            timer.cancel()

    # ---- messages ----------------------------------------------------------------------------
    def _save_page(self) -> None:
        """The scene shown, as a standalone web page, downloaded by this browser."""
        from .export_html import render_html
        from .server import gate_of  # (the server module imports this one)

        d, result = self.drawing, self.result
        if d is None or result is None or self.drawing_spec != self.spec.name:
            self.notify("Nothing to save yet", "The scene is still being computed.", color="yellow")
            return
        gate = gate_of(self.server, self.client.client_id)
        if (time.monotonic() - self._saved_at < SAVE_PAGE_EVERY_S
                or (gate is not None and gate.sent() < self._saved_upto)):
            self.notify("Not saved again yet", "The page saved a moment ago is still on its way: try again in a few "
                        "seconds.", color="yellow")
            return
        if not SAVE_PAGES_AT_ONCE.acquire(blocking=False):
            self.notify("Not saved", "Other pages are being made for the class: try again in a moment.", color="yellow")
            return
        try:
            page = render_html(d, result).encode("utf-8")
        finally:
            SAVE_PAGES_AT_ONCE.release()
        name = f"theoria-{self.spec.name}.html"
        try:
            self.client.send_file_download(name, page, save_immediately=True)  # one click saves it
        except Exception:  # the tab closed meanwhile
            return
        self._saved_at = time.monotonic()
        self._saved_upto = gate.pushed() if gate is not None else -1
        self.notify("Saved", f"{name} ({human_size(len(page))}): it plays in any browser, without a network.",
                    color="green")

    def notify(self, title: str, body: str, color: str = "red") -> None:
        try:
            self.client.add_notification(title, body, auto_close_seconds=8.0, color=color)
        except Exception:
            pass

    def _words_for(self, e: ParameterError, spec=None) -> tuple[str, str]:
        """(the control's name in words, what is allowed) for a refused value."""
        spec = spec or self.spec
        # the limits are the server's, set by whoever started it: no keyword or flag to a class
        allowed = re.sub(r" \((?:max_steps, --max-steps|max_memory, --max-memory)\)", " set for this server",
                         str(e.allowed))
        for q in sorted(spec.params, key=lambda q: -len(q.name)):  # a key in a formula: its words
            title = q.title()
            allowed = re.sub(rf"\b{re.escape(q.name)}\b" + ("" if "_" in q.name else r"(?=\s*[=≤≥<>+])"),
                             lambda m: title, allowed)
        try:
            p = spec.param(e.name)
            who = p.display()
            if p.unit:
                allowed = allowed.replace(f" {p.unit}", f" {p.unit_text()}" if p.unit_text() else "")
        except KeyError:
            who = {"parameters": "These values", "preset": "Preset", "scenario": "Scene",
                   "speed": "Playback speed", "exaggerate": "Exaggerate the shape", "exag": "Exaggerate the shape",
                   "cam": "Camera", "t": "Time", "play": "Playing"}.get(e.name, e.name)
        return who, readable(allowed)

    def _notify_bad(self, e: ParameterError, tail: str = "", spec=None) -> None:
        who, allowed = self._words_for(e, spec)
        shown = show_value(e.value)  # what was typed, when it was text
        if isinstance(e.value, (int, float)) and not isinstance(e.value, bool):
            try:  # a number as its field shows it (1000000, not 1e+06)
                shown = show_value(format_value((spec or self.spec).param(e.name), e.value))
            except (KeyError, TypeError, ValueError, ArithmeticError):
                pass
        self.notify(f"Not allowed: {who}", f"“{shown}”: {allowed}{tail}")

    def _restore_control(self, name: str) -> bool:
        """A refused value leaves its control: it shows the value of the last good run again (or
        the scenario's default before any), so the next change of another control is not refused
        for it. True when the control's value changed."""
        if name not in self.controls.handles:
            return False
        good = self.good_values if self.good_values is not None and self.drawing_spec == self.spec.name \
            else self.spec.resolve(None)
        if name not in good:
            return False
        before = self.controls.values().get(name)
        self.controls.set_values({name: good[name]})
        return self.controls.values().get(name) != before

    def _on(self, fn, *args, clicks: bool = False):
        """A callback for viser's on_update (or, `clicks`, on_click / on_trigger): `fn(*args)`
        through `_safe`. A browser's own events (the event names its client) run one at a time per
        session; a control's value is read when its event is handled, so a newer value replaces
        its event still waiting (a click is never dropped: two Steps are two). A value the server
        sets itself calls the callback at once on the setting thread (no client): not queued
        behind a browser's event, which may be waiting for the view lock that thread holds."""
        def callback(event):
            if getattr(event, "client", None) is None:
                self._safe(fn, *args)
            else:
                self._browser_event(fn, *args, key=None if clicks else callback)
        return callback

    def _typed_into(self, handle):
        """What a browser typed into the box of one of the app's own sliders: checked against the
        slider's range (refused with it, named), then set as the slider's value, whose callback
        acts as for a move of the slider."""
        param = number_param(handle)

        def take(text: str) -> None:
            handle.value = param.parse(str(text).strip())

        return lambda typed: self._browser_event(take, typed.text, key=take)

    def _clicked(self, fn):
        """A button group's click: `fn(button clicked)`. viser sets the group's value to the button
        and then runs its callbacks on its pool; read there, two clicks close together (Pause, then
        a step, while a drawing held the session) both read the second: two steps while the run
        played on. A callback that is a coroutine runs in viser's loop as the click arrives: the
        button is read then, and the click joins the session's line in the order the clicks came."""
        async def clicked(event):
            button = event.target.value
            if getattr(event, "client", None) is None:
                self._safe(fn, button)
            elif self._enqueue(fn, (button,), None):
                try:
                    self.client.gui._thread_executor.submit(self._drain).add_done_callback(self._drained)
                except RuntimeError:  # the server is stopping: its pool takes nothing more
                    with self._waiting_lock:
                        self._handling = False
        return clicked

    def _browser_event(self, fn, *args, key=None) -> None:
        """`fn(*args)` for something the browser did, after its earlier events are handled. An
        event with a `key` (a control's new value) replaces one with the same key still waiting:
        a browser sending values faster than they are drawn makes the server draw the newest, not
        every one in turn. One thread of viser's pool handles a session's events in order while
        the others return at once (a pool thread waiting for a busy session is one fewer for every
        other student)."""
        if self._enqueue(fn, args, key):
            self._drain()

    def _enqueue(self, fn, args, key) -> bool:
        """Put an event in the session's line; True when no thread is handling the line (the
        caller is to `_drain` it)."""
        self._linked_time = None  # the view is the browser's now, not the link's
        with self._waiting_lock:
            if self._closed:
                return False
            if key is not None:  # the newer value goes where the user's latest action is: last
                self._waiting.pop(key, None)
            self._waiting[key if key is not None else object()] = (fn, args)
            if self._handling:
                return False
            self._handling = True
            return True

    def _drain(self) -> None:
        """Handle the session's waiting events in order until none is left. An error that gets
        past a callback's own guard is logged and the line goes on: the events behind it (a
        slider's last value) are still handled."""
        while True:
            with self._waiting_lock:
                if not self._waiting or self._closed:
                    self._waiting.clear()
                    self._handling = False
                    return
                _, (fn, args) = self._waiting.popitem(last=False)
            try:
                with self._callback_lock:
                    if not self._closed:
                        self._safe(fn, *args)
            except Exception as e:
                self._log_error(e)
            except BaseException:  # never leave the session's line without a thread to handle it
                with self._waiting_lock:
                    self._handling = False
                raise

    def _drained(self, future) -> None:
        e = None if future.cancelled() else future.exception()
        if e is not None:
            self._log_error(e)

    def _log_error(self, e: BaseException) -> None:
        self.worker.pool.logger.line("theoria: error in a browser's callback:\n" + "".join(
            traceback.format_exception(type(e), e, e.__traceback__)), once_key=("callback", type(e).__name__, _where(e)))

    def _safe(self, fn, *args) -> None:
        """Run a callback (playback giving way meanwhile); no exception reaches viser's loop, and
        nothing a browser sends writes more than the rate-limited log's lines to the console.
        Not under the browser's event lock: a drawing thread sets the scrubber while it holds the
        view lock, and the callback viser runs at once for it waited for a browser's event that
        waited for the view lock (every drawing thread of the server stuck, every class frozen)."""
        try:
            with playback.showing():
                fn(*args)
        except ParameterError as e:
            self._notify_bad(e)
            self._restore_control(e.name)
        except Exception as e:  # a bug in a scenario or the scene must not kill the server
            self._log_error(e)
            self.notify("Something went wrong", f"{type(e).__name__}; the scene keeps its last good state")

    def _set_title(self) -> None:
        browser.call(self.client, "title", f"theoria — {self.spec.name}")

    # ---- scenario ------------------------------------------------------------------------------
    def _on_scenario(self) -> None:
        name = self._labels.get(self.dd.value)
        if name is None:  # not one of the dropdown's scenes (only a hand-made message sends that)
            shown = gallery.label(self.spec)
            self._notify_bad(ParameterError("scenario", self.dd.value, "one of the scenes in the list"))
            self._guard = True
            try:
                self.dd.value = shown
            finally:
                self._guard = False
            return
        if name == self.spec.name:
            return
        self._switch_scenario(name)
        self.request()

    def _switch_scenario(self, name: str) -> None:
        """The panel for scenario `name` (its controls, presets, texts); the caller requests a run."""
        self.spec = self.scenarios[name]
        label = gallery.label(self.spec)
        if self.dd.value != label:
            self.dd.value = label  # its callback sees the scenario already switched
        self.controls.remove()
        self.controls = self._make_controls()
        if self.present:
            self.controls.set_hidden(True)
        self._pguard = True
        try:
            options = self._preset_options(self.spec)
            self.presets.options = options
            self.presets.value = options[0]
        finally:
            self._pguard = False
        self.heading.content = heading_markdown(self.spec)
        self.read.content = read_markdown(self.spec)
        self.errata.content = ""
        self._set_title()
        self.good_values = None
        self.view_opts = View(exaggerate=self.view_opts.exaggerate, text_scale=self.view_opts.text_scale)
        self._restore = None
        # until its run is drawn, nothing of the scene before reads as this one's: its numbers, its
        # clock and its plot are taken down, its bodies hidden (on a loaded machine a class read
        # the Moon's DE421 table and "t = 176 of 365.2 days" under "Hyperion" for seconds)
        self.compare.content = compare_html(None)
        self.time_md.content = f"*computing {self.spec.title}…*"
        self._hide_previous_scene(True)

    def _hide_previous_scene(self, hide: bool) -> None:
        """The bodies and the plot of the scene shown, hidden (or shown again once this scenario's
        own run is drawn)."""
        for h in (self._world, self.plot):
            if h is not None and h.visible == hide:
                try:
                    h.visible = not hide
                except Exception:  # the tab closed meanwhile
                    pass

    # ---- the sweep's map ------------------------------------------------------------------------
    def _build_sweep_tab(self) -> None:
        """The Sweep tab: the map of one metric over two swept parameters, what it shows, and which
        run the scene replays. Rendering happens on the map's own thread (SweepMaps)."""
        gui, sw = self.client.gui, self.sweep
        sizes = " × ".join(str(sw.ds.sizes[d]) for d in sw.dims)
        about = sw.preset.description if sw.preset is not None else ""
        self.sweep_head = gui.add_markdown(
            f"**Map: {_md(sw.title())}** — {sizes} = {sw.ds['status'].size} runs. "
            "**Click a pixel** to replay that run in the scene.")
        self.sweep_map = gui.add_html("<p><i>Drawing the map…</i></p>")
        self.sweep_shown = gui.add_markdown("")
        self._metric_labels: dict[str, str] = {}
        for m in sw.metrics:
            label = sw.metric_text(m)
            self._metric_labels[label if label not in self._metric_labels else f"{label} [{m}]"] = m
        first = next(iter(self._metric_labels))
        self.sweep_metric = gui.add_dropdown("Colour shows", list(self._metric_labels), initial_value=first)
        views = [lab for lab, _ in sw.views(self._metric_labels[first])]
        self.sweep_view = gui.add_dropdown("Summary", views, initial_value=sw.default_view(self._metric_labels[first]),
                                           hint="a dimension that is not on the map is summarised")
        self.sweep_view.visible = len(views) > 1
        # a click on the map sets this hidden field ("row,column,view,count": the page's script)
        self.sweep_pixel = gui.add_text("Run on the map", initial_value="", visible=False)
        if about:
            gui.add_markdown(f"*{_md(about)}*")
        self._sweep_pic = None
        self._sweep_mark: dict | None = None  # the values of the run shown (its pixel is marked)
        self._sweep_want: tuple[str, str] | None = None
        self.sweep_metric.on_update(self._on(self._on_sweep_metric))
        self.sweep_view.on_update(self._on(self._on_sweep_view))
        self.sweep_pixel.on_update(self._on(self._on_sweep_click))
        self._show_map()

    def _on_sweep_metric(self) -> None:
        if self._sguard:
            return
        metric = self._metric_labels[self.sweep_metric.value]
        views = [lab for lab, _ in self.sweep.views(metric)]
        keep = self.sweep_view.value if self.sweep_view.value in views else self.sweep.default_view(metric)
        self._sguard = True
        try:
            self.sweep_view.options = views
            self.sweep_view.value = keep
            self.sweep_view.visible = len(views) > 1
        finally:
            self._sguard = False
        self._show_map()

    def _on_sweep_view(self) -> None:
        if not self._sguard:
            self._show_map()

    def _show_map(self) -> None:
        """Post the chosen view's rendering (cached after the first time); it is shown when ready."""
        want = (self._metric_labels[self.sweep_metric.value], self.sweep_view.value)
        self._sweep_want = want
        fut = self.sweep.picture_async(*want)
        fut.add_done_callback(lambda f: self._browser_event(self._map_ready, f, want))

    def _map_ready(self, fut, want) -> None:
        if want != self._sweep_want or self._closed:
            return  # another view was chosen meanwhile
        pic = fut.result()
        self._sweep_pic = pic
        self._draw_map()

    def _draw_map(self) -> None:
        from .sweep_map import map_html

        pic = self._sweep_pic
        if pic is None:
            return
        self.sweep_map.content = map_html(self.sweep, pic, self.sweep_pixel._impl.uuid, self._mark_in(pic))

    def _mark_in(self, pic) -> tuple[int, int] | None:
        """The pixel of `pic` that holds the run shown in the scene (if it is on this map)."""
        v = self._sweep_mark
        if v is None:
            return None
        m = pic.map

        def index(values, x):
            hits = np.flatnonzero(np.asarray(values) == x)
            return int(hits[0]) if hits.size else None

        j = index(m.x_values, v.get(m.x))
        i = index(m.y_values, v.get(m.y)) if m.y else 0
        return None if i is None or j is None else (i, j)

    def _on_sweep_click(self) -> None:
        from .sweep_map import parse_click

        pic = self._sweep_pic
        ij = parse_click(self.sweep_pixel.value, pic) if pic is not None else None
        if ij is not None:
            self.replay_pixel(*ij)

    def replay_pixel(self, i: int, j: int) -> dict:
        """Replay the run at row i, column j of the map shown: the sweep's scenario with that run's
        full parameters, through the worker like any other change. Returns the values."""
        pic = self._sweep_pic
        values = pic.map.run_values(i, j)
        name = pic.map.scenario
        if name != self.spec.name:
            self._switch_scenario(name)
        self.controls.set_values(values)
        self._set_preset_for(values)
        self._sweep_mark = values
        self.sweep_shown.content = f"**In the scene:** {_md(self.sweep.pixel_words(pic, i, j))}"
        self._draw_map()
        self.request(dict(values))
        return values

    # ---- playback controls -----------------------------------------------------------------------
    def _on_playback(self, which: str) -> None:
        if self._guard:
            return
        if which in (PLAY, PAUSE):
            self._toggle_play()
        elif which == RESET:
            self._reset()
        elif which == BACK:
            self._step(-1)
        elif which == FORWARD:
            self._step(1)

    def _set_playing(self, on: bool) -> None:
        was = self.playing
        self._advance()
        self.playing = bool(on)
        self._guard = True
        try:
            self.playback.options = [PAUSE if self.playing else PLAY, RESET, BACK, FORWARD]
        except Exception:
            pass
        finally:
            self._guard = False
        if was and not self.playing:  # the frame the page stopped at, set by the server too
            self._show_clock(force=True)
            self._time_gui()
        self._send_clock()

    def _toggle_play(self) -> None:
        self._set_playing(not self.playing)

    def _reset(self) -> None:
        """The clock back to the start of the run, playing or paused."""
        self._set_clock(0.0)
        self._show_clock(force=True)
        self._time_gui()
        self._send_clock()

    def _step(self, sign: int) -> None:
        """Pause and move the clock by STEP_FRACTION of the run (at least one frame)."""
        self._set_playing(False)
        n = self.drawing.n_frames if self.drawing is not None else 100
        step = max(STEP_FRACTION, 1.0 / max(n - 1, 1))
        self._set_clock(self.clock + sign * step)
        self._show_clock(force=True)
        self._time_gui()
        self._send_clock()

    def _on_scrub(self) -> None:
        if self._guard:
            return
        self._scrub_taken = getattr(self.scrub, "update_timestamp", 0.0)
        self._scrub_moved = time.perf_counter()
        self._set_clock(float(self.scrub.value) / 100.0)
        self._show_clock()
        self._time_gui(scrub=False)
        self._send_clock()

    def _on_exaggerate(self) -> None:
        """Each new exaggeration is a new drawing of the run: dragged, the slider's last value is drawn."""
        if self.result is None or self._settles("exaggerate", self._exaggerate):
            return
        self._exaggerate()

    def _exaggerate(self) -> None:
        if self.result is not None:
            self.view_opts.exaggerate = float(self.exag.value)
            self._redraw()

    def _on_toggle(self, key: str) -> None:
        if self._guard:
            return
        with self._view_lock, self.client.atomic():
            self.view.set_overlay(key, self.toggles[key].value)
            self._send_tracks()  # a group switched on for the first time brings new nodes

    # ---- presenter mode ------------------------------------------------------------------------
    def _on_present_cb(self) -> None:
        if not self._guard:
            self._set_present(bool(self.present_cb.value))

    def _set_present(self, on: bool) -> None:
        if on == self.present:
            return
        self.present = on
        self._guard = True
        try:
            self.present_cb.value = on
        finally:
            self._guard = False
        self._apply_present()
        if self.result is not None:
            self._redraw()

    def _apply_present(self) -> None:
        """Presenter mode: large type in the panel and the scene, controls hidden (the keys play,
        step and pick presets)."""
        for h in self._present_hidden:
            try:
                h.visible = not self.present
            except Exception:
                pass
        self._show_class_link()
        self.controls.set_hidden(self.present)
        self.view.label_scale = PRESENT_LABEL_SCALE if self.present else 1.0
        # the scene grows with the screen's rows, the labels by their scale: kept apart at that size
        self.view_opts.text_scale = PRESENT_LABEL_SCALE * APP_ROWS / PRESENT_ROWS if self.present else 1.0
        try:  # the docked panel widens by the scale its type grows by (app/browser.py `present`)
            self.client.gui.main_panel.set_width(PANEL_PX * (PRESENT_PANEL_SCALE if self.present else 1.0))
        except AttributeError:  # a test's fake client
            pass
        browser.call(self.client, "present", self.present, PRESENT_PANEL_SCALE)

    # ---- simulation worker -----------------------------------------------------------------
    def request(self, given: dict | None = None) -> None:
        """Post (scenario, values) for simulation; only the newest request is kept."""
        given = self.controls.values() if given is None else given
        self._status("Computing the scene…")
        self._tick_text(f"*simulating {self.spec.title}…*")
        self.worker.submit(self.spec, given)

    @property
    def timing(self) -> dict[str, float]:
        """perf_counter stamps of the last request: request, start, simulated, shown (bench, tests)."""
        req = self.worker.last
        return req.stamps if req is not None else {}

    def _failed(self, req, e: Exception) -> None:
        name = req.spec.name
        if self.updates == 0:  # nothing drawn: the panel (with the error) replaces the loading line
            page.set_loading(self.client, None)
        if isinstance(e, ParameterError):
            who, allowed = self._words_for(e, req.spec)
            if req.spec.name == self.spec.name and self.drawing_spec != self.spec.name \
                    and self._restore_control(e.name):
                # nothing of this scene shown yet (a link's values that pass one by one and together
                # go over the budget): it is drawn with that value at its default
                self._notify_bad(e, " — drawn with its default value", spec=req.spec)
                self._status(f"Not allowed: {who} ({allowed}); drawn with its default value.")
                self.request()
                return
            self._notify_bad(e, " — keeping the last good state", spec=req.spec)
            if req.spec.name == self.spec.name and self._restore_control(e.name):
                self._set_preset_for(self.controls.values())  # back to the preset's values: its name again
            self._status(f"Not allowed: {who} ({allowed}); the scene shows the last good values.")
        else:
            self.notify(f"Error in {req.spec.title}", f"{type(e).__name__}: {e} — keeping the last good state")
            self._status(f"Error: {type(e).__name__}; the scene shows the last good values.")
        self._tick_text(f"*simulation failed: {name}*")

    def _show_progress(self, pct: float | None, text: str | None = None) -> None:
        """Progress of a long run in the panel (None hides the bar)."""
        try:
            if pct is None:
                self.progress.visible = False
                return
            self.progress.value = pct
            if not self.progress.visible:
                self.progress.visible = True
            self._status(capitalised(text) if text else f"Computing the scene… {pct:.0f} %")
            if self.updates == 0:  # nothing drawn yet: the line over the page says what is happening
                page.set_loading(self.client, "theoria — " + (text or f"computing the scene… {pct:.0f} %"))
        except Exception:
            pass

    def _status(self, text: str) -> None:
        try:
            self.status.content = f"*{text}*" if text else ""
        except Exception:
            pass

    def _tick_text(self, text: str) -> None:
        try:
            self._tick_md.content = text
        except Exception:
            pass

    def _restore_view(self, restore, drawing) -> None:
        """A link's playing, time, speed and camera on the run just drawn."""
        # playing first: pausing brings a playing clock up to now, which moved a restored time on
        # by the time since the last tick (one frame, now and then)
        self._set_playing(restore.playing)
        if restore.time is not None and drawing.n_frames > 1:
            self._set_clock_at(restore.time, drawing)
        if restore.speed is not None:
            self.speed.value = float(restore.speed)
        if restore.camera is not None:
            self._set_camera_from_link(restore.camera)

    def _apply(self, req, result, t_sim: float) -> None:
        """Show a finished run (the worker's thread): its drawing, table, plot and status."""
        spec, values = req.spec, req.values
        req.stamps["drawing"] = time.perf_counter()
        with self._view_lock, self.client.atomic():
            if not self.worker.current(req) or spec.name != self.spec.name:
                return  # a newer request, or another scenario chosen meanwhile
            restore = self._restore if (self._restore is not None and
                                        self._restore.scenario in (None, spec.name)) else None
            drawing = drawing_of(spec, result, self.view_opts)
            new_scenario = self.drawing_spec != spec.name
            if new_scenario:  # the scenario's own overlay defaults and camera
                overlays = dict(drawing.overlays)
                if restore is not None:
                    overlays.update({k: v for k, v in restore.overlays.items() if k in self.toggles})
                for k, cb in self.toggles.items():
                    self._guard = True
                    try:
                        cb.value = overlays.get(k, True)
                    finally:
                        self._guard = False
                self._offer_toggles(drawing)
            else:
                overlays = {k: bool(cb.value) for k, cb in self.toggles.items()}
            self.view.show(drawing, overlays)
            old = self.drawing
            self.drawing, self.drawing_spec = drawing, spec.name
            if new_scenario or old is None or old.camera != drawing.camera:
                self._set_camera(drawing)
            self._sync_scene_options()
            self.result, self.good_values = result, values
            preview = self._preview_shown = bool(getattr(req, "preview", False))
            self._show_result_text(result, preview)
            self._update_plot(result)
            self._hide_previous_scene(False)
            if restore is not None:
                self._restore = None
                self._restore_view(restore, drawing)
                # a quick preview's frames are not the full run's: the link's time once more on it
                self._linked_time = restore.time if preview else None
                if not preview and restore.time is not None:
                    self._say_if_outside(restore.time, drawing)
            elif self._linked_time is not None and not preview and drawing.n_frames > 1:
                linked, self._linked_time = self._linked_time, None
                self._set_clock_at(linked, drawing)
                self._say_if_outside(linked, drawing)
            self.view.set_frame(self._frame_index())
            self._follow_camera()
            self._time_gui()
            self._send_tracks()
            req.stamps["shown"] = time.perf_counter()
            timing_log(spec.name, req, self.worker.pool)
            if self.updates == 0:
                page.set_loading(self.client, None)
            self.updates += 1
            warn = result.warnings
            self._status("⚠ This run comes with a note: see the Compare tab." if warn else "")
            if getattr(req, "preview", False):
                self._status("Quick preview; computing the full run…")
                self._tick_text(f"*quick preview ({len(result.trajectory.t)} samples); computing the full run… "
                                f"(update #{self.updates})*")
            else:
                self._tick_text(f"*simulated {len(result.trajectory.t)} samples in {1000 * t_sim:.0f} ms "
                                f"(update #{self.updates})*")

    def _show_result_text(self, result, preview: bool = False) -> None:
        self.compare.content = compare_html(result, preview)
        errata, other = split_notes(result.notes)
        self.notes_md.content = "\n\n".join(f"*{_md(readable(n))}*" for n in other if n not in result.warnings)
        self.errata.content = ("**Where the printed text is wrong**\n\n" + "\n\n".join(f"- {_md(readable(n))}" for n in errata)
                               if errata else "")
        self.numbers.content = numbers_markdown(result)

    def _redraw(self) -> None:
        """The same run drawn again (a scene option, the shape exaggeration or presenter mode changed)."""
        if self.result is None:
            return
        with self._view_lock, self.client.atomic():
            old = self.drawing
            self.drawing = drawing_of(self.spec, self.result, self.view_opts)
            self.view.show(self.drawing, {k: bool(cb.value) for k, cb in self.toggles.items()})
            self._offer_toggles(self.drawing)
            if old is None or old.camera != self.drawing.camera:
                self._set_camera(self.drawing)
            self._update_plot()
            self.view.set_frame(self._frame_index())
            self._follow_camera()
            self._send_tracks()

    def _offer_toggles(self, drawing) -> None:
        """Only the overlays this drawing has are offered (a three-body scene has no principal axes,
        polhode or body shape)."""
        groups = {it.group for it in drawing.items}
        for k, cb in self.toggles.items():
            if cb.visible != (k in groups):
                cb.visible = k in groups
        if self.exag.visible != drawing.rotation:  # no body's shape to exaggerate
            self.exag.visible = drawing.rotation

    def _sync_scene_options(self) -> None:
        """Checkboxes for the scenario's own options (Scenario.options)."""
        spec = self.spec
        if spec.name == self._options_key:
            return
        self._options_key = spec.name
        for h in self._option_handles:
            h.remove()
        self._option_handles = []
        with self.options_folder:
            for k, opt in spec.options.items():
                label = capitalised(opt.label)
                cb = self.client.gui.add_checkbox(label, initial_value=self.view_opts.option(k, spec))
                cb.on_update(self._on(self._on_option, k, cb))
                self._option_handles.append(cb)
        try:
            self.options_folder.visible = bool(spec.options)
        except Exception:
            pass

    def _on_option(self, key: str, cb) -> None:
        self.view_opts.options[key] = bool(cb.value)
        self._redraw()

    def _update_plot(self, result=None) -> None:
        d = self.drawing
        t = d.plot_t
        series = dict(d.plot) or {"energy": self.result.trajectory.energy}
        idx = np.unique(np.linspace(0, len(t) - 1, min(UPLOT_POINTS, len(t))).round().astype(int))
        c = d.clock
        x, words = time_axis(np.asarray(t)[idx] * c.scale, c.words)
        ys, e = value_axis([np.asarray(v, float)[idx] for v in series.values()])
        data = (x,) + tuple(ys)
        ser = ({"label": f"{c.name} ({words})" if words else c.name},) + tuple(
            {"label": series_label(k), "stroke": "rgb(%d,%d,%d)" % palette(i), "width": 1.5}
            for i, k in enumerate(series))
        key = tuple(s["label"] for s in ser)
        axes = ({}, {"size": y_axis_px(data[1:])})  # the default 50 px cut "-" and leading digits off
        if e:  # the values' power of ten, beside the axis
            axes[1].update(label=f"×10{superscript(e)}", labelSize=18)
        if self.plot is not None and getattr(self, "_plot_key", None) == key:
            self.plot.data = data  # same series: update in place
            self.plot.axes = axes
            return
        self._plot_key = key
        if self.plot is not None:
            self.plot.remove()
        with self.plot_folder:
            # x is the simulation time, not a date (uPlot's default x scale is a clock); the legend
            # names the curves without values ("--" beside each name until the pointer is on the plot)
            # the top tick's label and the last time's sit half outside the plot: room for them
            self.plot = self.client.gui.add_uplot(data, ser, aspect=1.6, scales={"x": {"time": False}}, axes=axes,
                                                  legend={"live": False}, padding=(10, 16, 0, 0))

    # ---- playback ----------------------------------------------------------------------------
    def _frame_index(self) -> int:
        if self.drawing is None:
            return 0
        d = self.drawing
        if d.pace is not None:
            p = d.pace
            return min(max(int(p.searchsorted(self.clock - 1e-9)), 0), len(p) - 1)
        t = d.times  # called for every playback tick of every browser: no numpy wrappers
        span = t[-1] - t[0]
        # the first frame at the clock's time, rounding forgiven: a link's t = 3.77 came back as
        # 3.7700000000000005 through the clock's fraction and showed the frame of 3.78
        target = t[0] + self.clock * span - 1e-9 * span
        return min(max(int(t.searchsorted(target)), 0), len(t) - 1)

    def _show_clock(self, force: bool = False) -> None:
        if self.result is None:
            return
        i = self._frame_index()
        if force or i != self.view.frame:
            with self._view_lock, self.client.atomic():
                self.view.set_frame(i, force=force, moving=self.playing)
                self._follow_camera()

    def wants_ticks(self) -> bool:
        """Playing a finished run, or the address bar due to follow the view (the playback thread
        skips a session with nothing to do)."""
        if self._closed:
            return False
        now = time.perf_counter()
        if not (self.playing and self.result is not None):
            self._last_tick = None
            return now - self._link_time > LINK_EVERY_S
        return True

    def _tick(self, now: float) -> None:
        """One frame of playback (called by app/playback.py's thread): the clock advances by the
        real time since the last frame, so fewer frames a second never slow the run down. The
        address bar follows the view at most every LINK_EVERY_S (1 s while playing)."""
        if self._closed:
            return
        if self.playing and self.result is not None:
            if self._advance(now):
                alone = self.tick_hz() < playback.PLAY_HZ  # the page moves everything shown
                if not alone:
                    self._show_clock()
                if now - self._last_gui > CLOCK_TEXT_EVERY:
                    self._last_gui = now
                    follow = now - self._scrub_moved > SCRUB_HOLD_S  # no hand on the scrubber
                    if alone:  # the read-out at the page's frame, one batch (one wake-up of the sender)
                        self.view.frame = self._frame_index()
                        with self._view_lock, self.client.atomic():
                            self._time_gui(scrub=follow)
                    else:
                        self._time_gui(scrub=follow)
        if now - self._link_time > (1.0 if self.playing else LINK_EVERY_S):
            self._link_time = now
            self._sync_link()

    def _advance(self, now: float | None = None) -> bool:
        """Bring the clock to `now`: while playing it runs at real time × speed. False when the
        clock only starts now."""
        now = time.perf_counter() if now is None else now
        with self._clock_lock:
            if not (self.playing and self.result is not None):
                self._last_tick = None
                return False
            last = self._last_tick
            if last is None:
                self._last_tick = now
                return False
            # a time read on another thread before the last one (a pause, a tick's pass begun
            # meanwhile) moves nothing: the clock of a playing run never runs backward
            self._last_tick = max(last, now)
            self.clock = (self.clock + max(0.0, now - last) * float(self.speed.value) / RUN_SECONDS) % 1.0
        return True

    def _set_clock(self, fraction: float) -> None:
        """Put the clock at `fraction` of the run; a playing clock runs on from there."""
        with self._clock_lock:
            self.clock = float(np.clip(fraction, 0.0, 1.0))
            self._last_tick = None

    def _say_if_outside(self, t: float, drawing) -> None:
        """A link's time outside the run (t=999 of a 30-s run, t=-5) is shown at the run's end or
        start, and the class is told so."""
        t0, t1 = float(drawing.times[0]), float(drawing.times[-1])
        if t0 - 1e-9 * abs(t1 - t0) <= t <= t1 + 1e-9 * abs(t1 - t0):
            return
        c = drawing.clock
        where = "its end" if t > t1 else "its start"
        span = f"{c.name} = {human_number(t0 * c.scale)} to {human_number(t1 * c.scale)}{' ' + c.words if c.words else ''}"
        self.notify("Not allowed: Time", f"“{show_value(t)}”: outside the run ({span}); from the link: {where} is shown")

    def _set_clock_at(self, t: float, drawing) -> None:
        """Put the clock at time `t` of `drawing` (in its time unit)."""
        self._set_clock(drawing.pace_at(t))

    def tick_hz(self) -> float:
        """At most this many playback ticks a second: a page that plays by itself needs the server
        only for the time read-out, unless the scene has something only the server can move."""
        follows = self.drawing is not None and self.drawing.follow is not None  # a camera the server moves
        return playback.PLAY_HZ if (self._server_moves or follows or not self.page_plays) else PAGE_TICK_HZ

    def _send_tracks(self) -> None:
        """The scene's moving parts, for a page that plays by itself, then its clock."""
        self._server_moves = self.view.server_moves()
        if self.page_plays:
            browser.call_json(self.client, "tracks", self.view.tracks_json())
            self._send_clock()

    def _send_clock(self) -> None:
        """The playback clock, for the page: where it stands (0..1 of the run, and the frame shown),
        how fast it runs and whether it runs; the page extrapolates from the moment it arrives."""
        if not self.page_plays:
            return
        self._advance()
        browser.call(self.client, "clock", {
            "clock": float(self.clock), "k": int(self.view.frame), "rate": float(self.speed.value) / RUN_SECONDS,
            "playing": bool(self.playing and self.result is not None)})

    def _time_gui(self, scrub: bool = True) -> None:
        """The scrubber and the time read-out follow the clock (playing or not)."""
        d = self.drawing
        # none while a newly chosen scenario computes: the scene before's clock is not this one's
        if d is None or self.drawing_spec != self.spec.name:
            return
        # not over a browser's scrub whose callback has yet to run (viser sets the value as the
        # message arrives, and runs the callback later on a thread of its pool)
        if scrub and getattr(self.scrub, "update_timestamp", 0.0) <= self._scrub_taken:
            self._guard = True
            try:
                self.scrub.value = round(100 * self.clock, 1)
            finally:
                self._guard = False
            self._scrub_taken = getattr(self.scrub, "update_timestamp", 0.0)
        t = d.times
        now = t[min(self.view.frame, len(t) - 1)]
        self.time_md.content = d.clock.reading(now, t[-1], human_number)

    # ---- the view as a link ------------------------------------------------------------------
    def link_state(self) -> linkmod.LinkState | None:
        """The view now: what the address bar holds."""
        d, values = self.drawing, self.good_values
        if d is None or values is None or self.drawing_spec != self.spec.name:
            # a scenario chosen and still computing: the link names it already (it named the one before)
            return linkmod.LinkState(scenario=self.spec.name, present=self.present) if d is not None else None
        if self._preview_shown:  # a quick preview's shorter run stands in: the link holds the values asked for
            values = {**values, **self.controls.values()}
        # only what differs from the scene's defaults (the link fills in the rest): a class link of
        # `?s=moon&p.years=2`, not 230 characters of every key, which no student types and whose QR
        # code is too dense to read from the back of the room
        defaults = self._defaults()
        texts = {p.name: linkmod.param_text(p, values[p.name]) for p in self.spec.params if p.name in values}
        params = {k: v for k, v in texts.items()
                  if k not in defaults or v != linkmod.param_text(self.spec.param(k), defaults[k])}
        cam = None
        c = self.client.camera
        try:
            if c.position is not None and c.look_at is not None:
                cam = tuple(float(x) for x in (*c.position, *c.look_at))
                up = tuple(float(x) for x in c.up_direction)
                if np.linalg.norm(np.subtract(up, (0.0, 0.0, 1.0))) > 1e-6:
                    cam = cam + up
        except Exception:
            cam = None
        overlays = {k: bool(cb.value) for k, cb in self.toggles.items() if bool(cb.value) != d.overlays.get(k, True)}
        options = {k: self.view_opts.option(k, self.spec) for k in self.spec.options
                   if self.view_opts.option(k, self.spec) != self.spec.options[k].default}
        return linkmod.LinkState(scenario=self.spec.name, params=params,
                                 time=float(d.times[min(self.view.frame, d.n_frames - 1)]),
                                 playing=self.playing, camera=cam, options=options, overlays=overlays,
                                 present=self.present, speed=float(self.speed.value),
                                 exaggerate=float(self.view_opts.exaggerate))

    def _defaults(self) -> dict:
        """The scene's default values (cached per scenario)."""
        if self.spec.name not in self._defaults_of:
            self._defaults_of[self.spec.name] = self.spec.resolve(None)
        return self._defaults_of[self.spec.name]

    def link_query(self) -> str | None:
        st = self.link_state()
        return None if st is None else linkmod.to_query(st, self.spec)

    def _sync_link(self) -> None:
        """Keep the address bar on the view, and the class's link and QR code on the scene."""
        st = self.link_state()
        if st is None:
            return
        q = linkmod.to_query(st, self.spec)
        if q != self._link_sent:
            if browser.call(self.client, "url", q):
                self._link_sent = q
        self._sync_class_link(st)

    def _sync_class_link(self, st) -> None:
        try:
            host, port = self.server.get_host(), self.server.get_port()
        except Exception:
            return
        base = linkmod.class_link(host, port, self.address)
        shared = linkmod.LinkState(scenario=st.scenario, params=st.params, options=st.options,
                                   overlays=st.overlays)
        key = (base, linkmod.to_query(shared, self.spec))
        if key == self._class_key:
            return
        self._class_key = key
        self._show_class_link()
        if base is None:
            self.class_html.content = ("<p style='color:#666;font-size:0.9em'>Students on the same network can open "
                                       "this scene when the server is started with <b>--host 0.0.0.0</b>.</p>")
            return
        url = base + "?" + key[1]
        self.class_html.content = (
            "<div style='font-size:0.9em'><b>Students open</b><br>"
            f"<a href='{_attr(url)}' style='word-break:break-all'>{_html(url)}</a><br>"
            f"<img alt='QR code of the class link' src='{linkmod.qr_svg_uri(url)}' "
            "style='width:180px;height:180px;margin-top:4px;image-rendering:pixelated'></div>")

    def _show_class_link(self) -> None:
        """The class link and its QR code are for the projector too; the note on how to start a
        server students can reach is the teacher's, not shown there."""
        local = self._class_key is None or self._class_key[0] is None
        try:
            self.class_html.visible = not (self.present and local)
        except AttributeError:  # made before the panel's Read tab
            pass

    def close(self) -> None:
        if not self._closed:
            ClientSession.active = max(0, ClientSession.active - 1)
        self._closed = True
        playback.ticker().remove(self)
        for key in list(self._settling):
            self._unsettle(key)
        with self._waiting_lock:
            self._waiting.clear()
        self.worker.close()


def _md(text: str) -> str:
    return str(text).replace("*", "\\*").replace("_", "\\_")


def _html(text: str) -> str:
    import html

    return html.escape(text)


def _attr(text: str) -> str:
    import html

    return html.escape(text, quote=True)
