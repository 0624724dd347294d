"""One browser's session: its own scenario, parameters, run, drawing, scene nodes and playback
clock, so two people on one server do not disturb each other.

A parameter change posts a request to the session's `SimulationWorker` (app/worker.py: off the
event loop, the newest request wins, an older run is cancelled); the run's drawing is then shown
in one `client.atomic()` batch. Playback runs in its own thread and moves only what the drawing
animates. Bad input: the ParameterError (one line naming the parameter and the allowed range) is
shown as a notification and the scene keeps the last good run. Any other exception in a scenario
is reported the same way and never reaches the server loop.
"""
from __future__ import annotations

import threading
import time
import traceback
from typing import Any

import numpy as np
import viser

from theoria.physics.errors import ParameterError
from theoria.scenarios import all_scenarios, get
from theoria.scenarios.drawing import OVERLAYS, View, palette

from . import gallery, page, playback
from .controls import ParamControls
from .export_html import configure_scene
from .panel import UPLOT_POINTS, comparison_markdown, info_markdown, y_axis_px
from .scene import SceneView
from .worker import SimulationWorker, drawing_of, limits_text

# Playback: one thread for every browser within a share of a core (app/playback.py); with many
# browsers each plays back at a lower rate and slider changes stay quick.
RUN_SECONDS = 20.0  # at speed 1 a whole run plays in this many seconds
CLOCK_TEXT_EVERY = 0.5  # s between updates of the time read-out and the scrubber while playing


def playback_hz(active_sessions: int) -> float:
    """Playback rate of each session when `active_sessions` browsers are playing."""
    return playback.ticker().rate(active_sessions)


