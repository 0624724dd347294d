"""Shared by the three-body scenarios: a Trajectory for bodies that do not rotate.
"""
from __future__ import annotations

import numpy as np
from ..physics.trajectory import Trajectory


GROUP = "three bodies"


def orbit_trajectory(t, bodies: dict, time_unit: str, series: dict | None = None) -> Trajectory:
    """A Trajectory for an orbit scene: identity attitude, zero spin, the bodies' positions."""
    n = len(t)
    q = np.zeros((n, 4))
    q[:, 0] = 1.0
    return Trajectory(np.asarray(t, float), q, np.zeros((n, 3)), np.ones(3), time_unit=time_unit,
                      bodies={k: np.asarray(v, float) for k, v in bodies.items()}, series=dict(series or {}))
