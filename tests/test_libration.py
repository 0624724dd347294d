"""Chapter 16, Problems 91–94 (§815–838) and spin–orbit chaos: each result against an
independent reference (exact integration over the body, exact pendulum periods, scipy DOP853
on the planar equation, Euler's closed forms where they hold)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from theoria.physics import libration as lib
from theoria.physics.constants import JULIAN_CENTURY_DAYS
from theoria.physics.gravity_gradient import (ellipsoid_quadrature, exact_torque_force, extra_force_first_order,
                                      fitted_order, force_error_vs_size, starting_axis, torque_error_vs_size,
                                      torque_euler_components, torque_first_order)
from theoria.physics.inertia import ellipsoid_moments
from theoria.physics.orbits import KeplerOrbit
from theoria.physics.params import ParameterError
from theoria.scenarios.base import get

SEMI = np.array([1.0, 0.8, 0.6])
DIR = np.array([0.6, 0.5, 0.3])


# ------------------------------------------------------------------ §815–818 torque and force

def test_quadrature_is_exact_for_second_moments_and_the_shell_theorem():
    pts, dm = ellipsoid_quadrature(SEMI, mass=2.0)
    I = np.array([np.sum(dm * (pts[:, 1] ** 2 + pts[:, 2] ** 2)), np.sum(dm * (pts[:, 2] ** 2 + pts[:, 0] ** 2)),
                  np.sum(dm * (pts[:, 0] ** 2 + pts[:, 1] ** 2))])
    assert np.allclose(I, ellipsoid_moments(SEMI, 2.0), rtol=1e-13)
    # a homogeneous ball attracts like a point (Newton): F = GMm/s², no torque
    tau, F = exact_torque_force([1, 1, 1], [0.0, 3.0, 0.0], gm=1.0, mass=1.0)
    assert np.allclose(F, [0, 1 / 9, 0], rtol=0, atol=1e-14)
    assert np.max(np.abs(tau)) < 1e-15


def test_first_order_torque_in_euler_components_and_zero_for_equal_moments():
    I = np.array([2.0, 3.0, 4.5])
    s = np.array([3.0, -1.0, 2.0]) * 10
    r = np.linalg.norm(s)
    assert np.allclose(torque_first_order(I, s, 7.0), torque_euler_components(I, r, s / r, 7.0), rtol=1e-14)
    assert np.max(np.abs(torque_first_order([2, 2, 2], s, 7.0))) < 1e-18  # §817
    # arrays broadcast: N positions at once give the same rows as one at a time
    S = np.array([[3.0, -1.0, 2.0], [1.0, 2.0, -0.5], [0.2, 0.0, 5.0]]) * 10
    R = np.linalg.norm(S, axis=1)
    tau = torque_euler_components(I, R, S / R[:, None], 7.0)
    assert tau.shape == (3, 3)
    assert np.allclose(tau, [torque_euler_components(I, r_, s_ / r_, 7.0) for r_, s_ in zip(R, S)], rtol=1e-15)
    assert np.allclose(tau, torque_first_order(I, S, 7.0), rtol=1e-14)
    axes, rates = starting_axis(I, tau)
    assert axes.shape == (3, 3) and rates.shape == (3,)
    assert np.allclose(rates, [starting_axis(I, t_)[1] for t_ in tau], rtol=1e-15)


def test_first_order_torque_error_is_second_order_in_size_over_distance():
    """§816: the neglected terms are (size/s)² relative (odd multipoles vanish)."""
    ratios = np.array([0.2, 0.1, 0.05, 0.025])
    err = torque_error_vs_size(SEMI, DIR, ratios)
    assert abs(fitted_order(ratios, err) - 2.0) < 0.02
    # and the coefficient is O(1): the approximation fails at size ~ distance
    assert 0.05 < err[0] / ratios[0] ** 2 < 5


def test_euler_extra_force_818_against_exact_force():
    ratios = np.array([0.1, 0.05, 0.025])
    err = force_error_vs_size(SEMI, DIR, ratios)
    assert abs(fitted_order(ratios, err) - 2.0) < 0.02
    assert err[-1] < 1e-3
    # equal moments: only Mee/ss remains (§818)
    assert np.max(np.abs(extra_force_first_order([1, 1, 1], [3.0, 1.0, 2.0]))) < 1e-16


def test_accuracy_scenario_and_quadrature_convergence_close_to_the_body():
    r = get("gravity-gradient-accuracy").simulate({})
    assert abs(r.metrics["torque_error_order"] - 2) < 0.02 and abs(r.metrics["force_error_order"] - 2) < 0.02
    assert all(len(v) == len(r.trajectory.t) for v in r.plot_series.values())
    # F only 1.25 sizes away: the quadrature has converged (doubling the points changes < 1e-5)
    s = DIR / np.linalg.norm(DIR) * 1.25
    t1, f1 = exact_torque_force(SEMI, s)
    t2, f2 = exact_torque_force(SEMI, s, n=(32, 32, 64))
    assert np.linalg.norm(t1 - t2) < 1e-5 * np.linalg.norm(t2) and np.linalg.norm(f1 - f2) < 1e-5 * np.linalg.norm(f2)


# ------------------------------------------------------------------ orbits

def test_kepler_orbit_against_two_body_integration():
    e, n = 0.3, 1.3
    orb = KeplerOrbit(a=1.0, e=e, n=n, inclination=0.2, node=0.4, argp=1.0)
    t = np.linspace(0, 3 * 2 * np.pi / n, 50)
    x0 = orb.position(np.array([0.0]))[0]
    h = 1e-6
    v0 = (orb.position(np.array([h]))[0] - orb.position(np.array([-h]))[0]) / (2 * h)
    gm = n * n  # a = 1
    sol = solve_ivp(lambda _, y: np.concatenate([y[3:], -gm * y[:3] / np.linalg.norm(y[:3]) ** 3]), (0, t[-1]),
                    np.concatenate([x0, v0]), t_eval=t, method="DOP853", rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(sol.y[:3].T - orb.position(t))) < 1e-7  # limited by the finite-difference v0
    ff = orb.true_anomaly(t)
    fd = (orb.true_anomaly(t + h) - orb.true_anomaly(t - h)) / (2 * h)
    assert np.allclose(orb.true_anomaly_rate(t), fd, rtol=1e-7)
    assert np.all(np.diff(ff) > 0)


# ------------------------------------------------------------------ §820–822

def test_gravity_start_axis_and_rate():
    r = get("gravity-start").simulate({})
    assert r.metrics["start_axis_angle_error_rad"] < 1e-6
    assert abs(r.metrics["angular_acceleration_rad_per_s2"] / r.metrics["angular_acceleration_euler_rad_per_s2"] - 1) < 1e-5
    # §821: F in the AB plane → the body starts about C exactly
    r = get("gravity-start").simulate({"direction": "0.8,0.6,0"})
    w = r.trajectory.omega_body
    assert np.max(np.abs(w[:, :2])) < 1e-14 and np.all(w[1:, 2] != 0)
    I = np.array([2.0, 3.0, 4.0])
    axis, rate = starting_axis(I, [1.0, 0.0, 0.0])
    assert np.allclose(axis, [1, 0, 0]) and rate == 0.5


def test_gravity_start_axis_drifts_as_t_squared_against_dop853():
    """§820 holds at the first instant; at finite t the full equations (scipy DOP853, independent of
    the splitting integrator) pull the axis off Euler's as t² (ω = ω̇₀t + O(t³) from rest)."""
    from theoria.scenarios.gravity_start import _angle_from, gravity_start_reference

    sc = get("gravity-start")
    values = sc.resolve({"direction": "0.3,0.9,-0.5", "turn_deg": 20.0})
    tr = sc.simulate_fn(values).trajectory
    I = np.asarray(values["inertia"], float)
    u = np.array([0.3, 0.9, -0.5]) / np.linalg.norm([0.3, 0.9, -0.5])
    axis_e, _ = starting_axis(I, torque_first_order(I, u * values["distance"], values["gm"]))
    idx = np.array([50, 100, 200, 400, len(tr.t) - 1])
    w_ref = gravity_start_reference(values, tr.t[idx])
    assert np.max(np.abs(tr.omega_body[idx] - w_ref)) < 1e-9 * np.max(np.abs(w_ref))  # DOP853 rtol 1e-12
    d = _angle_from(w_ref, axis_e)
    slopes = np.diff(np.log(d)) / np.diff(np.log(tr.t[idx]))
    assert np.all(np.abs(slopes[:3] - 2) < 0.03), slopes  # t² while the drift is small
    assert d[-1] > 0.05  # and it does leave Euler's axis (20° of turn)


