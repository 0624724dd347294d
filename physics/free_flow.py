"""The exact torque-free flow of a rigid body over one step, compiled with numba.

The body-frame angular momentum follows Jacobi's elliptic functions (the modern closed form
of the motion Euler reduced to a quadrature in §808); the attitude follows from the fixed
spatial L and the precession angle ψ about it, whose rate
    ψ̇ = |L| (L₁²/J₁ + L₂²/J₂) / (L₁² + L₂²)
(Landau & Lifshitz, Mechanics §37) is integrated over the step by Gauss–Legendre quadrature of
an analytic integrand. Everything is recomputed from the current state on each step, so the
step keeps |L| and the spatial L to round-off and admits torque kicks between steps. A body of
revolution (two equal moments) needs neither: its flow is two uniform rotations (`_drift_symmetric`).

Frames: body axes are permuted (a proper rotation Π) so that axis 3 is the axis the angular
momentum circulates about (largest moment if |L|² > 2EB, smallest otherwise) and axis 2 the
middle one. In that frame, with λ and k² below,
    ω₁ = a₁ cn(u),  ω₂ = σ a₂ sn(u),  ω₃ = s a₃ dn(u),  u = u₀ + λt.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from .errors import StepTooLarge

# Gauss–Legendre rules on [0, 1] for the quadrature of ψ̇ over a step: row i holds the
# GL_N[i]-node rule (padded with zeros). A piece of u no longer than GL_SPAN[i] times ½√ρ (see
# `prepare`) takes rule i: each is as accurate as 10 nodes over a whole ½√ρ (relative error
# ≤ 4e-16 against mpmath's quadrature of the same integrand with sn, cn at 30 digits, 300 random
# bodies; tests/test_free_flow.py), and most steps of a body under torque are far shorter than ½√ρ.
GL_N = np.array([5, 7, 10])
GL_SPAN = np.array([0.2, 0.6, 1.0])
GL_X = np.zeros((3, 10))
GL_W = np.zeros((3, 10))
for _i, _n in enumerate(GL_N):
    _x, _w = np.polynomial.legendre.leggauss(_n)
    GL_X[_i, :_n] = 0.5 * (_x + 1.0)
    GL_W[_i, :_n] = 0.5 * _w
_MACHEP = 1.11022302462515654042e-16
# Quadrature pieces per step beyond which a step is refused rather than computed: λh this large
# means the body spins (or tumbles) thousands of times per step (e.g. moments 1e6 : 1e-6 under a
# torque: ω ~ 1e9 rad/s), and the table of sn/cn/dn would need gigabytes (found by tests/test_fuzz.py:
# the run hung with >1 GB of memory). Ordinary runs need at most a few hundred.
MAX_NSUB = 20000


@nb.njit(cache=True, nogil=True)
def _ellipj_core(u, m, m1):
    """sn, cn, dn by the arithmetic–geometric mean and descending Landen transformation
    (Abramowitz & Stegun 16.4; the algorithm of Cephes `ellpj`), with its series for m near 0
    and near 1; b₀ = √m1 from the complementary parameter itself."""
    if m < 1e-9:
        t = math.sin(u)
        b = math.cos(u)
        ai = 0.25 * m * (u - t * b)
        return t - ai * b, b + ai * t, 1.0 - 0.5 * m * t * t
    if m1 <= 1e-10 and m1 * math.cosh(min(abs(u), 300.0)) ** 2 <= 1e-8:
        # A&S 16.15: sn, cn, dn to first order in m1; the first-order terms grow like m1·cosh²u,
        # so the series is used only while that is ≤ 1e-8 (the neglected second order ≤ 1e-16, relative)
        ai = 0.25 * m1
        b = math.cosh(u)
        t = math.tanh(u)
        phi = 1.0 / b
        twon = b * math.sinh(u)
        sn = t + ai * (twon - u) / (b * b)
        ai *= t * phi
        cn = phi - ai * (twon - u)
        dn = phi + ai * (twon + u)
        return sn, cn, dn
    a, c, top, twon = _landen(m, m1)
    return _landen_sn_cn_dn(u, m, m1, a, c, top, twon)


@nb.njit(cache=True, nogil=True)
def _landen(m, m1):
    """The arithmetic–geometric mean's sequence for parameter m (it does not depend on u): the
    a's and c's, the last index and 2^index. Made once, it serves every argument of one m."""
    a = np.empty(16)
    c = np.empty(16)
    a[0] = 1.0
    b = math.sqrt(m1)
    c[0] = math.sqrt(m)
    twon = 1.0
    i = 0
    while abs(c[i] / a[i]) > _MACHEP:
        if i > 14:  # b = √m1 ≥ 1e-154 needs at most ~12 steps
            break
        ai = a[i]
        i += 1
        c[i] = 0.5 * (ai - b)
        t = math.sqrt(ai * b)
        a[i] = 0.5 * (ai + b)
        b = t
        twon *= 2.0
    return a, c, i, twon


@nb.njit(cache=True, nogil=True)
def _landen_sn_cn_dn(u, m, m1, a, c, top, twon):
    """sn, cn, dn of u from the sequence `_landen(m, m1)` (descending Landen transformation)."""
    i = top
    phi = twon * a[i] * u
    while i > 0:
        t = c[i] * math.sin(phi) / a[i]
        phi = 0.5 * (math.asin(t) + phi)
        i -= 1
    sn = math.sin(phi)
    cn = math.cos(phi)
    # dn² = 1 − m sn² = m1 + m cn²: a sum of positive terms, accurate where Cephes'
    # cn/cos(φ − b) divides two small numbers
    return sn, cn, math.sqrt(m1 + m * cn * cn)


@nb.njit(cache=True, nogil=True)
def ellipk_m1(m1):
    """K from the complementary parameter m1 = 1 − k²: π/(2·AGM(1, √m1)) (A&S 17.6)."""
    a = 1.0
    b = math.sqrt(m1)
    for _ in range(40):
        if abs(a - b) <= 4.0 * _MACHEP * a:
            break
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return 0.5 * math.pi / a


@nb.njit(cache=True, nogil=True)
def ellipj(u, m, m1=-1.0):
    """Jacobi sn, cn, dn (u real, any sign; dn > 0) of argument u and parameter m = k² ∈ [0, 1].

    `m1` = 1 − m, the complementary parameter, when the caller has it more precisely than
    1 − m can be formed (near the separatrix 1 − m is below the rounding of m: a body nudged by
    1e-9 off its middle axis has 1 − m ~ 1e-18, and m itself rounds to 1); negative: 1 − m.

    Near the separatrix (m1 < 1e-3) the argument is first reduced by quarter periods to
    |w| ≤ K/2 (A&S 16.8: sn(K − w) = cd w, cn(K − w) = k′ sd w, dn(K − w) = k′ nd w; sn, cn,
    dn of 2K − w are sn w, −cn w, dn w), so cn and dn keep their relative precision where they
    are as small as k′ (the body passing its unstable axis): the Landen algorithm alone gives
    them as cos φ with φ next to π/2, i.e. with an absolute, not relative, error of 1e-16.
    """
    if m1 < 0.0:
        m1 = 1.0 - m
    if m1 < 1e-3 and m >= 1e-9:
        K = ellipk_m1(m1)
        kp = math.sqrt(m1)
        x = u - 4.0 * K * math.floor(u / (4.0 * K) + 0.5)  # in [−2K, 2K)
        sg = 1.0
        if x < 0.0:
            x = -x
            sg = -1.0
        if x > 1.5 * K:
            sw, cw, dw = _ellipj_core(2.0 * K - x, m, m1)
            return sg * sw, -cw, dw
        if x > 0.5 * K:
            sw, cw, dw = _ellipj_core(K - x, m, m1)
            return sg * cw / dw, kp * sw / dw, kp / dw
        sw, cw, dw = _ellipj_core(x, m, m1)
        return sg * sw, cw, dw
    return _ellipj_core(u, m, m1)


@nb.njit(cache=True, nogil=True)
def quat_mul(p, q):
    r = np.empty(4)
    r[0] = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3]
    r[1] = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2]
    r[2] = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1]
    r[3] = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0]
    return r


@nb.njit(cache=True, nogil=True)
def quat_from_matrix(M):
    """Shepperd's method: the largest of w, x, y, z is taken from the diagonal first."""
    tr = M[0, 0] + M[1, 1] + M[2, 2]
    q = np.empty(4)
    if tr >= M[0, 0] and tr >= M[1, 1] and tr >= M[2, 2]:
        s = 2.0 * math.sqrt(1.0 + tr)
        q[0] = 0.25 * s
        q[1] = (M[2, 1] - M[1, 2]) / s
        q[2] = (M[0, 2] - M[2, 0]) / s
        q[3] = (M[1, 0] - M[0, 1]) / s
    elif M[0, 0] >= M[1, 1] and M[0, 0] >= M[2, 2]:
        s = 2.0 * math.sqrt(1.0 + M[0, 0] - M[1, 1] - M[2, 2])
        q[0] = (M[2, 1] - M[1, 2]) / s
        q[1] = 0.25 * s
        q[2] = (M[0, 1] + M[1, 0]) / s
        q[3] = (M[0, 2] + M[2, 0]) / s
    elif M[1, 1] >= M[2, 2]:
        s = 2.0 * math.sqrt(1.0 + M[1, 1] - M[0, 0] - M[2, 2])
        q[0] = (M[0, 2] - M[2, 0]) / s
        q[1] = (M[0, 1] + M[1, 0]) / s
        q[2] = 0.25 * s
        q[3] = (M[1, 2] + M[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 + M[2, 2] - M[0, 0] - M[1, 1])
        q[0] = (M[1, 0] - M[0, 1]) / s
        q[1] = (M[0, 2] + M[2, 0]) / s
        q[2] = (M[1, 2] + M[2, 1]) / s
        q[3] = 0.25 * s
    if q[0] < 0.0:
        q = -q
    return q


@nb.njit(cache=True, nogil=True)
def rotate_inverse(q, v):
    """Inertial vector v in body coordinates (q rotates body into inertial)."""
    w = q[0]
    ux = -q[1]
    uy = -q[2]
    uz = -q[3]
    tx = 2.0 * (uy * v[2] - uz * v[1])
    ty = 2.0 * (uz * v[0] - ux * v[2])
    tz = 2.0 * (ux * v[1] - uy * v[0])
    r = np.empty(3)
    r[0] = v[0] + w * tx + (uy * tz - uz * ty)
    r[1] = v[1] + w * ty + (uz * tx - ux * tz)
    r[2] = v[2] + w * tz + (ux * ty - uy * tx)
    return r


@nb.njit(cache=True, nogil=True)
def _nutation_frame(l1, l2, l3):
    """P(l) = Rx(θ)·Rz(φ), the rotation taking the body unit vector l to +z, where
    l = (sin θ sin φ, sin θ cos φ, cos θ) (Euler angles z-x-z, body → space = Rz(ψ)Rx(θ)Rz(φ))."""
    s = math.sqrt(l1 * l1 + l2 * l2)
    th = math.atan2(s, l3)
    ph = math.atan2(l1, l2)
    ct, st = math.cos(th), math.sin(th)
    cp, sp = math.cos(ph), math.sin(ph)
    P = np.empty((3, 3))
    P[0, 0] = cp
    P[0, 1] = -sp
    P[0, 2] = 0.0
    P[1, 0] = ct * sp
    P[1, 1] = ct * cp
    P[1, 2] = -st
    P[2, 0] = st * sp
    P[2, 1] = st * cp
    P[2, 2] = ct
    return P


@nb.njit(cache=True, nogil=True)
def _turned(P0, cz, sz, P1):
    """P0ᵀ · Rz · P1, Rz the turn by ψ about z (cos, sin given), written out: a 3×3 product
    through BLAS cost more than the rest of the attitude's update."""
    A = np.empty((3, 3))
    for j in range(3):
        A[0, j] = cz * P1[0, j] - sz * P1[1, j]
        A[1, j] = sz * P1[0, j] + cz * P1[1, j]
        A[2, j] = P1[2, j]
    M = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            M[i, j] = P0[0, i] * A[0, j] + P0[1, i] * A[1, j] + P0[2, i] * A[2, j]
    return M


@nb.njit(cache=True, nogil=True)
def _axis_angle_quat(x, y, z, angle):
    n = math.sqrt(x * x + y * y + z * z)
    q = np.empty(4)
    q[0] = math.cos(0.5 * angle)
    s = math.sin(0.5 * angle) / n if n > 0.0 else 0.0
    q[1] = s * x
    q[2] = s * y
    q[3] = s * z
    return q


# kinds of motion in `prepare`
GENERAL, PERMANENT, SPHERE, SYMMETRIC = 0, 1, 2, 3


@nb.njit(cache=True, nogil=True)
def prepare(L, I, h):
    """Constants of the free flow through L over steps of h.

    The amplitudes come from 2EJ₃ − |L|² and |L|² − 2EJ₁ written as sums of terms of one sign
    (no cancellation for a spin close to a principal axis), and stay fixed while the body is
    free, so round-off cannot make E or |L| drift from step to step.
    The complementary parameter 1 − k² = (J₃ − J₁)(|L|² − 2EJ₂)/((J₃ − J₂)(|L|² − 2EJ₁)) is
    formed from |L|² − 2EJ₂ = J₁(J₁ − J₂)ω₁² + J₃(J₃ − J₂)ω₃² (the middle-axis term cancels
    exactly), not as 1 − k²: near the separatrix (a spin nudged 1e-9 off the middle axis gives
    1 − k² ~ 1e-18) k² rounds to 1 and the motion would be taken for the separatrix itself.
    Returns (ip, c, tab): ip = [i1, i2, i3, sig, kind, nsub, rule of GL_N]; c = [J1, J2, J3, a1, a2, a3, λ,
    m, |L|, p, r, m1]; tab = sn, cn, dn at λh and at the quadrature nodes of [0, λh].
    """
    ip = np.zeros(7, np.int64)
    c = np.zeros(12)
    G = L[0] * L[0] + L[1] * L[1] + L[2] * L[2]
    lo, mid, hi = 0, 1, 2  # the axes by increasing moment (three comparisons, no array)
    if I[mid] < I[lo]:
        lo, mid = mid, lo
    if I[hi] < I[mid]:
        mid, hi = hi, mid
        if I[mid] < I[lo]:
            lo, mid = mid, lo
    if G == 0.0 or I[hi] - I[lo] <= 1e-15 * I[hi]:
        ip[4] = SPHERE
        return ip, c, np.zeros((1, 3))
    if I[lo] == I[mid] or I[mid] == I[hi]:
        # a body of revolution (two equal moments): the flow is two rotations in closed form
        # (`drift`), with no elliptic function and no quadrature
        ip[4] = SYMMETRIC
        ip[0] = hi if I[lo] == I[mid] else lo  # the figure axis: the moment that differs
        c[0], c[2] = I[mid], I[ip[0]]
        c[8] = math.sqrt(G)
        return ip, c, np.zeros((1, 3))
    # which axis L circulates about: sign of |L|² − 2E·I_mid, written without cancellation
    s = L[lo] * L[lo] * (1.0 - I[mid] / I[lo]) + L[hi] * L[hi] * (1.0 - I[mid] / I[hi])
    cc = hi if s > 0.0 else lo
    o = lo if cc == hi else hi
    if I[cc] == I[mid]:
        cc, o = o, cc
    i1, i2, i3 = o, mid, cc
    sig = ((i1 - i2) * (i2 - i3) * (i3 - i1)) // 2  # Levi-Civita: keeps Π proper
    ip[0], ip[1], ip[2], ip[3] = i1, i2, i3, sig
    J1, J2, J3 = I[i1], I[i2], I[i3]
    W1 = L[i1] / J1
    W2 = L[i2] / J2
    W3 = sig * L[i3] / J3
    D3 = W1 * W1 * J1 * (J3 - J1) + W2 * W2 * J2 * (J3 - J2)  # 2EJ₃ − |L|²
    D1 = W2 * W2 * J2 * (J2 - J1) + W3 * W3 * J3 * (J3 - J1)  # |L|² − 2EJ₁
    c[0], c[1], c[2] = J1, J2, J3
    c[8] = math.sqrt(G)
    if D3 == 0.0 or D1 == 0.0:
        ip[4] = PERMANENT  # a permanent rotation about a principal axis: ω fixed
        return ip, c, np.zeros((1, 3))
    a1 = math.sqrt(D3 / (J1 * (J3 - J1)))
    a2 = math.sqrt(D3 / (J2 * (J3 - J2)))
    a3 = math.sqrt(D1 / (J3 * (J3 - J1)))
    lam = math.sqrt((J3 - J2) * D1 / (J1 * J2 * J3))
    m = min(max((J2 - J1) * D3 / ((J3 - J2) * D1), 0.0), 1.0)
    D2 = W1 * W1 * J1 * (J1 - J2) + W3 * W3 * J3 * (J3 - J2)  # |L|² − 2EJ₂, same sign as J₃ − J₂
    m1 = min(max((J3 - J1) * D2 / ((J3 - J2) * D1), 0.0), 1.0)
    p = J1 * a1 * a1
    r = J2 * a2 * a2
    c[3], c[4], c[5], c[6], c[7], c[9], c[10], c[11] = a1, a2, a3, lam, m, p, r, m1
    # quadrature of ψ̇: Gauss–Legendre over pieces of at most ½√ρ in u, ρ = J₁p/(J₂r) ≤ 1 being
    # how sharp the integrand gets near sn = 0; a step shorter than that takes fewer nodes (GL_SPAN)
    v = lam * h
    du_max = 0.5 * math.sqrt(max(J1 * p / (J2 * r), 1e-6))
    if not abs(v) / du_max <= MAX_NSUB:
        raise StepTooLarge("free flow: step too large for this spin")
    nsub = max(1, int(math.ceil(abs(v) / du_max)))
    rule = GL_N.shape[0] - 1
    if nsub == 1:
        while rule > 0 and abs(v) <= GL_SPAN[rule - 1] * du_max:
            rule -= 1
    ip[5] = nsub
    ip[6] = rule
    n = GL_N[rule]
    tab = np.empty((1 + nsub * n, 3))
    dv = v / nsub
    if m >= 1e-9 and m1 >= 1e-3:  # `ellipj`'s Landen path, its sequence made once for all the nodes
        la, lc, top, twon = _landen(m, m1)
        tab[0, 0], tab[0, 1], tab[0, 2] = _landen_sn_cn_dn(v, m, m1, la, lc, top, twon)
        for j in range(nsub):
            for k in range(n):
                tab[1 + j * n + k, 0], tab[1 + j * n + k, 1], tab[1 + j * n + k, 2] = _landen_sn_cn_dn(
                    (j + GL_X[rule, k]) * dv, m, m1, la, lc, top, twon)
        return ip, c, tab
    tab[0, 0], tab[0, 1], tab[0, 2] = ellipj(v, m, m1)
    for j in range(nsub):
        for k in range(n):
            tab[1 + j * n + k, 0], tab[1 + j * n + k, 1], tab[1 + j * n + k, 2] = ellipj((j + GL_X[rule, k]) * dv, m, m1)
    return ip, c, tab


@nb.njit(cache=True, nogil=True)
def _add(sn0, cn0, dn0, snv, cnv, dnv, m):
    """Addition theorem: sn, cn, dn of u₀ + v from those of u₀ and of v."""
    den = 1.0 - m * sn0 * sn0 * snv * snv
    return (
        (sn0 * cnv * dnv + snv * cn0 * dn0) / den,
        (cn0 * cnv - sn0 * snv * dn0 * dnv) / den,
        (dn0 * dnv - m * sn0 * snv * cn0 * cnv) / den,
    )


@nb.njit(cache=True, nogil=True)
def _drift_symmetric(L, q, h, u, J, Ju, Lnorm):
    """The free flow of a body of revolution (moments J, J and Ju about its figure axis u) over h.
    With ω = L/J + Ω e_u, Ω = L_u (1/Ju − 1/J), Euler's equations give dL/dt = L × ω =
    Ω L × e_u: in the body L turns about the figure axis at −Ω while L_u stays (Landau &
    Lifshitz, Mechanics §33, the free symmetrical top), and the attitude is the composition of two
    uniform rotations, R(t) = rot(L_space, |L|t/J) · R(0) · rot(e_u, Ωt) (differentiate it: the
    body angular velocity is Rᵀ L_space/J + Ω e_u = ω). In the body's quaternion form
    q(t) = q(0) ⊗ rot(L_body(0), |L|t/J) ⊗ rot(e_u, Ωt)."""
    om = L[u] * (1.0 / Ju - 1.0 / J)
    dqa = _axis_angle_quat(L[0], L[1], L[2], Lnorm * h / J)
    e = np.zeros(3)
    e[u] = 1.0
    dqb = _axis_angle_quat(e[0], e[1], e[2], om * h)
    qn = quat_mul(quat_mul(q, dqa), dqb)
    qn = qn / math.sqrt(qn[0] * qn[0] + qn[1] * qn[1] + qn[2] * qn[2] + qn[3] * qn[3])
    # L_body(h) = rot(e_u, −Ωh) L_body(0)
    a, b = (u + 1) % 3, (u + 2) % 3
    cs, sn = math.cos(om * h), math.sin(om * h)
    Ln = np.empty(3)
    Ln[u] = L[u]
    Ln[a] = cs * L[a] + sn * L[b]
    Ln[b] = -sn * L[a] + cs * L[b]
    return Ln, qn


@nb.njit(cache=True, nogil=True)
def drift(L, q, I, h, ip, c, tab):
    """Advance body angular momentum L and attitude q (w,x,y,z) by the exact free flow over h,
    with the constants `prepare(L, I, h)` computed for the same invariants and step.
    Returns (L_new, q_new)."""
    kind = ip[4]
    if kind == SPHERE or h == 0.0:
        w0, w1, w2 = L[0] / I[0], L[1] / I[1], L[2] / I[2]
        wn = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
        if wn == 0.0:
            return L.copy(), q.copy()
        qn = quat_mul(q, _axis_angle_quat(w0, w1, w2, wn * h))
        return L.copy(), qn / math.sqrt(np.sum(qn * qn))
    if kind == SYMMETRIC:
        return _drift_symmetric(L, q, h, ip[0], c[0], c[2], c[8])
    i1, i2, i3, sig = ip[0], ip[1], ip[2], ip[3]
    J1, J2, J3 = c[0], c[1], c[2]
    Lnorm = c[8]
    W1 = L[i1] / J1
    W2 = L[i2] / J2
    W3 = sig * L[i3] / J3
    Wn = np.empty(3)
    if kind == PERMANENT:
        Wn[0], Wn[1], Wn[2] = W1, W2, W3
        dqp = _axis_angle_quat(W1, W2, W3, math.sqrt(W1 * W1 + W2 * W2 + W3 * W3) * h)
    else:
        a1, a2, a3, m, p, r, m1 = c[3], c[4], c[5], c[7], c[9], c[10], c[11]
        s3 = 1.0 if W3 >= 0.0 else -1.0
        sg2 = s3 if J3 > J1 else -s3
        # phase u₀ of the current state, put back on sn² + cn² = 1, dn² + m sn² = 1
        cn0 = W1 / a1
        sn0 = W2 / (sg2 * a2)
        nr = math.sqrt(sn0 * sn0 + cn0 * cn0)
        sn0 /= nr
        cn0 /= nr
        # dn from the orbit's constants, dn² = m1 + m·cn²: where the body passes its unstable axis
        # cn and dn are both ~k′ and their difference, which decides how long it lingers there,
        # is the separatrix gap m1 itself; taken from ω₃ it would be lost in ω₃'s rounding
        # accumulated where ω₁ and ω₃ are large (the flip)
        dn0 = math.sqrt(m1 + m * cn0 * cn0)
        sn1, cn1, dn1 = _add(sn0, cn0, dn0, tab[0, 0], tab[0, 1], tab[0, 2], m)
        nr = math.sqrt(sn1 * sn1 + cn1 * cn1)
        sn1 /= nr
        cn1 /= nr
        dn1 = math.sqrt(m1 + m * cn1 * cn1)
        Wn[0] = a1 * cn1
        Wn[1] = sg2 * a2 * sn1
        Wn[2] = s3 * a3 * dn1
        # ψ̇ = |L| (p cn² + r sn²) / (J₁ p cn² + J₂ r sn²), p = J₁a₁², r = J₂a₂²
        nsub, rule = ip[5], ip[6]
        n = GL_N[rule]
        acc = 0.0
        for j in range(nsub):
            for k in range(n):
                row = 1 + j * n + k
                snk, cnk, dnk = _add(sn0, cn0, dn0, tab[row, 0], tab[row, 1], tab[row, 2], m)
                c2 = cnk * cnk
                s2 = snk * snk
                acc += GL_W[rule, k] * (p * c2 + r * s2) / (J1 * p * c2 + J2 * r * s2)
        dpsi = Lnorm * acc * h / nsub
        P0 = _nutation_frame(J1 * W1 / Lnorm, J2 * W2 / Lnorm, J3 * W3 / Lnorm)
        P1 = _nutation_frame(J1 * Wn[0] / Lnorm, J2 * Wn[1] / Lnorm, J3 * Wn[2] / Lnorm)
        dqp = quat_from_matrix(_turned(P0, math.cos(dpsi), math.sin(dpsi), P1))
    # back to body coordinates: Δ = Πᵀ Δ' Π with Π's rows e_i1, e_i2, sig·e_i3; as a
    # quaternion that is the vector part permuted back
    dq = np.empty(4)
    dq[0] = dqp[0]
    dq[1 + i1] = dqp[1]
    dq[1 + i2] = dqp[2]
    dq[1 + i3] = sig * dqp[3]
    qn = quat_mul(q, dq)
    qn = qn / math.sqrt(qn[0] * qn[0] + qn[1] * qn[1] + qn[2] * qn[2] + qn[3] * qn[3])
    Ln = np.empty(3)
    Ln[i1] = J1 * Wn[0]
    Ln[i2] = J2 * Wn[1]
    Ln[i3] = sig * J3 * Wn[2]
    return Ln, qn


@nb.njit(cache=True, nogil=True)
def free_flow(L, q, I, h):
    """One exact free step from scratch (prepare + drift)."""
    ip, c, tab = prepare(L, I, h)
    return drift(L, q, I, h, ip, c, tab)
