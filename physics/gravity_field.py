"""The torque of a distant point mass on a body's third-degree gravity field.

Euler's §815 keeps the first term of the body's field, the quadrupole (its moments A, B, C):
τ = 3GM/s⁵ · (s × I s). The next term of the expansion of the body's potential in spherical
harmonics is of degree 3; for the Moon (unnormalised coefficients, LLR/GRAIL) it is about 1% of
the quadrupole at the Earth's distance: (R/s)·C₃ₘ/C₂₂ ≈ 0.0045 · 28.5e-6/22.4e-6. Its torque
shifts the Moon's mean orientation by about a minute of arc (it is why the principal-axis frame
of JPL's ephemerides sits ~68″ and ~79″ from the mean-Earth frame) and adds arcsecond terms to
the physical libration.

Derivation. The body's potential at a body-frame point s (|s| = r, R the reference radius,
M_b the body's mass, unnormalised associated Legendre functions without the Condon–Shortley
phase, as JPL's DE files use them):

    Φ(s) = −G M_b / r · [1 + Σₙ (R/r)ⁿ Σₘ Pₙₘ(sin φ)(Cₙₘ cos mλ + Sₙₘ sin mλ)],  Cₙ₀ = −Jₙ.

Each degree-n term is −G M_b Rⁿ Hₙ(s) / r²ⁿ⁺¹ with Hₙ a homogeneous polynomial of degree n (a
solid harmonic). For n = 3, with r³Pₙₘ(z/r)·(cos mλ, sin mλ) written in x, y, z:

    P₃₀: z³ − 3/2·z(x² + y²)           P₃₁: 3/2·(4z² − x² − y²)·(x, y)
    P₃₂: 15z(x² − y²), 30xyz           P₃₃: 15(x³ − 3xy²), 15(3x²y − y³)

The mutual energy of the body and a point mass M at s is U = M·Φ(s) (by reciprocity). Turning the
body by a small angle δθ moves the point, in body coordinates, by −δθ × s, so δU = −δθ·(s × ∇U)
and the torque on the body is τ = s × ∇U. (For the quadrupole this gives MacCullagh's
3GM/s⁵ (s × I s), which is how the sign is checked.) The radial part of ∇(r^−(2n+1)) is along s
and drops out of the cross product:

    τₙ = −G M · M_b Rⁿ · (s × ∇Hₙ) / r²ⁿ⁺¹.

The integrator works with moments scaled to C = 1, so the torque enters divided by C:
τ₃/C = −GM · (M_b R²/C) · R · (s × ∇H₃)/r⁷. The tests check it against a numerical derivative of
U with respect to turning the body, and the quadrupole form against MacCullagh's.
"""
from __future__ import annotations

import numba as nb
import numpy as np

# order of the seven degree-3 coefficients everywhere in theoria
DEGREE3_NAMES = ("C30", "C31", "S31", "C32", "S32", "C33", "S33")


@nb.njit(cache=True, nogil=True)
def grad_h3(c, x, y, z):
    """∇H₃ at (x, y, z) for the coefficients c = (C30, C31, S31, C32, S32, C33, S33)."""
    c30, c31, s31, c32, s32, c33, s33 = c[0], c[1], c[2], c[3], c[4], c[5], c[6]
    gx = (c30 * (-3.0 * x * z)
          + c31 * (6.0 * z * z - 4.5 * x * x - 1.5 * y * y) + s31 * (-3.0 * x * y)
          + c32 * (30.0 * x * z) + s32 * (30.0 * y * z)
          + c33 * (45.0 * (x * x - y * y)) + s33 * (90.0 * x * y))
    gy = (c30 * (-3.0 * y * z)
          + c31 * (-3.0 * x * y) + s31 * (6.0 * z * z - 1.5 * x * x - 4.5 * y * y)
          + c32 * (-30.0 * y * z) + s32 * (30.0 * x * z)
          + c33 * (-90.0 * x * y) + s33 * (45.0 * (x * x - y * y)))
    gz = (c30 * (3.0 * z * z - 1.5 * (x * x + y * y))
          + c31 * (12.0 * x * z) + s31 * (12.0 * y * z)
          + c32 * (15.0 * (x * x - y * y)) + s32 * (30.0 * x * y))
    return gx, gy, gz


@nb.njit(cache=True, nogil=True)
def degree3_torque_into(t, s, c, k):
    """Add τ₃/C = −k · (s × ∇H₃)/r⁷ to t (3,), with k = GM · (M_b R²/C) · R."""
    x, y, z = s[0], s[1], s[2]
    r2 = x * x + y * y + z * z
    f = -k / (r2 * r2 * r2 * np.sqrt(r2))
    gx, gy, gz = grad_h3(c, x, y, z)
    t[0] += f * (y * gz - z * gy)
    t[1] += f * (z * gx - x * gz)
    t[2] += f * (x * gy - y * gx)


def h3(c, s):
    """H₃(s) (the solid harmonic of degree 3; numpy, s (..., 3)): Φ₃ = −G M_b R³ H₃/r⁷."""
    c = np.asarray(c, float)
    s = np.asarray(s, float)
    x, y, z = s[..., 0], s[..., 1], s[..., 2]
    rho2 = x * x + y * y
    return (c[0] * (z ** 3 - 1.5 * z * rho2)
            + 1.5 * (4 * z * z - rho2) * (c[1] * x + c[2] * y)
            + 15 * z * (c[3] * (x * x - y * y)) + 30 * c[4] * x * y * z
            + 15 * c[5] * (x ** 3 - 3 * x * y * y) + 15 * c[6] * (3 * x * x * y - y ** 3))


def degree3_torque(c, s, k):
    """τ₃/C (numpy, one point s (3,)): −k (s × ∇H₃)/r⁷, k = GM · (M_b R²/C) · R."""
    t = np.zeros(3)
    degree3_torque_into(t, np.asarray(s, float), np.asarray(c, float), float(k))
    return t


def degree3_potential(c, s, k):
    """U₃/C = −k · H₃(s)/r⁷ (same scaling as `degree3_torque`): the energy whose derivative with
    respect to turning the body is the torque (used by the tests)."""
    s = np.asarray(s, float)
    r = np.linalg.norm(s, axis=-1)
    return -k * h3(c, s) / r ** 7
