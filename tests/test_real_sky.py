"""The real sky as a reference: the Moon against JPL's DE421 (read from the `de421` package's own
file), the degree-3 field's torque against its energy, and the frames JPL's lunar memo defines.
The long-term pole (Vondrák et al. 2011 through ERFA) and the Cassini state have their own files."""
from __future__ import annotations

import math

import numpy as np
import pytest

from theoria import ParameterError
from theoria.scenarios import get
from theoria.physics import constants as C
from theoria.physics import quaternion as quat
from theoria.physics import real_moon
from theoria.physics.constants import ARCSEC_RAD
from theoria.physics.gravity_field import degree3_potential, degree3_torque, h3
from theoria.physics.gravity_gradient import torque_first_order
from theoria.scenarios._real_sky import de421


def test_lunar_constants_are_the_ephemeris_files():
    """Every DE421 value typed into physics.constants stands in the ephemeris file's header."""
    sky = de421()
    assert C.MOON_BETA_DE421 == sky.constant("LBET")
    assert C.MOON_GAMMA_DE421 == sky.constant("LGAM")
    assert C.MOON_C22_DE421 == sky.constant("C22M")
    names = ("J3M", "C31M", "S31M", "C32M", "S32M", "C33M", "S33M")
    file_values = [sky.constant(n) for n in names]
    file_values[0] = -file_values[0]  # C30 = −J3
    assert C.MOON_DEGREE3_DE421 == tuple(file_values)
    assert C.MOON_REFERENCE_RADIUS_KM == sky.constant("AM")
    assert C.MOON_CORE_MOMENT_FRACTION_DE421 == sky.constant("IFAC")
    assert C.MOON_LOVE_K2_DE421 == sky.constant("K2M")
    assert C.MOON_TIDE_DELAY_DE421_DAYS == sky.constant("TAUM")
    assert C.MOON_CORE_FRICTION_DE421_PER_DAY == sky.constant("KVC")
    # the derived C/MR² is consistent with the file's J2: J2 + 2C22 = (C − A)/MR² = β·B/MR²
    k = C.MOON_POLAR_MOMENT_FACTOR_DE421
    g, b = C.MOON_GAMMA_DE421, C.MOON_BETA_DE421
    B = k * (1 - (sky.constant("J2M") - 2 * C.MOON_C22_DE421) / k)
    assert (sky.constant("J2M") + 2 * C.MOON_C22_DE421) / B == pytest.approx(b, rel=1e-12)
    assert 4 * C.MOON_C22_DE421 / k == pytest.approx(g, rel=1e-15)
    # LLR's β, γ (DE430, the scenario's defaults) and DE421's agree to 1e-4
    assert C.MOON_BETA_LLR == pytest.approx(b, rel=1e-5) and C.MOON_GAMMA_LLR == pytest.approx(g, rel=2e-4)


def test_euler_313_attitude_against_scipy():
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(3)
    ang = rng.uniform(-3, 3, (3, 20))
    q = real_moon.euler313_quaternion(*ang)
    ref = Rotation.from_euler("ZXZ", ang.T).as_matrix()  # intrinsic z-x-z: Rz(φ) Rx(θ) Rz(ψ)
    assert np.allclose(quat.to_matrix(q), ref, atol=1e-14)


def test_body_rates_of_de421_match_the_derivative_of_its_attitude():
    """ω_body from DE421's angle rates (Euler's kinematics for 3-1-3) against 2 q* dq/dt, the
    derivative of DE421's own attitude by central differences."""
    sky = de421()
    t = np.array([-3000.0, 0.0, 9131.0, 20000.0])
    h = 1e-3
    q, w = sky.moon_attitude(t)
    qp, _ = sky.moon_attitude(t + h)
    qm, _ = sky.moon_attitude(t - h)
    w_fd = 2 * quat.multiply(quat.conjugate(q), (qp - qm) / (2 * h))[:, 1:]
    # rad/day (ω ≈ 0.23): the difference quotient itself is off by h²ω³/6 ≈ 2e-9
    assert np.max(np.abs(w - w_fd)) < 5e-9
    assert np.allclose(np.linalg.norm(w, axis=1), 2 * np.pi / C.SIDEREAL_MONTH_DAYS, rtol=2e-3)


