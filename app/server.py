"""`theoria serve`: the viser web app.

Each browser gets its own `ClientSession` (built in `on_client_connect`): its own scenario,
parameters, simulation result, scene nodes and playback clock, so two people on one server do
not disturb each other.

Responsiveness (issue 3): a parameter change posts a request to the session's worker thread;
the worker always takes the newest request, simulates off the event thread, and drops a result
when a newer request arrived meanwhile (a running integration is aborted from its progress
callback). The scene update is batched in `client.atomic()`. Playback runs in its own thread at
display rate and moves only poses, two short arrows and chunk visibility.

Bad input: `Scenario.resolve` raises ParameterError (one line naming the parameter and the allowed
range); the browser gets a notification and the scene keeps the last good result. Any other
exception in a scenario is reported the same way and never reaches the server loop.
"""
from __future__ import annotations

import threading
import time
import traceback
from typing import Any

import numpy as np
import viser

from theoria.physics.params import ParameterError
from theoria.scenarios import all_scenarios, get

from . import gallery
from .controls import ParamControls
from theoria.scenarios.drawing import OVERLAYS, View

from .scene import SceneView

PLAY_HZ = 60.0  # playback tick for one browser (messages go out each 1/60 s)
# Pose updates per second shared by all browsers: the server runs on one core (the GIL), and 30
# sessions at 60 Hz alone took 75% of it (docs/robustness.md), so with many browsers each plays
# back at a lower rate and slider changes stay quick.
PLAY_BUDGET = 360.0
PLAY_HZ_MIN = 12.0


def playback_hz(active_sessions: int) -> float:
    """Playback rate of each session when `active_sessions` browsers are connected."""
    return max(PLAY_HZ_MIN, min(PLAY_HZ, PLAY_BUDGET / max(1, active_sessions)))
RUN_SECONDS = 20.0  # at speed 1 a whole run plays in this many seconds
UPLOT_POINTS = 2000
PROGRESS_SHOW_AFTER = 0.4  # s: the progress bar appears only for runs longer than this
PROGRESS_EVERY = 0.15  # s: at most this often a progress message goes to the browser


def y_axis_px(series_values, px_per_char: float = 7.2, min_px: int = 50) -> int:
    """Width (CSS px) of a uPlot y axis for these series: uPlot labels ticks with en-US grouping
    ("-250,000", "0.0005") at about five ticks; the longest label's characters × the 12 px font's
    width, plus ticks and gap (15 px)."""
    v = np.concatenate([np.asarray(a, float).ravel() for a in series_values]) if len(series_values) else np.zeros(1)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return min_px
    lo, hi = float(v.min()), float(v.max())
    span = hi - lo or abs(hi) or 1.0
    step = 10 ** np.floor(np.log10(span / 5))
    decimals = int(max(0, -np.floor(np.log10(step))))
    widest = 0
    for x in (lo, hi):
        text = f"{x:,.{decimals}f}"
        widest = max(widest, len(text))
    return int(max(min_px, np.ceil(widest * px_per_char + 15)))


def configure_lighting(scene) -> None:
    """Plain lights, no image-based environment map and no shadows: in software WebGL
    (SwiftShader) the environment map alone takes the body scene from ~28 to ~10 frames/s."""
    scene.configure_environment_map(hdri=None)
    scene.configure_default_lights(enabled=True, cast_shadow=False)
    scene.add_light_ambient("/lights/ambient", intensity=1.2)


def camera_position(spec) -> tuple[float, float, float]:
    """The scenario's curated camera position (app/gallery.py CAMERAS)."""
    return gallery.camera_for(spec)[0]


# the control panel covers the right ~30 % of the canvas: orbit scenes are centred in the free part
PANEL_SHIFT = 0.3


def camera_view(spec) -> tuple[tuple, tuple]:
    """(camera position, look-at point): the gallery's camera; orbit scenes are moved left of the
    control panel by shifting the camera to the right (along the screen's right direction) by
    PANEL_SHIFT of its distance."""
    position, look_at = (np.asarray(v, float) for v in gallery.camera_for(spec))
    if spec.kind != "rotation":
        fwd = look_at - position
        right = np.cross(fwd, (0.0, 0.0, 1.0))
        if np.linalg.norm(right) > 0:
            shift = PANEL_SHIFT * np.linalg.norm(fwd) * right / np.linalg.norm(right)
            position, look_at = position + shift, look_at + shift
    return tuple(float(x) for x in position), tuple(float(x) for x in look_at)


class _Stale(Exception):
    """A newer request arrived: abandon this simulation."""


def scenario_label(spec) -> str:
    return gallery.label(spec)


