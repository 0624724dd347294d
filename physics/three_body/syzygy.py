"""Euler 1766, *Considerationes de motu corporum coelestium* (seed 003, §5–§16), as the circular
restricted three-body problem.

The Moon kept in perpetual conjunction (or opposition) with the Sun. Units: the Sun's mean
distance a = 1 and the mean motion of the Sun–Earth orbit 1 (time unit = 1/2π sidereal year),
Earth at the origin, the Sun on a circle (Euler: u = a, θ = ζ, §11). The Moon is massless.

Masses. `m` is the mass ratio M_earth/M_sun (3.0035e-6). Kepler's third law for the Sun–Earth
orbit gives n² a³ = G(M_sun + M_earth): with G·M_sun = 1 the mean motion is √(1 + m), or, in
the units used here (mean motion 1), G(M_sun + M_earth) = 1 and
    G·M_earth = μ,  G·M_sun = 1 − μ,   μ = m/(1 + m).
Euler's own constant m = n²c³/a³ (§7; n: lunar revolutions per year, c: the Moon's distance)
is this μ: n²c³ = G·M_earth (a massless Moon) and a³ = G(M_sun + M_earth) by his own equation
for the Sun (§5, ddu − u dθ² + a³/u² = 0). His §5 equations for the Moon then use the same a³
for the Sun's pull on the Moon, where the Sun alone pulls with a³(1 − μ): Euler's model is the
restricted problem with the Sun's attraction too large by the factor 1 + m. The difference is of
relative order m in the distance (−2μ/9) and the frequency, invisible at the Earth's mass ratio
(3e-6), 0.2 % and 0.4 % at m = 0.01. (A frame turning at rate 1 with G·M_sun = 1, i.e. without
the (1 + m) of Kepler's law, makes the same error.)

In the frame turning with the Sun (Sun fixed at (1, 0)) the restricted problem reads

    ẍ − 2ẏ − x = −μ x/r³ + (1 − μ)[(1 − x)/ρ³ − 1],   ÿ + 2ẋ − y = −μ y/r³ − (1 − μ) y/ρ³,

r = |(x, y)|, ρ = |(1 − x, −y)|; the "−1" is the Sun's pull on the Earth (the indirect term).

The collinear points (the syzygy): the Moon at x = γ (conjunction, L1) or x = −γ (opposition,
L2), γ the positive root of the quintics (Szebehely 1967, *Theory of Orbits*, §4.5)
    L1:  γ⁵ − (3 − μ)γ⁴ + (3 − 2μ)γ³ − μγ² + 2μγ − μ = 0,
    L2:  γ⁵ + (3 − μ)γ⁴ + (3 − 2μ)γ³ − μγ² − 2μγ − μ = 0,
(the force balance on the x axis multiplied out, derived in `collinear_quintic`). The same points
are roots of Euler's 1767 quintic (`collinear.lagrange_alphas`), an independent route.

Linearised about a collinear point, with c₂ = μ/γ³ + (1 − μ)/(1 ∓ γ)³,
    ẍ − 2ẏ = (1 + 2c₂) x,   ÿ + 2ẋ = (1 − c₂) y,
    s⁴ + (2 − c₂)s² + (1 + 2c₂)(1 − c₂) = 0,
    ω² = (2 − c₂ + √(9c₂² − 8c₂))/2 (the swing),   λ² = (c₂ − 2 + √(9c₂² − 8c₂))/2 (the escape).
In Hill's limit (μ → 0) c₂ → 4 and this is Euler's λ⁴ − 2λ² − 27 = 0 (§16).

Results and the text's errors:
- §7: conjunction at v = αa with m(1−α)² = α² − α²(1−α)³ (re-derived for Euler's model,
  correct). The substitution printed as "2 − α = x, mx² = (1−x³)(1−x)²" must be x = 1 − α.
- §8: Euler's series α = ε − ⅓ε² − m/27 + mε/81, ε = (m/3)^{1/3}. The first three terms are
  right (m/27 = ε³/9); the fourth is not: expanding the equation gives
  α = ε − ε²/3 − ε³/9 + 4ε⁴/81 + 16ε⁵/243 …, i.e. the last term must be 4mε/243, not
  mε/81 = 3mε/243 (`series_conjunction` has the corrected coefficients; tests check both
  against the root of Euler's equation: the printed 4-term series errs by ≈ ε⁴/81).
- §9: opposition: m(1+α)² = α²(1+α)³ − α² (the text prints (1−α)³, a typo; its own remark
  "take m and α negative" gives (1+α)³); series α = ε + ε²/3 − ε³/9 − 4ε⁴/81 (the text's
  "m³" in the last term is m, and its coefficient 1/81 is again 4/243).
- §12–16: Hill's approximation (u ≫ v) linearised about v = b, η = 0 gives
  η̈ + 2ẋ + 3η = 0, ẍ − 9x − 2η̇ = 0 (x = v/b − 1, m = 3 at equilibrium), whose characteristic
  equation is λ⁴ − 2λ² − 27 = 0. Euler takes λ = iα: α⁴ + 2α² = 27, α² = √28 − 1,
  α = 2.071594 and v = b(1 − 0.311717 A cos ω). The other pair, λ² = 1 + √28, is real:
  λ = ±2.5083 — the equilibrium is unstable and the Moon leaves after a few swings. Euler,
  having assumed an oscillation, did not see it.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from .. import constants as C

# Euler's numbers (1766 §8, §16)
EULER_N_SQUARED = 175.0  # "n² = 175": (lunar revolutions per year)²
HILL_FREQUENCY = math.sqrt(math.sqrt(28.0) - 1.0)  # α of §16, 2.0715939...
HILL_ESCAPE_EXPONENT = math.sqrt(math.sqrt(28.0) + 1.0)  # the real root Euler missed, 2.5083...
AMPLITUDE_COEFFICIENT = (HILL_FREQUENCY**2 - 3.0) / (2.0 * HILL_FREQUENCY)  # 0.311717 (§16)

# Earth/Sun mass ratio GM⊕/GM☉ (3.0034896e-6; sources in physics.constants)
EARTH_SUN_MASS_RATIO = C.GM_EARTH_KM3_S2 / C.GM_SUN_KM3_S2
# sidereal year 365.256363 d / sidereal month 27.3216615 d (sources in physics.constants)
MOON_REVOLUTIONS_PER_YEAR = C.SIDEREAL_YEAR_DAYS / C.SIDEREAL_MONTH_DAYS


def reduced_mass(m: float) -> float:
    """μ = G·M_earth / G(M_sun + M_earth) = m/(1 + m) for the mass ratio m = M_earth/M_sun; it is
    also Euler's m = n²c³/a³ of §7 (module docstring)."""
    m = float(m)
    return m / (1.0 + m)


