"""Forced libration in an eccentric orbit (Problem 94, §833–838): ζ = A²α/(A²−2N) sin At, the
periodic (forced) solution found by shooting, and the free libration beside it.

Check rows E8 (the forced amplitude) and E8.free (the free period).
"""
from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
from scipy.integrate import solve_ivp
from ..physics import libration as lib
from ..physics import quaternion as quat
from ..physics.integrator import PointMass, integrate, step_count
from ..physics.kept import kept
from ..physics.orbits import KeplerOrbit
from ..physics.params import Param, ParameterError
from ..physics.trajectory import Trajectory
from .drawing import Camera
from .base import Batch, Comparison, Run, Scenario, register
from .budget import Cost, trajectory_bytes
from .base import get
from .checks import register_check
from ._libration import batched_planar_runs, planar_moments, run_samples, stride_for, zeta_of
from ._ch16_drawing import ORBIT_OPTION, ZETA_OPTION, body_scene, centre_of_force, f_and_zeta
from . import _validity

# Euler's forced amplitude (§833) is called outside its regime when it is off the periodic
# solution's first harmonic by more than this (relative), or when a body started on his formula
# leaves the libration within EULER_START_ORBITS orbits
EULER_AMPLITUDE_TOLERANCE = 0.10
EULER_START_ORBITS = 10


class ForcedSolution:
    """The forced (periodic) libration on the Kepler orbit (periapse at t = 0), §838: found
    once by shooting (physics.libration.periodic_libration), evaluated at any t."""

    def __init__(self, gamma, e, n, progress=None):
        self.orbit = KeplerOrbit(a=1.0, e=e, n=n)
        N = lib.euler_N(gamma, n * n, 1.0)
        m = lib.forced_amplitude_euler(2 * e, n, N)
        zeq = lib.equilibrium_zeta(gamma)
        if gamma == 0:  # no torque (§837, n = 0): uniform rotation, ζ is the equation of the centre
            lam0, lamdot0, P = -zeq, float(n), 2 * np.pi / n
        else:
            guess = (-zeq, float(self.orbit.true_anomaly_rate(np.array([0.0]))[0] - m * n))
            try:
                lam0, lamdot0, P = lib.periodic_libration(self.orbit, gamma, n * n, guess=guess, progress=progress)
                # Euler's guess far off (near the resonance A² = 2N): Newton may land on the other
                # family, the long axis across the line to F at periapse (unstable)
                jumped = abs(np.remainder(lam0 - guess[0] + 0.5 * np.pi, np.pi) - 0.5 * np.pi) > 0.25 * np.pi
            except ParameterError as err:
                lam0, jumped, refused = None, True, err
            else:
                refused = None
            if jumped:
                found = _continued(gamma, e, n, zeq)
                if found is None:
                    if refused is not None:
                        raise refused
                else:
                    lam0, lamdot0, P = found
        lam0 = float(np.remainder(lam0 + 0.5 * np.pi, np.pi) - 0.5 * np.pi)  # ζ ≡ ζ + π
        self.lam0, self.lamdot0, self.P = lam0, lamdot0, P
        self.sol = solve_ivp(lib.planar_rhs(self.orbit, gamma, n * n), (0.0, P), [lam0, lamdot0],
                             method="DOP853", rtol=1e-12, atol=1e-13, dense_output=True).sol

    def once(self, name: str, compute):
        """A property of the forced solution alone (its stability, Euler's start), computed once."""
        if name not in self.__dict__:
            self.__dict__[name] = compute()
        return self.__dict__[name]

    def zeta(self, t):
        tt = np.remainder(np.asarray(t, float), self.P)
        return self.orbit.true_anomaly(tt) - self.sol(tt)[0]


CONTINUATION_STEPS = 8