# ------------------------------------------------------------------ §825–831

def _planar_reference(t, zeta0, zetadot0, N):
    sol = solve_ivp(lambda _, y: [y[1], -N * np.sin(2 * y[0])], (0, t[-1]), [zeta0, zetadot0], t_eval=t,
                    method="DOP853", rtol=1e-12, atol=1e-12)
    return sol.y[0]


@pytest.mark.parametrize("zeta0_deg", [20.0, 60.0, 85.0])
def test_libration_period_matches_exact_pendulum_within_integrator_error(zeta0_deg):
    r = get("libration-circular").simulate({"zeta0_deg": zeta0_deg, "asymmetry": 0.05, "periods": 3,
                                            "steps_per_period": 800})
    m = r.metrics
    k = np.sin(np.radians(zeta0_deg))
    T_exact = 4 * ellipk(k * k) / np.sqrt(3 * 0.05)  # 4K(k)/√(2N), 2N = 3γδ², δ = 1
    assert abs(m["libration_period_exact"] / T_exact - 1) < 1e-12
    # the 4th-order splitting error, estimated by step doubling without the exact answer:
    # (T₄₀₀ − T₈₀₀)/15 (2.2e-10, 2.9e-10, 6.2e-9 at 20°, 60°, 85°); allowed 3× that
    m2 = get("libration-circular").simulate({"zeta0_deg": zeta0_deg, "asymmetry": 0.05, "periods": 3,
                                             "steps_per_period": 400}).metrics
    est = abs(m2["libration_period"] - m["libration_period"]) / 15 / T_exact
    assert 0 < est < 1e-8
    assert abs(m["libration_period"] / T_exact - 1) < 3 * est
    assert abs(m["libration_amplitude_rad"] - np.radians(zeta0_deg)) < 1e-6
    # the whole curve against the planar equation integrated by scipy (independent reference)
    t = r.trajectory.t
    ref = _planar_reference(t, np.radians(zeta0_deg), 0.0, 1.5 * 0.05)
    assert np.max(np.abs(r.plot_series["zeta_rad"] - ref)) < 1e-6  # 4th-order splitting at T/800


def test_euler_small_oscillation_period_within_its_order_zeta0_squared():
    """§831: 2π/√(2N) is the k → 0 limit of 4K(k)/√(2N) = T₀(1 + k²/4 + 9k⁴/64 …)."""
    for z0 in (3.0, 6.0, 12.0):
        m = get("libration-circular").simulate({"zeta0_deg": z0, "periods": 3}).metrics
        rel = m["libration_period"] / m["libration_period_euler"] - 1
        k2 = np.sin(np.radians(z0)) ** 2
        assert k2 / 4 < rel < k2 / 4 + k2**2  # the first neglected term and the next


def test_four_cases_of_826():
    sc = get("libration-circular")
    # 1st: locked — stays exactly
    r = sc.simulate({"start": "locked"})
    assert np.max(np.abs(r.plot_series["zeta_rad"])) < 1e-12
    assert r.notes[0].startswith("Euler's case: locked")
    # 2nd: librating, bounded by arcsin k
    r = sc.simulate({"zeta0_deg": 10.0, "spin_ratio": 1.2})
    assert "librating" in r.notes[0]
    assert np.max(np.abs(r.plot_series["zeta_rad"])) < np.pi / 2
    assert abs(r.metrics["libration_amplitude_rad"] - r.metrics["libration_amplitude_exact_rad"]) < 1e-5
    # 3rd: separatrix — the time to creep from 10° to 80° is Euler's ln tan(45° + ζ/2)/√(2n)
    r = sc.simulate({"start": "separatrix", "zeta0_deg": 10.0})
    assert "separatrix" in r.notes[0]
    assert abs(r.metrics["separatrix_time_to_80deg"] / r.metrics["separatrix_time_to_80deg_euler"] - 1) < 1e-4
    # 4th: circulating — ζ passes 90° and keeps going; period of a half turn = 2K(1/k)/(k√(2N))
    r = sc.simulate({"zeta0_deg": 0.0, "spin_ratio": 1.5, "periods": 6})
    assert "circulating" in r.notes[0]
    z = r.plot_series["zeta_rad"]
    assert np.all(np.diff(z) < 0) and z[-1] < -np.pi  # spin faster than F: ζ = f − λ decreases
    assert abs(r.metrics["libration_period"] / r.metrics["libration_period_exact"] - 1) < 1e-3


