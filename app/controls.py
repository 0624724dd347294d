"""The controls of a scenario's parameters, generated from its `Param`s.

- A float or int with a finite range that a slider can hold exactly (every default and preset on
  its grid, ≤ MAX_SLIDER_STEPS steps) → a slider. The session debounces it: while it is dragged
  only the last value is simulated. A number typed into the box beside it reaches the server as
  text on Enter or blur (app/browser.py) and is taken as a text field's is (`Typed`, `on_typed`).
- Any other number, and a vec3 ("1, 0.5, 1.5") → a text field in a form of its own. What is typed
  is taken only on Enter or when the field loses focus (never per keystroke), through
  `Param.parse`: "1e9", "2.5e6", "1e-3" and "-0.5" are taken exactly, a value out of range is
  refused with the allowed range and the field goes back to the last good value. (viser's number
  field takes its displayed precision from the initial value and mangles exponents: typed 0.001
  into a field made with 1000 it shows 1 and sends 0.)
- A choice → a dropdown of the choices' words (`Param.choice_labels`).

A control that the chosen values leave unused (`Param.applies`: collinear's energy while the line
turns) is hidden until a choice uses it.

Labels are `Param.display()` ("Spin rate about the middle axis (rad/s)"), never the keys.
Numerical settings and modelling details (`Param.advanced`: steps, sample spacings, which
ephemeris) go into a folder kept folded ("More settings").
"""
from __future__ import annotations

import decimal
import math
import threading
from dataclasses import dataclass
from typing import Any, Callable

from theoria.physics.errors import ParameterError
from theoria.physics.params import Param
from .format import capitalised, readable

MAX_SLIDER_STEPS = 2000


def _step(p: Param) -> float:
    if p.kind == "int":
        return max(1, int(p.step or 1))
    if p.step:
        return float(p.step)
    if p.minimum is not None and p.maximum is not None and p.maximum > p.minimum:
        span = p.maximum - p.minimum
        return float(10 ** math.floor(math.log10(span / 200)))
    return 0.01


def label_of(p: Param) -> str:
    return p.display()


def hint_of(p: Param) -> str:
    allowed = p.allowed()
    if p.kind == "choice":
        return readable(p.help)
    return readable(f"{capitalised(p.help)}. Allowed: "
                    f"{allowed.split(' ', 2)[-1] if allowed.startswith('allowed range') else allowed}")


def _on_grid(v: float, lo: float, step: float) -> bool:
    k = (v - lo) / step
    return abs(k - round(k)) <= 1e-6 * max(1.0, abs(k))


def slider_range(p: Param, presets=()) -> tuple[float, float, float] | None:
    """(min, max, step) if the parameter is shown as a slider, else None (a text field).

    A slider must hold its default and every preset value exactly: each lies in [min, max] on the
    slider's grid (a default small against its range, pole-near-axis's tidal 1 in (0, 10⁶], or a
    preset of 10⁻⁶ on a 0.001 grid would otherwise be rounded and simulated at values far off)."""
    if p.kind not in ("float", "int") or p.minimum is None or p.maximum is None:
        return None
    step = _step(p)
    lo = p.minimum + (step if p.exclusive_min else 0)
    if p.maximum <= lo or (p.maximum - lo) / step > MAX_SLIDER_STEPS:
        return None
    for v in (p.default, *presets):
        if not isinstance(v, (int, float)):
            continue
        if not (lo <= v <= p.maximum) or not _on_grid(float(v), lo, step):
            return None
    return lo, p.maximum, step


def _decimals(v: float) -> int:
    """Digits after the point that show `v` exactly (its shortest form: 0.1234 → 4, 1e-06 → 6)."""
    return max(0, -decimal.Decimal(repr(float(v))).as_tuple().exponent)


SHOWN_DIGITS = 10  # significant digits a field shows (the obliquity's 23.439279444444445 as 23.43927944)


def format_value(p: Param, v: Any) -> str:
    """The text a field shows for value `v`: at most SHOWN_DIGITS significant digits. A field
    whose text is still this when it is submitted keeps `v` exactly (`ParamControls._take_text`)."""
    def short(x):
        return f"{float(x):.{SHOWN_DIGITS}g}"

    if p.kind == "choice":
        return p.choice_text(v)
    if p.kind == "vec3":
        return ", ".join(short(x) for x in v)
    if p.kind == "int":
        return str(int(v))
    return short(v)


