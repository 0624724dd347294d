"""Shared by the two Earth scenarios (`earth`, `earth-long-view`).
"""
from __future__ import annotations

from ..physics import earth_precession as EP


YR = EP.DAYS_PER_YEAR


MIN_STEPS = 20  # integrator steps in the shortest run
