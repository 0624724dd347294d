"""Precession and nutation of an oblate spinning body pulled by a centre on a circle (Problem 96,
§844–849): the mean rate N cos n, the nutation in 2φ, and the breakdown near ε = 2δ.

Check rows E10, E10.nutation and E10.resonance.
"""
from __future__ import annotations

import numpy as np
from ..physics import quaternion as quat
from ..physics.integrator import PointMass, integrate, samples_kept
from ..physics.kept import kept
from ..physics.params import Param
from ..physics.precession import (TYPOS_844_849, euler_N, fit_pole, linear_theory,
                          pole_angles, resonance_849)
from ..physics.trajectory import Trajectory
from .drawing import Camera
from .base import Comparison, Run, Scenario, get, register
from .budget import Cost, trajectory_bytes
import functools
from .checks import register_check
from ._precession import MAX_SAMPLES
from .drawing import Option
from ._ch16_drawing import body_scene, centre_line, centre_of_force, pole_cone
from . import _validity

# Euler's nutation (§844) is outside its regime when his amplitudes differ from the linear theory
# with the gyroscopic term he dropped (which puts the resonance at ε' = εC/A = 2δ instead of ε = 2δ)
# by more than this: far from the resonance the two differ by ~C/A − 1 (10 % at f = 0.1), near it
# the difference blows up
EULER_NUTATION_TOLERANCE = 0.5
# the corrected linear theory itself fails where its denominator ε'² − 4δ² is within this many
# times ε'N of zero (the O(N) terms both theories drop shift the resonance by ~N)
RESONANCE_WIDTHS = 10.0
# Euler's small-α hypothesis (§845): the pole of rotation near the figure axis
ALPHA_MAX_RAD = 0.1
# The mean precession −N cos n (A/C) is first order in N/δ; holding p and λ fixed inside the
# equations drops terms of relative order N/δ, and near an obliquity of 90° the first-order rate
# shrinks with cos n while they do not: the dropped part is of relative size ~(N/δ)/cos n (at the
# default N/δ = 0.0079, 89° gives 0.45 and the rate is 31 % off the simulated one; 85°: 0.09, 6 %;
# 60°: 0.016, 0.6 %). Warned beyond this.
NEXT_ORDER_MAX = 0.1


def spheroid_moments(flattening):
    """Homogeneous oblate spheroid, semi-axes a = b = 1, c = 1 − f (unit mass):
    A = B = (1 + (1−f)²)/5, C = 2/5."""
    c = 1.0 - flattening
    return np.array([(1 + c * c) / 5, (1 + c * c) / 5, 0.4])


def figure_frame(n, lam):
    """Unit vectors â (figure axis at colatitude n, longitude λ), e_p (increasing p), e_λ."""
    a = np.array([np.sin(n) * np.cos(lam), np.sin(n) * np.sin(lam), np.cos(n)])
    ep = np.array([np.cos(n) * np.cos(lam), np.cos(n) * np.sin(lam), -np.sin(n)])
    el = np.array([-np.sin(lam), np.cos(lam), 0.0])
    return a, ep, el


def attitude_from_pole(n, lam, spin_phase=0.0):
    """q taking body z to the figure axis (n, λ): Rz(λ)·Ry(n)·Rz(spin_phase)."""
    qz = quat.from_axis_angle([0, 0, 1.0], lam)
    qy = quat.from_axis_angle([0, 1.0, 0], n)
    qs = quat.from_axis_angle([0, 0, 1.0], spin_phase)
    return quat.multiply(quat.multiply(qz, qy), qs)


def initial_state_844(theory, n, lam0, delta, h):
    """ω₀ (body frame) and q₀ so that the pole of rotation O sits at Euler's x, y (§844, §848):
    the forced offset at φ₀ = λ₀ plus the free part (u, v) = (0, h). On the sphere O − A =
    −ε⁻¹... i.e. ω = ε(â − x e_p − y e_λ) (x = α cos ZAO, y = α sin ZAO: x > 0 points toward Z
    moving A east, y > 0 moves A toward Z, as equations 1–2 of §844 require)."""
    x, y = theory.offset(lam0)
    y = y + h
    a, ep, el = figure_frame(n, lam0)
    w_in = theory.eps * (a - x * ep - y * el)
    q0 = attitude_from_pole(n, lam0)
    return quat.rotate_inverse(q0, w_in), q0