def test_principal_axes_and_mean_earth_frames_of_de421():
    """On DE421's mean-Earth axes the Earth's mean direction over a nodal cycle is the axes' origin
    (within ~10″: the cycle is not whole in every term); on its principal axes it sits ~1′ away,
    the offset the memo's rotation (67.92″, 78.56″, 0.30″) undoes."""
    sky = de421()
    t = np.arange(9131.0, 9131.0 + 6798.0, 0.05)
    q, _ = sky.moon_attitude(t)
    s_pa = quat.rotate_inverse(q, sky.earth_from_moon(t))
    s_me = s_pa @ real_moon.pa_to_me_matrix().T
    for s, lo, hi in ((s_pa, 60.0, 130.0), (s_me, 0.0, 12.0)):
        lon = np.arctan2(s[:, 1], s[:, 0]).mean() / ARCSEC_RAD
        lat = np.arcsin(s[:, 2] / np.linalg.norm(s, axis=1)).mean() / ARCSEC_RAD
        assert lo <= math.hypot(lon, lat) <= hi, (lon, lat)


def test_degree3_potential_is_the_legendre_series():
    """H₃/r³ against Σₘ P₃ₘ(sin φ)(C₃ₘ cos mλ + S₃ₘ sin mλ) from scipy's Legendre functions (which
    carry the Condon–Shortley phase (−1)ᵐ that JPL's unnormalised coefficients do not)."""
    from scipy.special import lpmv

    rng = np.random.default_rng(5)
    c = rng.normal(size=7)
    s = rng.normal(size=(50, 3)) * 3.0
    r = np.linalg.norm(s, axis=1)
    lat, lon = np.arcsin(s[:, 2] / r), np.arctan2(s[:, 1], s[:, 0])
    u = np.sin(lat)
    P = {m: (-1) ** m * lpmv(m, 3, u) for m in range(4)}
    ref = P[0] * c[0] + sum(P[m] * (c[2 * m - 1] * np.cos(m * lon) + c[2 * m] * np.sin(m * lon)) for m in (1, 2, 3))
    assert np.allclose(h3(c, s) / r ** 3, ref, rtol=1e-12, atol=1e-12)


def _turned(s, axis, angle):
    """A body-frame point after the body turns by `angle` about `axis`: the point turns the other way."""
    return quat.rotate(quat.from_axis_angle(axis, -angle), s)


def test_degree3_torque_is_minus_the_derivative_of_the_energy():
    """τ·e = −dU/dθ for a turn of the body about e, by central differences of the energy; and the
    same convention gives MacCullagh's quadrupole torque from U₂ = 3GM sᵀIs/(2r⁵) (the sign check)."""
    rng = np.random.default_rng(11)
    c = np.array(C.MOON_DEGREE3_DE421)
    I = np.array([0.9994, 0.99963, 1.0])
    h = 1e-5
    for _ in range(5):
        s = rng.normal(size=3) * 60.0
        k = 1.7
        tau3 = degree3_torque(c, s, k)
        tau2 = torque_first_order(I, s, 2.0)
        for e in np.eye(3):
            dU3 = (degree3_potential(c, _turned(s, e, h), k) - degree3_potential(c, _turned(s, e, -h), k)) / (2 * h)
            assert tau3 @ e == pytest.approx(-dU3, rel=1e-6, abs=1e-9 * np.abs(tau3).max())

            # U₂ = 3GM pᵀIp/(2r⁵) less 3GM r²/(2r⁵), which no turn changes (pᵀp = r²): with I close to
            # 1 that part dominates U₂, and its rounding (1e-16 of it) was 2e-6 of the difference a
            # turn of 1e-5 makes (numpy 2.4's rounding failed the 1e-6 tolerance)
            def U2(p):
                return 3 * 2.0 * (p @ ((I - 1.0) * p)) / (2 * np.linalg.norm(p) ** 5)

            dU2 = (U2(_turned(s, e, h)) - U2(_turned(s, e, -h))) / (2 * h)
            assert tau2 @ e == pytest.approx(-dU2, rel=1e-6, abs=1e-9 * np.abs(tau2).max())


