"""Libration of a body spinning about its C axis while F moves in the plane normal to C
(Euler ch. 16, Problems 93–94, §825–838), and spin–orbit chaos (Hyperion).

Planar equations (derived again; modern units). Let λ be the angle of the body's A axis and
f the angle of F, both in the orbital plane from a fixed direction; ζ = f − λ is Euler's arc
AF. The §815 torque about C is R = 3GM/s³·(B−A)·cos ζ sin ζ, so
    C λ̈ = (3GM/2s³)(B−A) sin 2ζ,      ζ̈ = f̈ − (3GM/2s³)·γ·sin 2ζ,    γ = (B−A)/C.
For the circular orbit (§825) f̈ = 0 and Euler's equation dd ζ + N dt² sin 2ζ = 0 holds with
    N = 3GM(B−A)/(2Cs³)    (Euler writes 3gee(bb−aa)/(cc s³): his 2g is our 1, his Mbb our B).
With a Keplerian F, GM/s³ = n² (n the orbital rate δ), so N = (3/2)γn².

§831 small oscillations: ζ̈ + 2Nζ = 0, angular frequency √(2N) = n√(3γ), period π/… — Euler's
"time of one oscillation π/√(2n)" is the half period (there and back is 2π/√(2n)); his n is
our N. With θ = 2ζ this is a pendulum θ̈ + 2N sin θ = 0: the finite-amplitude period is
4K(k)/√(2N) with k = sin ζ_max (complete elliptic integral, modulus k).

Case II (B < A, §827): the equilibrium is ζ = 90° (the B axis toward F); everything holds
with φ = ζ − 90° and |N|. Below, φ = ζ − ζ_eq is the offset from the stable equilibrium.
"""
from __future__ import annotations

import numba as nb
import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ellipkm1

from . import hansen
from .kept import kept
from .params import ParameterError

CASES = ("locked", "librating", "separatrix", "circulating")


def euler_N(gamma, gm, s):
    """§825: N = 3GM(B−A)/(2Cs³) (Euler's n in §826, our units)."""
    return 1.5 * gm * gamma / s**3


def equilibrium_zeta(gamma):
    """Stable ζ: 0 (A axis toward F) for B > A (§826); π/2 (B axis toward F) for B < A (§827)."""
    return 0.0 if gamma >= 0 else 0.5 * np.pi


def small_oscillation_omega(gamma, gm, s):
    """§831: angular frequency √(2N) = √(3GM|γ|/s³) (= n√(3γ) on a Kepler circle)."""
    return np.sqrt(2.0 * abs(euler_N(gamma, gm, s)))


def small_oscillation_period(gamma, gm, s):
    """§831: full libration period 2π/√(2N). (Euler's π/√(2n) is the half swing there and back
    to F once; his n is our N.)"""
    return 2.0 * np.pi / small_oscillation_omega(gamma, gm, s)


def pendulum_modulus_sq(phi0, phidot0, omega0):
    """k² = sin²φ₀ + (φ̇₀/ω₀)² for φ̈ = −(ω₀²/2) sin 2φ; k < 1 libration, k > 1 circulation."""
    return np.sin(phi0) ** 2 + (phidot0 / omega0) ** 2


def pendulum_modulus_gap(phi0, phidot0, omega0):
    """1 − k² = cos²φ₀ − (φ̇₀/ω₀)², formed as (cos φ₀ − |φ̇₀|/ω₀)(cos φ₀ + |φ̇₀|/ω₀): near the
    separatrix (k² → 1) this keeps its relative precision where 1 − k² computed from k² is
    rounding noise (below ~1e-8 it would carry fewer than 8 digits; below 1e-16 none)."""
    c = np.cos(phi0)
    r = np.abs(phidot0) / omega0
    return (c - r) * (c + r)


def pendulum_period(phi0, phidot0, omega0):
    """Exact period of φ̈ = −(ω₀²/2) sin 2φ. Libration (k < 1): 4K(k)/ω₀ — the time to come back
    to the same state. Circulation (k > 1): 2K(1/k)/(k ω₀) — the time for φ to advance by π (the
    body turns half a turn relative to F; ζ and ζ+π are the same face pair). Separatrix: inf.
    K from the complementary parameter (`pendulum_modulus_gap`, scipy's ellipkm1), so starts
    within 1e-16 of the separatrix still get their (long, logarithmic) period."""
    k2 = pendulum_modulus_sq(phi0, phidot0, omega0)
    gap = pendulum_modulus_gap(phi0, phidot0, omega0)
    if gap > 0.0:
        return 4.0 * float(ellipkm1(gap)) / omega0
    if gap < 0.0:
        return 2.0 * float(ellipkm1(-gap / k2)) / (np.sqrt(k2) * omega0)  # 1 − 1/k² = −gap/k²
    return np.inf


