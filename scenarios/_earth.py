"""Shared by the two Earth scenarios (`earth`, `earth-long-view`).
"""
from __future__ import annotations

import numpy as np

from ..physics.constants import JULIAN_YEAR_DAYS

YR = JULIAN_YEAR_DAYS  # the scenarios' time unit, in days


MIN_STEPS = 20  # integrator steps in the shortest run


# REBOUND IAS15 on the Sun–Earth–Moon problem with an output every 0.5 day: 2924 steps over 730.5 days
# (measured); an adaptive step, so a rate, not a count
REBOUND_STEPS_PER_DAY = 4.0
# the Moon's osculating elements calibrated once per process (EP.calibrated_moon_elements, cached):
# three REBOUND runs of four years
CALIBRATION_STEPS = 3 * 4 * JULIAN_YEAR_DAYS * REBOUND_STEPS_PER_DAY


def rotation_run(duration_days: float, step_days: float, sample_days: float) -> tuple[float, float]:
    """(steps, states kept) of one `EP.run_earth` over duration_days at step_days, a state kept
    every sample_days (rounded to whole steps, at least every step)."""
    from ..physics.integrator import samples_kept, step_count

    n = step_count(duration_days, step_days)
    if not np.isfinite(n):  # an absurdly small step: the states are still one per sample_days
        return n, float(np.ceil(duration_days / sample_days) + 1)
    return n, samples_kept(n, max(1, int(round(sample_days / step_days))))