def _continued(gamma, e, n, zeq):
    """The forced solution followed from a nearly circular orbit out to eccentricity e in
    CONTINUATION_STEPS steps, each started from the last (its offset from the orbit's own rate at
    periapse scaled with e): where Euler's first-order guess is too far off for Newton (near the
    resonance A² = 2N: e = 0.1, (B − A)/C = 0.3 was refused, e = 0.05, 0.32 found the unstable
    family), the solution of the nearby orbit is not. None when a step fails."""
    y, e_prev = None, 0.0
    for k in range(1, CONTINUATION_STEPS + 1):
        e_k = e * k / CONTINUATION_STEPS
        orbit = KeplerOrbit(a=1.0, e=e_k, n=n)
        rate0 = float(orbit.true_anomaly_rate(np.array([0.0]))[0])
        if y is None:
            N = lib.euler_N(gamma, n * n, 1.0)
            guess = (-zeq, rate0 - lib.forced_amplitude_euler(2 * e_k, n, N) * n)
        else:
            guess = (y[0], rate0 + y[2] * e_k / e_prev)
        try:
            lam0, lamdot0, P = lib.periodic_libration(orbit, gamma, n * n, guess=guess)
        except ParameterError:
            return None
        y, e_prev = (lam0, lamdot0, lamdot0 - rate0), e_k
    return y[0], y[1], 2.0 * np.pi / n


@kept(32)
def forced_solution(gamma, e, n, progress=None) -> ForcedSolution:
    """The forced solution of these numbers, made once (read-only): moving any other slider reuses it."""
    return ForcedSolution(gamma, e, n, progress=progress)


def signed_amplitude(a, b) -> float:
    """The amplitude of a sin M + b cos M with the sign of a: Euler's ζ = m sin M (§833) has m < 0
    above the resonance ((B−A)/C > 1/3, A² < 2N: the swing is opposite to the orbit's), and the
    forced solution started at periapse is a sin M with b ≈ 0. Unsigned, the two agreed in size and
    read as "200 % off"."""
    return float(np.copysign(np.hypot(a, b), a))


def _forced_amplitude_of_run(t, zeta, n, period, free_period):
    """First harmonic (frequency n) of ζ(t) from the rigid-body run, fitted over its whole orbits
    with the 2nd and 3rd harmonics and, when the run has a free swing, sin/cos at its period; with
    the sign of its sin M part (`signed_amplitude`)."""
    keep = t - t[0] <= period * np.floor((t[-1] - t[0]) / period + 1e-9)
    if np.count_nonzero(keep) < 16:  # less than one whole orbit: fit what there is
        keep = np.ones_like(t, bool)
    tt, z = t[keep] - t[0], zeta[keep]
    cols = [np.ones_like(tt)] + [f(k * n * tt) for k in (1, 2, 3) for f in (np.sin, np.cos)]
    if np.isfinite(free_period) and free_period > 0:
        w = 2 * np.pi / free_period
        cols += [np.sin(w * tt), np.cos(w * tt)]
    coef, *_ = np.linalg.lstsq(np.stack(cols, 1), z, rcond=None)
    return signed_amplitude(coef[1], coef[2])


def _setup(values, progress=None):
    """Everything before the integration: the checks, the orbit, the forced (periodic) solution
    found by shooting, and the start λ₀ − dz, λ̇₀ (shared by the single run and the batched path)."""
    g, e, n = values["asymmetry"], values["eccentricity"], values["orbital_rate"]
    if n < 1e-100:  # as in libration-circular: n² must not underflow
        raise ParameterError("orbital_rate", n, "at least 1e-100 (its square must not underflow), allowed range (0, 100] rad/unit")
    if abs(1.0 - 3.0 * g) < 0.03:
        raise ParameterError("asymmetry", g, "not within 0.01 of 1/3 (resonance A² = 2N: no forced libration)")
    P = 2 * np.pi / n
    duration = values["orbits"] * P
    step = P / values["steps_per_orbit"]
    fs = forced_solution(float(g), float(e), float(n), progress=progress)
    dz = np.radians(values["free_zeta0_deg"])
    nst = int(np.ceil(duration / step))
    return SimpleNamespace(g=g, e=e, n=n, I=planar_moments(g), gm=n * n, orbit=KeplerOrbit(a=1.0, e=e, n=n), P=P,
                           duration=duration, step=step, fs=fs, dz=dz, n_steps=nst, stride=stride_for(nst),
                           lam_start=fs.lam0 - dz, lamdot0=fs.lamdot0)


def _libration_eccentric(values, progress=None):
    s = _setup(values, progress)
    q0 = quat.from_axis_angle([0, 0, 1], s.lam_start)  # ζ₀ = f(0) − λ₀ + dz, f(0) = 0
    t, L, q = integrate(s.I, np.array([0.0, 0.0, s.lamdot0]), s.duration, s.step, q0=q0,
                        masses=[PointMass(s.gm, s.orbit.position)], scheme="yoshida4", stride=s.stride,
                        progress=(lambda f: progress(0.1 + 0.9 * f)) if progress is not None else None)
    return _finish(values, s, t, L, q)


