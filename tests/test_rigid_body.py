"""The rigid-body core against independent references: scipy's elliptic functions and Carlson
integrals (the exact solution), tight-tolerance DOP853 on Euler's equations, scipy Rotation."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipj as sp_ellipj
from scipy.spatial.transform import Rotation

from theoria.physics import quaternion as quat
from theoria.physics.euler_equations import rhs_state
from theoria.physics import free_flow as ff
from theoria.physics.free_flow import ellipj, free_flow, prepare, drift
from theoria.physics.integrator import PointMass, integrate
from theoria.physics.torque_free_exact import exact_free_motion, free_motion

BODIES = [
    ((1.0, 2.0, 3.0), (0.3, 1.0, 0.2)),  # circulates about C
    ((1.0, 2.0, 3.0), (1.0, 0.1, 0.3)),  # circulates about A
    ((3.0, 2.0, 1.0), (0.3, 1.0, -0.2)),  # reversed order
    ((2.0, 1.0, 3.0), (0.1, -1.0, 0.05)),  # middle moment on x, spin near it
    ((1.0, 1.0, 2.0), (0.3, 0.1, 1.0)),  # oblate, symmetric
    ((1.0, 2.0, 2.0), (0.3, 0.1, 1.0)),  # prolate, symmetric
    ((1.0, 1.000228, 1.000631), (0.001, 0.002, 1.0)),  # Moon-like
    ((1.0, 2.0, 3.0), (0.0, 0.0, 1.0)),  # permanent rotation
    ((1.0, 2.0, 3.0), (0.0, 1.0, 0.0)),  # unstable permanent rotation
    ((2.0, 2.0, 2.0), (0.3, -0.4, 1.0)),  # sphere
]
Q0 = quat.normalize(np.array([0.9, 0.1, -0.2, 0.3]))


def dop853(I, w0, q0, t_end, t_eval=None, torque=None):
    s = solve_ivp(rhs_state, (0, t_end), np.concatenate([w0, q0]), method="DOP853", rtol=1e-13, atol=1e-14,
                  args=(np.asarray(I, float), torque), t_eval=t_eval)
    return s.y[:3].T, quat.normalize(s.y[3:].T)


@pytest.mark.parametrize("m", [0.0, 1e-12, 1e-5, 0.3, 0.9, 0.999999, 1 - 1e-11, 1.0])
def test_ellipj_against_mpmath_and_scipy(m):
    mp = pytest.importorskip("mpmath")
    mp.mp.dps = 30
    for u in np.linspace(-4, 4, 41):
        ref = [float(mp.ellipfun(f, u, m=m)) for f in ("sn", "cn", "dn")]
        assert np.allclose(ellipj(u, m), ref, rtol=0, atol=4e-15)
        assert np.allclose(ellipj(u, m), sp_ellipj(u, m)[:3], rtol=0, atol=4e-15)


@pytest.mark.parametrize("I,w0", BODIES)
def test_free_flow_steps_match_dop853(I, w0):
    I, w0 = np.array(I), np.array(w0)
    L, q = I * w0, Q0.copy()
    for _ in range(200):
        L, q = free_flow(L, q, I, 0.05)
    w_ref, q_ref = dop853(I, w0, Q0, 10.0)
    assert np.max(np.abs(L / I - w_ref[-1])) < 1e-11
    assert quat.angle_between(q, q_ref[-1]) < 1e-11


@pytest.mark.parametrize("I,w0", [b for b in BODIES[:7]])
def test_exact_solution_matches_dop853(I, w0):
    t = np.linspace(0, 20, 9)
    w, q = exact_free_motion(I, w0, t, Q0)
    w_ref, q_ref = dop853(I, np.array(w0), Q0, 20.0, t_eval=t)
    assert np.max(np.abs(w - w_ref)) < 1e-11
    assert np.max(quat.angle_between(q, q_ref)) < 1e-11
    # evaluating at one late time alone gives the same state (nothing depends on t[0])
    w1, q1 = exact_free_motion(I, w0, t[-1:], Q0)
    assert quat.angle_between(q1[0], q[-1]) < 1e-12


def _spin_period(w0):
    return 2 * np.pi / np.linalg.norm(w0)


@pytest.mark.parametrize("I,w0", [((1.0, 2.0, 3.0), (0.3, 1.0, 0.2)),  # strongly triaxial
                                  ((1.0, 1.000228, 1.000631), (0.01, 0.02, 1.0))])  # Moon-like
@pytest.mark.parametrize("steps_per_period", [50, None])
def test_attitude_after_100_spin_periods(I, w0, steps_per_period):
    """The free body's attitude within 1e-8 rad of the exact solution after 100 periods,
    at T/50 and at the free-tumble scenario's default step (0.01 s)."""
    T = _spin_period(w0)
    h = T / steps_per_period if steps_per_period else 0.01
    t, L, q = integrate(I, w0, 100 * T, h, stride=10**9)
    w_ex, q_ex = exact_free_motion(I, w0, [t[-1]])
    assert t[-1] == pytest.approx(100 * T, rel=1e-14)
    assert quat.angle_between(q[-1], q_ex[0]) < 1e-8
    assert np.max(np.abs(L[-1] / np.asarray(I) - w_ex[0])) < 1e-10