def simulate_circular(eps_over_delta, flattening, obliquity, h, orbits, steps_per_orbit,
                      scheme="yoshida4", lam0=np.pi / 2, progress=None, max_samples=MAX_SAMPLES, on_axis=False):
    """Run §844's problem: δ = 1, GM/s³ = 1, s = 1. Returns (t, L, q, I, N, corrected theory).

    The pole of rotation starts at its forced place (plus h) of the corrected linear theory, or
    on the figure axis if `on_axis` or if that place is infinite (at the resonance)."""
    I = spheroid_moments(flattening)
    delta, eps = 1.0, eps_over_delta
    N = euler_N(1.0, I[2], I[0], eps)
    corr = linear_theory(N, eps, delta, obliquity, I[2] / I[0], corrected=True)
    if on_axis or not (np.isfinite(corr.F) and np.isfinite(corr.G)):
        q0 = attitude_from_pole(obliquity, lam0)
        w0 = np.array([0.0, 0.0, eps])
    else:
        w0, q0 = initial_state_844(corr, obliquity, lam0, delta, h)
    dur = 2 * np.pi * orbits
    n = int(np.ceil(orbits * steps_per_orbit))
    centre = lambda t: np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], -1)  # noqa: E731
    t, L, q = integrate(I, w0, dur, dur / n, q0=q0, masses=[PointMass(1.0, centre)], scheme=scheme,
                        stride=max(1, int(np.ceil(n / max_samples))), progress=progress)
    return t, L, q, I, N, corr


def fit_circular(t, axis, delta, eps_gyro):
    """Two-pass fit of the figure-axis pole: secular + 2φ terms + the free wobble at ε'."""
    p, lam = pole_angles(axis)
    c1, c0 = np.polyfit(t, lam, 1)
    phi = c0 + c1 * t - delta * t
    # the free wobble's frequency is ε' shifted by terms of order N (the torque): over a long run
    # that shift smears a fit at exactly ε', so the frequency is refined by maximising its amplitude
    span = t[-1] - t[0]
    f0 = fit_pole(t, axis, {"2phi": 2 * phi})
    tc = t - 0.5 * (t[0] + t[-1])
    res = p - f0.mean_obliquity - f0.rate_obliquity * tc - f0.obliquity["2phi"][0] * np.sin(2 * phi) \
        - f0.obliquity["2phi"][1] * np.cos(2 * phi)
    ws = eps_gyro + np.linspace(-8.0, 8.0, 33) * np.pi / max(span, 1e-300)
    ph = np.outer(ws, t)
    power = (np.sin(ph) @ res) ** 2 + (np.cos(ph) @ res) ** 2
    w = ws[int(np.argmax(power))]
    return fit_pole(t, axis, {"2phi": 2 * phi, "free": w * t}), phi


@kept(32)  # depends on two of the scenario's numbers: other sliders reuse it
def resonance_sweep(flattening, obliquity, ratios=(20.0, 8.0, 4.0, 3.0, 2.5, 2.2), orbits=30, steps=100):
    """The 2φ nutation in obliquity measured at several ε/δ beside Euler's (§844) and the corrected
    value: shows the growth toward ε = 2δ (Euler) / ε = 2δA/C (corrected). Rows (ε/δ, simulated,
    Euler, corrected), a tuple."""
    out = []
    for r in ratios:
        t, L, q, I, N, corr = simulate_circular(r, flattening, obliquity, 0.0, orbits, steps, max_samples=4000)
        traj = Trajectory(t, q, L, I)
        fit, _ = fit_circular(t, traj.figure_axis, 1.0, corr.eps_gyro)
        out.append((r, -fit.obliquity["2phi"][1], linear_theory(N, r, 1.0, obliquity).obliquity_amplitude,
                    corr.obliquity_amplitude))
    return tuple(out)