def libration_amplitude(phi0, phidot0, omega0):
    """Largest |φ| of a libration: arcsin k (π/2 at and above the separatrix)."""
    k2 = pendulum_modulus_sq(phi0, phidot0, omega0)
    return float(np.arcsin(np.sqrt(k2))) if k2 < 1 else 0.5 * np.pi


def classify(phi0, phidot0, omega0, tol=1e-9):
    """Euler's four cases (§826): C = −n locked, −n < C < n librating (1st–2nd), C = n
    separatrix (3rd: 90° reached after infinite time), C > n circulating (4th)."""
    k2 = pendulum_modulus_sq(phi0, phidot0, omega0)
    gap = pendulum_modulus_gap(phi0, phidot0, omega0)
    if k2 < tol:
        return "locked"
    if abs(gap) < tol:
        return "separatrix"
    return "librating" if gap > 0 else "circulating"


def separatrix_rate(phi, omega0):
    """The separatrix φ̇ = ±ω₀ cos φ (§826 3rd: dζ/dt = √(2n)·cos ζ)."""
    return omega0 * np.cos(phi)


def separatrix_time_euler(phi, omega0):
    """§826 3rd: t = ln tan(45° + φ/2)/√(2n) on the separatrix from φ = 0."""
    return np.log(np.tan(0.25 * np.pi + 0.5 * np.asarray(phi))) / omega0


def measured_period(t, phi, circulating=False):
    """Period from a sampled φ(t): libration — mean spacing of upward zero crossings (linear
    interpolation of the crossing times; needs ≥ 2 crossings); circulation — time for the
    unwrapped φ to advance by π (fit of the crossing times of multiples of π)."""
    t = np.asarray(t, float)
    x = np.asarray(phi, float)
    if circulating:
        x = x / np.pi
        s = np.sign(x[-1] - x[0]) or 1.0
        x = s * x
        k = np.floor(x)
        idx = np.nonzero(k[1:] > k[:-1])[0]
    else:
        idx = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
        k = None
    if len(idx) < 2:
        return np.nan
    if circulating:
        lev = np.floor(x[idx + 1])
        tc = t[idx] + (lev - x[idx]) / (x[idx + 1] - x[idx]) * (t[idx + 1] - t[idx])
    else:
        tc = t[idx] - x[idx] / (x[idx + 1] - x[idx]) * (t[idx + 1] - t[idx])
    return float((tc[-1] - tc[0]) / (len(tc) - 1))


# ---------------------------------------------------------------- §833–838, eccentric orbit

def forced_amplitude_euler(alpha, A, N):
    """§833: ζ = A²α/(A² − 2N)·sin At (first harmonic). On a Kepler ellipse α = 2e, A = δ = n,
    2N = 3γn², so ζ = 2e/(1 − 3γ) sin M. Resonance (failure) at A² = 2N."""
    return A * A * alpha / (A * A - 2.0 * N)


def second_order_euler(alpha, beta, A, N):
    """§835 (Euler, with N ≪ A²): coefficient of sin 2At, nαβ/(4(A² − 2n)).
    Rederived without N ≪ A²: N β A² α /((A² − 2N)(4A² − 2N)). On a real ellipse the true
    anomaly also has (5/4)e² sin 2M, which adds 5e²A²/(4A² − 2N) to the sin 2At term (not in
    Euler's parametrisation XF = δt + α sin At, which stops at first order)."""
    return N * alpha * beta / (4.0 * (A * A - 2.0 * N))


def second_order_full(alpha, beta, A, N):
    m = forced_amplitude_euler(alpha, A, N)
    return N * beta * m / (4.0 * A * A - 2.0 * N)


def planar_rhs(orbit, gamma, gm):
    """y = (λ, λ̇): C λ̈ = (3GM/2r³)(B−A) sin 2(f − λ) for an orbit with anomalies_at(t) (f, r at one t)."""

    def rhs(t, y):
        f, r = orbit.anomalies_at(t)
        return [y[1], 1.5 * gm * gamma / r**3 * np.sin(2.0 * (f - y[0]))]

    return rhs


