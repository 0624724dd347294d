"""Precession and nutation of a spinning body: Euler's Problems 95–96 (ch. 16, §840–849),
derived again, and the least-squares extraction of precession and nutation from a simulated
pole.

Notation (Euler → here)
-----------------------
Euler writes the moments as Maa, Mbb, Mcc about his principal poles A, B, C and the force of
the centre as "equal to gravity at distance e", so his 6g·ee multiplies the torque where the
modern gravity-gradient torque (§815, MacCullagh) has 3GM:  2g·ee = GM  (his g is half the
modern acceleration of gravity, the convention of his Mechanica, v² = 4g·height). Hence every
``3gee`` of §843–849 is ``3GM/2`` here.

For Problem 96 the body is axisymmetric: Euler's singular axis A (moment aa) is our body z with
moment C, his equal equatorial moments bb = cc are our A = B. The centre of force F moves on a
great circle (our XY plane, the "ecliptic") at the angular rate δ; the body spins at ε in the
same sense. Euler's Z is the pole of that circle (our +Z), p = ZA the colatitude of the figure
axis ("obliquity"), λ = XZA its longitude, φ = FZA = λ − δt. GM/s³ is written ``tidal``
(= δ² for a centre that orbits the body, Kepler's third law).

What Euler neglected, and what it costs (derived below, measured in tests/test_precession.py)
-------------------------------------------------------------------------------------------
§840 drops the gyroscopic terms (aa−cc)/bb·xz of the Euler equations because y, z vanish at the
instant considered. Kept in Problem 96 they turn the rotation of the small offset of the pole
from ε into ε' = ε·C/A (the free wobble in space turns at |L|/A = εC/A, not ε). Redoing §844
with ε' in equations 4–5 (and ε kept in the kinematic equations 1–3) gives the corrected linear
theory ``linear_theory(..., corrected=True)``:
  * mean precession  −N cos n · A/C instead of −N cos n: Euler's rate is too fast by the factor
    C/A = 1 + (C−A)/A (0.33% for the Earth, 10% for a flattening of 0.1);
  * the resonance sits at ε' = 2δ, i.e. ε/δ = 2A/C, not at ε/δ = 2.
The other neglected terms are of relative order N/δ (he holds p, λ constant inside equations
4–5 and sets dφ = −δ dt although dφ = −(δ + N cos n) dt), the nutation amplitude itself
(sin p, cos p not expanded), and α² (the offset of the pole).

Typos in the translation (checked by the derivation and by the simulation)
------------------------------------------------------------------------
  * §840: the displayed γ'dβ and γ'dγ lack a minus sign: dy = −γ'dβ, so
    γ'dβ = −6gee(aa−cc)cosζ cosθ dt/(bb s³) (as §841 itself then writes for bb = cc).
  * §844: in the second display of x and y the coefficient of sin 2φ is printed
    N sin n (ε − 2δ cos n)/(εε − 4δδ); it is N sin n (ε + 2δ cos n)/(εε − 4δδ), the G found
    just before and used again in §848.
  * §844: "dv + εv dφ/δ = 0" should read dv + εu dφ/δ = 0.
  * §844: the pair of equations "2Ndt sin p sin(A − λt)…" writes A − λt for λ − δt.
  * §847 prints −h sin (ε/δ)(φ + ζ) in ZA where §844 (correctly, from dp = −εy dt) has +h.
  * §849: the maximal prosthaphaeresis of the longitude (corrected by C. H. in the Opera
    Omnia) is printed εN sin n (ε + 2δ cos n)/(2δ(εε − 4δδ)); integrating dλ = εx dt/sin p with
    §844's x gives εN(ε cos n + 2δ)/(2δ(εε − 4δδ)), which is what §844 itself has.
  * §846, §848 print N = 3gee(aa−cc)/(eccs³) for ε·cc·s³.
Everything else of §840–849 (including the resonant solution of §849) checks out.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Where the printed text (Bruce's translation of §840–849) is wrong, for the app to show
TYPOS_840_843 = (
    "§840: γ'dβ and γ'dγ are printed without their minus sign (dy = −γ'dβ); §841 has it right.",
)
TYPOS_844_849 = (
    "§844: the second display of y prints N sin n(ε − 2δ cos n)/(εε − 4δδ); it is (ε + 2δ cos n), the G found just before.",
    "§844: 'dv + εv dφ/δ = 0' should read dv + εu dφ/δ = 0; 'sin(A − λt)' stands for sin(λ − δt).",
    "§847 prints −h sin(ε/δ)(φ + ζ) in ZA; §844's +h is what dp = −εy dt gives.",
    "§849: the maximal prosthaphaeresis of the longitude is εN(ε cos n + 2δ)/(2δ(εε − 4δδ)) (as in §844), "
    "not εN sin n(ε + 2δ cos n)/(2δ(εε − 4δδ)) as printed.",
    "§846, §848: N = 3gee(aa − cc)/(eccs³) stands for 3gee(aa − cc)/(ε cc s³).",
)


# --------------------------------------------------------------------------------------------
# §840–843: the momentary motion of the pole near a principal axis
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PoleRates:
    """Euler §840: rates of change of the spin γ' and of the arcs β = OB, γ = OC from the pole
    of rotation O (close to the principal pole A) to the principal poles B, C."""

    dspin_dt: np.ndarray  # dγ'/dt (scalar for scalar inputs)
    dbeta_dt: np.ndarray  # dβ/dt
    dgamma_dt: np.ndarray  # dγ/dt

    @property
    def pole_speed(self) -> float:
        """|Oo|/dt = √(dβ² + dγ²)/dt (§840)."""
        return np.hypot(self.dbeta_dt, self.dgamma_dt)


def _last_axis(x):
    """The three components of x (..., 3) as arrays (broadcasting over the leading axes)."""
    x = np.asarray(x, float)
    return x[..., 0], x[..., 1], x[..., 2]


def pole_rates_840(moments, spin, cosines, tidal) -> PoleRates:
    """Euler §840: momentary change of the spin and of the pole of rotation O ≈ A.

    moments = (aa, bb, cc): Euler's moments about A (the pole O is near), B, C (any units; only
    ratios and the torque/moment enter). spin = γ'. cosines = (cos ζ, cos η, cos θ): direction
    cosines of the line to the centre of forces F with the axes A, B, C. tidal = GM/s³.

        dγ'/dt = 3GM(cc − bb) cos η cos θ / (aa s³)
        γ' dβ/dt = −3GM(aa − cc) cos ζ cos θ / (bb s³)      (§840 prints it without the minus)
        γ' dγ/dt = −3GM(bb − aa) cos ζ cos η / (cc s³)

    Exact at the instant O = A (the gyroscopic terms Euler drops, (aa−cc)/bb·xz etc., vanish
    there); for O at a distance α from A they add the free wobble γ'(aa−cc)/bb·α.

    Array inputs broadcast: moments and cosines (..., 3), spin and tidal (...)."""
    a, b, c = _last_axis(moments)
    cz, ce, ct = _last_axis(cosines)
    k = 3.0 * np.asarray(tidal, float)
    spin = np.asarray(spin, float)
    return PoleRates(
        dspin_dt=k * (c - b) * ce * ct / a,
        dbeta_dt=-k * (a - c) * cz * ct / (b * spin),
        dgamma_dt=-k * (b - a) * cz * ce / (c * spin),
    )


def equal_moments_841(moments, spin, cosines, tidal) -> dict:
    """Euler §841–843, bb = cc: the spin does not change, dβ cos η + dγ cos θ = 0 (the pole O
    moves at right angles to the arc FO, §842), with speed

        |Oo|/dt = 2N cos ζ sin ζ,   N = 3GM(aa − cc)/(2 γ' cc s³)      (§843 [a])

    and, if aa > cc, "around A in the sense CB" (§843): the displacement of O from A, written
    on the B, C axes, is 2N cos ζ (cos θ, −cos η) dt, i.e. the projection of F turned by −90°.
    Returns N, the speed, and the unit direction (on B, C, last axis) of the displacement of O.
    Array inputs broadcast as in `pole_rates_840`."""
    a, b, c = _last_axis(moments)
    cz, ce, ct = _last_axis(cosines)
    N = 1.5 * np.asarray(tidal, float) * (a - c) / (np.asarray(spin, float) * c)
    sin_zeta = np.sqrt(np.clip(1.0 - cz * cz, 0.0, None))
    d = np.stack(np.broadcast_arrays(ct, -ce), axis=-1)
    nd = np.linalg.norm(d, axis=-1, keepdims=True)
    sgn = np.where(N * cz != 0, np.sign(N * cz), 1.0)[..., None]
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(nd > 0, d / np.where(nd > 0, nd, 1.0), d)
    return dict(N=N, pole_speed=2.0 * np.abs(N * cz) * sin_zeta, direction_BC=unit * sgn)


# --------------------------------------------------------------------------------------------
# §844–849: precession and nutation of an oblate body under a centre moving on a circle
# --------------------------------------------------------------------------------------------

def euler_N(tidal, C, A, spin) -> float:
    """Euler's N of §844: N = 3gee(aa − cc)/(ε cc s³) = 3GM(C − A)/(2 A ε s³).

    (Euler's aa is the polar moment C, cc the equatorial A.) The mean precession of the
    figure axis is −N cos n (§846); the corrected theory has N·A/C."""
    return 1.5 * tidal * (C - A) / (A * spin)


@dataclass(frozen=True)
class LinearTheory:
    """Euler's solution of §844 (or its corrected form, ε → ε' = εC/A in equations 4–5).

    Pole of the figure axis, with φ = λ − δt (φ₀ its value at t = 0, the mean motion of φ taken
    as −δ as Euler does):
        p(t) = n − a_p cos 2φ + (ε/ε') h sin(ε'(t₀ − t))                (ZA, obliquity)
        λ(t) = m + rate·t + a_λ sin 2φ + (ε/ε') h/sin n · cos(ε'(t₀ − t))   (XZA, longitude)
    a_p = εG/(2δ), a_λ = −εF/(2δ sin n); x = E + F cos 2φ + u, y = G sin 2φ + v.
    """

    N: float
    eps: float  # spin ε
    eps_gyro: float  # ε (Euler) or ε' = εC/A (corrected)
    delta: float
    n: float  # mean obliquity (rad)
    E: float
    F: float
    G: float

    @property
    def precession_rate(self) -> float:
        """dλ/dt of the mean pole: εE/sin n = −N cos n·ε/ε' (§846: −N cos n)."""
        return self.eps * self.E / np.sin(self.n)

    @property
    def obliquity_amplitude(self) -> float:
        """a_p: p = n − a_p cos 2φ. §849: max − min of ZA is 2a_p = εN sin n(ε + 2δ cos n)/(δ(εε − 4δδ))."""
        return self.eps * self.G / (2.0 * self.delta)

    @property
    def longitude_amplitude(self) -> float:
        """a_λ: λ = m − N t cos n + a_λ sin 2φ; a_λ = εN(ε cos n + 2δ)/(2δ(εε − 4δδ)) (§844)."""
        return -self.eps * self.F / (2.0 * self.delta * np.sin(self.n))

    def offset(self, phi):
        """(x, y) of the forced offset of the pole of rotation O from the figure axis A (§844):
        x = α cos ω = E + F cos 2φ, y = α sin ω = G sin 2φ, ω = ZAO."""
        phi = np.asarray(phi, float)
        return self.E + self.F * np.cos(2 * phi), self.G * np.sin(2 * phi)

    def pole(self, t, m, h=0.0, t0=0.0):
        """(p, λ) of the figure axis at times t (§844, §847), φ = m − δt, free part of
        amplitude h with phase zero at t = t0."""
        t = np.asarray(t, float)
        phi = m - self.delta * t
        r = self.eps / self.eps_gyro
        th = self.eps_gyro * (t0 - t)
        p = self.n - self.obliquity_amplitude * np.cos(2 * phi) + r * h * np.sin(th)
        lam = m + self.precession_rate * t + self.longitude_amplitude * np.sin(2 * phi) \
            + r * h / np.sin(self.n) * np.cos(th)
        return p, lam


def linear_theory(N, eps, delta, n, C_over_A=1.0, corrected=False) -> LinearTheory:
    """The particular solution of §844 (equations 4–5 with p = n, dφ = −δ dt):

        dx/dt + ε' y = N sin n sin 2φ,   dy/dt − ε' x = N sin n cos n (1 + cos 2φ)

    E = −N sin n cos n/ε', F = −N sin n(ε' cos n + 2δ)/(ε'² − 4δ²),
    G = N sin n(ε' + 2δ cos n)/(ε'² − 4δ²).  Euler: ε' = ε. Corrected (the gyroscopic term
    Euler dropped in §840 kept): ε' = ε·C/A. Diverges at ε' = 2δ (§849)."""
    eg = eps * (C_over_A if corrected else 1.0)
    s, c = np.sin(n), np.cos(n)
    den = eg * eg - 4.0 * delta * delta
    with np.errstate(divide="ignore"):
        F = -N * s * (eg * c + 2 * delta) / den if den != 0 else np.inf
        G = N * s * (eg + 2 * delta * c) / den if den != 0 else np.inf
    return LinearTheory(N, eps, eg, delta, n, -N * s * c / eg, F, G)


def resonance_849(N, delta, n) -> dict:
    """Euler §849, ε = 2δ: x = E + F cos 2φ + 𝔄φ sin 2φ, y = G sin 2φ + 𝔅φ cos 2φ with
    E = −N sin n cos n/(2δ), 𝔄 = 𝔅 = −N sin n(1 + cos n)/(2δ), F + G = N sin n(1 − cos n)/(4δ)
    (checked: these satisfy equations 4–5). Since φ = φ₀ − δt the offset α = √(x² + y²) of
    the pole of rotation grows without bound, at the mean rate |𝔄|δ = N sin n(1 + cos n)/2."""
    s, c = np.sin(n), np.cos(n)
    AB = -N * s * (1 + c) / (2 * delta)
    return dict(E=-N * s * c / (2 * delta), A=AB, B=AB, F_plus_G=N * s * (1 - c) / (4 * delta),
                alpha_growth_rate=abs(AB) * delta)


def precession_rate_circular(tidal, C, A, spin, obliquity) -> float:
    """Modern averaged precession of the angular momentum (≈ figure) axis under a centre on a
    circle in the reference plane: −(3/2)(GM/s³)(C − A)/(C ω) cos n.  Equals Euler's −N cos n
    times A/C."""
    return -1.5 * tidal * (C - A) / (C * spin) * np.cos(obliquity)


def precession_rate_orbit(gm, a, e, inc, H, spin, obliquity) -> float:
    """Modern mean precession rate (rad per time) of a spinning axisymmetric body with
    dynamical ellipticity H = (C − A)/C under a mass on a Keplerian orbit (a, e) whose plane is
    inclined by `inc` to the reference plane with a node that circulates (averaged over it):

        −(3/2) GM/(a³(1 − e²)^{3/2}) · H/ω · cos n · (1 − (3/2) sin² inc)

    (the orbit-averaged quadrupole torque; e.g. Lambeck, The Earth's Variable Rotation, §9.1).
    Euler's §846 value is this with e = 0, inc = 0 and A in place of C."""
    return -1.5 * gm / (a ** 3 * (1 - e * e) ** 1.5) * H / spin * np.cos(obliquity) * (1 - 1.5 * np.sin(inc) ** 2)


# --------------------------------------------------------------------------------------------
# Extraction of precession and nutation from a simulated pole (least squares)
# --------------------------------------------------------------------------------------------

def pole_angles(axis):
    """Obliquity p (angle from +Z) and unwrapped longitude λ of unit vectors (N,3)."""
    axis = np.asarray(axis, float)
    p = np.arccos(np.clip(axis[:, 2] / np.linalg.norm(axis, axis=1), -1.0, 1.0))
    lam = np.unwrap(np.arctan2(axis[:, 1], axis[:, 0]))
    return p, lam


@dataclass
class PoleFit:
    """Least-squares fit of λ(t) and p(t) to c₀ + c₁t (+ c₂t²) + Σ_k (s_k sin θ_k + c_k cos θ_k)."""

    rate_longitude: float  # dλ/dt of the mean pole (rad per time unit)
    rate_obliquity: float
    longitude: dict  # name → (sin coefficient, cos coefficient) in rad
    obliquity: dict
    rms_longitude: float
    rms_obliquity: float
    mean_obliquity: float

    def amplitude(self, name, which="longitude"):
        s, c = (self.longitude if which == "longitude" else self.obliquity)[name]
        return float(np.hypot(s, c))


def fit_pole(t, axis, arguments: dict, quadratic=False) -> PoleFit:
    """Fit the pole path (unit vectors (N,3) at times t) by linear least squares.

    arguments: name → θ_k(t) array (N,) (e.g. 2φ, the Moon's node Ω, 2L☉). The coefficients
    of sin θ_k and cos θ_k in λ and in p are returned; λ and p also get a constant and a
    secular term (t centred on the middle of the run, so the rate is the mean rate)."""
    t = np.asarray(t, float)
    p, lam = pole_angles(axis)
    tc = t - 0.5 * (t[0] + t[-1])
    cols = [np.ones_like(t), tc] + ([tc * tc] if quadratic else [])
    names = list(arguments)
    for k in names:
        th = np.asarray(arguments[k], float)
        cols += [np.sin(th), np.cos(th)]
    M = np.stack(cols, axis=1)
    scale = np.max(np.abs(M), axis=0)
    scale[scale == 0] = 1.0
    out = []
    coefs, *_ = np.linalg.lstsq(M / scale, np.stack([lam, p], 1), rcond=None)
    for j, y in enumerate((lam, p)):
        coef = coefs[:, j] / scale
        res = y - M @ coef
        out.append((coef, float(np.sqrt(np.mean(res * res)))))
    j0 = 3 if quadratic else 2
    dl = {k: (float(out[0][0][j0 + 2 * i]), float(out[0][0][j0 + 2 * i + 1])) for i, k in enumerate(names)}
    do = {k: (float(out[1][0][j0 + 2 * i]), float(out[1][0][j0 + 2 * i + 1])) for i, k in enumerate(names)}
    return PoleFit(float(out[0][0][1]), float(out[1][0][1]), dl, do, out[0][1], out[1][1], float(out[1][0][0]))


def mean_longitude(t, direction):
    """Mean longitude θ₀ + θ̇t of a body from its directions (N,3): a straight line fitted to
    the unwrapped true longitude (eccentricity and perturbation terms average out over many
    revolutions). Returns (θ₀, θ̇, θ_mean(t))."""
    t = np.asarray(t, float)
    lam = np.unwrap(np.arctan2(direction[:, 1], direction[:, 0]))
    c1, c0 = np.polyfit(t, lam, 1)
    return float(c0), float(c1), c0 + c1 * t
