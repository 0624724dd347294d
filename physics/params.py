"""Parameter specifications and their validation, shared by the CLI, the app and the tests.

A bad value raises `ParameterError`, whose message names the parameter, the value and the
allowed range in one line.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from .errors import ParameterError, did_you_mean

MAX_TEXT_CHARS = 200  # a value given as longer text is refused before it is parsed (a pasted paragraph)
POSITIVE = ">0"  # `Param.applies`: the condition "this number parameter is above zero"


@dataclass(frozen=True)
class Param:
    """One scenario parameter: name, unit, range, default, help; kind float | int | vec3 | choice.

    `name` is the key scripts and the command line use (`--set spin=6`); `label` is what a person
    reads in the app ("Spin rate"), shown with its unit by `display()` ("Spin rate (rad/s)");
    `choice_labels` are the words shown for `choices` (same order); `advanced` marks a numerical
    setting or modelling detail (a step, a sample spacing, an ephemeris) that the app keeps out of
    the first screen.
"""

    name: str
    default: Any
    minimum: float | None = None
    maximum: float | None = None
    unit: str = ""
    help: str = ""
    kind: str = "float"
    step: float | None = None
    choices: tuple = field(default_factory=tuple)
    exclusive_min: bool = False  # the minimum itself is not allowed (e.g. a step > 0)
    label: str = ""
    choice_labels: tuple = field(default_factory=tuple)
    advanced: bool = False
    # used only with these values of choice parameters: {"motion": ("rotating", "restricted")}, or
    # with a number parameter above zero: {"zoom_years": POSITIVE}; every condition must hold. A
    # list of such dicts: any one of them ([{"model": "full"}, {"model": "secular", "zoom_years":
    # POSITIVE}]). Kept as alternatives, each ((name, values), ...); elsewhere the app hides the
    # control and a run says it is unused
    applies: Any = ()

    def __post_init__(self):
        a = self.applies
        if isinstance(a, dict):
            a = [a]
        if a and isinstance(a[0], dict):
            a = tuple(tuple((k, tuple(v) if isinstance(v, (tuple, list)) else (v,)) for k, v in d.items()) for d in a)
        object.__setattr__(self, "applies", tuple(a))

    def applies_to(self, values: dict[str, Any]) -> bool:
        """Whether these values (all of a scenario's) use this parameter."""
        def holds(k, allowed):
            v = values.get(k)
            if allowed == (POSITIVE,):
                return isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0
            return str(v) in map(str, allowed)
        return not self.applies or any(all(holds(k, allowed) for k, allowed in alt) for alt in self.applies)

    def applies_text(self) -> str:
        """Where it is used, in words: "with motion = rotating or restricted", "with zoom_years > 0",
        "with model = full, or with model = secular and with zoom_years > 0"."""
        return ", or ".join(" and ".join(f"with {k} > 0" if allowed == (POSITIVE,) else
                                         f"with {k} = {' or '.join(map(str, allowed))}" for k, allowed in alt)
                            for alt in self.applies)

    def title(self) -> str:
        """The human name: `label`, else the key with its underscores as spaces."""
        return self.label or self.name.replace("_", " ")

    def unit_text(self) -> str:
        """The unit as printed ("kg·m²", "1/s²"); empty for a pure number."""
        return pretty_unit(self.unit)

    def display(self) -> str:
        """The control's label: "Spin rate (rad/s)"."""
        u = self.unit_text()
        return f"{self.title()} ({u})" if u else self.title()

    def choice_text(self, choice: Any) -> str:
        """The words shown for one of `choices`."""
        for c, text in zip(self.choices, self.choice_labels):
            if str(c) == str(choice):
                return str(text)
        return str(choice)

    def choice_of(self, text: str) -> str:
        """The choice whose words (or key) are `text`."""
        for c in self.choices:
            if self.choice_text(c) == text or str(c) == text:
                return str(c)
        return text

    def allowed(self) -> str:
        unit = f" {self.unit}" if self.unit and self.unit != "1" else ""
        if self.kind == "choice":
            return "one of " + ", ".join(map(str, self.choices))
        lo = "-inf" if self.minimum is None else f"{self.minimum:g}"
        hi = "inf" if self.maximum is None else f"{self.maximum:g}"
        left = "(" if self.exclusive_min else "["
        what = "each component in" if self.kind == "vec3" else "allowed range"
        return f"{what} {left}{lo}, {hi}]{unit}"

    def parse(self, text: Any) -> Any:
        """Parse a string (or a value) and check it against the range."""
        if isinstance(text, str) and len(text) > MAX_TEXT_CHARS:
            raise ParameterError(self.name, text, f"a value of at most {MAX_TEXT_CHARS} characters")
        if self.kind == "choice":  # as the scenario names are: "DE421" is de421, " Full" is full
            given = str(text).strip().lower()
            for c in self.choices:
                if str(c).lower() == given:
                    return str(c)
            raise ParameterError(self.name, text, self.allowed() + did_you_mean(str(text), map(str, self.choices)))
        if self.kind == "vec3":
            if isinstance(text, str):
                parts = [p for p in text.replace(" ", "").split(",")]
            elif isinstance(text, (set, frozenset, dict)):  # no order: which number is x?
                raise ParameterError(self.name, text, "three numbers in order (x, y, z), " + self.allowed())
            else:
                try:
                    parts = list(text)
                except TypeError:
                    parts = [text]
            if len(parts) != 3:
                raise ParameterError(self.name, text, "three comma-separated numbers, " + self.allowed())
            vals = [self._number(p, text) for p in parts]
            for v in vals:
                self._check_range(v, text)
            return tuple(vals)
        v = self._number(text, text)
        if self.kind == "int":
            if v != int(v):
                raise ParameterError(self.name, text, "an integer, " + self.allowed())
            v = int(v)
        self._check_range(v, text)
        return v

    def _number(self, part: Any, whole: Any) -> float:
        if isinstance(part, (bool, np.bool_)) or np.iscomplexobj(part):
            # True is 1 to Python, not a number a user meant; float() of a numpy complex drops its
            # imaginary part with only a warning
            raise ParameterError(self.name, whole, "a number, " + self.allowed())
        if isinstance(part, (bytes, bytearray)):  # text all the same (float() reads b"1_0" as 10)
            part = part.decode("ascii", "replace")
        try:
            v = read_number(part) if isinstance(part, str) else float(part)
        except OverflowError:  # an int beyond float range (10**400): as infinite as "inf"
            raise ParameterError(self.name, whole, "a finite number, " + self.allowed()) from None
        except (TypeError, ValueError):
            raise ParameterError(self.name, whole, "a number, " + self.allowed()) from None
        if not math.isfinite(v):
            raise ParameterError(self.name, whole, "a finite number, " + self.allowed())
        return v

    def _check_range(self, v: float, whole: Any) -> None:
        if self.minimum is not None and (v < self.minimum or (self.exclusive_min and v == self.minimum)):
            raise ParameterError(self.name, whole, self.allowed())
        if self.maximum is not None and v > self.maximum:
            raise ParameterError(self.name, whole, self.allowed())


# exponents as they are written, both ways: "-3" ↔ "⁻³" (also app/format.py's read-outs)
SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")
_FROM_SUPERSCRIPT = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻⁺", "0123456789-+")
# "2.5 × 10⁶", "2.5×10^6", "1 x 10^-3": a power of ten as people (and the app's own read-outs) write it
_TIMES_TEN = re.compile(r"(?:([+-]?(?:\d+\.?\d*|\.\d+))\s*[×xX*·]\s*)?10\s*(?:\^\s*([+-]?\d+)|([⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+))")


def plain_number(text: str) -> str:
    """A number as written by a person or copied from the app's panel, in Python's form: the true
    minus sign "−" as "-", thin spaces dropped, "2.5 × 10⁶" / "2.5×10^6" as "2.5e6", "10⁻³" as
    "1e-3". Anything else is returned stripped, for float() to take or refuse."""
    t = text.strip().replace("\u2212", "-").replace("\u2009", "").replace("\u202f", "")
    m = _TIMES_TEN.fullmatch(t)
    if m:
        return f"{m[1] or 1}e{m[2] if m[2] is not None else m[3].translate(_FROM_SUPERSCRIPT)}"
    return t


# a number as written with ASCII digits: Python's float() also reads "1_0" as 10 and other scripts'
# digits ("١٠", "１０"), which no one types meaning that number
NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|[+-]?(?:inf|infinity|nan)", re.ASCII | re.IGNORECASE)


def read_number(text: str) -> float:
    """The number a person wrote (`plain_number`'s forms); ValueError for anything else."""
    t = plain_number(text)
    if not NUMBER.fullmatch(t):
        raise ValueError(f"not a number: {text!r}")
    return float(t)


def whole_number(value) -> int:
    """A count or a seed as a person or a script gives it: an int, a float or text that is whole
    ("1000", "1e3", 1000.0); ValueError for anything else (2.5, True, "１０", "1_0")."""
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"not a whole number: {value!r}")
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (bytes, bytearray)):  # float() reads bytes as text, "1_0" included
        raise ValueError(f"not a whole number: {value!r}")
    if isinstance(value, str) and re.fullmatch(r"[+-]?[0-9]+", value.strip()):
        return int(value.strip())  # exactly: a seed of twenty digits is not rounded through a float
    v = read_number(value) if isinstance(value, str) else float(value)
    if not math.isfinite(v) or v != int(v):
        raise ValueError(f"not a whole number: {value!r}")
    return int(v)