def _check_side(side: str) -> None:
    if side not in ("conjunction", "opposition"):
        raise ValueError(f"side must be 'conjunction' or 'opposition', not {side!r}")


def collinear_quintic(m: float, side: str = "conjunction") -> np.ndarray:
    """Coefficients (highest power first) of the quintic whose positive root is γ, the Moon's
    distance from the Earth at the collinear point, in units of the Sun–Earth distance.

    Conjunction (L1, x = γ): the x force balance in the turning frame,
        γ − (1 − μ) + (1 − μ)/(1 − γ)² − μ/γ² = 0,
    times γ²(1 − γ)²:  γ⁵ − (3 − μ)γ⁴ + (3 − 2μ)γ³ − μγ² + 2μγ − μ = 0.
    Opposition (L2, x = −γ):  −γ − (1 − μ) + (1 − μ)/(1 + γ)² + μ/γ² = 0, times −γ²(1 + γ)²:
        γ⁵ + (3 − μ)γ⁴ + (3 − 2μ)γ³ − μγ² − 2μγ − μ = 0.
    (Szebehely 1967, §4.5, with μ = m/(1 + m).)"""
    _check_side(side)
    mu = reduced_mass(m)
    if side == "conjunction":
        return np.array([1.0, -(3.0 - mu), 3.0 - 2.0 * mu, -mu, 2.0 * mu, -mu])
    return np.array([1.0, 3.0 - mu, 3.0 - 2.0 * mu, -mu, -2.0 * mu, -mu])


def _quintic_root(m: float, side: str) -> float:
    """The physical root: the one in (0, 1) for L1 (the force balance is monotonic between the
    bodies), the single positive root for L2 (one change of sign: Descartes)."""
    c = collinear_quintic(m, side)
    f = lambda g: float(np.polyval(c, g))  # noqa: E731
    hi = 1.0 - 1e-15 if side == "conjunction" else 2.0
    return float(brentq(f, 1e-300, hi, xtol=1e-300, rtol=1e-15, maxiter=400))