def _precession_circular(values, progress=None):
    r = values["eps_over_delta"]
    n = np.radians(values["obliquity_deg"])
    h = values["h"]
    t, L, q, I, N, corr = simulate_circular(r, values["flattening"], n, h, values["orbits"],
                                            values["steps_per_orbit"], progress=progress)
    delta, eps = 1.0, r
    eul = linear_theory(N, eps, delta, n)
    cen = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], -1)
    traj = Trajectory(t, q, L, I, time_unit="1/δ", bodies={"centre": cen},
                      moment_unit="M a^2")
    fit, phi = fit_circular(t, traj.figure_axis, delta, corr.eps_gyro)
    ap = -fit.obliquity["2phi"][1]  # p = n − a_p cos 2φ
    al = fit.longitude["2phi"][0]  # λ = … + a_λ sin 2φ
    alpha = np.arccos(np.clip(np.sum(traj.rotation_axis * traj.figure_axis, axis=1), -1, 1))
    res = resonance_849(N, delta, n)
    m = dict(
        precession_rate=fit.rate_longitude, precession_rate_euler=eul.precession_rate,
        precession_rate_corrected=corr.precession_rate,
        precession_period_orbits=abs(1.0 / fit.rate_longitude) if fit.rate_longitude else float("inf"),
        nutation_obliquity=ap, nutation_obliquity_euler=eul.obliquity_amplitude,
        nutation_obliquity_corrected=corr.obliquity_amplitude,
        nutation_longitude=al, nutation_longitude_euler=eul.longitude_amplitude,
        nutation_longitude_corrected=corr.longitude_amplitude,
        free_wobble_obliquity=fit.amplitude("free", "obliquity"), free_wobble_euler=h,
        N=N, N_over_delta=N / delta, C_over_A=I[2] / I[0],
        resonance_denominator_euler=eps ** 2 - 4 * delta ** 2,
        resonance_denominator_corrected=corr.eps_gyro ** 2 - 4 * delta ** 2,
        eps_over_delta_resonance_corrected=2 * I[0] / I[2],
        alpha_max_rad=float(np.max(alpha)), alpha_growth_rate_849=res["alpha_growth_rate"],
        fit_rms_longitude=fit.rms_longitude, fit_rms_obliquity=fit.rms_obliquity,
    )
    comps = [
        Comparison("mean precession of the axis", eul.precession_rate, fit.rate_longitude, corr.precession_rate,
                   "rad per 1/δ", "Euler §846: −N cos n; 'modern': the gyroscopic term kept, −N cos n·A/C"),
        Comparison("nutation in obliquity (coefficient of −cos 2φ)", eul.obliquity_amplitude, ap,
                   corr.obliquity_amplitude, "rad", "§844, §849: εN sin n(ε + 2δ cos n)/(2δ(εε − 4δδ))"),
        Comparison("nutation in longitude (coefficient of sin 2φ)", eul.longitude_amplitude, al,
                   corr.longitude_amplitude, "rad", "§844: εN(ε cos n + 2δ)/(2δ(εε − 4δδ)); §849 prints a different, wrong, form"),
        Comparison("free (diurnal) wobble of the axis in obliquity", h, m["free_wobble_obliquity"],
                   h * eps / corr.eps_gyro, "rad", "§844: h; with the gyroscopic term h·A/C"),
    ]
    notes = [f"N/δ = {N:.3g}: Euler holds p and λ fixed inside his equations 4–5, an error of relative order N/δ.",
             f"Euler drops the gyroscopic term of §840: his N has the equatorial moment where the true "
             f"precession has the polar one, so his rate is {I[2] / I[0]:.4f}× the corrected one."]
    warnings: list[str] = []
    pairs = ((eul.obliquity_amplitude, corr.obliquity_amplitude), (eul.longitude_amplitude, corr.longitude_amplitude))
    euler_finite = all(np.isfinite(e_) for e_, _ in pairs)
    off = max((abs(e_ / c_ - 1) for e_, c_ in pairs if np.isfinite(e_) and np.isfinite(c_) and c_ != 0), default=0.0)
    if not euler_finite or off > EULER_NUTATION_TOLERANCE:
        warnings.append(
            f"Euler's nutation (§844) is outside its regime: ε/δ = {r:g} is near his resonance ε = 2δ, where his "
            "amplitudes ∝ 1/(εε − 4δδ) "
            + (f"differ by {off:.0%} from" if euler_finite else "have no finite value, unlike")
            + f" those of the linear theory with the gyroscopic term he dropped (whose resonance is at ε/δ = 2A/C = "
            f"{2 * I[0] / I[2]:.4f}); read the simulated nutation (§849: \"the attempts found go to infinity\").")
    den_c = corr.eps_gyro ** 2 - 4 * delta ** 2
    if abs(den_c) < RESONANCE_WIDTHS * corr.eps_gyro * N:
        warnings.append(
            f"The linear nutation theory itself fails here: ε'/δ = {corr.eps_gyro:.4g} puts its denominator "
            f"ε'² − 4δ² = {den_c:.3g} within {RESONANCE_WIDTHS:g}·ε'N of zero, the size of the terms of order N it "
            "drops; only the simulation describes the nodding.")
    if m["alpha_max_rad"] > ALPHA_MAX_RAD:
        warnings.append(
            f"The pole of rotation went {np.degrees(m['alpha_max_rad']):.3g}° from the figure axis: Euler's "
            f"small-α hypothesis (§845) no longer holds (threshold {np.degrees(ALPHA_MAX_RAD):.3g}°), nor do his "
            "precession and nutation formulas built on it.")
    next_order = m["N_over_delta"] / max(abs(np.cos(n)), 1e-300)
    if next_order > NEXT_ORDER_MAX:
        warnings.append(
            f"At an obliquity of {values['obliquity_deg']:g}° the first-order precession −N cos n·A/C is small "
            f"(cos n = {np.cos(n):.3g}), and the terms of order N/δ that Euler's and the linear theory drop are "
            f"about (N/δ)/cos n = {next_order:.2g} of it: read the simulated rate, not the formulas.")
    # the step against the fastest period the torque kicks must follow: the forcing in 2φ (π/δ) and,
    # through the figure axis, the free (Eulerian) wobble at ε' = εC/A
    step = 2 * np.pi / values["steps_per_orbit"]
    _validity.add(warnings, _validity.coarse_step(step, min(np.pi / delta, 2 * np.pi / corr.eps_gyro),
                                                  "the wobble of the figure axis at ε' or the nodding in 2φ",
                                                  "1/δ", "steps_per_orbit"))
    if abs(r - 2) < 1.0 or abs(r - 2 * I[0] / I[2]) < 1.0:
        notes.append(f"ε/δ = {r:g} is near the resonance: Euler's formulas diverge at ε = 2δ (§849: "
                     f"\"the attempts found go to infinity\"), the corrected linear theory at ε/δ = 2A/C = "
                     f"{2 * I[0] / I[2]:.4f}. At the resonance the pole of rotation leaves the figure axis at the "
                     f"rate N sin n(1 + cos n)/2 = {res['alpha_growth_rate']:.3g} rad per 1/δ (§849); here it "
                     f"reached α = {np.degrees(m['alpha_max_rad']):.3g}°.")
    if m["alpha_max_rad"] > 0.1:
        notes.append(f"the pole of rotation went {np.degrees(m['alpha_max_rad']):.3g}° from the figure axis: "
                     "Euler's small-α hypothesis (§845) no longer holds.")
    notes += ["Text: " + t_ for t_ in TYPOS_844_849]
    if values["resonance_table"] == "on":
        rows = resonance_sweep(values["flattening"], n)
        notes.append("Nutation in obliquity toward the resonance (30 revolutions each, same flattening): "
                     + "; ".join(f"ε/δ = {r_:g}: simulated {a:.3g}, Euler {e:.3g}, corrected {c:.3g} rad"
                                 for r_, a, e, c in rows))
    pe, le = eul.pole(t, np.pi / 2, h)
    p, lam = pole_angles(traj.figure_axis)
    sec = eul.precession_rate * t
    series = {
        "obliquity p (rad)": p, "obliquity p, Euler §847 (rad)": pe,
        "longitude λ (rad)": lam, "longitude λ, Euler §847 (rad)": le,
        "λ − Euler's mean precession (rad)": lam - np.pi / 2 - sec,
        "Euler's nutation in λ (rad)": le - np.pi / 2 - sec,
    }
    # at ε = 2δ exactly Euler's curves have no value (his denominators vanish): left out, not drawn
    # as infinities (which would read as a diverged run)
    series = {k: v for k, v in series.items() if "Euler" not in k or np.all(np.isfinite(v))}
    return Run("precession-circular", values, traj, m, comps, notes, warnings=warnings, plot_series=series)