def _finish(values, s, t, L, q):
    """The run from its samples: ζ, its forced and free parts, the metrics and the table."""
    g, e, n, I, gm, orbit, N, P = s.g, s.e, s.n, s.I, s.gm, s.orbit, lib.euler_N(s.g, s.gm, 1.0), s.P
    fs, dz, step = s.fs, s.dz, s.step
    pos = orbit.position(t)
    traj = Trajectory(t, q, L, I, time_unit="unit", bodies={"attractor": pos}, moment_unit="C")  # n in rad per unit
    zeta = zeta_of(q, pos)
    z_forced = fs.zeta(t)
    zeta -= np.pi * np.round((zeta[0] - z_forced[0] - dz) / np.pi)
    z_forced = fs.zeta(t)
    z_free = zeta - z_forced
    # forced part: harmonics of the periodic solution over one period
    tp = np.linspace(0, P, 2049)[:-1]
    zf1 = fs.zeta(tp)
    a, b = lib.harmonics(tp, zf1, n, 3)
    alpha, beta, A = 2 * e, 3 * e, n
    # B < A: the stable state has the B axis toward F (§827, ζ = 90° + φ), where Euler's formulas
    # hold with |n|. His §837 reading of n < 0 as "smaller digressions" is about the A axis facing
    # F, which his own §837 separatrix shows is unstable — the simulation never stays there.
    Ns = abs(N)
    m1 = lib.forced_amplitude_euler(alpha, A, Ns)
    m2e = lib.second_order_euler(alpha, beta, A, Ns)
    w0 = lib.small_oscillation_omega(g, gm, 1.0)
    z_euler = m1 * np.sin(A * t) + (dz * np.cos(w0 * t) if w0 > 0 else dz)
    free_period = lib.measured_period(t, z_free) if dz != 0 else np.nan
    amp_run = _forced_amplitude_of_run(t, zeta, n, P, free_period)
    # is there a libration at all? the forced solution's stability (Floquet) and the run itself
    half_trace = fs.once("half_trace", lambda: lib.monodromy_half_trace(fs.orbit, g, gm, fs.lam0, fs.lamdot0)) \
        if g != 0 else 1.0
    forced_stable = abs(half_trace) <= 1.0
    free_max = float(np.max(np.abs(z_free)))
    tumbles = free_max >= 0.5 * np.pi  # the run went over to the next face pair: it circulates
    # Euler's formula as a motion: start on ζ = m₁ sin At at periapse (ζ = ζ_eq, ζ̇ = m₁A, A = n), i.e.
    # λ = −ζ_eq, λ̇ = ḟ(0) − m₁n; in the time unit 1/n of `leaves_libration`, λ̇/n = ḟ(0)/n − m₁
    euler_left, euler_max, euler_orbit = (False, 0.0, None)
    if g != 0:
        fdot0 = float(fs.orbit.true_anomaly_rate(np.array([0.0]))[0]) / n
        euler_left, euler_max, euler_orbit = fs.once("euler_start", lambda: lib.leaves_libration(
            e, g, -lib.equilibrium_zeta(g), fdot0 - m1, fs.lam0, orbits=EULER_START_ORBITS))
    mt = {
        "forced_amplitude_rad": amp_run,
        "forced_amplitude_periodic_rad": signed_amplitude(a[0], b[0]),
        "forced_amplitude_euler_rad": float(m1),
        "forced_amplitude_rel_error": float(abs(amp_run / m1 - 1)) if m1 else np.nan,
        "forced_second_harmonic_rad": float(a[1]),
        "second_order_euler_rad": float(m2e),
        "forced_max_rad": float(np.max(np.abs(zf1))),
        "free_amplitude_rad": free_max,
        "free_period": free_period,
        "free_period_euler": 2 * np.pi / w0 if w0 > 0 else np.inf,
        "forced_floquet_half_trace": half_trace,
        "euler_start_max_offset_rad": euler_max,
    }
    # modern: the linearised free period about the forced solution (Floquet, exact in e), lengthened by
    # the free swing's own amplitude φ²/4 (pendulum); only worth computing when there is a free part
    if dz != 0 and g > 0 and not tumbles:
        nu = fs.once("floquet_nu", lambda: lib.free_libration_floquet(fs.orbit, g, gm, fs.lam0, fs.lamdot0, near=w0))
        mt["free_period_floquet"] = 2 * np.pi / nu if nu > 0 else np.nan
        mt["free_period_modern"] = mt["free_period_floquet"] * (1 + dz**2 / 4)
    warnings: list[str] = []
    status = "ok"
    if tumbles:
        status = "tumbles"
        for k in ("forced_amplitude_rad", "forced_amplitude_rel_error", "free_amplitude_rad", "free_period",
                  "free_period_floquet", "free_period_modern"):
            if k in mt:
                mt[k] = np.nan
        if not forced_stable:
            for k in ("forced_amplitude_periodic_rad", "forced_second_harmonic_rad", "forced_max_rad"):
                mt[k] = np.nan
        warnings.append(
            f"No libration: the body tumbles (its angle from the forced solution passed a quarter turn, reaching "
            f"{free_max:.3g} rad)"
            + (f"; the forced (periodic) solution itself is unstable (½ tr M = {half_trace:.3g}, |·| > 1)"
               if not forced_stable else f", started {np.degrees(dz):g}° off a forced solution too narrow to hold it")
            + ". Euler's forced libration (§833) and free period (§838) do not apply here, and neither the forced "
              "amplitude nor the free period is reported.")
    elif not forced_stable:
        warnings.append(
            f"The forced (periodic) libration is unstable here (½ tr M = {half_trace:.3g}, |·| > 1, Floquet): a body "
            f"near it drifts away (this one has not yet, in {values['orbits']:g} orbits); Euler's §838 free libration "
            "about it does not exist.")
    if not tumbles:
        # (an orbit without eccentricity forces nothing: both are 0, the periodic one to round-off)
        off = abs(m1 - mt["forced_amplitude_periodic_rad"]) / max(abs(mt["forced_amplitude_periodic_rad"]), 1e-9)
        if euler_left or off > EULER_AMPLITUDE_TOLERANCE:
            why = []
            if off > EULER_AMPLITUDE_TOLERANCE:
                why.append(f"his amplitude {m1:.3g} rad is {off:.0%} off the forced solution's {mt['forced_amplitude_periodic_rad']:.3g} rad")
            if euler_left:
                why.append(f"a body started on his formula leaves the libration within {euler_orbit} "
                           f"orbit{'s' if euler_orbit != 1 else ''}")
            warnings.append(
                f"Euler's linear forced libration ζ = A²α/(A²−2N)·sin At (§833) is outside its regime here "
                f"(e = {e:g}, (B−A)/C = {g:g}): " + " and ".join(why) + "; it assumes e and ζ small and A² far from "
                "2N. The simulated forced libration (modern column) is the one to read.")
    # the step against the fastest period: the periapse passage (true anomaly's fastest turn) and
    # the free libration
    fdot_max = n * (1 + e) ** 2 / (1 - e * e) ** 1.5
    T_fast = min(2 * np.pi / fdot_max, 2 * np.pi / w0 if w0 > 0 else np.inf)
    _validity.add(warnings, _validity.coarse_step(step, T_fast, "the periapse passage or the free libration",
                                                  "time units", "steps_per_orbit"))
    comps = [
        Comparison("forced libration amplitude A²α/(A²−2N) (§833)", m1, mt["forced_amplitude_rad"],
                   mt["forced_amplitude_periodic_rad"], "rad",
                   "simulated: first harmonic of ζ in the rigid-body run (whole orbits; a free swing fitted "
                   "alongside at its measured period); modern: that of the periodic solution of the planar "
                   "equation (an 8th-order Runge–Kutta integration, DOP853; the ellipse to all orders)"),
        Comparison("sin 2At coefficient (§835)", m2e, mt["forced_second_harmonic_rad"], None, "rad",
                   "Euler keeps only the 1/s³ modulation β; the ellipse adds (5/4)e² sin 2M to the true anomaly, "
                   "which gives 5e²A²/(4A²−2N) — larger than Euler's term"),
        Comparison("free libration period 2π/√(2N) (§838)", mt["free_period_euler"], mt["free_period"],
                   mt.get("free_period_modern"), "unit",
                   "modern: Floquet period of small swings about the forced libration (the ellipse to all orders) "
                   "× (1 + φ²/4) for the free amplitude φ"),
    ]
    notes = ["Euler's α = 2e, A = n (anomalistic = orbital rate for a fixed ellipse), β = 3e: the ellipse to first order in e.",
             "For B < A the forced libration is about ζ = 90° (the B axis toward F) and Euler's formula is used with |n|; "
             "his §837 remark that n < 0 makes the digressions smaller concerns the unstable state with A toward F.",
             "The translation prints ζ = AA/(AA−2n) sin At (α dropped) at the end of §833; §834 has it right."]
    # a value the run could not measure says why (a sweep's NaN was otherwise unexplained)
    if w0 <= 0:
        why = "A = B: no torque, so no free libration to measure; Euler's free period 2π/√(2N) is infinite"
        notes.append(why + ".")
        comps[2] = dataclasses.replace(comps[2], missing=why)
    elif dz == 0:
        why = "no free swing was started (free_zeta0_deg = 0): the free period is not measured"
        notes.append(why[0].upper() + why[1:] + ".")
        comps[2] = dataclasses.replace(comps[2], missing=why)
    if not np.isfinite(mt["forced_amplitude_rel_error"]) and not tumbles:
        notes.append("A circular orbit (e = 0) forces nothing: the forced amplitude is 0, and its relative error "
                     "is undefined (NaN).")
    series = {"zeta_rad": zeta, "zeta_euler_rad": z_euler, "zeta_forced_rad": z_forced, "zeta_free_rad": z_free}
    traj.series.update(series)
    if tumbles:  # the run's values are not libration values: leave them out of the table
        def finite(v):
            return v if v is not None and np.isfinite(v) else None

        comps = [dataclasses.replace(c, simulated=finite(c.simulated), modern=finite(c.modern),
                                     note=c.note + "; the body tumbles: no libration to measure") for c in comps]
    return Run("libration-eccentric", values, traj, mt, comps, notes, plot_series=series, status=status,
               warnings=warnings)


