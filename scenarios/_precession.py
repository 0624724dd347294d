"""Shared by the ch. 16 pole and precession scenarios.
"""
from __future__ import annotations



MAX_SAMPLES = 20000