def _draw(run, spec, view):
    """The spinning body, F on its circle, and on the celestial sphere the cone swept by the
    figure axis about the orbit pole (precession) with its nodding magnified (nutation, §844)."""
    d, _ = body_scene(run, spec, view, bodies={"F": centre_of_force(run)})
    if view.option("cone", spec):
        pole_cone(d, run, run.trajectory.figure_axis, wiggle=view.option("wiggle", spec))
    centre_line(d, run, spec, view)
    return d


SWEEP_STEPS = 6 * 30 * 100  # resonance_sweep: six ratios, 30 revolutions at 100 steps


def _cost(values):
    """orbits × steps_per_orbit steps (yoshida4), the sweep toward the resonance when its table is
    on, the centre's position and six series of the pole per sample."""
    n = float(np.ceil(values["orbits"] * values["steps_per_orbit"]))
    samples = samples_kept(n, max(1, int(np.ceil(n / MAX_SAMPLES))))
    sweep = SWEEP_STEPS if values["resonance_table"] == "on" else 0
    return Cost(n + sweep, samples, trajectory_bytes(samples, bodies=1, series=6))


register(Scenario(
    series_units={"centre_[xyz]": "1"},  # the direction of the centre
    name="precession-circular",
    title="Precession and nutation under a centre on a circle",
    section="§844–849",
    group="ch. 16",
    summary=("An oblate body (flattened like the Earth) spins fast at rate ε while a mass F goes round "
            "it on a circle at rate δ. The figure axis turns slowly backward around the pole of F's "
            "orbit (precession, at the mean rate N cos n) and nods twice per revolution of F "
            "(nutation, in 2φ): watch the axis trace its path on the celestial sphere. Slide ε/δ down "
            "toward 2: Euler's nutation formulas blow up there (§849) while the simulated body does "
            "something finite but no longer small."),
    params=(
        Param("eps_over_delta", 20.0, 0.05, 1000.0, "1", "spin ε over the orbital rate δ of the centre", step=0.1,
              label="Spin ε / orbital rate δ"),
        Param("flattening", 0.1, 0.0, 0.5, "1", "flattening f of a homogeneous spheroid, c = a(1 − f)",
              exclusive_min=True, step=0.01, label="Flattening f"),
        Param("obliquity_deg", 23.44, 0.0, 89.0, "deg", "arc ZA between figure axis and pole of the orbit",
              exclusive_min=True, label="Obliquity (arc ZA)"),
        Param("h", 0.0, 0.0, 0.1, "rad", "Euler's h: free offset of the pole of rotation from its forced place",
              label="Free wobble h"),
        # at least half a turn: the fits of the secular rate and the 2φ term need it (orbits=1e-258,
        # found by tests/test_fuzz.py, made their SVD fail)
        Param("orbits", 100.0, 0.5, 1e5, "revolutions", "length of the run in revolutions of the centre",
              label="Length of the run"),
        Param("steps_per_orbit", 100, 8, 1e5, "1", "integrator steps per revolution (yoshida4)", kind="int",
              label="Integrator steps per revolution", advanced=True),
        # six more runs of 30 revolutions (18,000 steps, most of a run's CPU at the defaults): the
        # quick preview leaves them out, and so can a sweep that does not read the note
        Param("resonance_table", "on", kind="choice", choices=("on", "off"),
              help="the note's table of the nutation at six ε/δ toward the resonance (six runs of 30 revolutions)",
              label="Table toward the resonance", choice_labels=("on", "off"), advanced=True),
    ),
    camera=Camera((4.6, -4.0, 3.0), (0.0, 0.0, 0.4)),
    # the spin about C is fast: ω and L lie on the C axis, where drawn they only cover its label
    overlays={'vectors': False},
    preview={'orbits': 20.0, 'resonance_table': 'off'},
    simulate_fn=_precession_circular,
    draw=_draw,
    options={"cone": Option("precession cone (figure axis on the celestial sphere)"),
             "wiggle": Option("nutation wiggle, magnified"),
             "centre": Option("direction to the centre of force")},
    cost_fn=_cost,
    euler_formula=("ZA = n − εN sin n (ε + 2δ cos n) / (2δ(εε − 4δδ)) · cos 2φ + h sin(ε/δ · (φ + ζ)) (§844)\n"
                   "XZA = m − Nt cos n + εN (ε cos n + 2δ) / (2δ(εε − 4δδ)) · sin 2φ + h/sin n · cos(ε/δ · (φ + ζ))\n"
                   "N = 3gee (aa − cc) / (ε cc s³) (§847)"),
    presets=(
        ("Precession: fast spin, small nods", {}),
        ("Precession: ε/δ = 3, big nods", {"eps_over_delta": 3.0}),
        ("Precession: ε/δ = 2.2, Euler's nutation fails", {"eps_over_delta": 2.2}),
        ("Precession: with a free wobble h", {"h": 0.02}),
    ),
    # δ is the time unit's inverse (time is in 1/δ): a rate "δ" is a multiple of δ
    metric_units={r"precession_rate(_euler|_corrected)?": "δ",
                  r"nutation_(obliquity|longitude)(_euler|_corrected)?": "rad", "free_wobble_obliquity": "rad",
                  "free_wobble_euler": "rad", "N": "δ", "N_over_delta": "", "C_over_A": "",
                  r"resonance_denominator_(euler|corrected)": "δ^2", "eps_over_delta_resonance_corrected": "",
                  "alpha_growth_rate_849": "δ", "fit_rms_longitude": "rad", "fit_rms_obliquity": "rad"},
))