@dataclass
class Typed:
    """A number a browser typed into a slider's box, as its text (sent on Enter or when the box
    lost focus; app/browser.py)."""

    client: Any
    client_id: int
    target: Any  # the slider's handle
    text: str


TYPED = "theoria_typed"  # the attribute of a slider's handle that takes a `Typed` (app/server.py's gate)


def on_typed(handle, fn: Callable[[Typed], None]) -> None:
    """What is typed into `handle`'s box goes to `fn` as text, to be parsed by the app: viser would
    cast it to the slider's type itself (an int slider refused "1e3" and truncated "2.5")."""
    setattr(handle, TYPED, fn)


def number_param(handle) -> Param:
    """A Param for a slider of the app's own (the time, the playback speed): its label names it,
    its range is the slider's."""
    return Param(handle.label, handle.value, float(handle.min), float(handle.max))


class PerThread:
    """A flag each thread sees its own of (kept in the owner's `_flags`, a threading.local). The
    code that sets a control itself raises it, and the control's callback (which viser runs at
    once, on the same thread) then knows not to act; a browser's event handled meanwhile on
    another thread is not mistaken for it (a failed run putting a control back on a drawing
    thread, or playback moving the scrubber twice a second, made a browser's change that landed
    in that window be ignored)."""

    def __set_name__(self, owner, name: str) -> None:
        self.name = name

    def __get__(self, obj, owner=None):
        return self if obj is None else getattr(obj._flags, self.name, False)

    def __set__(self, obj, value) -> None:
        setattr(obj._flags, self.name, bool(value))