def _fmt(x) -> str:
    if x is None:
        return "–"
    try:
        x = float(x)
    except (TypeError, ValueError):
        return str(x)
    if not np.isfinite(x):
        return "–"
    return f"{x:.6g}"


def info_markdown(spec, result=None) -> str:
    lines = [f"### {spec.title}", f"**{spec.section}** · {spec.group} · `{spec.name}`", "", spec.summary, ""]
    if spec.euler_formula:  # plain Unicode text: viser's markdown renders no TeX
        lines += [gallery.formula_markdown(spec.euler_formula), ""]
    return "\n".join(lines)


def comparison_markdown(result) -> str:
    if result is None:
        return ""
    lines = []
    if result.comparisons:
        lines += ["| | Euler says | simulated | modern | unit |", "|---|---|---|---|---|"]
        for c in result.comparisons:
            note = f" ({c.note})" if c.note else ""
            label = (c.label + note).replace("|", "\\|")  # a | in a label (|H(p,e)|) would split the row
            lines.append(f"| {label} | {_fmt(c.euler)} | {_fmt(c.simulated)} | {_fmt(c.modern)} | {c.unit} |")
        lines.append("")
    if result.metrics:
        lines.append("**Metrics:** " + ", ".join(f"{k} = {_fmt(v)}" for k, v in result.metrics.items()))
    for n in result.notes:
        lines.append(f"\n*{n}*")
    return "\n".join(lines)