def equilibrium_conjunction(m: float) -> float:
    """α = γ = v/a for the Moon between Earth and Sun (the Sun–Earth L1): the root in (0, 1) of
    the restricted problem's quintic (`collinear_quintic`), m = M_earth/M_sun."""
    return _quintic_root(m, "conjunction")


def equilibrium_opposition(m: float) -> float:
    """α = γ = v/a for the Moon beyond the Earth (the Sun–Earth L2): the positive root of the
    restricted problem's quintic, m = M_earth/M_sun."""
    return _quintic_root(m, "opposition")


def euler_equilibrium_conjunction(m_euler: float) -> float:
    """Euler's own α (1766 §7): root in (0, 1) of m(1−α)² = α² − α²(1−α)³, with his
    m = n²c³/a³ (= μ, `reduced_mass`). His model pulls the Moon toward the Sun with a³ where the
    Sun alone gives a³(1 − μ): the root is short of the restricted problem's by 2μ/9 (relative, to
    first order: the extra pull adds ≈ 2μα to a force balance of slope ≈ 9)."""
    m = m_euler
    f = lambda a: m * (1 - a) ** 2 - a * a + a * a * (1 - a) ** 3  # noqa: E731
    return float(brentq(f, 1e-12, 1 - 1e-12, xtol=1e-16, rtol=1e-15))


def euler_equilibrium_opposition(m_euler: float) -> float:
    """Euler's own α beyond the Earth: root of m(1+α)² = α²(1+α)³ − α² (1766 §9, corrected: the
    text prints (1−α)³), m = n²c³/a³."""
    m = m_euler
    f = lambda a: m * (1 + a) ** 2 - a * a * (1 + a) ** 3 + a * a  # noqa: E731
    return float(brentq(f, 1e-12, 2.0, xtol=1e-16, rtol=1e-15))


def euler_series_conjunction(m: float, terms: int = 4) -> float:
    """Euler's series (1766 §8): α = (m/3)^{1/3} − ⅓(m²/9)^{1/3} − m/27 + m(m/3)^{1/3}/81
    (his m = n²c³/a³)."""
    e = (m / 3.0) ** (1.0 / 3.0)
    parts = [e, -(m * m / 9.0) ** (1.0 / 3.0) / 3.0, -m / 27.0, m * e / 81.0]
    return float(sum(parts[:terms]))


def euler_series_opposition(m: float, terms: int = 4) -> float:
    """Euler's series (1766 §9): α = (m/3)^{1/3} + ⅓(m²/9)^{1/3} − m/27 − m(m/3)^{1/3}/81
    (the text's "m³" in the last term read as m)."""
    e = (m / 3.0) ** (1.0 / 3.0)
    parts = [e, (m * m / 9.0) ** (1.0 / 3.0) / 3.0, -m / 27.0, -m * e / 81.0]
    return float(sum(parts[:terms]))


def series_conjunction(m: float) -> float:
    """The series of §8 with the fourth coefficient corrected: ε − ε²/3 − ε³/9 + 4ε⁴/81 + 16ε⁵/243
    (an expansion of the root of Euler's §7 equation, his m)."""
    e = (m / 3.0) ** (1.0 / 3.0)
    return e - e**2 / 3 - e**3 / 9 + 4 * e**4 / 81 + 16 * e**5 / 243


def series_opposition(m: float) -> float:
    """The series of §9 (α → −α, m → −m in §8), corrected: ε + ε²/3 − ε³/9 − 4ε⁴/81 + 16ε⁵/243."""
    e = (m / 3.0) ** (1.0 / 3.0)
    return e + e**2 / 3 - e**3 / 9 - 4 * e**4 / 81 + 16 * e**5 / 243


def lunar_units_per_sun_distance(m: float, n: float) -> float:
    """a/c, the Sun's distance in lunar distances, from Kepler's third law for both orbits:
    n²c³/a³ = G·M_earth/G(M_sun + M_earth) = μ (1766 §7), so a/c = (n²/μ)^{1/3} =
    (n²(1 + m)/m)^{1/3}; n = lunar revolutions per year, m = M_earth/M_sun."""
    return (n * n / reduced_mass(m)) ** (1.0 / 3.0)


