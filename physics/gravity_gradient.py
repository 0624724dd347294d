"""Torque and force of a distant point mass on an extended body (Euler ch. 16, §815–818).

Conventions: body frame = principal axes, moments (A, B, C) about x, y, z (Euler's Maa, Mbb,
Mcc). `s_body` is the body-frame vector from the body's centre of mass to the attracting mass
F; `gm` = G·M_F. Euler's `ee` is G·M_F in his gravity units: his force on dM at distance ZF is
ee/ZF²·dM (§815), and his angular accelerations carry his factor 2g (§806), so his "6gee" is
our 3GM.

First order (§815, MacCullagh):
    τ = 3GM/s³ · ŝ × (I ŝ),  i.e.  P = 3GM(C−B)ŝ_yŝ_z/s³, Q = 3GM(A−C)ŝ_zŝ_x/s³,
    R = 3GM(B−A)ŝ_xŝ_y/s³  (§815; Euler's cos ζ, cos η, cos ϑ are ŝ_x, ŝ_y, ŝ_z).
It vanishes for A = B = C (§817). §816: it is not exact; the neglected terms are of relative
order (size/s)² for a body symmetric under x → −x (odd multipoles vanish), shown here by
integrating over a homogeneous ellipsoid.

Text errors in the translation (checked by rederivation): in §815 "∫yy dM = ½M(aa + ce − bb)"
should read cc for ce, and "cos ν" in the first line of P should be cos ϑ; in §818 "3Meec cos ζ"
should be "3Mee cos ζ". Euler's §818 force is right (it equals `extra_force_first_order`).
"""
from __future__ import annotations

import numpy as np

from .inertia import ellipsoid_moments
from .kept import kept


def torque_first_order(inertia, s_body, gm=1.0):
    """Euler's §815 torque 3GM/s³·ŝ×(Iŝ) = 3GM/s⁵·s×(Is); s_body (...,3) → (...,3)."""
    I = np.asarray(inertia, float)
    s = np.asarray(s_body, float)
    r = np.linalg.norm(s, axis=-1, keepdims=True)
    return 3.0 * gm / r**5 * np.cross(s, I * s)


def torque_euler_components(inertia, s, cosines, gm=1.0):
    """§815 in Euler's own form: (P, Q, R) from the distance s and the direction cosines
    (cos ζ, cos η, cos ϑ) of IF with the axes A, B, C. P = 3GM(C−B)cos η cos ϑ/s³ etc.

    Broadcasts: s (...) and cosines (..., 3) (the last axis holds cos ζ, cos η, cos ϑ, as in
    `torque_first_order`) give (..., 3)."""
    A, B, C = np.asarray(inertia, float)
    cos = np.asarray(cosines, float)
    cz, ce, ct = cos[..., 0], cos[..., 1], cos[..., 2]
    f = 3.0 * gm / np.asarray(s, float) ** 3
    return np.stack([f * (C - B) * ce * ct, f * (A - C) * cz * ct, f * (B - A) * cz * ce], axis=-1)


def extra_force_first_order(inertia, s_body, gm=1.0):
    """§818: the orientation-dependent 1/s⁴ part of the force on the centre of mass.

    F = GM·m ŝ/s² + 3GM/(2s⁴)·[(tr I − 5 ŝ·Iŝ) ŝ + 2 I ŝ] + O(s⁻⁶). This returns the second
    term: Euler's single force along IF, 3Mee/(2s⁴)·Σ aa(1 − 5cos²ζ), plus his three forces
    3Mee·aa cos ζ/s⁴ along the axes (his aa is A/M). Zero-sum check: for A = B = C it is
    (3GM/(2s⁴))(3A − 5A + 2A)ŝ = 0 — Euler's remark that only Mee/ss remains.
    """
    I = np.asarray(inertia, float)
    s = np.asarray(s_body, float)
    r = np.linalg.norm(s, axis=-1, keepdims=True)
    u = s / r
    uIu = np.sum(u * I * u, axis=-1, keepdims=True)
    return 1.5 * gm / r**4 * ((I.sum() - 5.0 * uIu) * u + 2.0 * I * u)


def ellipsoid_quadrature(semi_axes, mass=1.0, n_radial=16, n_polar=16, n_azimuth=32):
    """Points (K,3) and masses (K,) of a product Gauss rule over a homogeneous ellipsoid.

    The unit ball is mapped by (x, y, z) = (a, b, c)·ρ·(sinθ cosφ, sinθ sinφ, cosθ):
    Gauss–Legendre in ρ (weight ρ² included), Gauss–Legendre in cos θ, and the trapezoid rule
    in φ (spectrally accurate for periodic integrands). Integrates polynomials of degree
    < 2·n exactly, so second moments are exact: Σm x² = M a²/5.
    """
    pts, w = _unit_ball_rule(int(n_radial), int(n_polar), int(n_azimuth))
    return pts * np.asarray(semi_axes, float), mass * w


