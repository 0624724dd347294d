"""Euler's closed forms of ch. 15 against Euler's equations integrated independently."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from theoria.physics import quaternion as quat
from theoria.physics.euler_ch15 import (axis_and_speed_rates, flip_interval_808, initial_axis,
                                initial_axis_angles_807, integrals_808, vis_viva)
from theoria.physics.euler_equations import direction_cosines_dot, omega_dot, rhs_state
from theoria.physics.inertia import ellipsoid_moments, ellipsoid_semi_axes
from theoria.physics.integrator import integrate
from theoria.physics.torque_free_exact import free_motion

I = np.array([1.0, 2.0, 3.0])


def _dop(w0, t_end, torque=None, n=50):
    t = np.linspace(0, t_end, n)
    s = solve_ivp(rhs_state, (0, t_end), np.concatenate([w0, quat.IDENTITY]), method="DOP853",
                  rtol=1e-13, atol=1e-14, args=(I, torque), t_eval=t)
    return t, s.y[:3].T


def test_vis_viva_and_808_integrals_constant_along_dop853():
    _, w = _dop(np.array([0.3, 1.0, 0.2]), 30.0)
    vv = vis_viva(w, I)
    ints = integrals_808(w, I)
    assert np.ptp(vv) / vv[0] < 1e-12
    assert np.allclose(ints, ints[0], rtol=1e-11, atol=1e-12)
    assert np.allclose(ints[:, 0], vv)


@pytest.mark.parametrize("torque", [(0, 0, 0), (0.3, -0.2, 0.5)])
def test_803_rates_of_axis_and_speed(torque):
    """§803/§805 against the same rates by differentiating cos α = x/γ' along Euler's equations."""
    w = np.array([0.3, 1.0, 0.2])
    wd = omega_dot(w, I, torque)
    g = np.linalg.norm(w)
    gd = w @ wd / g
    cos = w / g
    cos_d = (wd * g - w * gd) / g**2
    ang_d = -cos_d / np.sqrt(1 - cos**2)  # d(arccos c)/dt
    dg, da, db, dc = axis_and_speed_rates(w, I, torque)
    assert dg == pytest.approx(gd, rel=1e-13)
    assert np.allclose([da, db, dc], ang_d, rtol=1e-12)
    # arrays of states broadcast
    dgs = axis_and_speed_rates(np.stack([w, 2 * w]), I, torque)[0]
    assert dgs.shape == (2,) and dgs[0] == pytest.approx(gd, rel=1e-13)


def test_806_initial_axis_and_807_angles():
    tau = np.array([1.0, -0.7, 0.4])
    axis, acc = initial_axis(tau, I)
    wd = omega_dot(np.zeros(3), I, tau)  # Euler's equations at rest
    assert np.allclose(axis, wd / np.linalg.norm(wd))
    assert acc == pytest.approx(np.linalg.norm(wd))
    for tq in (tau, np.array([0.0, 1.0, 1.0]), np.array([-0.5, 0.0, -2.0])):  # P = 0 and P < 0 too
        ax, _ = initial_axis(tq, I)
        eta, th = initial_axis_angles_807(tq, I)
        assert np.allclose([np.cos(eta) * np.cos(th), -np.sin(eta) * np.cos(th), np.sin(th)], ax)
    with pytest.raises(ValueError):
        initial_axis((0, 0, 0), I)


def test_806_numerical_start_error_is_second_order():
    """ω(t) = ω̇₀t + O(t³) from rest, so the axis leaves Euler's by O(t²)."""
    tau = np.array([1.0, -0.7, 0.4])
    axis, _ = initial_axis(tau, I)
    errs = []
    for h in (0.02, 0.01):
        _, L, _ = integrate(I, np.zeros(3), h, h / 16, torque_body=tau)
        w = L[-1] / I
        errs.append(np.arctan2(np.linalg.norm(np.cross(axis, w)), axis @ w))
    assert 3.5 < errs[0] / errs[1] < 4.5


def test_811_direction_cosines_agree_with_the_attitude():
    """§811 integrated for the fixed pole Z gives the body components of Z = Rᵀ e_z."""
    w0 = np.array([0.3, 1.0, 0.2])
    q0 = quat.from_axis_angle([1, 1, 0], 0.4)
    z0 = quat.rotate_inverse(q0, [0, 0, 1])
    rhs = lambda t, y: np.concatenate([omega_dot(y[:3], I), direction_cosines_dot(y[3:], y[:3])])  # noqa: E731
    s = solve_ivp(rhs, (0, 25), np.concatenate([w0, z0]), method="DOP853", rtol=1e-13, atol=1e-14)
    t, L, q = integrate(I, w0, 25.0, 0.05, q0=q0)
    assert np.allclose(quat.rotate_inverse(q[-1], [0, 0, 1]), s.y[3:, -1], atol=1e-10)


@pytest.mark.parametrize("inertia,w0", [((1, 2, 3), (0.01, 1, 0.01)), ((1, 2, 3), (0.3, 1, 0.2)),
                                        ((3, 2, 1), (0.3, 1, 0.2)), ((1, 2, 3), (1, 0.1, 0.3))])
def test_808_quadrature_equals_jacobi_flip_interval(inertia, w0):
    assert flip_interval_808(inertia, w0) == pytest.approx(free_motion(inertia, w0).flip_interval, rel=1e-11)


def test_ellipsoid_semi_axes_round_trip():
    for inertia in [(2, 3, 4), (1, 1, 2), (1, 2, 2.5), (0.4, 0.4, 0.4)]:
        ax = ellipsoid_semi_axes(inertia, mass=2.0)
        assert np.allclose(ellipsoid_moments(ax, mass=2.0), inertia)


def test_a_run_too_long_for_its_samples_counts_no_flips_and_says_what_helps():
    """Over 50,000 s the 20,000 states kept are 2.5 s apart, more than half the 4.26-s interval
    between flips (2K(k)/λ): flips between two samples go unseen, so the count (16,517 of ~23,500
    at 1e5 s) is not reported, and the warning no longer says a finer step would help (the samples
    kept are capped, not the step)."""
    from theoria.scenarios.base import get

    r = get("middle-axis-flip").simulate({"duration": 50000, "step": 0.2})
    m = r.metrics
    assert np.isnan(m["flips_seen"]) and np.isnan(m["flip_interval"]) and m["flip_interval_exact"] > 4
    sparse = [w for w in r.warnings if "too sparse" in w]
    assert len(sparse) == 2 and all("shorten the run" in w and "Lower step" not in w for w in sparse), r.warnings
    # a short run at a coarse step: there the step is what to lower
    r = get("middle-axis-flip").simulate({"duration": 30, "step": 1.0})
    assert any("too sparse" in w and "Lower step" in w for w in r.warnings), r.warnings
    assert np.isfinite(get("middle-axis-flip").simulate({"duration": 30}).metrics["flips_seen"])
