"""The one Kepler solver (physics/kepler.py) against references that share nothing with it: the
root of M = E − e sin E found by mpmath at 40 digits and by scipy's brentq, the true anomaly from
Kepler's tan(f/2) relation, and REBOUND's own conversion of orbital elements to positions."""
from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest
from scipy.optimize import brentq

from theoria.physics import kepler
from theoria.physics.errors import ParameterError

ECCENTRICITIES = [0.0, 1e-3, 0.0549, 0.3, 0.5, 0.9, 0.99, 0.999999]
# m from 1e-12 (E tiny, where cancellation would show) to π, with both ends
MEAN_ANOMALIES = np.concatenate([[1e-12, 1e-9, 1e-6, 1e-4, 1e-3, 0.01], np.linspace(0.02, math.pi - 0.02, 40),
                                 [math.pi - 1e-9, math.pi]])


def _mp_root(M, e):
    """E with E − e sin E = M, M in [0, π], at 40 digits (bracketed on [0, π])."""
    if M == 0.0:
        return mp.mpf(0)
    with mp.workdps(40):
        M, e = mp.mpf(M), mp.mpf(e)
        return mp.findroot(lambda E: E - e * mp.sin(E) - M, (mp.mpf(0), mp.pi), solver="illinois")


@pytest.mark.parametrize("e", ECCENTRICITIES)
def test_solver_to_round_off_against_mpmath(e):
    """Within 2 ulp of E itself, including E ≈ 1e-10 at e = 0.999999 (1.3 ulp measured)."""
    E = kepler.eccentric_anomaly(MEAN_ANOMALIES, e)
    ref = [_mp_root(M, e) for M in MEAN_ANOMALIES]
    ulps = [float(abs(mp.mpf(float(a)) - r)) / np.spacing(float(r)) for a, r in zip(E, ref)]
    assert max(ulps) <= 2.0, (e, max(ulps), MEAN_ANOMALIES[int(np.argmax(ulps))])
    # odd in M, 2π-periodic in E − M: exactly at −M; several turns away within the rounding of
    # M + 2πk itself, magnified by dE/dM = 1/(1 − e cos E), and of 2πk added back
    assert np.array_equal(kepler.eccentric_anomaly(-MEAN_ANOMALIES, e), -E)
    for k in (1, -3, 50):
        Mk = MEAN_ANOMALIES + 2 * math.pi * k
        shifted = kepler.eccentric_anomaly(Mk, e)
        tol = 2 * np.spacing(np.abs(Mk)) / (1 - e * np.cos(E)) + 2 * np.spacing(2 * math.pi * abs(k))
        assert np.all(np.abs(shifted - 2 * math.pi * k - E) <= tol)


def test_solver_against_scipy_on_random_pairs():
    """Arrays of M (several turns, both signs) and of e broadcast together, against brentq on the
    unreduced equation. Tolerance: brentq's own (xtol + rtol|E|) plus the rounding of M itself
    (a few ulp of M), which any solver turns into an error in E of that times dE/dM =
    1/(1 − e cos E) (up to 1e6 here, where e = 1 − 1e-6 and E is near 0 mod 2π)."""
    rng = np.random.default_rng(5)
    M = rng.uniform(-20.0, 20.0, 400)
    e = np.concatenate([rng.uniform(0.0, 1.0, 350), 1.0 - 10.0 ** rng.uniform(-6, -1, 50)])
    E = kepler.eccentric_anomaly(M, e)
    assert E.shape == M.shape
    xtol, rtol = 1e-15, 8.9e-16
    ref = np.array([brentq(lambda x, m=m, ee=ee: x - ee * math.sin(x) - m, m - 1.0, m + 1.0, xtol=xtol, rtol=rtol)
                    for m, ee in zip(M, e)])
    tol = xtol + rtol * np.abs(ref) + 4 * np.spacing(np.abs(M)) / (1 - e * np.cos(ref))
    assert np.all(np.abs(E - ref) <= tol)
    assert np.median(np.abs(E - ref)) < 1e-14
    # broadcasting: a column of e against a row of M
    grid = kepler.eccentric_anomaly(M[None, :5], np.array([0.1, 0.5, 0.9])[:, None])
    assert grid.shape == (3, 5) and np.array_equal(grid[1], kepler.eccentric_anomaly(M[:5], 0.5))