def _draw(run, spec, view):
    """The body, F on its Kepler ellipse (true shape) and the arc ζ from the A axis to F (§833)."""
    d, _ = body_scene(run, spec, view, bodies={"F": centre_of_force(run)})
    f_and_zeta(d, run, spec, view)
    return d


BATCH_METRICS = ("forced_amplitude_rad", "forced_amplitude_periodic_rad", "forced_amplitude_euler_rad",
                 "forced_amplitude_rel_error", "forced_second_harmonic_rad", "second_order_euler_rad",
                 "forced_max_rad", "free_amplitude_rad", "free_period", "free_period_euler",
                 "free_period_floquet", "free_period_modern", "forced_floquet_half_trace", "euler_start_max_offset_rad")


def _batch(values, swept):
    """The sweep's batched path: each point's forced solution and start as in a single run, then
    every point sharing an orbit (eccentricity, orbital rate, length, step) integrated together by
    the planar kernel (the same scheme and kick times as the rigid-body integrator: the samples
    agree with a single run to round-off), then each point's metrics exactly as a single run."""
    from ..app.sweep import STATUS, ok_with_warnings

    n = len(next(iter(swept.values())))
    out = {k: np.full(n, np.nan) for k in BATCH_METRICS}
    status = np.full(n, STATUS["ok"], np.int8)
    messages = {}
    groups: dict[tuple, list] = {}
    for i in range(n):
        vals = {**values, **{k: (v[i].item() if hasattr(v[i], "item") else v[i]) for k, v in swept.items()}}
        try:
            s = _setup(vals)
        except ParameterError as e:
            status[i], messages[i] = STATUS["refused"], str(e)
            continue
        key = (s.e, s.n, vals["orbits"], vals["steps_per_orbit"])
        groups.setdefault(key, []).append((i, vals, s))
    for members in groups.values():
        s0 = members[0][2]
        runs = batched_planar_runs([m[2].lam_start for m in members], [m[2].lamdot0 for m in members],
                                   [1.5 * m[2].gm * m[2].g for m in members], s0.orbit, s0.duration, s0.step, s0.stride)
        for (i, vals, s), (t, L, q) in zip(members, runs):
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(L))):
                status[i], messages[i] = STATUS["diverged"], "non-finite spin in the run"
                continue
            run = _finish(vals, s, t, L, q)
            if run.status != "ok":  # e.g. "tumbles": a finished run whose status says what it found
                status[i], messages[i] = STATUS["flagged"], f"{run.status}: " + "; ".join(run.warnings)
            elif run.warnings:  # as a single run's: what its numbers cannot be read as
                messages[i] = ok_with_warnings(run.warnings)
            for k in BATCH_METRICS:
                if k in run.metrics:
                    out[k][i] = run.metrics[k]
    out["_status"], out["_messages"] = status, messages
    return out