def rhs_rotating(t, s, m):
    """The restricted problem in the frame turning with the Sun, Earth at the origin (module
    docstring); m = M_earth/M_sun."""
    mu = m / (1.0 + m)
    x, y, vx, vy = s
    r3 = (x * x + y * y) ** 1.5
    dx = 1.0 - x
    rho3 = (dx * dx + y * y) ** 1.5
    ax = 2 * vy + x - mu * x / r3 + (1.0 - mu) * (dx / rho3 - 1.0)
    ay = -2 * vx + y - mu * y / r3 - (1.0 - mu) * y / rho3
    return np.array([vx, vy, ax, ay])


def jacobian(m: float, x0: float, h: float | None = None) -> np.ndarray:
    """Jacobian of `rhs_rotating` at the point (x0, 0, 0, 0), central differences (a check on
    the closed form of `linear_modes`)."""
    h = h or 1e-6 * abs(x0)
    s0 = np.array([x0, 0.0, 0.0, 0.0])
    J = np.empty((4, 4))
    for k in range(4):
        d = np.zeros(4)
        d[k] = h
        J[:, k] = (rhs_rotating(0, s0 + d, m) - rhs_rotating(0, s0 - d, m)) / (2 * h)
    return J


def stiffness_c2(m: float, side: str = "conjunction") -> float:
    """c₂ = μ/γ³ + (1 − μ)/(1 ∓ γ)³ at the collinear point (−: conjunction, +: opposition):
    the restricted problem's Hessian there is diag(1 + 2c₂, 1 − c₂) (Richardson 1980)."""
    _check_side(side)
    mu = reduced_mass(m)
    g = equilibrium_conjunction(m) if side == "conjunction" else equilibrium_opposition(m)
    rho = 1.0 - g if side == "conjunction" else 1.0 + g
    return mu / g**3 + (1.0 - mu) / rho**3


def linear_modes(m: float, side: str = "conjunction") -> dict:
    """The restricted problem linearised at the collinear point, in closed form.

    With Uxx = 1 + 2c₂, Uyy = 1 − c₂ (`stiffness_c2`), the characteristic equation
    s⁴ + (2 − c₂)s² + Uxx·Uyy = 0 has s² = −ω² (the swing) and s² = λ² (the escape), with
    ω² = (2 − c₂ + √(9c₂² − 8c₂))/2, λ² = (c₂ − 2 + √(9c₂² − 8c₂))/2. The eigenvector of s is
    (1, k, s, s·k) with k = (s² − Uxx)/(2s) (from ẍ − 2ẏ = Uxx x). Euler's λ⁴ − 2λ² − 27 = 0
    is the case c₂ = 4."""
    _check_side(side)
    g = equilibrium_conjunction(m) if side == "conjunction" else equilibrium_opposition(m)
    x0 = g if side == "conjunction" else -g
    c2 = stiffness_c2(m, side)
    uxx = 1.0 + 2.0 * c2
    root = math.sqrt(9.0 * c2 * c2 - 8.0 * c2)
    w = math.sqrt(0.5 * (2.0 - c2 + root))
    lam = math.sqrt(0.5 * (c2 - 2.0 + root))

    def vec(s):
        k = (s * s - uxx) / (2.0 * s)
        return np.array([1.0, k, s, s * k], dtype=complex if isinstance(s, complex) else float)

    eig = np.array([1j * w, -1j * w, lam, -lam])
    return {"x0": x0, "c2": c2, "frequency": w, "escape_exponent": lam,
            "osc_vector": vec(1j * w), "escape_vector": vec(lam), "eigenvalues": eig}


def hill_frequencies() -> tuple[float, float]:
    """Roots of Euler's characteristic equation λ⁴ − 2λ² − 27 = 0 (1766 §16, Hill's limit):
    (oscillation frequency √(√28−1), escape exponent √(√28+1))."""
    return HILL_FREQUENCY, HILL_ESCAPE_EXPONENT