def periodic_libration(orbit, gamma, gm, guess=(0.0, None), rtol=1e-12, atol=1e-13, iters=40, max_cuts=3,
                       max_misses=2, progress=None):
    """§838's forced libration: the solution with the orbit's period (free part zero), by
    Newton shooting on (λ(0), λ̇(0)) − the orbit starts at periapse (t_peri = 0). Returns
    (λ0, λ̇0, P) with P the orbital period. Fails (ParameterError) near resonance.

    The Jacobian comes from the variational equations integrated with the orbit (one run per
    iteration, not five as with central differences); steps are capped at 0.3 (stay on the branch
    of the guess) and halved up to `max_cuts` times until the residual falls. When none lowers it
    the capped step is taken anyway, and after more than `max_misses` such steps in a row the search
    gives up (e.g. e = 0.5 with (B−A)/C = −0.45, chaotic: refused in seconds where the fixed-step
    search took two minutes). `progress(frac)` is called once per run (frac ≤ 0.1: the set-up)."""
    P = 2.0 * np.pi / orbit.n
    y = np.array([guess[0], orbit.true_anomaly_rate(np.array([0.0]))[0] if guess[1] is None else guess[1]])
    runs = [0]

    def rhs(t, z):  # (λ, λ̇) and the 2×2 matrix Φ = ∂(λ, λ̇)(t)/∂(λ, λ̇)(0), row-major
        f, r = orbit.anomalies_at(t)
        c = 1.5 * gm * gamma / r ** 3
        k = -2.0 * c * np.cos(2.0 * (f - z[0]))  # ∂λ̈/∂λ
        return [z[1], c * np.sin(2.0 * (f - z[0])), z[4], z[5], k * z[2], k * z[3]]

    def shoot(y):
        runs[0] += 1
        if progress is not None:
            progress(min(0.1, 0.1 * runs[0] / (2 * iters)))
        z = solve_ivp(rhs, (0.0, P), [y[0], y[1], 1.0, 0.0, 0.0, 1.0], method="DOP853", rtol=rtol, atol=atol).y[:, -1]
        r = z[:2] - y - np.array([2.0 * np.pi, 0.0])
        return r, z[2:].reshape(2, 2) - np.eye(2)

    r, J = shoot(y)
    misses = 0
    for _ in range(iters):
        res = float(np.max(np.abs(r)))
        if not np.isfinite(res):
            break
        if res < 1e-11:
            return y[0], y[1], P
        try:
            dy = np.linalg.solve(J, r)
        except np.linalg.LinAlgError:
            break
        step = dy * min(1.0, 0.3 / max(float(np.max(np.abs(dy))), 1e-300))  # damped: stay near the guess
        first = None
        for _cut in range(max_cuts + 1):
            r_new, J_new = shoot(y - step)
            first = first or (step, r_new, J_new)
            if float(np.max(np.abs(r_new))) < res:
                misses = 0
                break
            step = 0.5 * step
        else:  # no step along Newton's direction lowers the residual: take the capped one anyway (it
            # may lead out of a bad region), but give up after `max_misses` such steps in a row
            misses += 1
            if misses > max_misses:
                break
            step, r_new, J_new = first
        y, r, J = y - step, r_new, J_new
    raise ParameterError("eccentricity", orbit.e, f"small enough for a forced (periodic) libration with asymmetry "
                         f"(B−A)/C = {gamma:g}; none was found: lower eccentricity, or move asymmetry away from "
                         "the resonance (B−A)/C = ±1/3")


def free_libration_floquet(orbit, gamma, gm, lam0, lamdot0, rtol=1e-12, atol=1e-13, d=1e-6, near=None):
    """Frequency of small free librations about the forced (periodic) solution (λ0, λ̇0) of §838,
    with nothing of the ellipse neglected (beyond Euler's 2N: the 1/s³ modulation, the forced
    swing's cos 2ζ, all orders in e): the Floquet exponent ν of the linearised flow over one
    orbit, from the monodromy matrix M (central differences of DOP853 runs): tr M = 2 cos νP.
    tr M fixes νP only up to its sign and whole turns: the branch returned is the one nearest `near`
    (Euler's √(2N); the first branch, in (0, π/P), when None), so that a free swing faster than n/2
    ((B − A)/C > 1/12) gets its own frequency, not its alias. NaN when the forced solution is
    unstable (|tr M| > 2). Not valid for small-amplitude nonlinearity: a free swing of amplitude φ
    lengthens the period further by φ²/4 (the pendulum's K(k))."""
    P = 2.0 * np.pi / orbit.n
    c = 0.5 * np.trace(_monodromy(orbit, gamma, gm, lam0, lamdot0, rtol, atol, d))
    if abs(c) > 1:
        return float("nan")
    a = float(np.arccos(c))
    if near is None:
        return a / P
    k = np.arange(0, int(near * P / (2 * np.pi)) + 2)
    branches = np.concatenate([2 * np.pi * k + a, 2 * np.pi * k[1:] - a]) / P
    return float(branches[np.argmin(np.abs(branches - near))])


