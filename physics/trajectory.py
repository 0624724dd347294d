"""The one trajectory object every consumer reads (viser player, rerun recorder, metrics, JSON).

Derived paths are computed here, once: polhode (ω in the body frame), herpolhode (ω in space,
which moves on the invariable plane ω·L̂ = 2E/|L| when the body is free), the trail of the
rotation axis and of the figure axis in space, and L in space (fixed when the body is free).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import quaternion as quat


@dataclass(repr=False)
class Trajectory:
    """The samples of one run: times `t` (in `time_unit`), the attitude `quat_wxyz` (body → space),
    the angular momentum `L_body` on the body axes and the principal moments `inertia` (in
    `moment_unit`); the other bodies' positions (`bodies`) and extra series (`series`) on the same
    times. Derived once: `omega_body` (the polhode), `omega_inertial` (the herpolhode), `L_inertial`,
    `energy`, `momentum_norm`, `rotation_axis`, `figure_axis`."""

    t: np.ndarray  # (N,) times
    quat_wxyz: np.ndarray  # (N,4) attitude, body → inertial
    L_body: np.ndarray  # (N,3) angular momentum, body frame
    inertia: np.ndarray  # (3,) principal moments (A, B, C)
    time_unit: str = "s"
    bodies: dict[str, np.ndarray] = field(default_factory=dict)  # name → (N,3) inertial positions
    series: dict[str, np.ndarray] = field(default_factory=dict)  # extra scalar series (N,)
    figure_axis_index: int | None = None  # body axis drawn as the "figure axis" (default: largest moment)
    moment_unit: str = "kg m^2"  # of `inertia`: "C" where the moments are given as fractions of the largest

    def __post_init__(self):
        self.t = np.asarray(self.t, float)
        self.quat_wxyz = np.asarray(self.quat_wxyz, float)
        self.L_body = np.asarray(self.L_body, float)
        self.inertia = np.asarray(self.inertia, float)
        self.omega_body = self.L_body / self.inertia
        self.L_inertial = quat.rotate(self.quat_wxyz, self.L_body)
        self.omega_inertial = quat.rotate(self.quat_wxyz, self.omega_body)
        self.energy = 0.5 * np.sum(self.L_body * self.omega_body, axis=1)
        self.momentum_norm = np.linalg.norm(self.L_body, axis=1)
        w = np.linalg.norm(self.omega_inertial, axis=1, keepdims=True)
        self.rotation_axis = np.divide(self.omega_inertial, w, out=np.zeros_like(self.omega_inertial), where=w > 0)
        k = int(np.argmax(self.inertia)) if self.figure_axis_index is None else self.figure_axis_index
        self.figure_axis = quat.rotate(self.quat_wxyz, np.eye(3)[k])

    # the derived paths by the names used in the scenes
    @property
    def polhode(self) -> np.ndarray:
        """ω in the body frame (the curve ω traces on the body, Poinsot)."""
        return self.omega_body

    @property
    def herpolhode(self) -> np.ndarray:
        """ω in space: its tip rolls on the invariable plane (normal to L) for a free body."""
        return self.omega_inertial

    def __len__(self) -> int:
        return len(self.t)

    def __repr__(self) -> str:
        """One line (the arrays are in the fields): samples, span, what else it carries."""
        span = f"{self.t[0]:g}–{self.t[-1]:g} {self.time_unit}" if len(self.t) else "empty"
        extra = "".join(f"; {what}: {', '.join(d)}" for what, d in (("bodies", self.bodies), ("series", self.series)) if d)
        return f"<Trajectory of {len(self.t):,} samples, t = {span}{extra}>"

    def final_state(self) -> dict:
        return {
            "t": float(self.t[-1]),
            "quaternion_wxyz": [float(x) for x in self.quat_wxyz[-1]],
            "omega_body": [float(x) for x in self.omega_body[-1]],
        }

    def relative_drift(self) -> tuple[float, float]:
        """max |E/E₀ − 1| and max ||L|/|L₀| − 1| over the run (0 for a body at rest)."""
        e0, l0 = self.energy[0], self.momentum_norm[0]
        de = float(np.max(np.abs(self.energy / e0 - 1))) if e0 else 0.0
        dl = float(np.max(np.abs(self.momentum_norm / l0 - 1))) if l0 else 0.0
        return de, dl