def hill_first_order_coefficient(side: str = "conjunction") -> float:
    """c₁ in ω_linear/ω_Hill = 1 + c₁α + O(α²), α = v/a at syzygy: the size of what Euler's
    u ≫ v approximation (1766 §12) neglects in the swing frequency.

    Linearising the restricted problem (module docstring) at (x₀, 0):
    ẍ − 2ẏ = Kxx x, ÿ + 2ẋ = Kyy y with Kxx = 1 + 2c₂, Kyy = 1 − c₂, c₂ = μ/α³ + (1 − μ)/ρ³,
    ρ = 1 ∓ α. The equilibrium gives μ/α³ = 1 + (1 − μ)[(1−α)⁻² − 1]/α = 3 + 3α + O(α²) at
    conjunction (μ = O(α³)), and 1/ρ³ = 1 + 3α + O(α²), so Kxx = 9 + 12α, Kyy = −3 − 6α
    (Hill/Euler: 9 and −3). ω² solves ω⁴ + (Kxx + Kyy − 4)ω² + Kxx·Kyy = 0, i.e.
    ω⁴ + (2 + 6α)ω² − (27 + 90α) = 0; to first order ω² = √28 − 1 + α(24/√7 − 3), so
    c₁ = (24/√7 − 3)/(2(2√7 − 1)) = 0.70735. At opposition α → −α (the Moon beyond the Earth):
    c₁ → −c₁. The O(α²) remainder has a coefficient ≈ 0.9 (measured on `linear_modes`, both
    sides)."""
    c1 = (24.0 / math.sqrt(7.0) - 3.0) / (2.0 * (2.0 * math.sqrt(7.0) - 1.0))
    return c1 if side == "conjunction" else -c1


def euler_oscillation(b: float, amplitude: float, t, side: str = "conjunction"):
    """Euler's first-order solution (1766 §16): η = A sin αt, v = b(1 − 0.311717·A cos αt)."""
    t = np.asarray(t, float)
    w = HILL_FREQUENCY
    return amplitude * np.sin(w * t), b * (1.0 + AMPLITUDE_COEFFICIENT * -amplitude * np.cos(w * t))


def initial_state(m: float, amplitude: float, side: str = "conjunction", start: str = "euler",
                  escape_seed: float = 0.0) -> np.ndarray:
    """Rotating-frame state (x, y, ẋ, ẏ) at ω = 0 of Euler's oscillation: η = 0, η̇ = αA,
    v = b(1 − 0.3117 A) ("euler"), or on the exact linear centre mode with the same η̇
    ("linear-mode"); plus `escape_seed`·b along the unstable eigenvector."""
    modes = linear_modes(m, side)
    x0 = modes["x0"]
    b = abs(x0)
    sgn = 1.0 if side == "conjunction" else -1.0
    if start == "euler":
        v = b * (1.0 - AMPLITUDE_COEFFICIENT * amplitude)
        etadot = HILL_FREQUENCY * amplitude
        # η measured from the Sun line (conjunction) or from its prolongation (opposition)
        s = np.array([sgn * v, 0.0, 0.0, sgn * v * etadot])
    else:
        # the centre mode: real part of c·V e^{iωt}; choose the phase where y = 0, ẏ = v·η̇ > 0
        V = modes["osc_vector"]
        c = 1.0 / V[1] if abs(V[1]) > 0 else 1.0
        Vr = c * V  # y component = 1 (real) → at t = π/(2ω) later y = 0 ...
        # state at the phase where y = 0: take Im part (quarter period) scaled to η̇ = ωA
        s_mode = np.imag(Vr)  # y = 0 here
        scale = sgn * b * modes["frequency"] * amplitude / s_mode[3] if s_mode[3] != 0 else 0.0
        s = np.array([x0, 0.0, 0.0, 0.0]) + scale * s_mode
        s[3] = abs(s[3]) * sgn
    if escape_seed:
        e = modes["escape_vector"]
        s = s + escape_seed * b * e / np.linalg.norm(e[:2])
    return s