def _monodromy(orbit, gamma, gm, lam0, lamdot0, rtol, atol, d):
    """The monodromy matrix of the linearised flow over one orbit about (λ0, λ̇0), by central
    differences of DOP853 runs. A rate is measured in units of n: the nudge to λ̇ and its absolute
    tolerance are d·n and atol·n (with n = 10⁻⁶ a nudge of 10⁻⁶ to λ̇ was a swing as large as the
    orbit's own rate, and the period came out 67 % off)."""
    P = 2.0 * np.pi / orbit.n
    rhs = planar_rhs(orbit, gamma, gm)
    y0 = np.array([lam0, lamdot0], float)
    scale = np.array([1.0, orbit.n])

    def flow(y):
        return solve_ivp(rhs, (0.0, P), y, method="DOP853", rtol=rtol, atol=atol * scale).y[:, -1]

    return np.column_stack([(flow(y0 + d * s * e_) - flow(y0 - d * s * e_)) / (2 * d * s)
                            for s, e_ in zip(scale, np.eye(2))])


def monodromy_half_trace(orbit, gamma, gm, lam0, lamdot0, rtol=1e-12, atol=1e-13, d=1e-6):
    """½ tr M of the linearised flow over one orbit about the forced (periodic) solution (λ0, λ̇0)
    (central differences of DOP853 runs): |½ tr M| ≤ 1, the forced libration is stable (a body
    near it librates about it); > 1, it is unstable (tr M > 2: a saddle, < −2: period doubling)."""
    return float(0.5 * np.trace(_monodromy(orbit, gamma, gm, lam0, lamdot0, rtol, atol, d)))


def leaves_libration(e, gamma, lam0, lamdot0, forced_lam0, orbits=10, steps_per_orbit=256):
    """Whether a body started at periapse with (λ0, λ̇0) (time unit 1/n) leaves the libration about
    the forced solution (which passes periapse at `forced_lam0`, the same at every periapse) within
    `orbits`: its angle from the forced one, sampled at every periapse, reaches a quarter turn (ζ and
    ζ + π being the same face pair, π/2 is where it would go over to the next). The planar equation
    is that of `spin_orbit_section` with ω₀² = 3|γ| (B < A: the B axis, i.e. λ − π/2, plays the
    long axis). Returns (left, largest |angle| seen in rad, orbit where it left or None)."""
    shift = 0.0 if gamma >= 0 else 0.5 * np.pi
    th, _ = spin_orbit_section([lam0 - shift], [lamdot0], e, np.sqrt(3.0 * abs(gamma)), int(orbits), steps_per_orbit)
    k = np.arange(1, int(orbits) + 1)
    phi = th[0] - (forced_lam0 - shift) - 2.0 * np.pi * k
    phi0 = lam0 - forced_lam0
    phi = phi - np.pi * np.round((phi0) / np.pi)  # on the branch of the start
    big = np.nonzero(np.abs(phi) >= 0.5 * np.pi)[0]
    return bool(len(big)), float(np.max(np.abs(phi))), (int(big[0]) + 1 if len(big) else None)


def harmonics(t, x, omega, k_max=3):
    """Least-squares amplitudes of x(t) ≈ c + Σ_k a_k sin kωt + b_k cos kωt, returns
    (a, b) arrays of length k_max (index 0 ↔ k = 1)."""
    cols = [np.ones_like(t)]
    for k in range(1, k_max + 1):
        cols += [np.sin(k * omega * t), np.cos(k * omega * t)]
    coef, *_ = np.linalg.lstsq(np.stack(cols, 1), x, rcond=None)
    return coef[1::2], coef[2::2]


# ---------------------------------------------------------------- spin–orbit chaos (Hyperion)

def goldreich_peale_H(p, e):
    """Goldreich & Peale's (1966) coefficient H(p, e) of the spin–orbit resonance θ̇ = p·n,
    exact: the Hansen coefficient X^{−3,2}_{2p}(e) by quadrature over one orbit
    (`physics.hansen`), for any half-integer p and e < 1. Their truncated series in e is
    `hansen.goldreich_peale_series` (at e = 0.5 it puts the 5/2 width 11 % low)."""
    return hansen.hansen_H(p, e)


def resonance_half_width(p, e, omega0):
    """Half-width in θ̇/n of the p resonance: ω₀√|H(p,e)|, ω₀² = 3(B−A)/C (the averaged
    pendulum γ̈ = −(ω₀²/2)H sin 2γ, γ = θ − pM, has separatrix |γ̇| ≤ ω₀√|H|), H exact."""
    return hansen.resonance_half_width(p, e, omega0)


def resonance_centre_angle(p, e):
    """θ mod π of the island centre at periapse: 0 if H > 0 (long axis to the planet), π/2 if
    H < 0 (the 1/2 resonance)."""
    return 0.0 if goldreich_peale_H(p, e) > 0 else 0.5 * np.pi