# DOP853 steps of the search for the forced (periodic) solution: Newton on one orbit with the
# variational equations: 216-652 DOP853 steps for the defaults and presets (measured), a few dozen
# runs of one period at most
FORCED_SEARCH_STEPS = 3000


def _cost(values):
    """orbits × steps_per_orbit steps (the period cancels), the forced-solution search, F's
    position and four ζ series per sample."""
    n = step_count(values["orbits"], 1.0 / values["steps_per_orbit"])
    samples = run_samples(n)
    return Cost(n + FORCED_SEARCH_STEPS, samples, trajectory_bytes(samples, bodies=1, series=4))


register(Scenario(
    series_units={"attractor_[xyz]": "a"},  # the orbit's semi-major axis
    name="libration-eccentric",
    title="Forced libration in an eccentric orbit (Problem 94)",
    section="§833–838",
    group="ch. 16",
    summary=("Now F moves on a Kepler ellipse, fast near periapse and slow far away. Its uneven motion "
            "forces the body to swing, ζ ≈ A²α/(A² − 2N) · sin At (§833), on top of any free swing "
            "left from the start (§838). Raise the eccentricity to see where Euler's first-order "
            "formula stops matching; bring (B − A)/C toward 1/3 to approach the resonance A² = 2N, "
            "where his amplitude blows up."),
    params=(
        Param("asymmetry", 0.05, -0.45, 0.45, "", "(B − A)/C", label="Asymmetry (B − A)/C"),
        Param("eccentricity", 0.05, 0.0, 0.5, "", "eccentricity e of F's orbit", label="Eccentricity e of F's orbit"),
        Param("orbital_rate", 1.0, 0.0, 100.0, "rad/unit", "mean motion n", exclusive_min=True, label="Mean motion n"),
        Param("free_zeta0_deg", 2.0, -60.0, 60.0, "deg", "initial offset from the forced libration (free part)",
              label="Free swing at the start"),
        Param("orbits", 20.0, 1.0, 500.0, "", "orbits to simulate", label="Orbits"),
        Param("steps_per_orbit", 400, 50, 20000, "", "integrator steps per orbit", kind="int",
              label="Integrator steps per orbit", advanced=True),
    ),
    camera=Camera((0.8, -2.0, 5.2), (0.0, 0.0, 0.0)),
    preview={'orbits': 5.0},
    simulate_fn=_libration_eccentric,
    draw=_draw,
    options={**ZETA_OPTION, **ORBIT_OPTION},
    cost_fn=_cost,
    euler_formula=("ζ = A²α/(A² − 2N) · sin At + Nαβ/(4(A² − 2N)) · sin 2At (§833–835)"),
    presets=(
        ("Forced swing: a nearly circular orbit", {}),
        ("Forced swing: e = 0.3, beyond Euler's first order", {"eccentricity": 0.3}),
        ("Forced swing: near the resonance A² = 2N", {"asymmetry": 0.3}),
    ),
    batch=Batch(_batch,
                sweepable=("asymmetry", "eccentricity", "orbital_rate", "free_zeta0_deg", "orbits", "steps_per_orbit"),
                metrics=BATCH_METRICS, chunk=16),
    # times in the unit of `orbital_rate` (rad per time unit)
    metric_units={"free_period": "unit", "free_period_euler": "unit", "free_period_floquet": "unit",
                  "free_period_modern": "unit", "forced_amplitude_rel_error": "", "forced_floquet_half_trace": ""},
))