def integrate(m: float, s0, t_end: float, n_samples: int = 2000, rtol: float = 1e-12, atol: float = 1e-15,
              leave_factor: float = 3.0, progress=None):
    """Integrate the rotating-frame equations (DOP853) until t_end or until the Moon leaves
    (distance outside [b/leave_factor, b·leave_factor] or |η| > 90°). Returns t, states (N,4)."""
    b = math.hypot(s0[0], s0[1])
    sgn = np.sign(s0[0])

    def leave(t, s, *_):
        r = math.hypot(s[0], s[1])
        eta = math.atan2(sgn * s[1], sgn * s[0])
        return min(r / b - 1.0 / leave_factor, leave_factor - r / b, math.pi / 2 - abs(eta))

    leave.terminal = True
    t_eval = np.linspace(0.0, t_end, n_samples)
    from .nbody import with_progress  # progress(frac) every 200 evaluations; it may raise to stop the run

    sol = solve_ivp(with_progress(rhs_rotating, 0.0, t_end, progress), (0.0, t_end), np.asarray(s0, float),
                    method="DOP853", t_eval=t_eval,
                    args=(m,), rtol=rtol, atol=atol, events=leave, dense_output=True)
    return sol.t, sol.y.T, sol


def eta_and_distance(states: np.ndarray, side: str = "conjunction"):
    """Euler's variables: η (angle of the Moon from the Sun line, from its prolongation for
    opposition) and v (distance from the Earth)."""
    x, y = states[:, 0], states[:, 1]
    if side != "conjunction":
        x, y = -x, -y
    return np.arctan2(y, x), np.hypot(x, y)


def measured_frequency(t, eta, max_eta: float) -> tuple[float, int]:
    """Frequency from the zero crossings of η while |η| ≤ max_eta (before the escape):
    ω = π·(number of half periods)/(time between first and last crossing)."""
    ok = np.abs(eta) <= max_eta
    stop = np.argmin(ok) if not np.all(ok) else len(eta)
    t, eta = t[:stop], eta[:stop]
    s = np.sign(eta)
    idx = np.nonzero(s[:-1] * s[1:] < 0)[0]
    tc = t[idx] - eta[idx] * (t[idx + 1] - t[idx]) / (eta[idx + 1] - eta[idx])
    if len(tc) < 2:
        return float("nan"), 0
    return float(math.pi * (len(tc) - 1) / (tc[-1] - tc[0])), len(tc) - 1


def measured_escape_exponent(m: float, side: str = "conjunction", seed: float = 1e-9,
                             lo: float = 1e-7, hi: float = 1e-3) -> float:
    """The real exponent measured on the nonlinear equations: start `seed`·b along the unstable
    eigenvector, fit log(|r − r_eq|/b) against t while it grows from `lo` to `hi`."""
    modes = linear_modes(m, side)
    x0 = modes["x0"]
    b = abs(x0)
    e = modes["escape_vector"]
    s0 = np.array([x0, 0.0, 0.0, 0.0]) + seed * b * e / np.linalg.norm(e[:2])
    t_end = 1.5 * math.log(hi / seed) / max(modes["escape_exponent"], 1e-3)
    t = np.linspace(0.0, t_end, 3000)
    sol = solve_ivp(rhs_rotating, (0.0, t_end), s0, method="DOP853", t_eval=t, args=(m,), rtol=1e-12, atol=1e-16)
    d = np.hypot(sol.y[0] - x0, sol.y[1]) / b
    ok = (d > lo) & (d < hi)
    return float(np.polyfit(sol.t[ok], np.log(d[ok]), 1)[0])


def fit_swing_and_escape(t, eta, amplitude: float, window: float = 20.0, guess: tuple[float, float] | None = None):
    """Measure the frequency ω and the real exponent λ on a run: least-squares fit of
    η(t) = a cos ωt + b sin ωt + c e^{λt} + d e^{−λt} while |η| ≤ window·amplitude (the linear
    regime). Starting guesses `guess` = (ω, λ), Hill's values if not given; returns
    (ω, λ, rms residual / amplitude)."""
    from scipy.optimize import least_squares

    ok = np.abs(eta) <= window * amplitude
    stop = int(np.argmin(ok)) if not np.all(ok) else len(eta)
    t, eta = t[:stop], eta[:stop]

    def model(p):
        w, lam, a, b, c, d = p
        return a * np.cos(w * t) + b * np.sin(w * t) + c * np.exp(lam * t) + d * np.exp(-lam * t)

    w0, l0 = guess if guess is not None else (HILL_FREQUENCY, HILL_ESCAPE_EXPONENT)
    p0 = [w0, l0, 0.0, amplitude, amplitude * 1e-3, 0.0]
    sol = least_squares(lambda p: (model(p) - eta) / amplitude, p0, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    res = float(np.sqrt(np.mean(sol.fun**2)))
    return float(sol.x[0]), float(abs(sol.x[1])), res