class ParamControls:
    """The controls of one scenario. `values()` gives the values last taken (parsed and in range
    for text fields; what the sliders and dropdowns show otherwise).

    `on_change(name, debounce)`: a value was taken (debounce True for a slider being dragged).
    `on_error(ParameterError)`: a typed value was refused (the field shows the last good value)."""

    _guard = PerThread()  # set while the code itself shows values (their callbacks do nothing)

    def __init__(self, gui, spec, values: dict[str, Any] | None = None,
                 on_change: Callable[[str, bool], None] | None = None,
                 on_error: Callable[[ParameterError], None] | None = None, advanced=None,
                 order: float | None = None, wrap: Callable | None = None):
        self._flags = threading.local()  # _guard, one for each thread
        self.spec = spec
        # wrap(fn) → a viser callback calling fn() (the session's: one browser event at a time)
        self._wrap = wrap or (lambda fn: (lambda event: fn()))
        self._removed = False
        self.hidden = False  # all of them, as presenter mode has it (`show_applicable`)
        self.gui = gui
        self.on_change, self.on_error = on_change, on_error
        self.handles: dict[str, Any] = {}
        self.forms: dict[str, Any] = {}
        self.kinds: dict[str, str] = {}  # name → "slider" | "text" | "choice"
        self._containers: list = []  # what remove() takes away
        self._order = order  # place in the panel (viser's `order`): between two elements made earlier
        self._k = 0
        vals = spec.resolve(None) if values is None else dict(values)
        self._values = dict(vals)
        main = [p for p in spec.params if not p.advanced]
        extra = [p for p in spec.params if p.advanced]
        self._top = True
        self._add(main, vals)
        if extra:
            if advanced is None:
                advanced = gui.add_folder("More settings", expand_by_default=False, order=self._next())
                self._containers.append(advanced)
                self._top = False  # its elements go with the folder
            with advanced:
                self._add(extra, vals)
        self._top = True
        self.show_applicable()

    def _next(self) -> float | None:
        if self._order is None:
            return None
        self._k += 1
        return self._order + 0.001 * self._k

    def _add(self, params, vals) -> None:
        for p in params:
            presets = [given[p.name] for given in self.spec.presets.values() if p.name in given]
            self._add_one(p, vals[p.name], presets)

    def _add_one(self, p: Param, value, presets) -> None:
        gui, name = self.gui, p.name
        hint = hint_of(p)
        if p.kind == "choice":
            h = gui.add_dropdown(p.display(), [p.choice_text(c) for c in p.choices],
                                 initial_value=p.choice_text(value), hint=hint, order=self._next())
            h.on_update(self._wrap(lambda name=name: self._taken(name, self.handles[name].value, False)))
            self.kinds[name] = "choice"
            self._keep(h)
        elif (rng := slider_range(p, presets)) is not None:
            lo, hi, step = rng
            v = min(max(value, lo), hi)
            h = gui.add_slider(p.display(), min=lo, max=hi, step=step,
                               initial_value=int(v) if p.kind == "int" else float(v), hint=hint, order=self._next())
            h.on_update(self._wrap(lambda name=name: self._taken(name, self.handles[name].value, True)))
            on_typed(h, lambda typed, name=name: self._wrap(lambda: self._take_text(name, typed.text))(typed))
            self.kinds[name] = "slider"
            self._keep(h)
        else:
            form = gui.add_form(None, order=self._next())
            with form:
                h = gui.add_text(p.display(), format_value(p, value), hint=hint)
            form.on_submit(self._wrap(lambda name=name: self._submitted(name)))
            self.forms[name] = form
            self.kinds[name] = "text"
            self._keep(form)
        self.handles[name] = h

    def _keep(self, h) -> None:
        if self._top:
            self._containers.append(h)

    # ---- values in -------------------------------------------------------------------------
    def _taken(self, name: str, shown, debounce: bool) -> None:
        if self._guard or self._removed:  # removed: an event that came for the panel of another scenario
            return
        p = self.spec.param(name)
        self._values[name] = p.choice_of(shown) if p.kind == "choice" else shown
        self.show_applicable()  # a choice, or a number another control needs above zero (a zoom's length)
        if self.on_change is not None:
            self.on_change(name, debounce)

    def _submitted(self, name: str) -> None:
        """Enter in a text field, or the field lost focus: parse what it shows."""
        if self._guard or self._removed:
            return
        self._take_text(name, self.handles[name].value)

    def _take_text(self, name: str, text) -> None:
        """A typed value (a text field's, or a number typed into a slider's box), taken exactly,
        even between a slider's marks, or refused with the allowed range."""
        if self._removed:
            return
        p = self.spec.param(name)
        text = str(text).strip()
        if text == format_value(p, self._values.get(name, p.default)):
            return  # the field as it was shown (a value of more digits than it shows is kept whole)
        try:
            v = p.parse(text)
        except ParameterError as e:
            self._show(name, self._values[name])
            if self.on_error is not None:
                self.on_error(e)
            return
        if v == self._values.get(name):
            return  # unchanged (a blur with nothing typed)
        self._values[name] = v
        if self.kinds[name] == "slider":
            self._show(name, v)
        if self.on_change is not None:
            self.on_change(name, False)

    def enter(self, name: str, text: str) -> None:
        """Type `text` into a field and press Enter (scripts and tests; the browser does the same)."""
        h = self.handles[name]
        if self.kinds[name] == "text":
            h.value = text
            self.forms[name].submit()
        elif self.kinds[name] == "choice":
            h.value = self.spec.param(name).choice_text(text)
        else:
            h.value = self.spec.param(name).parse(text)

    # ---- values out ------------------------------------------------------------------------
    def values(self) -> dict[str, Any]:
        return dict(self._values)

    def set_values(self, values: dict[str, Any]) -> None:
        """Show `values` (a preset, a link) without calling on_change."""
        self._guard = True
        try:
            for name in self.handles:
                if name in values:
                    self._values[name] = values[name]
                    self._show(name, values[name])
            self.show_applicable()
        finally:
            self._guard = False

    def set_hidden(self, on: bool) -> None:
        """Every control hidden (presenter mode: the keys play, step and choose presets) or shown
        again, each as the values use it."""
        self.hidden = on
        for c in self._containers:
            try:
                c.visible = not on
            except Exception:
                pass
        self.show_applicable()

    def show_applicable(self) -> None:
        """Only the controls these values use are shown (collinear's energy while the bodies fly
        apart, its turns while they turn): a field that changes nothing is not offered. With
        `hidden` (presenter mode) none of them is."""
        for p in self.spec.params:
            if p.applies and p.name in self.handles:
                shown = self.forms.get(p.name, self.handles[p.name])
                on = not self.hidden and p.applies_to(self._values)
                if shown.visible != on:
                    shown.visible = on

    def _show(self, name: str, v) -> None:
        p = self.spec.param(name)
        h = self.handles[name]
        guard, self._guard = self._guard, True
        try:
            if self.kinds[name] == "slider":
                if p.kind != "int" and _decimals(v) > getattr(h, "precision", 99):
                    h.precision = _decimals(v)  # a typed 0.1234 on a 0.001 slider is shown whole
                h.value = int(v) if p.kind == "int" else float(v)
            else:
                h.value = format_value(p, v)
        finally:
            self._guard = guard

    def remove(self) -> None:
        self._removed = True
        for c in self._containers:
            try:
                c.remove()
            except Exception:
                pass
        self._containers = []
