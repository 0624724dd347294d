"""Parameter specifications and their validation, shared by the CLI, the app and the tests.

A bad value raises `ParameterError`, whose message names the parameter, the value and the
allowed range in one line.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

from .errors import ParameterError


@dataclass(frozen=True)
class Param:
    """One scenario parameter: name, unit, range, default, help; kind float | int | vec3 | choice."""

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
        if self.kind == "choice":
            if str(text) not in map(str, self.choices):
                raise ParameterError(self.name, text, self.allowed())
            return str(text)
        if self.kind == "vec3":
            if isinstance(text, str):
                parts = [p for p in text.replace(" ", "").split(",")]
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
        try:
            v = float(part)
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


def resolve(params: Sequence[Param], given: dict[str, Any] | None) -> dict[str, Any]:
    """Defaults overridden by `given` (strings or values), each parsed and range-checked."""
    given = dict(given or {})
    known = {p.name: p for p in params}
    for key in given:
        if key not in known:
            raise ParameterError(key, given[key], "unknown parameter; known: " + ", ".join(known))
    out = {}
    for p in params:
        out[p.name] = p.parse(given[p.name]) if p.name in given else p.parse(p.default)
    return out
