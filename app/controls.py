"""GUI controls generated from a scenario's parameter spec (physics.params.Param).

float / int → a slider when the range is finite and not too fine for one (≤ MAX_SLIDER_STEPS
steps), otherwise a number input; vec3 → a vector input; choice → a dropdown. The GUI limits
are deliberately NOT enforced in the browser for number and vector inputs: every value goes
through `Scenario.resolve`, so a bad value gives the same one-line message (naming the
parameter and the allowed range) as the CLI.
"""
from __future__ import annotations

import math
from typing import Any

from theoria.physics.params import Param

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
    unit = f" [{p.unit}]" if p.unit and p.unit != "1" else ""
    return f"{p.name}{unit}"


def hint_of(p: Param) -> str:
    return f"{p.help} — {p.allowed()}".strip(" —")


def slider_range(p: Param, presets=()) -> tuple[float, float, float] | None:
    """(min, max, step) if the parameter is shown as a slider, else None (a number input).

    A slider must hold its default exactly and reach the values around it: the default lies in
    [min, max] and at least one step above min (unless it is min), and every preset value lies in
    [min, max]. A parameter whose default is small against its range (pole-near-axis's tidal
    1 in (0, 10⁶], gravity-start's GM 1000 in (0, 10²⁰]) would otherwise have been clamped to the
    slider's first step and simulated at values 1000× off."""
    if p.kind not in ("float", "int") or p.minimum is None or p.maximum is None:
        return None
    step = _step(p)
    lo = p.minimum + (step if p.exclusive_min else 0)
    if p.maximum <= lo or (p.maximum - lo) / step > MAX_SLIDER_STEPS:
        return None
    d = p.default
    if isinstance(d, (int, float)) and not (lo <= d <= p.maximum and (d == lo or d - lo >= step * (1 - 1e-9))):
        return None
    if any(not (lo <= v <= p.maximum) for v in presets if isinstance(v, (int, float))):
        return None
    return lo, p.maximum, step


def add_param_control(gui, p: Param, value: Any, presets=()):
    """One GUI element for parameter `p`, showing `value` (`presets`: the values presets give it)."""
    label, hint = label_of(p), hint_of(p)
    if p.kind == "choice":
        return gui.add_dropdown(label, [str(c) for c in p.choices], initial_value=str(value), hint=hint)
    if p.kind == "vec3":
        return gui.add_vector3(label, tuple(float(x) for x in value), step=p.step or 0.001, hint=hint)
    rng = slider_range(p, presets)
    if rng is not None:
        lo, hi, step = rng
        v = min(max(value, lo), hi)
        return gui.add_slider(label, min=lo, max=hi, step=step, initial_value=int(v) if p.kind == "int" else float(v),
                              hint=hint)
    # number inputs: the spec's step if it has one, else viser's own (precision of the value)
    step = 1 if p.kind == "int" else (float(p.step) if p.step else None)
    return gui.add_number(label, int(value) if p.kind == "int" else float(value), step=step, hint=hint)


class ParamControls:
    """The folder of controls of one scenario; `values()` gives the raw values for resolve()."""

    def __init__(self, gui, spec, values: dict[str, Any] | None = None, on_change=None):
        self.spec = spec
        self.folder = gui.add_folder(f"Parameters: {spec.name}")
        self.handles = {}
        vals = spec.resolve(None) if values is None else values
        with self.folder:
            for p in spec.params:
                presets = [given[p.name] for given in spec.presets.values() if p.name in given]
                h = add_param_control(gui, p, vals[p.name], presets)
                self.handles[p.name] = h
                if on_change is not None:
                    h.on_update(lambda event, name=p.name: on_change(name))

    def values(self) -> dict[str, Any]:
        out = {}
        for name, h in self.handles.items():
            v = h.value
            out[name] = tuple(float(x) for x in v) if isinstance(v, (tuple, list)) else v
        return out

    def set_values(self, values: dict[str, Any]) -> None:
        for name, h in self.handles.items():
            if name in values:
                h.value = values[name]

    def remove(self) -> None:
        self.folder.remove()