def test_energy_and_momentum_1e6_steps_bounded():
    """Energy and |L| kept to |ΔE/E|, |Δ|L||/|L| ≤ 1e-12 after 10⁶ steps at T/50, no secular drift:
    the error over 10⁶ steps is no larger than √100 times the error over 10⁴ (round-off level)."""
    I, w0 = np.array([1.0, 2.0, 3.0]), np.array([0.3, 1.0, 0.2])
    h = _spin_period(w0) / 50
    t, L, _ = integrate(I, w0, 1e6 * h, h, stride=100)
    E = np.sum(L * L / I, axis=1)
    G = np.linalg.norm(L, axis=1)
    eE = np.abs(E / E[0] - 1)
    eG = np.abs(G / G[0] - 1)
    assert eE.max() <= 1e-12 and eG.max() <= 1e-12
    ulp = np.finfo(float).eps
    first = max(eE[:101].max(), eG[:101].max(), 4 * ulp)  # first 10⁴ steps
    assert max(eE.max(), eG.max()) <= 10 * first


def _torque_case():
    I = np.array([1.0, 2.0, 3.0])
    w0 = np.array([0.3, 1.0, 0.2])
    n, r = 0.3, 5.0
    gm = n * n * r**3

    def pos(t):
        t = np.asarray(t, float)
        return r * np.stack([np.cos(n * t), np.sin(n * t), 0.2 * np.ones_like(t)], axis=-1)

    def torque(t, q, w):
        s = quat.rotate_inverse(quat.normalize(q), pos(np.array([t]))[0])
        return 3 * gm / np.linalg.norm(s) ** 5 * np.cross(s, I * s)

    return I, w0, PointMass(gm, pos), torque


@pytest.mark.parametrize("scheme,order", [("strang", 2), ("yoshida4", 4)])
def test_order_of_convergence_with_gravity_gradient(scheme, order):
    I, w0, mass, torque = _torque_case()
    w_ref, q_ref = dop853(I, w0, quat.IDENTITY, 10.0, torque=torque)
    errs = []
    for h in (0.1, 0.05, 0.025):
        _, L, q = integrate(I, w0, 10.0, h, masses=[mass], scheme=scheme)
        errs.append(max(np.max(np.abs(L[-1] / I - w_ref[-1])), quat.angle_between(q[-1], q_ref[-1])))
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(rates - order) < 0.15), rates