class ClientSession:
    """GUI, scene, worker and playback of one browser."""

    active = 0  # sessions open on this process (sets the playback rate)

    def __init__(self, server: viser.ViserServer, client: viser.ClientHandle, scenario: str | None,
                 run=None):
        """`run`: a finished Run to show first (`Run.show()`), with its scenario and parameters."""
        self.server, self.client = server, client
        ClientSession.active += 1
        self.scenarios = {s.name: s for s in all_scenarios()}
        self.spec = get(scenario) if scenario else self.scenarios.get("free-tumble") or next(iter(self.scenarios.values()))
        self.view = SceneView(client.scene, "/world")
        self.view_opts = View()
        self.drawing = None
        self.drawing_spec: str | None = None  # the scenario whose drawing is shown
        self.result = None
        self.good_values: dict[str, Any] | None = None
        self.playing = True
        self.clock = 0.0  # playback time as a fraction of the run, 0..1
        self._guard = False  # set while the code itself moves the scrubber
        self._pguard = False  # set while the code itself sets the preset or the parameter controls
        self._view_lock = threading.RLock()  # the worker rebuilds while the player animates
        self._closed = False
        self.updates = 0  # scene rebuilds done (tests and bench read it)
        self._build_gui()
        page.set_title(client, self.spec.name)
        page.set_loading(client, f"theoria — preparing {self.spec.name}…")
        self.worker = SimulationWorker(f"sim-{client.client_id}", self._apply, self._failed, self._show_progress)
        self._last_tick = None
        self._last_gui = 0.0
        playback.ticker().add(self)
        if run is not None and run.scenario == self.spec.name:
            self.controls.set_values(run.params)
            self._apply(self.worker.adopt(self.spec, run.params), run, 0.0)
        else:
            self.request()

    # ---- GUI -------------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.client.gui
        client = self.client
        client.scene.set_up_direction("+z")
        configure_scene(client.scene)
        self._set_camera(self.spec)
        gui.configure_theme(control_width="large", show_share_button=False)
        order = gallery.ordered(self.scenarios.values())
        self._labels = {gallery.label(s): s.name for s in order}
        self.dd = gui.add_dropdown("Scenario", list(self._labels), initial_value=gallery.label(self.spec),
                                   hint="Euler's ch. 15, ch. 16, then the three-body papers, in § order")
        self.dd.on_update(lambda e: self._safe(self._on_scenario))
        self.presets = gui.add_dropdown("Presets", self._preset_options(self.spec),
                                        initial_value=self._preset_options(self.spec)[0],
                                        hint="starting points named after what they show")
        self.presets.on_update(lambda e: self._safe(self._on_preset))
        self.info = gui.add_markdown(info_markdown(self.spec))
        self.table = gui.add_markdown("")
        self.status = gui.add_markdown("*simulating…*")
        self.progress = gui.add_progress_bar(0.0, visible=False, animated=True)
        with gui.add_folder("Playback"):
            self.play_btn = gui.add_button("Pause")
            self.play_btn.on_click(lambda e: self._safe(self._toggle_play))
            self.reset_btn = gui.add_button("Reset")
            self.reset_btn.on_click(lambda e: self._safe(self._reset))
            self.speed = gui.add_slider("speed", min=0.1, max=10.0, step=0.1, initial_value=1.0,
                                        hint=f"1 = the whole run in {RUN_SECONDS:g} s")
            self.scrub = gui.add_slider("time (% of run)", min=0.0, max=100.0, step=0.1, initial_value=0.0)
            self.scrub.on_update(lambda e: self._safe(self._on_scrub))
            self.time_md = gui.add_markdown("t = 0")
        self.params_parent = gui.add_folder("Parameters (§)")
        with self.params_parent:
            self.controls = ParamControls(gui, self.spec, on_change=self._on_param)
        with gui.add_folder("Overlays", expand_by_default=False):
            self.exag = gui.add_slider("exaggerate shape", min=1.0, max=20.0, step=0.5, initial_value=1.0,
                                       hint="multiplies the departures of the semi-axes from their mean")
            self.exag.on_update(lambda e: self._safe(self._on_exaggerate))
            self.toggles = {}
            for key, (label, _, _) in OVERLAYS.items():
                cb = gui.add_checkbox(label, initial_value=True)
                cb.on_update(lambda e, key=key: self._safe(self._on_toggle, key))
                self.toggles[key] = cb
        self.options_folder = gui.add_folder("Scene options")
        self._option_handles: list = []
        self._options_key = None
        self.plot_folder = gui.add_folder("Plot")
        self.plot = None
        self.limits_md = gui.add_markdown(limits_text())

    def _follow_camera(self) -> None:
        """Apply the drawing's moving camera (e.g. the Moon seen from the Earth) while it has one;
        give the scenario's view back when it stops."""
        d = self.drawing
        follow = d.follow if d is not None else None
        want = None
        if follow is not None:
            want = dict(position=tuple(float(x) for x in follow.position[self.view.frame]), look_at=follow.look_at,
                        up=follow.up, fov_deg=follow.fov_deg)
        cam = self.client.camera
        if want is None:
            if getattr(self, "_following", False):
                self._following = False
                cam.fov = np.radians(75.0)  # viser's default
                self._set_camera(self.spec)
            return
        self._following = True
        if want.get("fov_deg") is not None and abs(getattr(cam, "fov", 0.0) - np.radians(want["fov_deg"])) > 1e-6:
            cam.fov = np.radians(want["fov_deg"])
        cam.up_direction = want.get("up", (0.0, 0.0, 1.0))
        cam.position = want["position"]
        cam.look_at = want.get("look_at", (0.0, 0.0, 0.0))

    def _set_camera(self, spec) -> None:
        position, look_at = gallery.camera_view(spec)
        cam = self.client.camera
        cam.position = position
        cam.look_at = look_at
        cam.up_direction = (0.0, 0.0, 1.0)

    # ---- presets -----------------------------------------------------------------------------
    @staticmethod
    def _preset_options(spec) -> list[str]:
        return gallery.preset_names(spec) + [gallery.CUSTOM]

    def _on_preset(self) -> None:
        """A preset chosen: its values (validated by Scenario.resolve) go into the controls and
        are simulated at once."""
        if self._pguard or self.presets.value == gallery.CUSTOM:
            return
        values = self.spec.preset(self.presets.value)
        self._pguard = True
        try:
            self.controls.set_values(values)
        finally:
            self._pguard = False
        self.request(dict(values))

    def _on_param(self, name: str) -> None:
        """A parameter moved by hand: the preset no longer describes the values."""
        if self._pguard:
            return
        if self.presets.value != gallery.CUSTOM:
            self._pguard = True
            try:
                self.presets.value = gallery.CUSTOM
            finally:
                self._pguard = False
        self.request()

    def notify(self, title: str, body: str, color: str = "red") -> None:
        try:
            self.client.add_notification(title, body, auto_close_seconds=8.0, color=color)
        except Exception:
            pass

    def _safe(self, fn, *args) -> None:
        """Run a callback; no exception reaches viser's loop."""
        try:
            fn(*args)
        except ParameterError as e:
            self.notify(f"Bad value for {e.name}", str(e))
        except Exception as e:  # a bug in a scenario or the scene must not kill the server
            traceback.print_exc()
            self.notify("Error", f"{type(e).__name__}: {e}")

    def _on_scenario(self) -> None:
        name = self._labels[self.dd.value]
        if name == self.spec.name:
            return
        self.spec = self.scenarios[name]
        self.controls.remove()
        with self.params_parent:
            self.controls = ParamControls(self.client.gui, self.spec, on_change=self._on_param)
        self._pguard = True
        try:
            options = self._preset_options(self.spec)
            self.presets.options = options
            self.presets.value = options[0]
        finally:
            self._pguard = False
        self.info.content = info_markdown(self.spec)
        self.good_values = None
        self.view_opts = View()
        self.request()

    def _toggle_play(self) -> None:
        self.playing = not self.playing
        self.play_btn.label = "Pause" if self.playing else "Play"

    def _reset(self) -> None:
        self.clock = 0.0
        self._show_clock(force=True)

    def _on_scrub(self) -> None:
        if self._guard:
            return
        self.clock = float(self.scrub.value) / 100.0
        self._show_clock()

    def _on_exaggerate(self) -> None:
        if self.result is None:
            return
        self.view_opts.exaggerate = float(self.exag.value)
        self._redraw()

    def _on_toggle(self, key: str) -> None:
        if self._guard:
            return
        with self._view_lock, self.client.atomic():
            self.view.set_overlay(key, self.toggles[key].value)

    # ---- simulation worker -----------------------------------------------------------------
    def request(self, given: dict | None = None) -> None:
        """Post (scenario, raw values) for simulation; only the newest request is kept."""
        given = self.controls.values() if given is None else given
        self._status(f"simulating {self.spec.name}…")
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
            self.notify(f"Bad value for {e.name}", f"{e} — keeping the last good state")
            self._status("bad value: " + str(e))
        else:
            self.notify(f"Error in {name}", f"{type(e).__name__}: {e} — keeping the last good state")
            self._status(f"error: {type(e).__name__}: {e}")

    def _show_progress(self, pct: float | None, text: str | None = None) -> None:
        """Progress of a long run in the panel (None hides the bar)."""
        try:
            if pct is None:
                self.progress.visible = False
                return
            self.progress.value = pct
            if not self.progress.visible:
                self.progress.visible = True
            if text:
                self._status(text)
                if self.updates == 0:  # nothing drawn yet: the line over the page says what is happening
                    page.set_loading(self.client, "theoria — " + text)
        except Exception:
            pass

    def _status(self, text: str) -> None:
        try:
            self.status.content = f"*{text}*"
        except Exception:
            pass

    def _apply(self, req, result, t_sim: float) -> None:
        """Show a finished run (the worker's thread): its drawing, table, plot and status."""
        spec, values = req.spec, req.values
        with self._view_lock, self.client.atomic():
            if not self.worker.current(req) or spec.name != self.spec.name:
                return  # a newer request, or another scenario chosen meanwhile
            drawing = drawing_of(spec, result, self.view_opts)
            new_scenario = self.drawing_spec != spec.name
            if new_scenario:  # the scenario's own overlay defaults and camera
                page.set_title(self.client, spec.name)
                overlays = dict(drawing.overlays)
                if self.drawing_spec is not None:
                    self._set_camera(spec)
                for k, cb in self.toggles.items():
                    self._guard = True
                    try:
                        cb.value = overlays.get(k, True)
                    finally:
                        self._guard = False
            else:
                overlays = {k: bool(cb.value) for k, cb in self.toggles.items()}
            self.view.show(drawing, overlays)
            self.drawing, self.drawing_spec = drawing, spec.name
            self._sync_scene_options()
            self.result, self.good_values = result, values
            self.table.content = comparison_markdown(result)
            self._update_plot(result)
            self.view.set_frame(self._frame_index())
            self._follow_camera()
            req.stamps["shown"] = time.perf_counter()
            if self.updates == 0:
                page.set_loading(self.client, None)
            self.updates += 1
            if getattr(req, "preview", False):
                self._status(f"quick preview ({len(result.trajectory.t)} samples); computing the full run… "
                             f"(update #{self.updates})")
            else:
                self._status(f"simulated {len(result.trajectory.t)} samples in {1000 * t_sim:.0f} ms "
                             f"(update #{self.updates})")

    def _redraw(self) -> None:
        """The same run drawn again (a scene option or the shape exaggeration changed)."""
        if self.result is None:
            return
        with self._view_lock, self.client.atomic():
            self.drawing = drawing_of(self.spec, self.result, self.view_opts)
            self.view.show(self.drawing, {k: bool(cb.value) for k, cb in self.toggles.items()})
            self._update_plot()
            self.view.set_frame(self._frame_index())
            self._follow_camera()

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
                cb = self.client.gui.add_checkbox(opt.label, initial_value=self.view_opts.option(k, spec))
                cb.on_update(lambda e, k=k, cb=cb: self._safe(self._on_option, k, cb))
                self._option_handles.append(cb)

    def _on_option(self, key: str, cb) -> None:
        self.view_opts.options[key] = bool(cb.value)
        self._redraw()

    def _update_plot(self, result=None) -> None:
        d = self.drawing
        t = d.plot_t
        series = dict(d.plot) or {"energy": self.result.trajectory.energy}
        idx = np.unique(np.linspace(0, len(t) - 1, min(UPLOT_POINTS, len(t))).round().astype(int))
        data = (np.asarray(t)[idx],) + tuple(np.asarray(v, float)[idx] for v in series.values())
        ser = ({"label": f"t [{d.time_unit}]"},) + tuple(
            {"label": k, "stroke": "rgb(%d,%d,%d)" % palette(i), "width": 1.5} for i, k in enumerate(series))
        key = tuple(s["label"] for s in ser)
        axes = ({}, {"size": y_axis_px(data[1:])})  # the default 50 px cut "-" and leading digits off
        if self.plot is not None and getattr(self, "_plot_key", None) == key:
            self.plot.data = data  # same series: update in place
            self.plot.axes = axes
            return
        self._plot_key = key
        if self.plot is not None:
            self.plot.remove()
        with self.plot_folder:
            # x is the simulation time, not a date (uPlot's default x scale is a clock)
            self.plot = self.client.gui.add_uplot(data, ser, title=self.spec.name, aspect=1.6,
                                                  scales={"x": {"time": False}}, axes=axes)

    # ---- playback ----------------------------------------------------------------------------
    def _frame_index(self) -> int:
        if self.drawing is None:
            return 0
        t = self.drawing.times
        target = t[0] + self.clock * (t[-1] - t[0])
        return int(np.clip(np.searchsorted(t, target), 0, len(t) - 1))

    def _show_clock(self, force: bool = False) -> None:
        if self.result is None:
            return
        i = self._frame_index()
        if force or i != self.view.frame:
            with self._view_lock, self.client.atomic():
                self.view.set_frame(i)
                self._follow_camera()

    def wants_ticks(self) -> bool:
        """Playing a finished run (the playback thread skips a paused session)."""
        if not (self.playing and self.result is not None and not self._closed):
            self._last_tick = None
            return False
        return True

    def _tick(self, now: float) -> None:
        """One frame of playback (called by app/playback.py's thread): the clock advances by the
        real time since the last frame, so fewer frames a second never slow the run down."""
        last, self._last_tick = self._last_tick, now
        if last is None or self._closed:
            return
        self.clock = (self.clock + (now - last) * float(self.speed.value) / RUN_SECONDS) % 1.0
        self._show_clock()
        if now - self._last_gui > CLOCK_TEXT_EVERY:
            self._last_gui = now
            d = self.drawing
            self._guard = True
            try:
                self.scrub.value = round(100 * self.clock, 1)
            finally:
                self._guard = False
            self.time_md.content = f"t = {d.times[self.view.frame]:.4g} {d.time_unit}"

    def close(self) -> None:
        if not self._closed:
            ClientSession.active = max(0, ClientSession.active - 1)
        self._closed = True
        playback.ticker().remove(self)
        self.worker.close()