whole_number.__name__ = "whole number"  # what argparse names in "invalid whole number value: '2.5'"


# units whose symbol means little on a panel, in words
_UNIT_WORDS = {"deg": "°", "d": "days", "day": "days", "1/yr": "per year", "G=1 mass": "mass units, G = 1",
               "G=1 units": "units, G = 1", "rad/unit": "rad per time unit", "b": "× the Moon's distance b",
               "n": "× the mean motion n", "arcsec": "″", "arcsec/yr": "″/yr", "arcsec/century": "″/century",
               "deg/yr": "°/yr", "1/orbit": "per orbit", "unit": "time units", "1/unit^2": "per time unit²",
               "δ": "× δ", "δ^2": "× δ²", "1/δ": "× 1/δ", "1/n": "× 1/n", "rad per 1/δ": "× δ",
               "n_sun": "× the Sun's mean motion", "LD": "lunar distances"}


def pretty_unit(unit: str) -> str:
    """A unit as a person writes it: "kg m^2" → "kg·m²", "m^3/s^2" → "m³/s²", "1" → ""."""
    import re

    u = (unit or "").strip()
    if u in ("", "1"):
        return ""
    if u in _UNIT_WORDS:
        return _UNIT_WORDS[u]
    u = re.sub(r"\^(-?\d+)", lambda m: m.group(1).translate(SUPERSCRIPT), u)
    return re.sub(r"(?<=[A-Za-z²³])\s+(?=[A-Za-z])", "·", u)


def resolve(params: Sequence[Param], given: dict[str, Any] | None) -> dict[str, Any]:
    """Defaults overridden by `given` (strings or values), each parsed and range-checked."""
    given = dict(given or {})
    known = {p.name: p for p in params}
    for key in given:
        if key not in known:
            raise ParameterError(key, given[key], "unknown parameter" + did_you_mean(key, known) + "; known: "
                                 + ", ".join(known))
    out = {}
    for p in params:
        out[p.name] = p.parse(given[p.name]) if p.name in given else p.parse(p.default)
    return out