def _circular(r, f, n_deg=23.44, orbits=60, steps=200, on_axis=False):
    t, L, q, I, N, corr = simulate_circular(r, f, np.radians(n_deg), 0.0, orbits, steps, on_axis=on_axis)
    from ..physics.trajectory import Trajectory

    traj = Trajectory(t, q, L, I)
    fit, _ = fit_circular(t, traj.figure_axis, 1.0, corr.eps_gyro)
    return fit, N, corr, I, traj


# E10 rows: 800 steps per orbit (hε' = 0.39 rad per step). At 200 steps (1.6 rad per step) the
# splitting error in the nutation amplitudes was 4.5N (ε/δ = 50, f = 0.01), at 400 1.6N, at 800
# 1.4N, the same in units of N at f = 0.005: converged to the O(N/δ) terms the theories drop.
E10_STEPS = 800


@functools.lru_cache(maxsize=2)
def _circular_e10(r, f):
    return _circular(r, f, steps=E10_STEPS)


def _rows_vs_corrected(pairs, N, k=3):
    """pairs: (simulated, corrected theory, Euler). Passed when every simulated value is within 3N
    of the corrected linear theory (Euler's with the gyroscopic term he dropped; what remains is
    of order N/δ, tests/test_precession.py) AND Euler's value is off the simulated one by his
    predicted offset (Euler/corrected − 1, which comes from his A for C) within the same 3N:
    a check that can tell his rate from the right one."""
    rel = max(abs(s / c - 1) for s, c, _ in pairs)
    euler_gap = max(abs((e / s - 1) - (e / c - 1)) for s, c, e in pairs)
    return rel, euler_gap, rel <= k * N and euler_gap <= k * N