_W1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
_W0 = -(2.0 ** (1.0 / 3.0)) * _W1
# Symmetric kick–drift schemes for θ̈ = F(θ, t): kick c_j·h, then drift d_j·h (last drift 0).
_BM_B = (0.0829844064174052, 0.396309801498368, -0.0390563049223486)
_BM_A = (0.245298957184271, 0.604872665711080)
_Y6 = [0.0, -1.17767998417887, 0.235573213359357, 0.784513610477560]
_Y6[0] = 1.0 - 2.0 * sum(_Y6[1:])
SCHEMES = {
    # Yoshida (1990) triple jump of leapfrog: order 4, 3 force evaluations per step
    "yoshida4": (np.array([_W1 / 2, (_W1 + _W0) / 2, (_W0 + _W1) / 2, _W1 / 2]),
                 np.array([_W1, _W0, _W1, 0.0])),
    # Yoshida (1990) solution A: order 6, 7 evaluations per step
    "yoshida6": (np.array([_Y6[3] / 2, (_Y6[3] + _Y6[2]) / 2, (_Y6[2] + _Y6[1]) / 2, (_Y6[1] + _Y6[0]) / 2,
                           (_Y6[0] + _Y6[1]) / 2, (_Y6[1] + _Y6[2]) / 2, (_Y6[2] + _Y6[3]) / 2, _Y6[3] / 2]),
                 np.array([_Y6[3], _Y6[2], _Y6[1], _Y6[0], _Y6[1], _Y6[2], _Y6[3], 0.0])),
    # Blanes & Moan (2002) SRKN_6^b: order 4, 6 evaluations per step, error constant ~100×
    # smaller than Yoshida's
    "blanes-moan4": (np.array([_BM_B[0], _BM_B[1], _BM_B[2], 1 - 2 * sum(_BM_B), _BM_B[2], _BM_B[1], _BM_B[0]]),
                     np.array([_BM_A[0], _BM_A[1], 0.5 - sum(_BM_A), 0.5 - sum(_BM_A), _BM_A[1], _BM_A[0], 0.0])),
}


_ORBIT_TABLES: dict = {}  # (e, steps per orbit, drifts) → table (shared: never written to)
_ORBIT_TABLES_MAX = 32


def _orbit_table(e, steps_per_orbit, drifts):
    """(a/r)³, sin 2f, cos 2f at every kick time of one orbit (n = 1, periapse at t = 0). The
    table is periodic, so it is computed once for the whole run, and kept: a search for a
    resonance's fixed point (`periapse_fixed_point`) maps hundreds of sections of one orbit, and
    solving Kepler's equation for each was 3/4 of a Hyperion run."""
    key = (float(e), int(steps_per_orbit), tuple(float(x) for x in np.ravel(drifts)))
    hit = _ORBIT_TABLES.get(key)
    if hit is not None:
        return hit
    from .orbits import KeplerOrbit

    h = 2.0 * np.pi / steps_per_orbit
    at = np.concatenate([[0.0], np.cumsum(drifts)[:-1]])
    tk = h * (np.arange(steps_per_orbit)[:, None] + at[None, :])
    f, r = KeplerOrbit(a=1.0, e=e, n=1.0).anomalies(tk.ravel())
    table = ((1.0 / r**3).reshape(tk.shape), np.sin(2 * f).reshape(tk.shape), np.cos(2 * f).reshape(tk.shape))
    if len(_ORBIT_TABLES) >= _ORBIT_TABLES_MAX:
        _ORBIT_TABLES.pop(next(iter(_ORBIT_TABLES)))
    _ORBIT_TABLES[key] = table
    return table


@nb.njit(cache=True, inline="always", fastmath=True)
def _rot_small(x):
    """sin x, cos x by Taylor series to degree 15/16: exact to round-off for |x| ≤ 0.8."""
    x2 = x * x
    sx = x * (1.0 - x2 * (1.0 / 6.0) * (1.0 - x2 * (1.0 / 20.0) * (1.0 - x2 * (1.0 / 42.0) * (
        1.0 - x2 * (1.0 / 72.0) * (1.0 - x2 * (1.0 / 110.0) * (1.0 - x2 * (1.0 / 156.0) * (
            1.0 - x2 * (1.0 / 210.0))))))))
    cx = 1.0 - x2 * 0.5 * (1.0 - x2 * (1.0 / 12.0) * (1.0 - x2 * (1.0 / 30.0) * (1.0 - x2 * (1.0 / 56.0) * (
        1.0 - x2 * (1.0 / 90.0) * (1.0 - x2 * (1.0 / 132.0) * (1.0 - x2 * (1.0 / 182.0) * (
            1.0 - x2 * (1.0 / 240.0))))))))
    return sx, cx


