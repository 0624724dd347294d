"""Shared by the two Earth scenarios (`earth`, `earth-long-view`).
"""
from __future__ import annotations

from ..physics.constants import JULIAN_YEAR_DAYS

YR = JULIAN_YEAR_DAYS  # the scenarios' time unit, in days


MIN_STEPS = 20  # integrator steps in the shortest run