def test_moon_stays_within_20_arcsec_of_de421_for_six_years():
    """The goal: started from DE421's Moon, with DE421's Earth and Sun, the model's attitude stays
    within 20″ of DE421's for 6 years (measured 0.8″ at the end, 1.6″ at most); without the
    degree-3 field it does not (~120″: the principal axes' offset from the mean Earth is that
    field's doing), nor does Euler's quadrupole Moon started on the mean frame (~170″)."""
    from theoria.scenarios.moon import DE421_TOLERANCE_ARCSEC, de421_residual

    full = de421_residual()
    assert full["max"] < 3.0 and full["final"] < DE421_TOLERANCE_ARCSEC
    assert de421_residual({"field": "quadrupole"})["final"] > 60.0
    assert de421_residual({"field": "quadrupole", "sun_torque": "off", "core_fraction": 0.0,
                           "start": "forced"})["final"] > 100.0


def test_runs_outside_de421_are_refused_naming_the_parameter():
    from theoria.scenarios.base import get

    with pytest.raises(ParameterError) as e:
        get("moon").simulate({"start_year": 1899.5})
    assert e.value.name == "start_year"
    with pytest.raises(ParameterError) as e:
        get("moon").simulate({"start_year": 2180.0, "years": 25.0})
    assert e.value.name == "years" and "DE421" in str(e.value)
    # Euler's own setting (lunar theory, mean-frame start) reads no ephemeris and is not limited by it
    assert get("moon").resolve({"start_year": 1900.0, "ephemeris": "lunar-theory", "start": "forced"})


@pytest.mark.slow
def test_optical_libration_maxima_quoted_are_de421s():
    """physics.constants' ranges of DE421's optical libration maxima per 18.6-year window,
    recomputed from the file (0.1-day samples, so within ~0.001° of the 0.02-day values)."""
    sky = de421()
    M = real_moon.pa_to_me_matrix()
    y0, n = C.MOON_OPTICAL_LIBRATION_DE421_WINDOWS
    lons, lats = [], []
    for w in y0 + 18.6 * np.arange(n):
        t = np.arange((w - 2000) * 365.25, (w + 18.6 - 2000) * 365.25, 0.1)
        t = t[t <= sky.last_day]
        q, _ = sky.moon_attitude(t)
        s = quat.rotate_inverse(q, sky.earth_from_moon(t)) @ M.T
        lons.append(np.degrees(np.abs(np.arctan2(s[:, 1], s[:, 0])).max()))
        lats.append(np.degrees(np.abs(np.arcsin(s[:, 2] / np.linalg.norm(s, axis=1))).max()))
    assert min(lons) == pytest.approx(C.MOON_OPTICAL_LIBRATION_LON_MAX_DE421_DEG[0], abs=0.002)
    assert max(lons) == pytest.approx(C.MOON_OPTICAL_LIBRATION_LON_MAX_DE421_DEG[1], abs=0.002)
    assert min(lats) == pytest.approx(C.MOON_OPTICAL_LIBRATION_LAT_MAX_DE421_DEG[0], abs=0.002)
    assert max(lats) == pytest.approx(C.MOON_OPTICAL_LIBRATION_LAT_MAX_DE421_DEG[1], abs=0.002)