@nb.njit(cache=True, fastmath=True)
def _kick_drift(thetadot, theta, sn, cs, g, cf, sf, d, scale):
    for i in range(theta.shape[0]):
        w = thetadot[i] - g * (sn[i] * cf - cs[i] * sf)
        thetadot[i] = w
        st = d * w
        theta[i] += st
        sx, cx = _rot_small(2.0 * st)
        a0 = sn[i]
        sn[i] = a0 * cx + cs[i] * sx
        cs[i] = cs[i] * cx - a0 * sx


@nb.njit(cache=True, fastmath=True)
def _kick_drift_halved(thetadot, theta, sn, cs, g, cf, sf, d, scale, p):
    for i in range(theta.shape[0]):
        w = thetadot[i] - g * (sn[i] * cf - cs[i] * sf)
        thetadot[i] = w
        st = d * w
        theta[i] += st
        sx, cx = _rot_small(2.0 * st * scale)
        for _ in range(p):
            sx, cx = 2.0 * sx * cx, cx * cx - sx * sx
        a0 = sn[i]
        sn[i] = a0 * cx + cs[i] * sx
        cs[i] = cs[i] * cx - a0 * sx


@nb.njit(cache=True)
def _section_run(theta, thetadot, k, s2f, c2f, h, n_orbits, ck, dk, out_theta, out_dot, lyap_on, dth, ddot, lyap_sum,
                 pending=False, finish=True):
    """The kick–drift chain for the whole ensemble, the ensemble in the innermost loop (no
    dependence between starts: the compiler vectorises it). The last kick of a step and the
    first of the next act at the same time and θ, so they are merged. `pending`: the last kick of
    an earlier piece is still to come, merged into this piece's first; `finish`: apply the last
    kick at the end (the whole run's last piece). A run cut into pieces thus rounds exactly as
    one uncut run: merged and split kicks round differently, and in the chaotic sea that
    last-bit difference grew into another Lyapunov exponent (Hyperion's preview: 0.88 against
    0.93 per orbit when the app, which cuts runs to report progress, ran it). sin 2θ and cos 2θ are
    carried along and rotated by each drift with a Taylor series (degree 15/16, exact to
    round-off for angles ≤ 0.8; larger angles are halved p times and doubled back), and
    re-synchronised from θ at every periapse, so rounding cannot accumulate."""
    n = theta.shape[0]
    m = s2f.shape[0]
    K = ck.shape[0]
    sn = np.empty(n)
    cs = np.empty(n)
    dmax = np.max(np.abs(dk)) * h
    for orb in range(n_orbits):
        wmax = 0.0
        for i in range(n):
            sn[i] = np.sin(2.0 * theta[i])
            cs[i] = np.cos(2.0 * theta[i])
            wmax = max(wmax, abs(thetadot[i]))
        # halvings so that the rotation angle stays ≤ 0.8 (velocity can grow within an orbit
        # by at most ∫|θ̈| ≤ 2π·ω₀²/2·max(a/r)³; margin: 2× the start-of-orbit value + 4)
        p = 0
        xmax = 2.0 * dmax * (2.0 * wmax + 4.0)
        while xmax > 0.8:
            xmax *= 0.5
            p += 1
        scale = 0.5**p
        for s in range(m):
            for j in range(K - 1):
                if j == 0:
                    c = ck[0] + (ck[K - 1] if (orb > 0 or s > 0 or pending) else 0.0)
                else:
                    c = ck[j]
                g = k[s, j] * c * h
                cf = c2f[s, j]
                sf = s2f[s, j]
                d = dk[j] * h
                if lyap_on:
                    for i in range(n):
                        # tangent map: δθ̈ = −ω₀²(a/r)³ cos 2(θ − f) δθ, at the kick's θ
                        ddot[i] -= 2.0 * g * (cs[i] * cf + sn[i] * sf) * dth[i]
                        dth[i] += d * ddot[i]
                if p == 0:
                    _kick_drift(thetadot, theta, sn, cs, g, cf, sf, d, 1.0)
                else:
                    _kick_drift_halved(thetadot, theta, sn, cs, g, cf, sf, d, scale, p)
        # periapse: the pending last kick applied for the record only
        g = k[0, 0] * ck[K - 1] * h
        for i in range(n):
            s0 = np.sin(2.0 * theta[i])
            c0 = np.cos(2.0 * theta[i])
            out_theta[i, orb] = theta[i]
            out_dot[i, orb] = thetadot[i] - g * (s0 * c2f[0, 0] - c0 * s2f[0, 0])
            if lyap_on:
                b_rec = ddot[i] - 2.0 * g * (c0 * c2f[0, 0] + s0 * s2f[0, 0]) * dth[i]
                nrm = np.sqrt(dth[i] * dth[i] + b_rec * b_rec)
                lyap_sum[i] += np.log(nrm)
                dth[i] /= nrm
                ddot[i] /= nrm
    if not finish:
        return
    g = k[0, 0] * ck[K - 1] * h
    for i in range(n):
        s0 = np.sin(2.0 * theta[i])
        c0 = np.cos(2.0 * theta[i])
        thetadot[i] -= g * (s0 * c2f[0, 0] - c0 * s2f[0, 0])
        ddot[i] -= 2.0 * g * (c0 * c2f[0, 0] + s0 * s2f[0, 0]) * dth[i]