class ClientSession:
    """GUI, scene, worker and playback of one browser."""

    active = 0  # sessions open on this process (sets the playback rate)

    def __init__(self, server: viser.ViserServer, client: viser.ClientHandle, scenario: str | None):
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
        self._lock = threading.Lock()
        self._cv = threading.Condition(self._lock)
        self._request: tuple[int, str, dict] | None = None
        self._gen = 0
        self._closed = False
        self.updates = 0  # scene rebuilds done (tests and bench read it)
        self.timing: dict[str, float] = {}  # perf_counter stamps of the last request (bench)
        self._build_gui()
        self._worker = threading.Thread(target=self._work, daemon=True, name=f"sim-{client.client_id}")
        self._worker.start()
        self._player = threading.Thread(target=self._play, daemon=True, name=f"play-{client.client_id}")
        self._player.start()
        self.request()

    # ---- GUI -------------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.client.gui
        client = self.client
        client.scene.set_up_direction("+z")
        configure_lighting(client.scene)
        self._set_camera(self.spec)
        gui.configure_theme(control_width="large", show_share_button=False)
        order = gallery.ordered(self.scenarios.values())
        self._labels = {scenario_label(s): s.name for s in order}
        self.dd = gui.add_dropdown("Scenario", list(self._labels), initial_value=scenario_label(self.spec),
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
        position, look_at = camera_view(spec)
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
        with self._cv:
            self._gen += 1
            self._request = (self._gen, self.spec.name, given)
            self.timing = {"request": time.perf_counter()}
            self._cv.notify()

    def _work(self) -> None:
        while True:
            with self._cv:
                while self._request is None and not self._closed:
                    self._cv.wait()
                if self._closed:
                    return
                gen, name, given = self._request
                self._request = None
            try:
                self._simulate(gen, name, given)
            except _Stale:
                continue
            except ParameterError as e:
                self.notify(f"Bad value for {e.name}", f"{e} — keeping the last good state")
                self._status("bad value: " + str(e))
            except Exception as e:
                traceback.print_exc()
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
        except Exception:
            pass

    def _status(self, text: str) -> None:
        try:
            self.status.content = f"*{text}*"
        except Exception:
            pass

    def _simulate(self, gen: int, name: str, given: dict) -> None:
        spec = self.scenarios[name]
        values = spec.resolve(given)
        self._status(f"simulating {name}…")
        self.timing["start"] = time.perf_counter()

        t0 = time.perf_counter()
        shown = {"t": 0.0, "pct": -1.0, "done": False}
        bar_lock = threading.Lock()

        def progress(frac):
            if self._gen != gen or self._closed:
                raise _Stale()
            now = time.perf_counter()
            if now - t0 < PROGRESS_SHOW_AFTER or now - shown["t"] < PROGRESS_EVERY:
                return  # throttled: short runs never show the bar, long ones ≤ 1/PROGRESS_EVERY msgs/s
            try:
                pct = min(max(100.0 * float(frac), 0.0), 100.0)
            except (TypeError, ValueError):
                return
            if not np.isfinite(pct) or abs(pct - shown["pct"]) < 0.5:
                return
            with bar_lock:
                if shown["done"]:
                    return
                shown["t"], shown["pct"] = now, pct
                self._show_progress(pct, f"simulating {name}… {pct:.0f}%")

        def still_running():  # a long run that reports no progress yet (e.g. a setup phase) shows the bar at 0
            with bar_lock:
                if not shown["done"] and shown["pct"] < 0 and self._gen == gen and not self._closed:
                    shown["pct"] = 0.0
                    self._show_progress(0.0)

        timer = threading.Timer(PROGRESS_SHOW_AFTER, still_running)
        timer.daemon = True
        timer.start()
        try:
            try:
                result = spec.simulate_fn(values, progress=progress)
            except TypeError as e:  # a simulate_fn without the progress keyword
                if "progress" not in str(e):
                    raise
                result = spec.simulate_fn(values)
        finally:
            timer.cancel()
            with bar_lock:
                shown["done"] = True
                if shown["pct"] >= 0:
                    self._show_progress(None)
        t_sim = time.perf_counter() - t0
        self.timing["simulated"] = time.perf_counter()
        if self._gen != gen:
            raise _Stale()
        with self._view_lock, self.client.atomic():
            if self._gen != gen or spec.name != self.spec.name:
                raise _Stale()
            drawing = spec.drawing(result, self.view_opts)
            new_scenario = self.drawing_spec != spec.name
            if new_scenario:  # the scenario's own overlay defaults and camera
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
            self.timing["shown"] = time.perf_counter()
            self.updates += 1
            self._status(f"simulated {len(result.trajectory.t)} samples in {1000 * t_sim:.0f} ms "
                         f"(update #{self.updates})")

    def _redraw(self) -> None:
        """The same run drawn again (a scene option or the shape exaggeration changed)."""
        if self.result is None:
            return
        with self._view_lock, self.client.atomic():
            self.drawing = self.spec.drawing(self.result, self.view_opts)
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
        from theoria.scenarios.drawing import palette

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

    def _play(self) -> None:
        last = time.perf_counter()
        last_gui = 0.0
        while not self._closed:
            now = time.perf_counter()
            dt, last = now - last, now
            try:
                if self.playing and self.result is not None:
                    self.clock = (self.clock + dt * float(self.speed.value) / RUN_SECONDS) % 1.0
                    self._show_clock()
                    if now - last_gui > 0.25:
                        last_gui = now
                        d = self.drawing
                        self._guard = True
                        try:
                            self.scrub.value = round(100 * self.clock, 1)
                        finally:
                            self._guard = False
                        self.time_md.content = f"t = {d.times[self.view.frame]:.4g} {d.time_unit}"
            except Exception:
                if self._closed:
                    return
                traceback.print_exc()
            time.sleep(max(0.0, 1.0 / playback_hz(ClientSession.active) - (time.perf_counter() - now)))

    def close(self) -> None:
        if not self._closed:
            ClientSession.active = max(0, ClientSession.active - 1)
        self._closed = True
        with self._cv:
            self._cv.notify()


def make_server(port: int = 8080, host: str = "127.0.0.1", scenario: str | None = None, verbose: bool = True):
    """A running viser server with one ClientSession per browser; returns (server, sessions)."""
    if scenario is not None:
        get(scenario)  # a bad name raises ParameterError before the server starts
    if verbose:
        server = viser.ViserServer(host=host, port=port, verbose=True)
    else:
        import contextlib
        import io

        with contextlib.redirect_stdout(io.StringIO()):  # viser prints its banner even when not verbose
            server = viser.ViserServer(host=host, port=port, verbose=False)
    sessions: dict[int, ClientSession] = {}

    @server.on_client_connect
    def _(client: viser.ClientHandle) -> None:
        try:
            sessions[client.client_id] = ClientSession(server, client, scenario)
        except Exception as e:
            traceback.print_exc()
            try:
                client.add_notification("Error", f"{type(e).__name__}: {e}", color="red")
            except Exception:
                pass

    @server.on_client_disconnect
    def _(client: viser.ClientHandle) -> None:
        s = sessions.pop(client.client_id, None)
        if s is not None:
            s.close()

    return server, sessions


def serve(port: int = 8080, host: str = "127.0.0.1", scenario: str | None = None) -> None:
    """Run the web app until interrupted, printing the URL to open."""
    server, _ = make_server(port=port, host=host, scenario=scenario, verbose=False)
    port = server.get_port()
    if host in ("0.0.0.0", "::", ""):
        import socket

        print(f"theoria: listening on all interfaces, port {port}; open http://{socket.gethostname()}:{port}/ "
              f"(or http://127.0.0.1:{port}/ on this machine). Ctrl-C to stop.", flush=True)
    else:
        print(f"theoria: open http://{host}:{port}/ in a browser (Ctrl-C to stop)", flush=True)
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
