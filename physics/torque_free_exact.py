"""The modern exact solution of the torque-free rigid body (the motion of Euler's §808).

Euler reduced the free motion to the quadrature
    dt = −𝔄dx √(𝔅ℭ) / (√(𝔄xx − 𝔄a² + 𝔅b²) √(𝔄xx − 𝔄a² + ℭc²))          (§808)
(his A, B, C there are aa/(cc−bb), bb/(aa−cc), cc/(bb−aa), not the moments). Jacobi's
elliptic functions invert it: with the body axes relabelled 1, 2, 3 so that axis 3 is the one
the angular momentum circulates about (the largest moment if |L|² > 2EB, the smallest if
|L|² < 2EB) and axis 2 the middle one (Landau & Lifshitz, Mechanics §37),
    ω₁ = a₁ cn u,  ω₂ = ±a₂ sn u,  ω₃ = ±a₃ dn u,   u = u₀ + λt,
    λ² = (J₃ − J₂)(|L|² − 2EJ₁)/(J₁J₂J₃),   k² = (J₂ − J₁)(2EJ₃ − |L|²)/((J₃ − J₂)(|L|² − 2EJ₁)).
The period of ω (the polhode) is 4K(k)/λ; the middle-axis component changes sign every
2K(k)/λ, the interval between flips of a body spun near its middle axis.

The attitude: with L along inertial z, body → space = Rz(ψ)·Rx(θ)·Rz(φ), and
    ψ(t) − ψ(0) = (|L|/λ) [c₁(u − u₀) + c₂(Π(n; am u | k²) − Π(n; am u₀ | k²))],
the incomplete elliptic integral of the third kind Π computed from Carlson's R_F and R_J.

This module uses scipy.special only; it is the independent reference for the stepping
integrator in `free_flow` (which uses its own elliptic functions and quadrature).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ellipj, ellipk, ellipkinc, ellipkm1, elliprf, elliprj
from scipy.spatial.transform import Rotation

from . import quaternion as quat
from .inertia import validate_moments
from .params import ParameterError


@dataclass(frozen=True)
class FreeMotion:
    """Constants of a torque-free motion, in the relabelled frame (see module docstring)."""

    axes: tuple[int, int, int]  # body indices of frame axes 1, 2, 3
    sign: int  # +1 or −1: frame axis 3 is sign·e_axes[2], so the frame stays right-handed
    J: np.ndarray  # moments in the relabelled frame
    a: np.ndarray  # amplitudes a₁, a₂, a₃
    lam: float  # λ, rate of the argument u
    m: float  # k²
    s3: float  # sign of ω₃
    sg2: float  # sign multiplying a₂ sn u
    u0: float
    L_norm: float
    energy: float
    m1: float = float("nan")  # 1 − k², formed without cancellation (see `free_motion`)
    m1_rel_uncertainty: float = 0.0  # relative rounding of m1 from the starting rates (see `free_motion`)

    @property
    def period_rel_uncertainty(self) -> float:
        """Relative uncertainty of K (and so of the polhode period and the flip interval) from the
        rounding of the starting rates in 1 − k²: zero where |L|² − 2EJ₂ is a sum of small terms (a
        spin near the middle axis), large where it is the difference of large ones (a start far from
        every axis, next to the separatrix: there the input itself does not fix 1 − k²)."""
        if not (self.m > 0.5 and np.isfinite(self.m1) and self.m1 > 0):
            return 0.0
        d = max(self.m1_rel_uncertainty, 1e-300)
        return float(abs(ellipkm1(self.m1 * (1 + d)) / ellipkm1(self.m1) - 1)) if d < 1 else float("inf")

    @property
    def K(self) -> float:
        """Complete elliptic integral K(k), from 1 − k² when k² is near 1 (scipy's ellipkm1)."""
        return float(ellipkm1(self.m1)) if self.m > 0.5 and np.isfinite(self.m1) else float(ellipk(self.m))

    @property
    def polhode_period(self) -> float:
        """Period of ω in the body frame: 4K(k)/λ."""
        return 4.0 * self.K / self.lam

    @property
    def flip_interval(self) -> float:
        """Time between sign changes of the middle-axis component: 2K(k)/λ."""
        return 2.0 * self.K / self.lam

    @property
    def circulation_axis(self) -> int:
        return self.axes[2]


def _perm_matrix(axes, sign):
    P = np.zeros((3, 3))
    P[0, axes[0]] = 1.0
    P[1, axes[1]] = 1.0
    P[2, axes[2]] = sign
    return P


def free_motion(inertia, omega0) -> FreeMotion:
    """Constants of the free motion starting from body rate omega0 (not a permanent rotation)."""
    I = validate_moments(inertia)
    w = np.asarray(omega0, float)
    L = I * w
    G = float(L @ L)
    if G == 0.0:
        raise ParameterError("omega0", tuple(w), "a nonzero rate (the body at rest does not move)")
    lo, mid, hi = np.argsort(I, kind="stable")
    if I[hi] - I[lo] <= 1e-15 * I[hi]:
        raise ValueError("a sphere: ω is constant, there is no polhode")
    s = L[lo] ** 2 * (1 - I[mid] / I[lo]) + L[hi] ** 2 * (1 - I[mid] / I[hi])
    c = hi if s > 0 else lo
    o = lo if c == hi else hi
    if I[c] == I[mid]:
        c, o = o, c
    axes = (int(o), int(mid), int(c))
    sign = int(np.linalg.det(_perm_matrix(axes, 1.0)))
    J = I[list(axes)]
    W = np.array([w[axes[0]], w[axes[1]], sign * w[axes[2]]])
    J1, J2, J3 = J
    D3 = W[0] ** 2 * J1 * (J3 - J1) + W[1] ** 2 * J2 * (J3 - J2)
    D1 = W[1] ** 2 * J2 * (J2 - J1) + W[2] ** 2 * J3 * (J3 - J1)
    if D3 == 0 or D1 == 0:
        raise ValueError("a permanent rotation about a principal axis: ω is constant")
    a = np.sqrt([D3 / (J1 * (J3 - J1)), D3 / (J2 * (J3 - J2)), D1 / (J3 * (J3 - J1))])
    lam = float(np.sqrt((J3 - J2) * D1 / (J1 * J2 * J3)))
    m = float(np.clip((J2 - J1) * D3 / ((J3 - J2) * D1), 0.0, 1.0))
    # 1 − k² = (J₃ − J₁)(|L|² − 2EJ₂)/((J₃ − J₂)(|L|² − 2EJ₁)), with |L|² − 2EJ₂ =
    # J₁(J₁ − J₂)ω₁² + J₃(J₃ − J₂)ω₃² (the middle-axis term cancels exactly): near the separatrix
    # 1 − k² is far below the rounding of k² (a nudge ε off the middle axis gives 1 − k² ∝ ε²),
    # and 1 − k computed as such would be 0 (K infinite) or noise
    t1, t3 = W[0] ** 2 * J1 * (J1 - J2), W[2] ** 2 * J3 * (J3 - J2)
    D2 = t1 + t3
    m1 = float(np.clip((J3 - J1) * D2 / ((J3 - J2) * D1), 0.0, 1.0))
    # the two terms have opposite signs: their rounding (a few ulps each) relative to their sum
    m1_unc = 4 * np.finfo(float).eps * (abs(t1) + abs(t3)) / abs(D2) if D2 != 0 else float("inf")
    s3 = 1.0 if W[2] >= 0 else -1.0
    sg2 = s3 if J3 > J1 else -s3
    phi0 = np.arctan2(W[1] / (sg2 * a[1]), W[0] / a[0])
    u0 = float(ellipkinc(phi0, m))
    return FreeMotion(axes, sign, J, a, lam, m, s3, sg2, u0, float(np.sqrt(G)), float(0.5 * L @ w), m1, float(m1_unc))


def _pi_incomplete(n, phi, m):
    """Π(n; φ | m) for any real φ, from Carlson's symmetric integrals (DLMF 19.25.14)."""
    phi = np.asarray(phi, float)
    j = np.round(phi / np.pi)
    pr = phi - j * np.pi
    s, c = np.sin(pr), np.cos(pr)
    inc = s * elliprf(c * c, 1 - m * s * s, 1.0) + n / 3.0 * s**3 * elliprj(c * c, 1 - m * s * s, 1.0, 1 - n * s * s)
    complete = elliprf(0.0, 1 - m, 1.0) + n / 3.0 * elliprj(0.0, 1 - m, 1.0, 1 - n)
    return 2.0 * j * complete + inc


def _nutation_rotation(l):
    """Rx(θ)·Rz(φ) taking unit vectors l (N,3) to +z, l = (sinθ sinφ, sinθ cosφ, cosθ)."""
    th = np.arctan2(np.hypot(l[:, 0], l[:, 1]), l[:, 2])
    ph = np.arctan2(l[:, 0], l[:, 1])
    # extrinsic "zx": first Rz(φ), then Rx(θ) about the fixed x axis, i.e. the matrix Rx(θ)Rz(φ)
    return Rotation.from_euler("zx", np.stack([ph, th], axis=1))


def exact_free_motion(inertia, omega0, t, q0=quat.IDENTITY):
    """Body angular velocity (N,3) and attitude quaternions (N,4, w first) at times t.

    scipy's ellipj takes k², not 1 − k²: within ~1e-8 of the separatrix (1 − k² below that) its
    sn, cn, dn are those of a neighbouring orbit and this reference loses digits over a flip;
    `free_flow` carries 1 − k² itself and is the one to trust there."""
    I = validate_moments(inertia)
    fm = free_motion(I, omega0)
    t = np.atleast_1d(np.asarray(t, float))
    u = fm.u0 + fm.lam * t
    sn, cn, dn, ph = ellipj(u, fm.m)
    W = np.stack([fm.a[0] * cn, fm.sg2 * fm.a[1] * sn, fm.s3 * fm.a[2] * dn], axis=1)
    J1, J2, _ = fm.J
    p, r = J1 * fm.a[0] ** 2, J2 * fm.a[1] ** 2
    if abs(J1 * p - J2 * r) <= 1e-15 * J1 * p:
        psi = fm.L_norm / J1 * t  # J₁ = J₂: ψ̇ = |L|/J₁
    else:
        n = 1.0 - J2 * r / (J1 * p)
        c1 = (p - r) / (J1 * p - J2 * r)
        c2 = 1.0 / J1 - c1
        _, _, _, ph0 = ellipj(fm.u0, fm.m)
        psi = fm.L_norm / fm.lam * (c1 * (u - fm.u0) + c2 * (_pi_incomplete(n, ph, fm.m) - _pi_incomplete(n, ph0, fm.m)))
    Lp = W * fm.J / fm.L_norm
    Pi = Rotation.from_matrix(_perm_matrix(fm.axes, fm.sign))
    Pt = _nutation_rotation(Lp)
    w0 = np.asarray(omega0, float)
    W0 = np.array([w0[fm.axes[0]], w0[fm.axes[1]], fm.sign * w0[fm.axes[2]]])
    P0 = _nutation_rotation((W0 * fm.J / fm.L_norm)[None])[0]  # at t = 0, whatever t holds
    R0 = Rotation.from_quat(quat.to_xyzw(q0))
    R = R0 * Pi.inv() * P0.inv() * Rotation.from_rotvec(np.outer(psi, [0.0, 0.0, 1.0])) * Pt * Pi
    omega = np.empty_like(W)
    omega[:, fm.axes[0]] = W[:, 0]
    omega[:, fm.axes[1]] = W[:, 1]
    omega[:, fm.axes[2]] = fm.sign * W[:, 2]
    return omega, quat.from_xyzw(R.as_quat())
