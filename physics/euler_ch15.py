"""Euler's closed forms of chapter 15 (§803–811), as functions of arrays.

Euler's letters: moments Maa, Mbb, Mcc (here A, B, C); x, y, z = γ'cos α, γ'cos β, γ'cos γ
the body components of the angular velocity; P, Q, R the moments of the forces about the
principal axes "in the sense BC, CA, AB" (body torque components). His factor 2g/M belongs
to his units of force; in SI it is 1/M and is absorbed into A, B, C here.
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import quad

from .inertia import validate_moments
from .torque_free_exact import free_motion


def vis_viva(omega_body, inertia):
    """§803, §805: the vis viva M γ'²(aa cos²α + bb cos²β + cc cos²γ) = A x² + B y² + C z²
    (twice the kinetic energy), constant for a free body."""
    w = np.asarray(omega_body, float)
    return np.sum(np.asarray(inertia, float) * w * w, axis=-1)


def axis_and_speed_rates(omega_body, inertia, torque=(0.0, 0.0, 0.0)):
    """§803 (§805 when the torque is zero): the rates of the angular speed γ' and of the arcs
    α, β, γ from the pole of rotation to the principal axes. Returns (dγ'/dt, dα/dt, dβ/dt, dγ/dt),
    each of the shape of omega_body[..., 0].

    dγ' = (cc−bb)(aa−cc)(bb−aa)/(aabbcc) γ'² cos α cos β cos γ dt + (P cos α/A + Q cos β/B + R cos γ/C) dt
    γ' dα sin α = (cc−bb)/aa γ'² cos β cos γ (1 + (aa−cc)(bb−aa)/(bbcc) cos²α) dt
                  + (Q cos α cos β/B + R cos α cos γ/C − P sin²α/A) dt       and cyclic.
    (The translation's §803 writes P in all three first equations; the second and third have Q, R.)
    """
    A, B, C = validate_moments(inertia)
    w = np.asarray(omega_body, float)
    P, Q, R = np.moveaxis(np.broadcast_to(np.asarray(torque, float), w.shape), -1, 0)
    g = np.linalg.norm(w, axis=-1)
    ca, cb, cc_ = np.moveaxis(w, -1, 0) / g
    sa2, sb2, sc2 = 1 - ca * ca, 1 - cb * cb, 1 - cc_ * cc_
    dg = (C - B) * (A - C) * (B - A) / (A * B * C) * g * g * ca * cb * cc_ + (P * ca / A + Q * cb / B + R * cc_ / C)
    da = ((C - B) / A * g * g * cb * cc_ * (1 + (A - C) * (B - A) / (B * C) * ca * ca)
          + (Q * ca * cb / B + R * ca * cc_ / C - P * sa2 / A)) / (g * np.sqrt(sa2))
    db = ((A - C) / B * g * g * ca * cc_ * (1 + (B - A) * (C - B) / (A * C) * cb * cb)
          + (R * cb * cc_ / C + P * cb * ca / A - Q * sb2 / B)) / (g * np.sqrt(sb2))
    dc = ((B - A) / C * g * g * ca * cb * (1 + (C - B) * (A - C) / (A * B) * cc_ * cc_)
          + (P * cc_ * ca / A + Q * cc_ * cb / B - R * sc2 / C)) / (g * np.sqrt(sc2))
    return dg, da, db, dc


def initial_axis(torque, inertia):
    """§806: a body at rest under moments P, Q, R starts to turn about the axis with
    cos α : cos β : cos γ = P/A : Q/B : R/C, gaining angular speed at the rate
    dγ'/dt = √(P²/A² + Q²/B² + R²/C²).

    (The translation prints cos α = P/aa · √(…); it must be P/aa divided by the root.)
    Returns (unit axis (3,), angular acceleration).
    """
    I = validate_moments(inertia)
    v = np.asarray(torque, float) / I
    n = float(np.linalg.norm(v))
    if n == 0.0:
        raise ValueError("zero torque: the body stays at rest")
    return v / n, n


def initial_axis_angles_807(torque, inertia):
    """§807: the same axis by the angles of Fig. 82, tan η = −Q·aa/(P·bb),
    tan ϑ = R·aa/(P·cc)·cos η, with cos α = cos η cos ϑ, cos β = −sin η cos ϑ, cos γ = sin ϑ.
    Returns (η, ϑ)."""
    A, B, C = validate_moments(inertia)
    P, Q, R = np.moveaxis(np.asarray(torque, float), -1, 0)
    eta = np.arctan2(-Q * A, P * B)
    # tan ϑ = R·aa/(P·cc)·cos η written so that P = 0 needs no special case:
    # cos ϑ ∝ √((P/A)² + (Q/B)²), sin ϑ ∝ R/C
    theta = np.arctan2(R / C, np.hypot(P / A, Q / B))
    return eta, theta


def integrals_808(omega_body, inertia):
    """§808: with no forces, aa xx + bb yy + cc zz and the two quantities
    aa/(cc−bb)·xx − bb/(aa−cc)·yy, aa/(cc−bb)·xx − cc/(bb−aa)·zz are constant
    (needs three different moments)."""
    A, B, C = validate_moments(inertia)
    x, y, z = np.moveaxis(np.asarray(omega_body, float), -1, 0)
    a_, b_, c_ = A / (C - B), B / (A - C), C / (B - A)
    return np.stack([A * x * x + B * y * y + C * z * z, a_ * x * x - b_ * y * y, a_ * x * x - c_ * z * z], axis=-1)


def flip_interval_808(inertia, omega0):
    """The interval between flips by Euler's §808 quadrature, dt = −𝔄 dx / (y z), with x the
    component of ω on the axis L circulates about and y, z from the integrals of §808:
        y² ∝ (x² − x_min²),  z² ∝ (x_max² − x²).
    x swings from x_max to x_min and back between two flips of the middle axis, so the interval
    is 2∫ dx/|ẋ| over [x_min, x_max]. This is Euler's reduction evaluated by quadrature,
    independent of elliptic functions.

    Near the separatrix x_min is tiny (∝ the nudge off the middle axis) and ẋ varies on that
    scale next to it: x_min² is formed without cancellation, x_min² = (|L|² − 2EJ₂)/(J₃(J₃ − J₂))
    with |L|² − 2EJ₂ = Σ Jᵢ(Jᵢ − J₂)ωᵢ² (the middle-axis term drops out exactly), and the lower
    half of the range is integrated in s with x = x_min cosh s (dx/√(x² − x_min²) = ds), where
    the integrand is smooth; the upper half keeps the end singularity as an 'alg' weight.
    """
    fm = free_motion(inertia, omega0)
    J1, J2, J3 = fm.J
    w = np.asarray(omega0, float)
    I = np.asarray(inertia, float)
    L = I * w
    G = float(L @ L)
    E2 = float(L @ w)  # 2E
    mid = fm.axes[1]
    D2 = float(np.sum([I[i] * (I[i] - I[mid]) * w[i] ** 2 for i in range(3) if i != mid]))  # |L|² − 2EJ₂
    xmin2 = max(D2 / (J3 * (J3 - J2)), 0.0)
    xmax2 = (G - E2 * J1) / (J3 * (J3 - J1))
    xmin, xmax = np.sqrt(xmin2), np.sqrt(xmax2)
    K = J3 * J3 * (J3 - J2) * (J3 - J1) / (J1 * J2 * (J2 - J1) ** 2)
    c = J3 / abs(J1 - J2) / np.sqrt(K)
    # |ẋ| = |J₁ − J₂|/J₃ · √(y²z²), y²z² = K (x² − x_min²)(x_max² − x²)
    if xmin == 0.0:
        return float("inf")  # on the separatrix: the body never gets past its middle axis
    xmid = 0.5 * (xmin + xmax)
    s_mid = float(np.arccosh(xmid / xmin))
    # lower part: x = x_min cosh s; 1/√(x_max² − x²) with the difference as a product
    g = lambda s: 1.0 / np.sqrt((xmax - xmin * np.cosh(s)) * (xmax + xmin * np.cosh(s)))  # noqa: E731
    low, _ = quad(g, 0.0, s_mid, epsabs=0, epsrel=1e-13, limit=200)
    # upper part: weight (x_max − x)^(−1/2)
    f = lambda x: 1.0 / np.sqrt((x - xmin) * (x + xmin) * (xmax + x))  # noqa: E731
    high, _ = quad(f, xmid, xmax, weight="alg", wvar=(0.0, -0.5), epsabs=0, epsrel=1e-13, limit=200)
    return 2.0 * c * (low + high)