@register_check("E10", "precession at the mean rate N cos n, ε ≫ δ (ε/δ = 50, f = 0.01)", "§844–846")
def e10():
    r, f = 50.0, 0.01
    fit, N, corr, I, _ = _circular_e10(r, f)
    eul = linear_theory(N, r, 1.0, np.radians(23.44))
    ca = (I[2] - I[0]) / I[0]
    rel, gap, ok = _rows_vs_corrected([(fit.rate_longitude, corr.precession_rate, eul.precession_rate)], N)
    return dict(euler=eul.precession_rate, simulated=fit.rate_longitude, modern=corr.precession_rate,
                rel_error=rel, tolerance=3 * N, unit="rad per 1/δ", passed=ok,
                note=f"modern = the corrected linear theory (C for A in N); tolerance 3N/δ = {3 * N:.2g}, the order of "
                     f"the terms it drops. Euler is {100 * (eul.precession_rate / fit.rate_longitude - 1):+.3f}% off the "
                     f"simulation, predicted {100 * (eul.precession_rate / corr.precession_rate - 1):+.3f}% "
                     f"(his N has A for C: (C−A)/A = {ca:.4f}); |measured − predicted| = {gap:.2g} ≤ 3N also required")


@register_check("E10.nutation", "nutation in 2φ: obliquity and longitude terms (ε/δ = 50, f = 0.01)", "§844, §847, §849")
def e10_nutation():
    r, f = 50.0, 0.01
    fit, N, corr, I, _ = _circular_e10(r, f)
    eul = linear_theory(N, r, 1.0, np.radians(23.44))
    ap = -fit.obliquity["2phi"][1]
    al = fit.longitude["2phi"][0]
    ca = (I[2] - I[0]) / I[0]
    rel, gap, ok = _rows_vs_corrected([(ap, corr.obliquity_amplitude, eul.obliquity_amplitude),
                                       (al, corr.longitude_amplitude, eul.longitude_amplitude)], N)
    return dict(euler=eul.obliquity_amplitude, simulated=ap, modern=corr.obliquity_amplitude, rel_error=rel,
                tolerance=3 * N, unit="rad", passed=ok,
                note=f"longitude term {al:.5g} (corrected theory {corr.longitude_amplitude:.5g}, Euler "
                     f"{eul.longitude_amplitude:.5g}); worst relative error of the two against the corrected linear "
                     f"theory, tolerance 3N/δ: the terms of order N/δ both theories drop (e.g. the 2φ term seen from the "
                     f"precessing pole has frequency 2(δ + N cos n), not 2δ: −0.92N in the amplitudes); measured "
                     f"{rel / N:.2f}N, the same in units of N at half the flattening ({E10_STEPS} steps per orbit; "
                     f"200 steps added a splitting error of 3N). Euler's offsets: obliquity {100 * (eul.obliquity_amplitude / ap - 1):+.3f}% "
                     f"(predicted {100 * (eul.obliquity_amplitude / corr.obliquity_amplitude - 1):+.3f}%), longitude "
                     f"{100 * (eul.longitude_amplitude / al - 1):+.3f}% (predicted "
                     f"{100 * (eul.longitude_amplitude / corr.longitude_amplitude - 1):+.3f}%), from his A for C "
                     f"((C−A)/A = {ca:.4f}); |measured − predicted| = {gap:.2g} ≤ 3N also required")