def test_circulation_period_against_euler_826_fourth_case():
    """§826 4th: with C = m²n, t√n ≈ ζ/m − sin 2ζ/(4m³), so half a turn relative to F takes
    π/(m√N)(1 + 3/(16m⁴) + …) — Euler's leading term is short by about 3/(16m⁴)."""
    for spin in (1.5, 2.0, 3.0):
        m = get("libration-circular").simulate({"zeta0_deg": 0.0, "spin_ratio": spin, "periods": 4}).metrics
        m2 = (1 - spin) ** 2 / (1.5 * 0.05) - 1  # Euler's C/n = ζ̇₀²/N − cos 2ζ₀
        rel = m["libration_period"] / m["circulation_period_euler"] - 1
        # ⟨(1 + cos 2ζ/m²)^(-1/2)⟩ = 1 + 3/(16m⁴) + 105/(1024m⁸) + …
        assert 3 / (16 * m2**2) < rel < 3 / (16 * m2**2) + 2 * 105 / (1024 * m2**4)
        assert abs(m["libration_period"] / m["libration_period_exact"] - 1) < 1e-3


def test_case_II_librates_about_90_degrees():
    r = get("libration-circular").simulate({"asymmetry": -0.05, "zeta0_deg": 70.0, "periods": 3})
    z = r.plot_series["zeta_rad"]
    assert abs(0.5 * (z.max() + z.min()) - np.pi / 2) < 1e-3
    assert abs(r.metrics["libration_period"] / r.metrics["libration_period_exact"] - 1) < 1e-3


def test_bad_input_names_the_parameter():
    with pytest.raises(ParameterError, match="asymmetry"):
        get("libration-circular").simulate({"asymmetry": "0.9"})
    with pytest.raises(ParameterError, match="eccentricity"):
        get("libration-eccentric").simulate({"eccentricity": "nan"})
    with pytest.raises(ParameterError, match="asymmetry"):
        get("libration-eccentric").simulate({"asymmetry": 1 / 3})
    with pytest.raises(ParameterError, match="direction"):
        get("gravity-start").simulate({"direction": "0,0,0"})


# ------------------------------------------------------------------ §833–838

def test_forced_amplitude_matches_euler_for_small_e_and_free_part_separates():
    e = 0.01
    r = get("libration-eccentric").simulate({"eccentricity": e, "free_zeta0_deg": 0.0, "orbits": 3})
    m = r.metrics
    assert abs(m["forced_amplitude_rad"] / m["forced_amplitude_euler_rad"] - 1) < 5 * e**2
    # the rigid-body run started on the forced solution (planar shooting) stays on it: its own first
    # harmonic (the "simulated" column) is that of the DOP853 periodic solution (the "modern" one)
    assert m["free_amplitude_rad"] < 1e-7
    assert abs(m["forced_amplitude_rad"] / m["forced_amplitude_periodic_rad"] - 1) < 1e-8
    # with a free part added, it oscillates at Euler's √(2N) (§838), amplitude kept
    r = get("libration-eccentric").simulate({"eccentricity": e, "free_zeta0_deg": 1.0, "orbits": 40})
    # Euler's period neglects the forced swing, the 1/s³ modulation (Floquet period, all orders in e) and
    # the 1° amplitude (φ²/4): together 1.9e-4 (the modern value); the run lies within 3× that of Euler's
    # and nearer the modern value than Euler's is (residual: zero-crossing jitter of the combination tones)
    m = r.metrics
    neglected = abs(m["free_period_modern"] / m["free_period_euler"] - 1)
    assert 1e-4 < neglected < 3e-4  # Floquet (linear, exact in e): +1.2e-4; amplitude φ²/4 = 7.6e-5
    assert abs(m["free_period"] / m["free_period_euler"] - 1) < 3 * neglected
    assert abs(m["free_period"] / m["free_period_modern"] - 1) < neglected
    assert abs(r.metrics["free_amplitude_rad"] - np.radians(1.0)) < 0.05 * np.radians(1.0)
    # the forced harmonic fitted beside the 1° free swing: within 1e-3 of the periodic solution's
    assert abs(m["forced_amplitude_rad"] / m["forced_amplitude_periodic_rad"] - 1) < 1e-3