def test_constant_body_torque_second_order():
    I, w0 = np.array([1.0, 2.0, 3.0]), np.array([0.3, 1.0, 0.2])
    tq = np.array([0.1, -0.2, 0.05])
    w_ref, _ = dop853(I, w0, quat.IDENTITY, 10.0, torque=lambda t, q, w: tq)
    e = [np.max(np.abs(integrate(I, w0, 10.0, h, torque_body=tq)[1][-1] / I - w_ref[-1])) for h in (0.05, 0.025)]
    assert 3.8 < e[0] / e[1] < 4.2


def test_output_stride_and_times():
    t, L, q = integrate((1, 2, 3), (0.3, 1, 0.2), 10.0, 0.01, stride=7)
    assert t[0] == 0 and t[-1] == pytest.approx(10.0)
    assert len(t) == len(L) == len(q) == 1000 // 7 + 2  # samples every 7 steps, plus the last
    assert np.allclose(np.diff(t)[:-1], 0.07)


@pytest.mark.parametrize("stride, masses", [(70_000, ()), (25_000, (PointMass(3.0, lambda t: np.stack(
    [10 * np.cos(0.01 * t), 10 * np.sin(0.01 * t), 0 * t], axis=-1)),))])
def test_kept_states_further_apart_than_a_chunk_report_progress_every_chunk(stride, masses):
    """With kept states further apart than a chunk (a long run at a fine step: 1e15 steps keep one
    state in ~3e11), the compiled loop ran a whole stride between two returns to Python, so neither
    the progress line nor Ctrl-C was seen for hours. It returns every chunk; the states are the
    same bits as one long chunk's."""
    seen = []
    args = ((1, 2, 3), (0.3, 1, 0.2), 2.0, 1e-5)
    t, L, q = integrate(*args, stride=stride, masses=masses, chunk_steps=20_000, progress=seen.append)
    t1, L1, q1 = integrate(*args, stride=stride, masses=masses, chunk_steps=10 ** 9)
    assert len(seen) >= 200_000 // 20_000 and np.all(np.diff(seen) <= 20_000 / 200_000 + 1e-12), seen
    assert np.array_equal(t, t1) and np.array_equal(L, L1) and np.array_equal(q, q1)
    assert len(t) == 200_000 // stride + 1 + (200_000 % stride > 0) and t[-1] == pytest.approx(2.0)
    assert np.allclose(np.diff(t)[:200_000 // stride], stride * 1e-5)


def test_prepare_drift_reuse_equals_fresh_steps():
    I = np.array([1.0, 2.0, 3.0])
    L = I * np.array([0.3, 1.0, 0.2])
    ip, c, tab = prepare(L, I, 0.05)
    L1, q1 = drift(L, Q0, I, 0.05, ip, c, tab)
    L2, q2 = free_flow(L, Q0, I, 0.05)
    assert np.allclose(L1, L2, atol=1e-15) and quat.angle_between(q1, q2) < 1e-14


@pytest.mark.parametrize("I,w0", [b for b in BODIES if len(set(b[0])) == 2])
def test_a_body_of_revolution_takes_the_closed_form_and_meets_the_elliptic_one(I, w0):
    """Two equal moments: the flow is two uniform rotations (no elliptic function). The same
    start on a body whose equal moments differ by 1e-12 (elliptic functions with k² ~ 1e-12,
    quadrature of ψ̇) ends in the same state after 2,000 steps; DOP853 checks both above."""
    I, w0 = np.array(I), np.array(w0)
    assert prepare(I * w0, I, 0.05)[0][4] == ff.SYMMETRIC
    J = I.copy()
    J[np.flatnonzero(I == np.median(I))[0]] *= 1 + 1e-12
    assert prepare(I * w0, J, 0.05)[0][4] == ff.GENERAL
    (La, qa), (Lb, qb) = (I * w0, Q0.copy()), (I * w0, Q0.copy())
    for _ in range(2000):
        La, qa = free_flow(La, qa, I, 0.05)
        Lb, qb = free_flow(Lb, qb, J, 0.05)
    assert np.max(np.abs(La - Lb)) < 1e-9 * np.linalg.norm(La)
    assert quat.angle_between(qa, qb) < 1e-9


def test_psi_quadrature_rules_against_mpmath():
    """Each Gauss–Legendre rule `prepare` may choose integrates ψ̇'s integrand over the longest
    piece it is given to the accuracy of 10 nodes (mpmath: sn, cn at 30 digits, its own
    quadrature), for random triaxial bodies, near-symmetric ones among them."""
    mp = pytest.importorskip("mpmath")
    mp.mp.dps = 30
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(60):
        I = np.sort(rng.uniform(0.1, 3.0, 3))
        if rng.random() < 0.3:
            I[1] = I[0] * (1 + 10 ** rng.uniform(-8, -1))
        ip, c, _ = prepare(rng.normal(size=3) * rng.uniform(0.1, 5.0), I, 1e-3)
        if ip[4] != ff.GENERAL:
            continue
        J1, J2, m, p, r = c[0], c[1], c[7], c[9], c[10]
        du_max = 0.5 * np.sqrt(max(J1 * p / (J2 * r), 1e-6))

        def f(u):
            sn, cn = mp.ellipfun("sn", u, m=m), mp.ellipfun("cn", u, m=m)
            return (p * cn ** 2 + r * sn ** 2) / (J1 * p * cn ** 2 + J2 * r * sn ** 2)

        u0 = mp.mpf(rng.uniform(0.0, 4.0))
        for rule, n in enumerate(ff.GL_N):
            v = mp.mpf(ff.GL_SPAN[rule] * du_max * rng.uniform(0.7, 1.0))
            ref = mp.quad(f, [u0, u0 + v])
            got = sum(float(v * f(u0 + v * mp.mpf(x))) * w for x, w in zip(ff.GL_X[rule, :n], ff.GL_W[rule, :n]))
            worst = max(worst, abs(got / float(ref) - 1))
    assert worst < 1e-15, worst


def test_the_step_table_holds_ellipj_values_bit_for_bit():
    """`prepare` makes the Landen sequence once for all the nodes of a step: each sn, cn, dn of its
    table is the one `ellipj` (checked against mpmath and scipy above) gives at that argument."""
    rng = np.random.default_rng(11)
    for _ in range(200):
        I = np.sort(rng.uniform(0.1, 3.0, 3))
        L = rng.normal(size=3) * rng.uniform(0.1, 5.0)
        h = 10 ** rng.uniform(-3, 0.5)
        ip, c, tab = prepare(L, I, h)
        if ip[4] != ff.GENERAL:
            continue
        m, m1, v = c[7], c[11], c[6] * h
        nsub, n = ip[5], ff.GL_N[ip[6]]
        dv = v / nsub
        args = [v] + [(j + x) * dv for j in range(nsub) for x in ff.GL_X[ip[6], :n]]
        assert np.array_equal(tab, np.array([ellipj(u, m, m1) for u in args])), (m, m1)


def test_polhode_period_and_flip_interval_from_dop853():
    """The flip interval 2K/λ against sign changes of ω₂ found in an independent DOP853 run."""
    I, w0 = np.array([1.0, 2.0, 3.0]), np.array([0.06, 6.0, 0.06])
    fm = free_motion(I, w0)
    ev = lambda t, y, *a: y[1]  # noqa: E731
    s = solve_ivp(rhs_state, (0, 20), np.concatenate([w0, quat.IDENTITY]), method="DOP853", rtol=1e-13,
                  atol=1e-14, args=(I, None), events=ev)
    crossings = s.t_events[0]
    assert len(crossings) >= 4
    assert np.mean(np.diff(crossings)) == pytest.approx(fm.flip_interval, rel=1e-9)
    assert fm.polhode_period == pytest.approx(2 * fm.flip_interval, rel=1e-15)


@pytest.mark.parametrize("I, w0", [((2.0, 3.0, 4.0), (1.0, 0.5, 1.5)), ((2.0, 3.0, 4.0), (2.0, 0.3, 0.3)),
                                   ((1.0, 2.5, 3.0), (0.2, -0.4, 3.0)), ((3.0, 3.0, 4.0), (1.0, 0.0, 1.5))])
def test_free_tumble_polhode_period_euler_simulated_modern(I, w0):
    """free-tumble's row: Euler's §808 quadrature (×2; for A = B his equations' circle), the period
    measured in theoria's run, and the modern 4K/λ, all against sign changes of ω on the middle
    axis in an independent DOP853 run."""
    from theoria.scenarios import get

    spec = get("free-tumble")
    res = spec.simulate_fn(spec.resolve({"inertia": ",".join(map(str, I)), "omega0": ",".join(map(str, w0)),
                                         "duration": "60"}))
    row = next(c for c in res.comparisons if c.label == "polhode period")
    k = int(np.argsort(I, kind="stable")[1])
    s = solve_ivp(rhs_state, (0, 60), np.concatenate([w0, quat.IDENTITY]), method="DOP853", rtol=1e-13,
                  atol=1e-14, args=(np.array(I), None), events=lambda t, y, *a: y[k])
    ref = 2 * np.mean(np.diff(s.t_events[0]))
    for value in (row.euler, row.simulated, row.modern):
        assert value == pytest.approx(ref, rel=1e-8)


# --- quaternion conventions ---------------------------------------------------------------

def test_quaternion_conventions_against_scipy():
    rng = np.random.default_rng(1)
    q = quat.normalize(rng.normal(size=(20, 4)))
    v = rng.normal(size=(20, 3))
    R = Rotation.from_quat(quat.to_xyzw(q))  # scipy is scalar-last
    assert np.allclose(quat.rotate(q, v), R.apply(v))
    assert np.allclose(quat.rotate_inverse(q, v), R.inv().apply(v))
    assert np.allclose(quat.to_matrix(q), R.as_matrix())
    assert np.allclose(quat.from_xyzw(quat.to_xyzw(q)), q)
    p = quat.normalize(rng.normal(size=(20, 4)))
    Rp = Rotation.from_quat(quat.to_xyzw(p))
    assert np.allclose(quat.rotate(quat.multiply(p, q), v), (Rp * R).apply(v))
    # scalar first: the identity is (1, 0, 0, 0)
    assert np.allclose(Rotation.from_quat(quat.to_xyzw(quat.IDENTITY)).as_matrix(), np.eye(3))
    # a quarter turn about z takes body x to inertial y
    qz = quat.from_axis_angle([0, 0, 1], np.pi / 2)
    assert np.allclose(quat.rotate(qz, [1, 0, 0]), [0, 1, 0])
    assert np.isclose(quat.angle_between(quat.IDENTITY, qz), np.pi / 2)


def test_body_rate_is_body_frame():
    """ω in the body frame: a body spinning about its x axis with attitude q turns about R·x."""
    I = np.array([1.0, 2.0, 3.0])
    q0 = quat.from_axis_angle([0, 1, 0], 0.7)
    t, L, q = integrate(I, (2.0, 0, 0), 0.5, 0.01, q0=q0)
    expected = quat.multiply(q0, quat.from_axis_angle([1, 0, 0], 1.0))
    assert quat.angle_between(q[-1], expected) < 1e-13


def test_a_run_of_a_few_steps_says_it_cannot_show_the_motion():
    """A teacher typed a length of 0.001 s with the 0.01-s step: the run held two states, the
    read-out stood at its end and the polhode had no value, without a word."""
    import theoria as th

    sc = th.scenario("free-tumble")
    short = sc.simulate(inertia=(1e-3, 2e-3, 2.5e-3), omega0=(1e-3, 0, 0), duration=1e-3)
    assert len(short.trajectory.t) == 2
    assert any("too few to show or measure the motion" in w and "0.001 s" in w for w in short.warnings), short.warnings
    assert not any("too few to show" in w for w in sc.simulate(duration=1.0).warnings)  # 100 steps
