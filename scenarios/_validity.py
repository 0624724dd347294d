"""Shared by every scenario: the sentences of `Run.warnings` that recur (a step too coarse for
the fastest period of the motion, a run sampled too sparsely for what is measured from it), with
their thresholds in one place. docs/validity.md lists every warning, its threshold and why.
"""
from __future__ import annotations

import math

# An integrator step must sample the fastest period of the forcing (the torque as the body and the
# attracting mass move) at least this many times: below 4 steps per period the sampled forcing
# aliases into slower terms (Nyquist is 2) and the splitting or RK4 error per period is of order one.
MIN_STEPS_PER_PERIOD = 4
# Stored samples from which a period, a crossing or a fit is measured: Nyquist (2 per period).
MIN_SAMPLES_PER_PERIOD = 2


def coarse_step(step: float, period: float, what: str, unit: str = "", param: str = "step") -> str | None:
    """The warning when `step` gives fewer than MIN_STEPS_PER_PERIOD steps per `period` (the
    fastest period of what the integrator steps through, described by `what`), else None."""
    if not (math.isfinite(step) and math.isfinite(period)) or period <= 0 or step <= 0:
        return None
    per = period / step
    if per >= MIN_STEPS_PER_PERIOD:
        return None
    u = f" {unit}" if unit else ""
    return (f"The step ({step:.3g}{u}) is too coarse for the fastest period of the motion, {what} "
            f"({period:.3g}{u}): {per:.2g} steps per period, fewer than {MIN_STEPS_PER_PERIOD}; that period "
            f"aliases and the results are not to be trusted. {_finer(param)}.")


def _finer(param: str) -> str:
    """What makes the step finer: a step is lowered, a count of steps per orbit or turn raised
    (the warning said "Lower steps_per_turn", the opposite of what helps)."""
    return f"Raise {param}" if param.startswith("steps_per") else f"Lower {param}"


def sparse_samples(spacing: float, period: float, what: str, unit: str = "", param: str = "step",
                   remedy: str | None = None) -> str | None:
    """The warning when stored samples `spacing` apart give fewer than MIN_SAMPLES_PER_PERIOD per
    `period` (what is measured or drawn from them aliases), else None. `remedy`: what to do, where
    lowering `param` does not help (the samples kept are capped, not the step)."""
    if not (math.isfinite(spacing) and math.isfinite(period)) or period <= 0 or spacing <= 0:
        return None
    per = period / spacing
    if per >= MIN_SAMPLES_PER_PERIOD:
        return None
    u = f" {unit}" if unit else ""
    return (f"The stored samples ({spacing:.3g}{u} apart) are too sparse for {what} ({period:.3g}{u}): "
            f"{per:.2g} per period, fewer than {MIN_SAMPLES_PER_PERIOD} (Nyquist), so it aliases in what is "
            f"measured and drawn. " + (remedy or f"Lower {param} or shorten the run."))


def add(warnings: list[str], *sentences: str | None) -> list[str]:
    """Append the sentences that are not None (each once)."""
    for s in sentences:
        if s and s not in warnings:
            warnings.append(s)
    return warnings