@pytest.mark.parametrize("e", [0.0549, 0.5, 0.99])
def test_true_anomaly_and_radius(e):
    """f from tan(f/2) = √((1+e)/(1−e)) tan(E/2) at 40 digits; r/a = 1 − e cos E; f continuous
    in M over several turns (it keeps M's turns)."""
    M = np.linspace(-3 * math.pi + 0.01, 3 * math.pi - 0.01, 301)
    E, f, r = kepler.anomalies(M, e)
    with mp.workdps(40):
        for Ek, fk, rk in zip(E[::10], f[::10], r[::10]):
            Em = mp.mpf(float(Ek))
            half = mp.atan(mp.sqrt((1 + mp.mpf(e)) / (1 - mp.mpf(e))) * mp.tan(Em / 2))
            fr = 2 * half + 2 * mp.pi * mp.nint((Em - 2 * half) / (2 * mp.pi))
            assert abs(float(fr) - fk) < 1e-14 * max(1.0, abs(fk))
            assert abs(float(1 - mp.mpf(e) * mp.cos(Em)) - rk) <= 2 * np.spacing(rk)
    assert np.all(np.diff(f) > 0)  # continuous and increasing through every periapse and apoapse
    assert np.allclose(kepler.true_anomaly(M, e), f, rtol=0, atol=0)


def test_position_against_rebound_elements():
    """Orbits in every orientation: positions from `kepler.position` against REBOUND's own
    conversion of (a, e, inc, Ω, ω, M) to Cartesian coordinates."""
    import rebound

    rng = np.random.default_rng(11)
    sim = rebound.Simulation()
    sim.add(m=1.0)
    for _ in range(60):
        a = rng.uniform(0.5, 3.0)
        e = rng.choice([rng.uniform(0.0, 0.95), 0.99])
        inc, node, argp, M = rng.uniform(0, math.pi), *rng.uniform(-math.pi, math.pi, 3)
        p = rebound.Particle(simulation=sim, primary=sim.particles[0], m=0.0, a=a, e=e, inc=inc, Omega=node,
                             omega=argp, M=M)
        got = kepler.position(M, a, e, inc, node, argp)
        assert np.allclose(got, [p.x, p.y, p.z], rtol=0, atol=1e-12 * a), (a, e, inc, node, argp, M)


def test_bad_eccentricity_is_a_parameter_error_and_bad_angles_give_nan():
    for bad in (1.0, 1.5, -0.1, math.nan):
        with pytest.raises(ParameterError, match="eccentricity"):
            kepler.eccentric_anomaly(0.3, bad)
    with pytest.raises(ParameterError, match="sun_eccentricity"):
        kepler.check_eccentricity([0.1, 1.0], "sun_eccentricity")
    with np.errstate(invalid="ignore"):  # numpy's warning for sin(inf) and the like
        E = kepler.eccentric_anomaly(np.array([math.nan, math.inf, 1.0]), 0.5)
    assert np.isnan(E[0]) and np.isnan(E[1]) and np.isfinite(E[2])
    # the compiled scalar function answers NaN instead of raising (for use inside numba code)
    assert math.isnan(kepler.eccentric_anomaly_scalar(1.0, 1.0))
    assert math.isnan(kepler.eccentric_anomaly_scalar(math.inf, 0.5))


def test_scalar_functions_are_the_array_ones():
    """The scalar entries (for numba code and single angles) give the array entries' numbers."""
    M = np.linspace(-7.0, 7.0, 29)
    for e in (0.0, 0.3, 0.99):
        E, f, r = kepler.anomalies(M, e)
        assert np.array_equal([kepler.eccentric_anomaly_scalar(m, e) for m in M], E)
        assert np.array_equal([kepler.true_anomaly_scalar(x, e) for x in E], f)
        assert np.array_equal([kepler.radius_scalar(x, e) for x in E], r)


def test_an_orbit_at_one_time_is_the_orbit_at_many():
    """`KeplerOrbit.anomalies_at` (one time, for an ODE's right-hand side) gives `anomalies`' numbers,
    bit for bit, over many turns, eccentricities up to 0.999 and a shifted periapse time."""
    from theoria.physics.orbits import KeplerOrbit

    t = np.random.default_rng(7).uniform(-1e3, 1e3, 400)
    for e in (0.0, 0.0549, 0.5, 0.999):
        orbit = KeplerOrbit(a=1.3, e=e, n=0.7, t_peri=0.2)
        f, r = orbit.anomalies(t)
        at = np.array([orbit.anomalies_at(x) for x in t])
        assert np.array_equal(at[:, 0], f) and np.array_equal(at[:, 1], r)
