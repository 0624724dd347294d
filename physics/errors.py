"""The errors theoria raises, by type: callers branch on the type, never on the message.

- `ParameterError` (a ValueError): a value outside what the model allows. Its message names the
  parameter, the value and the allowed range in one line; the CLI prints it and exits 2, the app
  shows it and keeps its last good state, `import theoria` users catch `theoria.ParameterError`.
- `Diverged`: a run with no finite sample at all (a ParameterError: these values cannot be run).
- `Cancelled`: a run stopped from its progress callback (a newer request, a closed tab, Ctrl-C).
- `StepTooLarge`: the exact free flow refuses a step of thousands of turns (raised inside the
  integrator, reworded there as a ParameterError naming the scenario's step).
- `BudgetExceeded`: a run refused before it starts, beyond the step or memory limit (a
  ParameterError naming the parameter that drives the cost and the value that fits).
"""
from __future__ import annotations

from typing import Any


class ParameterError(ValueError):
    """A parameter value outside what the model allows."""

    def __init__(self, name: str, value: Any, allowed: str):
        self.name = name
        self.value = value
        self.allowed = allowed
        super().__init__(f"{show_value(name)}={show_value(value)}: {allowed}")  # a name typed by hand is cut too

    def __reduce__(self):
        # unpickled as it was (a refusal from a worker process, a joblib or Dask task), every field
        # and subclass included: not through __init__, whose arguments a subclass changes
        return (_restored, (type(self), self.args, dict(self.__dict__)))


def _restored(cls, args, state):
    error = cls.__new__(cls)
    error.args = args
    error.__dict__.update(state)
    return error


class Diverged(ParameterError):
    """The run has no finite sample at all: these parameter values cannot be simulated."""


class Cancelled(Exception):
    """The run was stopped from its progress callback before it finished."""


class StepTooLarge(ValueError):
    """The free flow was asked for a step of thousands of turns (`free_flow.prepare`)."""


def did_you_mean(word: Any, choices) -> str:
    """The hint for a name typed wrong, " (did you mean 'spin'?)": the one choice it begins, else the
    one it is a part of ("flip" of "middle-axis-flip"), or the nearest spelling (difflib); "" when
    there is none or `word` is not text."""
    import difflib

    if not isinstance(word, str) or not word.strip():
        return ""
    choices = [c for c in choices if isinstance(c, str)]
    w = word.strip().lower()
    starts = [c for c in choices if c.lower().startswith(w)]
    if not starts and len(w) >= 3:
        starts = [c for c in choices if w in c.lower()]
    near = starts if len(starts) == 1 else difflib.get_close_matches(w, [c.lower() for c in choices], n=1, cutoff=0.6)
    if not near:
        return ""
    best = next(c for c in choices if c.lower() == near[0].lower())
    return f" (did you mean '{best}'?)"


SHOW_MAX = 60  # characters of a value shown in a message: a pasted paragraph is cut, never echoed


def show_value(value: Any) -> str:
    """The value as it appears in a one-line message: control characters escaped, long text (a
    400-digit integer, a pasted paragraph) cut to SHOW_MAX characters."""
    if isinstance(value, (list, tuple)):
        text = ",".join(show_value(v) for v in value[:8]) + (",…" if len(value) > 8 else "")
    elif isinstance(value, float):
        # short where that is exact: 50.0000001 refused must not read as the allowed 50
        text = next((t for t in (f"{value:g}", f"{value:.12g}") if float(t) == value), repr(value))
    elif isinstance(value, str) and len(value) > 4 * SHOW_MAX:
        text = value[: 4 * SHOW_MAX]
    else:
        text = str(value)
    if not text.isprintable():
        text = repr(text)[1:-1]
    return text if len(text) <= SHOW_MAX else text[: SHOW_MAX - 1] + "…"


class BudgetExceeded(ParameterError):
    """A run refused before it starts: it would take more integrator steps or keep more memory
    than the limits (scenarios.budget). Names the parameter that drives the cost; carries the
    estimate (`cost`), the limits and what fits: `reset` {parameter: default} of those to bring
    back to their defaults, then `fit` = (parameter, value), or None."""

    def __init__(self, name: str, value: Any, allowed: str, *, cost=None, limit_steps=None, limit_bytes=None,
                 fit=None, reset=None):
        super().__init__(name, value, allowed)
        self.cost = cost
        self.limit_steps = limit_steps
        self.limit_bytes = limit_bytes
        self.fit = fit
        self.reset = dict(reset or {})