def _periodic_forced_sin_coefficient(gamma, e):
    """Independent of theoria: the sin M coefficient of ζ = f − λ on the periodic solution of
    λ̈ = (3/2)γ n²(a/r)³ sin 2(f − λ) (n = a = 1), found by Newton (scipy fsolve) on one orbit
    integrated by DOP853 at rtol 1e-12, Kepler's equation solved by Newton here."""
    from scipy.optimize import fsolve

    def anomalies(t):
        M = np.asarray(t, float)
        E = M.copy()
        for _ in range(50):
            E = E - (E - e * np.sin(E) - M) / (1 - e * np.cos(E))
        f = 2 * np.arctan2(np.sqrt(1 + e) * np.sin(E / 2), np.sqrt(1 - e) * np.cos(E / 2))
        return f, 1 - e * np.cos(E)

    def rhs(t, y):
        f, r = anomalies(t)
        return [y[1], 1.5 * gamma / r**3 * np.sin(2 * (f - y[0]))]

    P = 2 * np.pi
    def miss(y0):
        y = solve_ivp(rhs, (0, P), y0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
        return [y[0] - y0[0] - 2 * np.pi, y[1] - y0[1]]

    lam0 = 0.0 if gamma > 0 else -np.pi / 2  # A toward F; B < A: B toward F (§827)
    y0 = fsolve(miss, [lam0, (1 + e) ** 2 / (1 - e * e) ** 1.5], xtol=1e-10)
    t = np.linspace(0, P, 1025)[:-1]
    lam = solve_ivp(rhs, (0, P), y0, method="DOP853", rtol=1e-12, atol=1e-14, t_eval=t).y[0]
    a, _ = lib.harmonics(t, anomalies(t)[0] - lam, 1.0, 3)
    return float(a[0])


@pytest.mark.parametrize("gamma,e", [(0.4, 0.001), (-0.4, 0.001), (0.2, 0.05), (-0.2, 0.05)])
def test_the_forced_amplitude_has_its_sign_on_both_sides_of_the_resonance(gamma, e):
    """Above (B−A)/C = 1/3 (A² < 2N) Euler's m = 2e/(1 − 3γ) of §833 is negative: the forced swing is
    opposite to the orbit's. The simulated and periodic amplitudes carry the same sign as an
    independent periodic solution, and Euler's formula is not called "200 % off" where it holds."""
    r = get("libration-eccentric").simulate({"asymmetry": gamma, "eccentricity": e, "free_zeta0_deg": 0.0,
                                             "orbits": 2})
    m, ref = r.metrics, _periodic_forced_sin_coefficient(gamma, e)
    assert abs(m["forced_amplitude_periodic_rad"] / ref - 1) < 1e-6, (m["forced_amplitude_periodic_rad"], ref)
    assert abs(m["forced_amplitude_rad"] / ref - 1) < 1e-6, (m["forced_amplitude_rad"], ref)
    assert np.sign(m["forced_amplitude_euler_rad"]) == np.sign(ref)
    assert m["forced_amplitude_rel_error"] < 10 * e  # first order in e
    assert not any("off the forced solution" in w for w in r.warnings), r.warnings


def test_a_circular_orbit_forces_nothing_and_euler_is_not_called_off():
    r = get("libration-eccentric").simulate({"eccentricity": 0.0, "free_zeta0_deg": 0.0, "orbits": 2})
    assert abs(r.metrics["forced_amplitude_periodic_rad"]) < 1e-12 and r.metrics["forced_amplitude_euler_rad"] == 0
    assert not any("off the forced solution" in w for w in r.warnings), r.warnings


@pytest.mark.slow
def test_euler_forced_amplitude_fails_as_e_squared_and_near_resonance():
    es = np.array([0.05, 0.1, 0.2])
    errs = np.array([get("libration-eccentric").simulate({"eccentricity": e, "free_zeta0_deg": 0.0, "orbits": 1})
                     .metrics["forced_amplitude_rel_error"] for e in es])
    assert abs(fitted_order(es, errs) - 2.0) < 0.3  # Euler's error is O(e²) relative
    assert errs[-1] > 0.01  # at e = 0.2 it is already a few per cent off
    # near the resonance A² = 2N ((B−A)/C = 1/3) the linear formula overshoots badly
    m = get("libration-eccentric").simulate({"eccentricity": 0.1, "asymmetry": 0.25, "free_zeta0_deg": 0.0,
                                             "orbits": 1}).metrics
    assert m["forced_amplitude_euler_rad"] > 1.2 * m["forced_amplitude_rad"]


@pytest.mark.slow
def test_forced_solution_search_gives_up_quickly_where_there_is_none():
    """e = 0.5 with (B−A)/C = −0.45 (chaotic): a clear refusal after a bounded number of runs (the
    fixed-step search used 200 DOP853 runs, two minutes), and the progress callback is called on
    every run, so the app can drop a request that a newer one replaced."""
    calls = []
    with pytest.raises(ParameterError, match="eccentricity=0.5"):
        get("libration-eccentric").simulate_fn(get("libration-eccentric").resolve(
            {"eccentricity": 0.5, "asymmetry": -0.45}), progress=calls.append)
    # at most half the fixed-step search's 200 runs (78 here; the search's own cap is 40 × 4 = 160)
    assert 3 <= len(calls) <= 100 and max(calls) <= 0.1
    # where a forced solution exists the search still finds it (e = 0.2, (B−A)/C = −0.45 and 0.25:
    # the previous search found these too), periodic to 1e-11 in λ and λ̇
    from theoria.scenarios.libration_eccentric import ForcedSolution

    for g in (-0.45, 0.25):
        fs = ForcedSolution(g, 0.2, 1.0)
        end = fs.sol(fs.P)
        assert abs(end[0] - fs.lam0 - 2 * np.pi) < 1e-9 and abs(end[1] - fs.lamdot0) < 1e-9


def test_forced_libration_case_II_about_the_B_axis():
    """B < A: the forced libration is about ζ = 90° (§827) with Euler's amplitude using |n|;
    the A axis facing F is unstable (§837's separatrix), so the body never librates there."""
    e = 0.01
    r = get("libration-eccentric").simulate({"eccentricity": e, "asymmetry": -0.05, "free_zeta0_deg": 0.0,
                                             "orbits": 2})
    m = r.metrics
    assert abs(m["forced_amplitude_rad"] / m["forced_amplitude_euler_rad"] - 1) < 5 * e**2
    z = r.plot_series["zeta_rad"]
    assert abs(np.remainder(z.mean(), np.pi) - np.pi / 2) < 1e-3


class _EulerOrbit:
    """Euler's §833 parametrisation taken literally: XF = At + α sin At, 1/s³ = (1 + β cos At)/f³."""

    def __init__(self, A, alpha, beta):
        self.n, self.A, self.alpha, self.beta, self.e = A, A, alpha, beta, alpha / 2

    def anomalies(self, t):
        t = np.asarray(t, float)
        return self.A * t + self.alpha * np.sin(self.A * t), (1 + self.beta * np.cos(self.A * t)) ** (-1 / 3)

    def anomalies_at(self, t):
        f, r = self.anomalies(t)
        return float(f), float(r)

    def true_anomaly_rate(self, t):
        return self.A * (1 + self.alpha * np.cos(self.A * np.asarray(t, float)))


def test_second_order_term_835_in_eulers_own_model():
    A, alpha, beta, gamma = 1.0, 0.004, 0.006, 0.02
    N = lib.euler_N(gamma, 1.0, 1.0)
    orb = _EulerOrbit(A, alpha, beta)
    m = lib.forced_amplitude_euler(alpha, A, N)
    lam0, lamdot0, P = lib.periodic_libration(orb, gamma, 1.0, guess=(0.0, A * (1 + alpha) - m * A))
    sol = solve_ivp(lib.planar_rhs(orb, gamma, 1.0), (0, P), [lam0, lamdot0], method="DOP853", rtol=1e-12,
                    atol=1e-14, dense_output=True)
    t = np.linspace(0, P, 1025)[:-1]
    zeta = orb.anomalies(t)[0] - sol.sol(t)[0]
    a, b = lib.harmonics(t, zeta, A, 3)
    assert abs(a[0] / m - 1) < 10 * alpha**2  # §833
    full = lib.second_order_full(alpha, beta, A, N)
    assert abs(a[1] / full - 1) < 0.02  # rederived coefficient, exact to O(α²)
    euler = lib.second_order_euler(alpha, beta, A, N)
    # Euler's N ≪ A² form differs from it by the factor (4A² − 2N)/(4A²): here 0.75 %
    assert abs(euler / full - (4 * A * A - 2 * N) / (4 * A * A)) < 1e-12
    assert abs(a[1] / euler - 1) < 0.03


# ------------------------------------------------------------------ spin–orbit chaos

def test_section_kernel_against_dop853_and_fourth_order():
    th0 = np.array([0.0, 0.5, 1.0, 0.2])
    w0 = np.array([0.6, 1.3, 2.2, 3.5])
    _, Wr = lib.spin_orbit_section_scipy(th0, w0, 0.1, 0.89, 1, rtol=1e-13, atol=1e-14)
    errs = []
    for spo in (64, 128):
        _, W = lib.spin_orbit_section(th0, w0, 0.1, 0.89, 1, spo)
        errs.append(np.max(np.abs(W[:, 0] - Wr[:, 0])))
    assert errs[1] < 1e-8
    assert 2 ** 3.5 < errs[0] / errs[1] < 2 ** 4.5  # 4th order (asymptotic from ~64 steps at θ̇ = 3.5)


@pytest.mark.parametrize("p", [0.5, 1.0, 1.5, 2.0])
def test_islands_where_resonance_theory_puts_them(p):
    """Small ω₀ (well separated resonances): a fixed point of the periapse map near θ̇ = p,
    inside the Goldreich–Peale zone p ± ω₀√|H(p,e)|, at θ = 0 (H > 0) or π/2 (H < 0), and
    elliptic (stable: |trace| < 2)."""
    e, w0 = 0.1, 0.2
    th_c = lib.resonance_centre_angle(p, e)
    th, wd = lib.periapse_fixed_point(th_c, p, e, w0)
    assert abs(np.remainder(th - th_c + np.pi / 2, np.pi) - np.pi / 2) < 1e-6
    assert abs(wd - p) < lib.resonance_half_width(p, e, w0)
    J = np.empty((2, 2))
    for j in range(2):
        d = np.zeros(2)
        d[j] = 1e-6
        tp, wp = lib.spin_orbit_section([th + d[0]], [wd + d[1]], e, w0, 1, 256)
        tm, wm = lib.spin_orbit_section([th - d[0]], [wd - d[1]], e, w0, 1, 256)
        J[:, j] = [(tp[0, 0] - tm[0, 0]) / 2e-6, (wp[0, 0] - wm[0, 0]) / 2e-6]
    assert abs(np.trace(J)) < 2 and abs(np.linalg.det(J) - 1) < 1e-6  # area-preserving, elliptic


def test_hyperions_quick_preview_leaves_out_the_island_centres_and_nothing_else():
    """The islands' periodic orbits (four continuations from small ω₀) are metrics and a note of
    the full run; the preview, and a run asked without them, skip them: the same section, body and
    other metrics, and the islands' steps out of the run's cost."""
    s = get("hyperion")
    given = {"n_starts": 6, "n_orbits": 40, "probe_orbits": 2, "eccentricity": 0.13}
    full = s.simulate(given)
    lean = s.simulate({**given, "islands": "off"})
    isl = {k for k in full.metrics if k.startswith("island_")}
    assert len(isl) == 12 and not isl & set(lean.metrics)
    assert lean.metrics == {k: v for k, v in full.metrics.items() if k not in isl}
    assert any(n.startswith("Periodic orbits followed") for n in full.notes)
    assert lean.notes == [n for n in full.notes if not n.startswith("Periodic orbits followed")]
    assert np.array_equal(lean.trajectory.quat_wxyz, full.trajectory.quat_wxyz)
    for k, v in full.extras["section"].items():
        assert np.array_equal(lean.extras["section"][k], v), k
    on, off = s.cost_of(s.resolve(given)).steps, s.cost_of(s.resolve({**given, "islands": "off"})).steps
    assert off < on  # the run's expected time (which decides whether it is previewed) leaves them out too
    assert s.preview["islands"] == "off"


def test_hyperion_chaotic_sea_and_regular_island():
    """WPM 1984: e = 0.1, ω₀ = 0.89 — the 1:1 and 3:2 zones overlap (Chirikov), a start between
    them is chaotic (Lyapunov time of a few orbits), the synchronous fixed point is not."""
    e, w0 = 0.1, 0.89
    assert lib.resonance_half_width(1.0, e, w0) + lib.resonance_half_width(1.5, e, w0) > 0.5
    th, wd = lib.periapse_fixed_point(0.0, 0.6, e, w0)
    _, _, lyap = lib.spin_orbit_section([th, 0.0], [wd, 1.4], e, w0, 400, 64, lyapunov=True)
    per_orbit = lyap * 2 * np.pi
    assert per_orbit[1] > 0.2  # chaotic: e-folding in a few orbits
    assert per_orbit[0] < 0.05 * per_orbit[1]
    r = get("hyperion").simulate({"n_starts": 20, "n_orbits": 100, "probe_orbits": 2})
    assert r.status == "ok" and not r.warnings  # the central divergence guard found nothing to cut
    assert 0 < r.metrics["chaotic_fraction"] < 1
    sec = r.extras["section"]
    assert sec["theta_mod_pi"].shape == sec["theta_dot"].shape == (20, 100) and sec["lyapunov_per_orbit"].shape == (20,)
    assert np.all(np.isfinite(sec["theta_mod_pi"])) and np.all(np.isfinite(sec["theta_dot"]))
    assert np.all((sec["theta_mod_pi"] >= 0) & (sec["theta_mod_pi"] < np.pi))
    assert all(np.all(np.isfinite(v)) for v in r.plot_series.values())
    # the synchronous, 1:2 and 2:1 islands survive at Hyperion's ω₀ (followed from the GP centres)
    for p in (0.5, 1.0, 2.0):
        assert abs(r.metrics[f"island_trace_{p:g}"]) < 2, p
    assert abs(r.metrics["island_rate_1"] - wd) < 1e-6  # the same synchronous orbit as found directly
    # the drawn body (rigid-body integrator, 3-D) agrees with the section kernel at periapse
    t = r.trajectory.t
    q = r.trajectory.quat_wxyz
    theta = np.unwrap(2 * np.arctan2(q[:, 3], q[:, 0]))
    k = np.argmin(np.abs(t[:, None] - 2 * np.pi * np.arange(1, 3)[None, :]), axis=0)
    assert np.max(np.abs(t[k] - 2 * np.pi * np.arange(1, 3))) < 1e-9  # the periapse passages are stored samples
    T, _ = lib.spin_orbit_section([0.0], [1.4], e, w0, 2, 128)
    assert np.max(np.abs(theta[k] - T[0])) < 1e-5


def test_hyperion_at_euler_resonance_omega0_1_has_no_euler_curve_and_does_not_diverge():
    """ω₀ = 1 is Euler's A² = 2N: his 2e/(1 − ω₀²) is infinite, so the curve is left out (not NaN)."""
    r = get("hyperion").simulate({"omega0": 1.0, "n_starts": 4, "n_orbits": 10, "probe_orbits": 1})
    assert r.status == "ok" and "zeta_euler_rad" not in r.plot_series
    assert any("A² = 2N" in n for n in r.notes)
    assert all(np.all(np.isfinite(v)) for v in r.plot_series.values())


# ------------------------------------------------------------------ the Moon

def test_lunar_position_and_optical_libration_against_meeus_examples():
    """Meeus, Astronomical Algorithms (2nd ed.), Example 47.a and 53.a: 1992 April 12, 0h TD
    (JD 2448724.5): λ = 133.162655°, β = −3.229126°, Δ = 368409.7 km (of date, no nutation);
    l′ = −1.206°, b′ = +4.194° (his values include nutation, ~0.005°)."""
    from theoria.physics import moon
    t = np.array([2448724.5 - 2451545.0])
    lon, lat, dist = moon.moon_geocentric(t)
    lon_of_date = np.degrees(lon[0]) + moon.PRECESSION_DEG_PER_CY * t[0] / JULIAN_CENTURY_DAYS
    assert abs(np.remainder(lon_of_date - 133.162655 + 180, 360) - 180) < 0.02  # 31 of Meeus's 60 terms
    assert abs(np.degrees(lat[0]) + 3.229126) < 0.01
    assert abs(dist[0] - 368409.7) < 30.0
    lp, bp = moon.optical_libration_meeus(t)
    assert abs(np.degrees(lp[0]) + 1.206) < 0.01 and abs(np.degrees(bp[0]) - 4.194) < 0.01
    # the Cassini frame's sub-Earth point is the same closed form (two independent routes)
    tt = np.linspace(0, 6800, 3000)
    l, b = moon.sub_earth_point(moon.mean_frame(tt), moon.earth_from_moon(tt))
    lp, bp = moon.optical_libration_meeus(tt)
    assert np.max(np.abs(np.remainder(l - lp + np.pi, 2 * np.pi) - np.pi)) < 1e-9
    # maxima over an 18.6-yr nodal cycle against DE421's Moon on its mean-Earth axes, the same dates
    # (the often quoted ±7.9° and ±6.8° are short of both): the uniformly rotating Moon differs from the
    # real one by the physical libration (≤ 0.05°) and the truncation of the lunar theory (~10″)
    from theoria.physics import quaternion as quat
    from theoria.physics import real_moon
    from theoria.scenarios._real_sky import de421

    sky = de421()
    q, _ = sky.moon_attitude(tt)
    s = quat.rotate_inverse(q, sky.earth_from_moon(tt)) @ real_moon.pa_to_me_matrix().T
    l_de, b_de = np.arctan2(s[:, 1], s[:, 0]), np.arcsin(s[:, 2] / np.linalg.norm(s, axis=1))
    assert np.degrees(np.max(np.abs(l_de))) > 8.0 and np.degrees(np.max(np.abs(b_de))) > 6.85
    assert abs(np.degrees(np.max(np.abs(lp)) - np.max(np.abs(l_de)))) < 0.05
    assert abs(np.degrees(np.max(np.abs(bp)) - np.max(np.abs(b_de)))) < 0.05


@pytest.mark.slow
def test_moon_physical_libration_against_dop853_euler_and_published_terms():
    from theoria.physics import moon
    from theoria.scenarios.moon import moon_runs

    runs = moon_runs()  # the 6-year run, the same at twice the step, and scipy DOP853 of the same model
    m = runs["run"]
    # the face seen from the Earth: optical libration, the body's own motion only arcminutes
    assert m["sub_earth_vs_uniform_lon_max_arcsec"] < 300
    # the run's Moon and DE421's on the same dates: the face's largest swings agree to ~0.0001°
    assert abs(m["optical_libration_lon_max_deg"] - m["optical_libration_lon_max_de421_deg"]) < 0.002
    assert abs(m["optical_libration_lat_max_deg"] - m["optical_libration_lat_max_de421_deg"]) < 0.002
    # the pass criterion: the same model (quadrupole, degree-3 field, Earth and Sun, mantle moments)
    # integrated independently (DOP853, rtol 1e-12)
    # gives the same fitted terms, within 3× the splitting error estimated by step doubling (4th order)
    for key in ("mprime", "annual"):
        sim, ref = m[f"physical_libration_{key}_arcsec"], runs["dop853"][key]
        est = abs(runs["run_2h"][f"physical_libration_{key}_arcsec"] - sim) / 15
        assert 0 < est < 1e-4, key  # the 4th-order splitting at 0.25 d: micro-arcseconds
        assert abs(sim - ref) < 3 * est, key
    # Euler's forced libration (§833/§836) term by term: linear in e and in each term, so a few %
    for key in ("mprime", "annual", "evection"):
        sim = m[f"physical_libration_{key}_arcsec"]
        eul = m[f"physical_libration_{key}_euler_arcsec"]
        assert abs(sim / eul - 1) < 0.05, key
    # published (Eckhardt 1981 via Meeus ch. 53): −16.8″ sin M′, +90.7″ E sin M, −4.14″ sin(2D−M′) —
    # information, not a criterion: Eckhardt's series is a different fit of an older lunar model. Only the
    # signs and magnitudes are asserted (a model off by a factor would be a bug, not a missing term).
    assert m["physical_libration_mprime_arcsec"] * m["physical_libration_mprime_published_arcsec"] > 0
    assert 0.8 < m["physical_libration_mprime_arcsec"] / m["physical_libration_mprime_published_arcsec"] < 1.2
    assert 0.8 < m["physical_libration_annual_arcsec"] / m["physical_libration_annual_published_arcsec"] < 1.2
    assert abs(m["physical_libration_evection_arcsec"] + 0.00115 * 3600) < 0.3
    # started on DE421's Moon: the fitted free term also takes up forced terms the fit leaves out
    assert m["free_libration_amplitude_arcsec"] < 20


@pytest.mark.slow
def test_moon_free_libration_period():
    """The model's free libration, measured as the difference of two runs that differ only by a 100″
    free swing at the start (the forced terms cancel): 1058.2 d against LLR's 1056 d (Rambaux &
    Williams 2011), the same whether the Moon starts on Euler's forced libration or uniformly.
    Euler's 2π/√(2N) (§838) is ~1% short: it neglects the 1/s³ modulation and the forced swing."""
    for start in ("forced", "uniform"):
        m = get("moon").simulate({"years": 6.0, "start": start}).metrics
        assert abs(m["free_libration_period_days"] / 1056.0 - 1) < 0.005, start
        assert abs(m["free_libration_period_days"] / m["free_libration_period_euler_days"] - 1) < 0.02, start
    assert m["free_libration_amplitude_arcsec"] > 100  # uniform start: a large free libration
    # a span under one free period measures nothing (and says so), it does not guess
    short = get("moon").simulate({"years": 2.0})
    assert np.isnan(short.metrics["free_libration_period_days"])


def test_a_section_cut_into_pieces_for_progress_is_the_uncut_run_bit_for_bit():
    """The app reports progress, so it runs the surface of section in pieces; the command line,
    a notebook and a sweep run it whole. In the chaotic sea a last-bit difference grows until the
    Lyapunov exponents differ in their first digit (Hyperion's preview gave 0.88 against 0.93 per
    orbit): the pieces must round exactly as the whole run."""
    th0 = np.zeros(12)
    wd0 = np.linspace(0.2, 3.0, 12)  # regular and chaotic starts (Hyperion's e and ω₀)
    whole = lib.spin_orbit_section(th0, wd0, 0.1, 0.89, 80, steps_per_orbit=48, lyapunov=True)
    seen = []
    cut = lib.spin_orbit_section(th0, wd0, 0.1, 0.89, 80, steps_per_orbit=48, lyapunov=True, progress=seen.append)
    assert len(seen) > 10  # it was cut
    for a, b in zip(whole, cut):
        np.testing.assert_array_equal(a, b)
    assert np.max(whole[2]) * 2 * np.pi > 0.1  # some start is chaotic: the test can see a last-bit slip


def test_libration_times_are_in_the_scenes_time_unit_for_any_orbital_rate():
    """With δ = 2 the period halves (it is in the time unit δ is given in, rad per unit), but the
    comparison said "1/δ" and the trajectory "1/δ·rad": in units of 1/δ it would not change.
    Against the small-oscillation period 2π/(δ√(3(B−A)/C)) (§831)."""
    import theoria as th

    sc = th.scenario("libration-circular")
    for rate in (1.0, 2.0):
        run = sc.simulate(orbital_rate=rate, asymmetry=0.2, zeta0_deg=1)
        (row,) = [c for c in run.comparisons if c.label.startswith("libration period")]
        assert row.unit == run.metric_units["libration_period"] == "unit" and run.trajectory.time_unit == "unit"
        assert row.euler == pytest.approx(2 * np.pi / (rate * np.sqrt(3 * 0.2)), rel=1e-12)
        assert row.simulated == pytest.approx(row.euler, rel=2e-4)  # 1° of swing: the pendulum's own correction


@pytest.mark.parametrize("rate", [1e-6, 1e-9, 100.0])
def test_the_modern_free_period_does_not_depend_on_the_unit_of_time(rate):
    """The planar equation has no time scale of its own: every period × n is the same number at any
    orbital rate n. The Floquet period nudged λ̇ by 10⁻⁶ whatever n: at n = 10⁻⁶ that was a swing
    as fast as the orbit, and the modern period came out 27.3/n against 16.3/n (the run's and
    Euler's agreeing with each other)."""
    sc = get("libration-eccentric")
    ref = sc.simulate(orbital_rate=1.0).metrics
    m = sc.simulate(orbital_rate=rate).metrics
    for key in ("free_period_modern", "free_period_floquet", "free_period"):
        assert m[key] * rate == pytest.approx(ref[key], rel=1e-5), key
    assert m["forced_floquet_half_trace"] == pytest.approx(ref["forced_floquet_half_trace"], abs=1e-5)


def test_a_sphere_is_refused_and_a_near_sphere_told_its_fitted_order_is_rounding():
    """semi_axes 1,1,1 gave a torque error order of 0.0025 (0/0) and 1,0.999999,1 of −1.19, against
    Euler's 2, with no warning; every preset's error curves are straight lines of slope 2."""
    import theoria as th

    sc = get("gravity-gradient-accuracy")
    with pytest.raises(th.ParameterError, match="^semi_axes=1,1,1: semi-axes not all equal"):
        sc.simulate(semi_axes=(1.0, 1.0, 1.0))
    near = sc.simulate(semi_axes=(1.0, 0.999999, 1.0))
    assert sum("not the approximation's" in w for w in near.warnings) == 2
    for name in [None, *sc.presets]:
        run = sc.simulate(preset=name) if name else sc.simulate()
        assert run.warnings == [], (name, run.warnings)
        assert run.metrics["torque_error_order"] == pytest.approx(2.0, abs=0.02)


@pytest.mark.parametrize("asymmetry", [0.1, 0.3])
def test_a_free_swing_faster_than_half_the_orbital_rate_gets_its_own_floquet_period(asymmetry):
    """tr M gives νP up to sign and whole turns; above (B − A)/C = 1/12 Euler's √(2N) exceeds n/2
    and the first branch is an alias: the modern free period was left out (NaN) there. The branch
    nearest √(2N) agrees with the rigid-body run's own free period (7.448 at 0.3; an outside
    shooting + monodromy computation gave 7.447)."""
    m = get("libration-eccentric").simulate(eccentricity=0.05, asymmetry=asymmetry).metrics
    assert m["free_period_floquet"] == pytest.approx(m["free_period"], rel=2e-3)
    assert m["free_period_modern"] == pytest.approx(m["free_period"], rel=2e-3)


@pytest.mark.parametrize("e, gamma", [(0.05, 0.32), (0.1, 0.3), (0.05, 0.315)])
def test_near_the_resonance_the_forced_libration_found_is_periodic_and_stable(e, gamma):
    """Euler's first-order guess is far off near A² = 2N: the search refused (0.1, 0.3) and
    (0.05, 0.315), and at (0.05, 0.32) found the other family (the long axis across the line to F,
    ½ tr M = 235: "tumbles"). Followed out from a nearly circular orbit, the solution found is
    checked here without theoria: it closes after one orbit of λ̈ = (3/2)γ(a/r)³ sin 2(f − λ)
    (DOP853, Kepler solved here) and its monodromy matrix has |½ tr M| ≤ 1."""
    from theoria.scenarios.libration_eccentric import forced_solution

    fs = forced_solution(gamma, e, 1.0)

    def rhs(t, y):
        M = np.asarray(t, float)
        E = M.copy()
        for _ in range(50):
            E = E - (E - e * np.sin(E) - M) / (1 - e * np.cos(E))
        f = 2 * np.arctan2(np.sqrt(1 + e) * np.sin(E / 2), np.sqrt(1 - e) * np.cos(E / 2))
        return [y[1], 1.5 * gamma / (1 - e * np.cos(E)) ** 3 * np.sin(2 * (f - y[0]))]

    def after_one_orbit(y0):
        return solve_ivp(rhs, (0, 2 * np.pi), y0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]

    y0 = np.array([fs.lam0, fs.lamdot0])
    assert np.allclose(after_one_orbit(y0) - [2 * np.pi, 0.0], y0, atol=1e-8)
    d = 1e-6
    M = np.column_stack([(after_one_orbit(y0 + d * v) - after_one_orbit(y0 - d * v)) / (2 * d) for v in np.eye(2)])
    assert abs(0.5 * np.trace(M)) <= 1.0
    assert get("libration-eccentric").simulate(eccentricity=e, asymmetry=gamma, orbits=5).status == "ok"


def test_a_start_at_the_unstable_point_has_an_infinite_period_and_no_torque_no_case():
    """ζ₀ = 90° at rest relative to F is the unstable equilibrium, on the separatrix (§826 3rd):
    its period is infinite, but cos 90° rounds to 6 × 10⁻¹⁷ and the "exact" period came out a
    finite 400. With A = B there is no torque and none of Euler's cases: the notes said
    "circulating" beside "nothing turns", and k² was +inf."""
    import theoria as th

    sc = th.scenario("libration-circular")
    r = sc.simulate(zeta0_deg=90)
    assert r.metrics["libration_period_exact"] == np.inf and np.isnan(r.metrics["libration_period"])
    assert r.notes[0] == "Euler's case: separatrix (§826)."
    r = sc.simulate(asymmetry=0)
    assert np.isnan(r.metrics["modulus_k2"]) and np.isnan(r.metrics["separatrix_gap_1_minus_k2"])
    assert r.notes[0].startswith("No torque (A = B): none of Euler's cases") and "circulating" not in " ".join(r.notes)
    # without a torque the body turns relative to F at its starting rate: half a turn in π/|ζ̇₀|
    r = sc.simulate(asymmetry=0, spin_ratio=2.0)  # ζ̇₀ = δ(1 − 2) = −1
    assert r.metrics["libration_period"] == pytest.approx(np.pi, rel=1e-9)
    # turning round relative to F, it has no largest digression, and its row says so
    for given in ({"asymmetry": 0, "spin_ratio": 2.0}, {"spin_ratio": 2.0}):
        row = next(c for c in sc.simulate(**given).comparisons if c.label.startswith("largest digression"))
        assert row.simulated is None or np.isnan(row.simulated)
        assert row.missing.startswith("the body turns round relative to F"), given


def test_what_a_run_could_not_measure_says_why():
    """A researcher's probe: `ok` runs gave NaN or infinite values without a word. ω started
    exactly on the middle axis (a permanent but unstable rotation, §808) was said to "circulate
    about the A axis" with an infinite period; a forced libration with no free swing, or with
    A = B, left the free period NaN unexplained. Each now says why, in a note and on its row."""
    import theoria as th

    r = th.scenario("free-tumble").simulate(omega0=(0.0, 1.0, 0.0))
    row = next(c for c in r.comparisons if c.label == "polhode period")
    assert row.modern == np.inf and row.simulated is None and "middle axis" in row.note
    assert "circulates" not in row.note and row.missing.startswith("on the separatrix")
    sc = th.scenario("libration-eccentric")
    for given, said in (({"free_zeta0_deg": 0}, "no free swing was started"), ({"asymmetry": 0}, "A = B: no torque")):
        r = sc.simulate(**given)
        assert np.isnan(r.metrics["free_period"])
        assert any(n.lower().startswith(said.lower()) for n in r.notes), r.notes
        assert r.comparisons[2].missing.lower().startswith(said.lower())
    r = sc.simulate(eccentricity=0)
    assert np.isnan(r.metrics["forced_amplitude_rel_error"]) and any("e = 0" in n for n in r.notes)