@register_check("E8", "forced libration in an eccentric orbit: ζ = A²α/(A²−2N) sin At", "§833–835")
def e8():
    e = 0.01
    r = get("libration-eccentric").simulate({"eccentricity": e, "asymmetry": 0.05, "free_zeta0_deg": 0.0,
                                             "orbits": 3})
    m = r.metrics
    rel = abs(m["forced_amplitude_rad"] / m["forced_amplitude_euler_rad"] - 1)
    run_vs_periodic = abs(m["forced_amplitude_rad"] / m["forced_amplitude_periodic_rad"] - 1)
    return {"euler": m["forced_amplitude_euler_rad"], "simulated": m["forced_amplitude_rad"],
            "modern": m["forced_amplitude_periodic_rad"], "rel_error": rel, "tolerance": 5 * e**2 + 1e-6, "unit": "rad",
            "note": (f"e = {e}, (B−A)/C = 0.05: first harmonic of ζ in the rigid-body run over 3 orbits; modern: "
                     f"the periodic solution of the planar equation (DOP853), {run_vs_periodic:.1e} from the run. "
                     "Euler's α = 2e drops the e³ terms of the true anomaly and ζ³ terms of sin 2ζ: relative O(e²)")}


@register_check("E8.free", "free + forced libration: free period 2π/√(2n) on an eccentric orbit", "§838")
def e8_free():
    m = get("libration-eccentric").simulate({"eccentricity": 0.01, "free_zeta0_deg": 1.0, "orbits": 40}).metrics
    Te, Tm, T = m["free_period_euler"], m["free_period_modern"], m["free_period"]
    neglected = abs(Tm / Te - 1)
    return {"euler": Te, "simulated": T, "modern": Tm,
            "rel_error": abs(T / Te - 1), "tolerance": 3 * neglected, "unit": "1/n",
            "note": (f"free part = run − forced (periodic) solution. Euler's 2π/√(2N) neglects (all computed in the "
                     f"modern value): the forced swing's cos 2ζ and the 1/s³ modulation (Floquet period of the "
                     f"linearised motion, {m['free_period_floquet'] / Te - 1:+.1e}) and the 1° free amplitude "
                     f"(φ²/4 = {np.radians(1.0) ** 2 / 4:.1e}): {neglected:.1e} in all; tolerance 3× that. The run is "
                     f"{abs(T / Tm - 1):.1e} from the modern value: zero-crossing jitter from the combination tones "
                     "ν ± n over ~15 free periods (it halves when the run is doubled)")}