@kept(8)
def _unit_ball_rule(n_radial, n_polar, n_azimuth):
    """The rule of `ellipsoid_quadrature` on the unit ball, weights summing to 1 (made once per size;
    read-only)."""
    xr, wr = np.polynomial.legendre.leggauss(n_radial)
    rho = 0.5 * (xr + 1.0)
    wrho = 0.5 * wr * rho**2
    mu, wmu = np.polynomial.legendre.leggauss(n_polar)
    phi = (np.arange(n_azimuth) + 0.5) * (2.0 * np.pi / n_azimuth)
    wphi = np.full(n_azimuth, 2.0 * np.pi / n_azimuth)
    R, MU, PH = np.meshgrid(rho, mu, phi, indexing="ij")
    W = wrho[:, None, None] * wmu[None, :, None] * wphi[None, None, :]
    st = np.sqrt(1.0 - MU**2)
    pts = np.stack([R * st * np.cos(PH), R * st * np.sin(PH), R * MU], axis=-1).reshape(-1, 3)
    w = W.ravel()
    w = w / w.sum()  # Σw = 4π/3 (volume of the unit ball)
    pts.flags.writeable = w.flags.writeable = False
    return pts, w


def exact_torque_force(semi_axes, s_body, gm=1.0, mass=1.0, n=(16, 16, 32)):
    """Torque and force of the point mass on the homogeneous ellipsoid, by quadrature over the
    solid (no expansion in size/s): τ = Σ x × GM dm (s−x)/|s−x|³, F = Σ GM dm (s−x)/|s−x|³.
    Accurate while the point is well outside the body (the integrand is smooth there); the
    quadrature error falls geometrically with n."""
    pts, dm = ellipsoid_quadrature(semi_axes, mass, *n)
    s = np.asarray(s_body, float)
    d = s[None, :] - pts
    f = gm * dm[:, None] * d / np.linalg.norm(d, axis=1, keepdims=True) ** 3
    return np.cross(pts, f).sum(axis=0), f.sum(axis=0)


def torque_error_vs_size(semi_axes, direction, ratios, gm=1.0, mass=1.0, n=(16, 16, 32)):
    """§816: relative error |τ₁ − τ|/|τ| of the first-order torque against the exact one, for
    a body of the given shape at distances s = size/ratio along `direction` (body frame),
    size = the largest semi-axis. Returns the errors (len(ratios),) — expected ∝ ratio²."""
    a = np.asarray(semi_axes, float)
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    I = ellipsoid_moments(a, mass)
    out = []
    for q in np.atleast_1d(ratios):
        s = u * a.max() / q
        tau, _ = exact_torque_force(a, s, gm, mass, n)
        out.append(np.linalg.norm(torque_first_order(I, s, gm) - tau) / np.linalg.norm(tau))
    return np.array(out)


def force_error_vs_size(semi_axes, direction, ratios, gm=1.0, mass=1.0, n=(16, 16, 32)):
    """§818: relative error of Euler's extra force (monopole removed) against the exact one:
    |F₂ − (F − GMm ŝ/s²)| / |F − GMm ŝ/s²|. Expected ∝ ratio² (next term ~ s⁻⁶)."""
    a = np.asarray(semi_axes, float)
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    I = ellipsoid_moments(a, mass)
    out = []
    for q in np.atleast_1d(ratios):
        s = u * a.max() / q
        _, F = exact_torque_force(a, s, gm, mass, n)
        r = np.linalg.norm(s)
        extra_exact = F - gm * mass * s / r**3
        e2 = extra_force_first_order(I, s, gm)
        out.append(np.linalg.norm(e2 - extra_exact) / np.linalg.norm(extra_exact))
    return np.array(out)


def fitted_order(ratios, errors):
    """Slope of log(error) against log(ratio) (least squares): the order of the error."""
    return float(np.polyfit(np.log(ratios), np.log(errors), 1)[0])


def starting_axis(inertia, torque):
    """§806/§820: a body at rest starts to turn with ω̇ = (P/A, Q/B, R/C): returns the unit
    axis (cos α, cos β, cos γ) and the rate |ω̇| = √(P²/A² + Q²/B² + R²/C²).

    The translation's "cos α = P/aa · √(…)" must read "P/aa : √(…)" (a division), else the
    cosines would not be unit. Euler's dγ' = (2g dt/M)·√(…) is |ω̇|dt in his units.
    Broadcasts: torque (..., 3) gives axis (..., 3) and rate (...) (a float for one torque)."""
    w = np.asarray(torque, float) / np.asarray(inertia, float)
    rate = np.linalg.norm(w, axis=-1)
    axis = np.divide(w, rate[..., None], out=np.zeros_like(w), where=rate[..., None] > 0)
    return axis, (float(rate) if rate.ndim == 0 else rate)
