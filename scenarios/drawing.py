"""What a scenario draws, as plain numpy data (design.md, "One drawing path")."""
from __future__ import annotations

from dataclasses import dataclass

Vec = tuple[float, float, float]


@dataclass(frozen=True)
class Camera:
    """Where the view starts: position and look-at in scene units (+z up unless `up` says)."""

    position: Vec
    look_at: Vec = (0.0, 0.0, 0.0)
    up: Vec = (0.0, 0.0, 1.0)
    fov_deg: float | None = None