def test_the_span_the_moon_scene_states_is_de421s():
    """The start year's help said DE421 covers 1900.01–2200.09 (and a docstring 1899–2053): the
    file the `de421` package ships starts 1899 December 4 and ends 2200 February 1 (erfa.jd2cal)."""
    import re

    import de421
    import erfa
    from jplephem.ephem import Ephemeris

    from theoria.scenarios import get

    e = Ephemeris(de421)
    assert erfa.jd2cal(e.jalpha, 0.0)[:3] == (1899, 12, 4) and erfa.jd2cal(e.jomega, 0.0)[:3] == (2200, 2, 1)
    help_text = get("moon").param("start_year").help
    lo, hi = map(float, re.search(r"covers (\d{4}\.\d+)–(\d{4}\.\d+)", help_text).groups())
    assert lo == pytest.approx(erfa.epj(e.jalpha, 0.0), abs=0.005) and hi == pytest.approx(erfa.epj(e.jomega, 0.0), abs=0.005)


@pytest.mark.parametrize("years, unmeasured", [(0.2, ("annual", "evection", "free")), (2.0, ("free",))])
def test_a_short_moon_run_measures_only_the_terms_its_span_tells_apart(years, unmeasured):
    """Fitted together over 0.2 yr, the libration terms traded amplitudes: the anomalistic-month
    term came out 3.9e7″ (Eckhardt 1981: −16.8″), the annual 2.2e8″, and no warning said so. A
    term is measured only when the span holds a whole cycle of it and a cycle apart from each
    larger neighbour; the others have no value, and the run says which."""
    from theoria.scenarios.moon import resolvable

    assert resolvable([1 / 13.777, 1 / 13.606], 1000.0) == [True, False]  # 2M′ and 2F: 3 yr to part them
    assert resolvable([1 / 13.777, 1 / 13.606], 1200.0) == [True, True]
    run = get("moon").simulate(years=years)
    m = run.metrics
    assert abs(m["physical_libration_mprime_arcsec"] / -16.8 - 1) < 0.25  # the published term, not 10⁷″
    keys = {"annual": "physical_libration_annual_arcsec", "evection": "physical_libration_evection_arcsec",
            "free": "free_libration_amplitude_arcsec"}
    for name, key in keys.items():
        assert np.isnan(m[key]) == (name in unmeasured), (name, m[key])
    assert any(f"span of {years:g} yr cannot tell" in w for w in run.warnings)


def test_an_observed_value_is_compared_only_with_a_run_of_that_body():
    """With H = 10⁻⁹ the Earth's precession is nearly nil, and IAU 2006's 50.4″/yr for the real
    Earth beside it read as a 100 % miss. A modern value that observes a real body is compared
    only while the run is that body; otherwise the note keeps it and says why."""
    earth = get("earth")
    real = earth.simulate(years=2)
    other = earth.simulate(years=2, H=1e-9)
    row = lambda run: next(c for c in run.comparisons if c.label == "luni-solar precession")  # noqa: E731
    assert row(real).modern == pytest.approx(50.404, abs=1e-3)
    assert row(other).modern is None and "the real Earth's 50.404″/yr, not compared" in row(other).note
    # the Moon's node against the stars does not hang on the Earth's figure: still compared
    node = lambda run: next(c for c in run.comparisons if "node regression" in c.label)  # noqa: E731
    assert node(other).modern == node(real).modern is not None
    moon = get("moon").simulate(years=3, gamma=3e-4)
    assert all(c.modern is None for c in moon.comparisons if "physical libration" in c.label)
    assert all(c.modern is not None for c in moon.comparisons if c.label.startswith("optical libration"))


@pytest.mark.parametrize("start", ["uniform", "forced"])
def test_a_moon_run_past_de421_is_refused_whatever_it_runs_with(start):
    """Every Moon run is compared with DE421's Moon. With the lunar theory's Earth and a start of
    its own, the date check was skipped and a run to 2210 ended in jplephem's DateError (a
    traceback; "Error: DateError" in the app). It is refused as a DE421 run is, naming `years`
    and what fits (DE421's span: 1899-07-29 to 2200-02-01, JPL's header of the file)."""
    import theoria as th

    sc = th.scenario("moon")
    with pytest.raises(th.ParameterError) as e:
        sc.simulate(ephemeris="lunar-theory", start=start, start_year=2190, years=20)
    assert e.value.name == "years" and "DE421 ends there" in str(e.value) and "years ≤ 10.0" in str(e.value)