@register_check("E10.resonance", "ε' = 2δ: the pole of rotation leaves the figure axis at N sin n(1 + cos n)/2", "§849")
def e10_resonance():
    f = 0.01
    I = spheroid_moments(f)
    r = 2 * I[0] / I[2]  # the resonance with the gyroscopic term kept (Euler: ε = 2δ)
    n = np.radians(23.44)
    fit, N, corr, _, traj = _circular(r, f, orbits=4, steps=400, on_axis=True)
    alpha = np.arccos(np.clip(np.sum(traj.rotation_axis * traj.figure_axis, axis=1), -1, 1))
    sel = traj.t > np.pi
    slope = np.polyfit(traj.t[sel], alpha[sel], 1)[0]
    # Euler's §849 rate with ε → ε' (the corrected N·A/C·… identical: N is fixed by the torque)
    pred = resonance_849(N, 1.0, n)["alpha_growth_rate"]
    rel = abs(slope - pred) / pred
    return dict(euler=pred, simulated=slope, modern=None, rel_error=rel, tolerance=0.05, unit="rad per 1/δ",
                note=f"ε/δ = 2A/C = {r:.4f}; α reached {alpha.max():.3g} rad in 4 revolutions (Euler's formulas diverge). "
                     "Tolerance: terms of order α and N/δ beside the secular growth over the fitted span")


@register_check("E10.euler-regime", "Euler's nutation near ε = 2δ is flagged (ε/δ = 2.2), not far from it (ε/δ = 8)",
                "§844, §849")
def e10_euler_regime():
    sc = get("precession-circular")
    near = sc.simulate(eps_over_delta=2.2, orbits=20.0)
    far = sc.simulate(eps_over_delta=8.0, orbits=20.0)
    warned = [w for w in near.warnings if w.startswith("Euler's nutation (§844) is outside its regime")]
    m = near.metrics
    ok = bool(warned) and not far.warnings
    return dict(euler=m["nutation_obliquity_euler"], simulated=m["nutation_obliquity"],
                modern=m["nutation_obliquity_corrected"], rel_error=0.0 if ok else 1.0, tolerance=0.0, passed=ok,
                unit="rad", note=f"threshold: Euler's amplitudes more than {EULER_NUTATION_TOLERANCE:.0%} off the linear "
                "theory with the gyroscopic term (docs/validity.md). " + (warned[0] if warned else "NO WARNING"))