SECTION_CHUNKS = 40  # with a progress callback: the orbits in this many compiled pieces


def spin_orbit_section(theta0, thetadot0, e, omega0, n_orbits, steps_per_orbit=128, lyapunov=False,
                       scheme="blanes-moan4", progress=None):
    """Surface of section of the planar spin–orbit problem θ̈ = −(ω₀²/2)(a/r)³ sin 2(θ − f)
    (time unit 1/n, periapse at t = 0, 2π, …), for an ensemble of starts at periapse.

    Fixed-step 4th-order symplectic kick–drift (Blanes & Moan 2002, or Yoshida 1990) with the
    orbit tabulated once per period; compiled with numba, one loop over the ensemble. Returns
    (θ, θ̇) of shape (N, n_orbits) at the periapse passages 1..n_orbits (θ unwrapped; take
    mod π to plot) and, if `lyapunov`, the largest Lyapunov exponent per start (per unit time,
    n = 1) from the tangent map renormalised every orbit. `progress(frac)`, if given, is called
    between pieces of about 1/SECTION_CHUNKS of the orbits (it may raise to stop the run); the
    pieces round exactly as one uncut run, so the result does not depend on `progress`."""
    ck, dk = SCHEMES[scheme]
    th = np.array(theta0, float).ravel().copy()
    wd = np.broadcast_to(np.asarray(thetadot0, float), th.shape).astype(float).copy()
    rr, s2f, c2f = _orbit_table(e, steps_per_orbit, dk)
    k = 0.5 * omega0**2 * rr
    h = 2.0 * np.pi / steps_per_orbit
    N = th.shape[0]
    out_t = np.empty((N, n_orbits))
    out_w = np.empty((N, n_orbits))
    a = np.ones(N)
    b = np.zeros(N)
    lsum = np.zeros(N)
    if progress is None:
        _section_run(th, wd, k, s2f, c2f, h, int(n_orbits), ck, dk, out_t, out_w, bool(lyapunov), a, b, lsum,
                     False, True)
    else:
        per = max(1, int(n_orbits) // SECTION_CHUNKS)
        for start in range(0, int(n_orbits), per):
            m = min(per, int(n_orbits) - start)
            pt, pw = np.empty((N, m)), np.empty((N, m))
            _section_run(th, wd, k, s2f, c2f, h, m, ck, dk, pt, pw, bool(lyapunov), a, b, lsum,
                         start > 0, start + m >= int(n_orbits))
            out_t[:, start:start + m] = pt
            out_w[:, start:start + m] = pw
            progress((start + m) / n_orbits)
    if lyapunov:
        return out_t, out_w, lsum / (2.0 * np.pi * n_orbits)
    return out_t, out_w


def spin_orbit_rhs_vectorised(e, omega0):
    """scipy reference/baseline: y = (θ₁..θ_N, θ̇₁..θ̇_N), the whole ensemble in one state."""
    from .orbits import KeplerOrbit

    orb = KeplerOrbit(a=1.0, e=e, n=1.0)

    def rhs(t, y):
        f, r = orb.anomalies_at(t)
        N = y.shape[0] // 2
        out = np.empty_like(y)
        out[:N] = y[N:]
        out[N:] = -0.5 * omega0**2 / r ** 3 * np.sin(2.0 * (y[:N] - f))
        return out

    return rhs


def spin_orbit_section_scipy(theta0, thetadot0, e, omega0, n_orbits, rtol=1e-10, atol=1e-12):
    """The same section with scipy DOP853 (ensemble in one state vector), sampled at periapse."""
    th = np.array(theta0, float).ravel()
    wd = np.broadcast_to(np.asarray(thetadot0, float), th.shape).astype(float)
    T = 2.0 * np.pi * np.arange(1, n_orbits + 1)
    sol = solve_ivp(spin_orbit_rhs_vectorised(e, omega0), (0.0, T[-1]), np.concatenate([th, wd]),
                    method="DOP853", rtol=rtol, atol=atol, t_eval=T)
    N = th.shape[0]
    return sol.y[:N], sol.y[N:]


def periapse_fixed_point(theta_guess, dot_guess, e, omega0, steps_per_orbit=256, iters=60, winding=None):
    """A fixed point of the periapse map (θ mod π, θ̇): Newton on one orbit's map with central
    differences. `winding`: the half-turns k that θ makes in one orbit (k = 2p for the p
    resonance, mean rate θ̇/n = p); without it any k is accepted (θ mod π), so Newton may end on
    another resonance's orbit. Returns (θ, θ̇) or raises ParameterError if Newton does not converge."""
    y = np.array([theta_guess, dot_guess], float)
    d = 1e-6
    shifts = np.array([[0, 0], [d, 0], [-d, 0], [0, d], [0, -d]], float)

    for _ in range(iters):
        # the point and its four neighbours as one ensemble of five starts: one compiled call
        # where five cost five calls' overhead (a Hyperion preview spent 0.06 s of its 0.09 s here)
        pts = y + shifts
        t, w = spin_orbit_section(pts[:, 0], pts[:, 1], e, omega0, 1, steps_per_orbit)
        dt = t[:, 0] - pts[:, 0]
        k = np.round(dt / np.pi) if winding is None else winding
        F = np.stack([dt - np.pi * k, w[:, 0] - pts[:, 1]], axis=1)
        r = F[0]
        if np.max(np.abs(r)) < 1e-10:
            return float(np.remainder(y[0] + 0.5 * np.pi, np.pi) - 0.5 * np.pi), float(y[1])
        J = np.column_stack([(F[1] - F[2]) / (2 * d), (F[3] - F[4]) / (2 * d)])
        dy = np.linalg.solve(J, r)
        y = y - dy * min(1.0, 0.05 / max(abs(dy[1]), 1e-300), 0.2 / max(abs(dy[0]), 1e-300))  # damped: stay local
    raise ParameterError("omega0", omega0, "no periodic spin state found near this start")


def periapse_map_trace(theta, thetadot, e, omega0, steps_per_orbit=128, d=1e-6):
    """Trace of the Jacobian of the periapse map at (θ, θ̇) (determinant 1: area preserving).
    |trace| < 2: elliptic (an island centre); > 2: hyperbolic."""
    pts = np.array([theta, thetadot], float) + np.array([[d, 0], [-d, 0], [0, d], [0, -d]], float)
    t, w = spin_orbit_section(pts[:, 0], pts[:, 1], e, omega0, 1, steps_per_orbit)
    return float((t[0, 0] - t[1, 0]) / (2 * d) + (w[2, 0] - w[3, 0]) / (2 * d))


@kept(64)  # moving a slider other than e or ω₀ reuses it
def continue_resonance(p, e, omega0, dw=0.05, steps_per_orbit=128, min_dw=0.05 / 64):
    """Follow the p resonance's fixed point of the periapse map from small ω₀ (where it sits at
    Goldreich & Peale's centre: θ = 0 or π/2, θ̇ = p) up to `omega0`, in steps of dw.
    The orbit keeps its winding (θ advances 2πp per orbit) and its symmetry line (θ = 0 or π/2
    at periapse); θ̇ is predicted by the secant through the last two points, and a step whose
    Newton has not converged in 12 iterations is halved (down to min_dw; it grows back after a
    success). At e = 0.5 the periapse rate of the 2:1 orbit falls by ~3.5 per unit ω₀: from the
    last point alone, at a fixed 0.05 step, Newton lost the 2:1 orbit at ω₀ = 1.35, and the 1:1
    and 3:2 searches, which accepted any winding, ended on the 2:1 orbit (checked against a
    scipy solve: tests/test_islands_independent.py). Returns (θ, θ̇, trace) at omega0; raises ParameterError if the branch is lost."""
    th_c = resonance_centre_angle(p, e)
    k = round(2 * p)
    w, th, wd, prev = 0.0, th_c, float(p), None
    step = dw
    while w < omega0:
        w1 = omega0 if omega0 - w < step * (1 + 1e-9) else w + step
        guess = wd if prev is None else wd + (wd - prev[1]) * (w1 - w) / (w - prev[0])
        try:
            th1, wd1 = periapse_fixed_point(th, guess, e, w1, steps_per_orbit=steps_per_orbit, iters=12, winding=k)
            if abs(np.remainder(th1 - th_c + 0.5 * np.pi, np.pi) - 0.5 * np.pi) > 1e-6:
                raise ParameterError("omega0", w1, "the periodic orbit left its symmetry line")
        except ParameterError:
            step *= 0.5
            if step < min_dw:
                raise ParameterError("omega0", omega0, f"the {p:g} resonance's periodic orbit lost near ω₀ = {w:.3g}")
            continue
        prev, (w, th, wd) = (w, wd), (w1, th1, wd1)
        step = min(dw, 2 * step)
    return th, wd, periapse_map_trace(th, wd, e, omega0, steps_per_orbit)