@register_check("E8.tumbles", "no libration at all (e = 0.27, 3(B−A)/C = 0.51): the run says it tumbles and "
                "reports no forced amplitude", "§833–838")
def e8_tumbles():
    r = get("libration-eccentric").simulate({"eccentricity": 0.27, "asymmetry": 0.17})
    m = r.metrics
    ok = (r.status == "tumbles" and not np.isfinite(m["forced_amplitude_rad"]) and not np.isfinite(m["free_period"])
          and abs(m["forced_floquet_half_trace"]) > 1 and any(w.startswith("No libration") for w in r.warnings))
    return dict(euler=m["forced_amplitude_euler_rad"], simulated=None, modern=None, rel_error=0.0 if ok else 1.0,
                tolerance=0.0, passed=ok, unit="rad",
                note=f"status {r.status!r}; the forced (periodic) solution is unstable (½ tr M = "
                     f"{m['forced_floquet_half_trace']:.3f}, Floquet) and the body started 2° off it leaves within the "
                     "run; Euler's 1.10 rad is shown, no simulated amplitude or free period is")


@register_check("E8.linear-regime", "forced libration beyond Euler's linear regime (e = 0.27, 3(B−A)/C = 0.17): the "
                "36° swing computed, Euler's formula flagged", "§833–835")
def e8_linear_regime():
    r = get("libration-eccentric").simulate({"eccentricity": 0.27, "asymmetry": 0.17 / 3})
    m = r.metrics
    rel = abs(m["forced_amplitude_rad"] / m["forced_amplitude_periodic_rad"] - 1)
    warned = [w for w in r.warnings if "outside its regime" in w]
    return dict(euler=m["forced_amplitude_euler_rad"], simulated=m["forced_amplitude_rad"],
                modern=m["forced_amplitude_periodic_rad"], rel_error=rel, tolerance=1e-3,
                passed=rel <= 1e-3 and r.status == "ok" and bool(warned), unit="rad",
                note=f"largest forced swing {np.degrees(m['forced_max_rad']):.1f}°, stable (½ tr M = "
                     f"{m['forced_floquet_half_trace']:.3f}); rel_error: the run's first harmonic against the periodic "
                     "solution's (free swing of 2° fitted alongside). " + (warned[0] if warned else "NO WARNING"))
