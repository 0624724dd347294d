"""Principal moments of inertia (A, B, C) and the homogeneous ellipsoid that has them.

Euler writes the moments as Maa, Mbb, Mcc (§791, §803); here they are A, B, C about the body
x, y, z axes.
"""
from __future__ import annotations

import numpy as np

from .params import ParameterError

# Relative slack in the triangle inequalities: a flat disc (A + B = C) is a real body.
_TRIANGLE_RTOL = 1e-12


def validate_moments(inertia, name: str = "inertia") -> np.ndarray:
    """Return (A, B, C) as an array, or raise ParameterError naming `name`.

    A real body has positive, finite moments obeying A + B ≥ C, B + C ≥ A, C + A ≥ B
    (each moment is ∫(y²+z²)dm etc., so the sum of two is at least the third).
    """
    try:
        I = np.asarray(inertia, dtype=float).reshape(3)
    except (TypeError, ValueError):
        raise ParameterError(name, inertia, "three positive numbers A,B,C") from None
    if not np.all(np.isfinite(I)) or np.any(I <= 0):
        raise ParameterError(name, tuple(I), "each moment finite and > 0")
    A, B, C = I
    tol = _TRIANGLE_RTOL * I.sum()
    for lhs, rhs, label in ((A + B, C, "A+B >= C"), (B + C, A, "B+C >= A"), (C + A, B, "C+A >= B")):
        if lhs < rhs - tol:
            raise ParameterError(
                name, tuple(float(x) for x in I), f"not a real body: needs {label} (triangle inequalities)"
            )
    return I


def ellipsoid_semi_axes(inertia, mass: float = 1.0) -> np.ndarray:
    """Semi-axes (a, b, c) of the homogeneous ellipsoid of `mass` with moments (A, B, C).

    A = m(b² + c²)/5 and cyclic, so a² = 5(B + C − A)/(2m) and cyclic. The triangle
    inequalities are exactly the condition that the squares are ≥ 0.
    """
    A, B, C = validate_moments(inertia)
    sq = 5.0 / (2.0 * mass) * np.array([B + C - A, C + A - B, A + B - C])
    return np.sqrt(np.clip(sq, 0.0, None))


def ellipsoid_moments(semi_axes, mass: float = 1.0) -> np.ndarray:
    """Moments of the homogeneous ellipsoid with semi-axes (a, b, c): m(b²+c²)/5 and cyclic."""
    a, b, c = np.asarray(semi_axes, float)
    return mass / 5.0 * np.array([b * b + c * c, c * c + a * a, a * a + b * b])
