"""The Moon kept in syzygy with the Sun (Euler 1766, §5–§16), as the circular restricted
three-body problem at any mass ratio: the distance from the collinear quintic (Euler's §7
equation beside it), the oscillation about the Sun–Earth line from the linearisation (Euler's
α⁴ + 2α² = 27 beside it) and the escape.

Check rows E12 (the frequency), E12.mass_ratio (the frequency at m = 0.01, both sides),
E12.richardson (a published value), E12.distance and E12.escape.
"""
from __future__ import annotations

import math
import numpy as np
from ..physics.constants import SIDEREAL_YEAR_DAYS
from ..physics.params import Param
from .drawing import Camera, Drawing, Label, Option, Segments, Sphere, View, circle, new_drawing, segments
from . import _three_body_drawing as tbd
from .base import Comparison, Run, Scenario, register
from .budget import Cost, trajectory_bytes
from ..physics.three_body import syzygy as sz
from .checks import register_check
from ..physics.kept import kept
from ._three_body import GROUP, orbit_trajectory


# DOP853 (rtol 1e-12) takes 81-130 steps for the displayed run (≤ 3 yr, often cut by the escape) and the
# 2-year measurement together (defaults and presets, measured): 60 per year of run is above that
STEPS_PER_YEAR = 60
N_SAMPLES = 4000  # the displayed run's samples (fewer when the Moon leaves)


@kept(16)  # depends on the mass ratio and the side only: a slider of the displayed run reuses it
def _measured_modes(m, side, guess, progress=None):
    """A clean measurement of the swing and the escape: the exact linear mode at a tiny amplitude
    plus a tinier seed of the escape over two years; fit η = a cos ωt + b sin ωt + c e^{λt} +
    d e^{−λt} in the linear regime. (ω, λ, relative rms residual of the fit)."""
    A_meas = 1e-6
    tm, Sm, _ = sz.integrate(m, sz.initial_state(m, A_meas, side, "linear-mode", 1e-9), 2 * math.pi * 2.0,
                             n_samples=8000, progress=progress)
    etam, _ = sz.eta_and_distance(Sm, side)
    return sz.fit_swing_and_escape(tm, etam, A_meas, guess=guess)


SWING_GROWN = 2.0  # η beyond this many times A: the small swing is no longer what the run shows


def _distance_left(t, v, v_e):
    """The time from which the run's distance v is more than SWING_GROWN swings (half the range of
    Euler's v_e = b(1 − kA cos αζ)) from Euler's, or None while it stays."""
    swing = float(np.ptp(v_e)) / 2.0
    if not swing > 0:
        return None
    far = np.flatnonzero(np.abs(np.asarray(v) - np.asarray(v_e)) > SWING_GROWN * swing)
    return float(t[far[0]]) if len(far) else None


def _syzygy(values, progress=None):
    from ..physics.three_body import syzygy as sz

    m, n = values["mass_ratio"], values["moon_revolutions_per_year"]
    side, A = values["side"], math.radians(values["amplitude_deg"])
    mu = sz.reduced_mass(m)  # = Euler's m = n²c³/a³ (§7)
    if side == "conjunction":
        alpha = sz.equilibrium_conjunction(m)
        alpha_e = sz.euler_equilibrium_conjunction(mu)
        series_e, series_c = sz.euler_series_conjunction(mu), sz.series_conjunction(mu)
    else:
        alpha = sz.equilibrium_opposition(m)
        alpha_e = sz.euler_equilibrium_opposition(mu)
        series_e, series_c = sz.euler_series_opposition(mu), sz.series_opposition(mu)
    scale = sz.lunar_units_per_sun_distance(m, n)  # a/c: lunar distances per Sun distance
    modes = sz.linear_modes(m, side)
    # the displayed run: Euler's start (or the exact linear mode) + optional seed of the escape
    s0 = sz.initial_state(m, A, side, values["start"], values["escape_seed"])
    part = (lambda a, b: None if progress is None else (lambda f: progress(a + (b - a) * f)))
    t, S, _ = sz.integrate(m, s0, 2 * math.pi * values["duration_yr"], n_samples=N_SAMPLES, progress=part(0.0, 0.5))
    eta, v = sz.eta_and_distance(S, side)
    left = t[-1] < 2 * math.pi * values["duration_yr"] * (1 - 1e-9)
    w_meas, lam_meas, fit_res = _measured_modes(m, side, (modes["frequency"], modes["escape_exponent"]),
                                                progress=part(0.5, 1.0))
    w_run, n_half_run = sz.measured_frequency(t, eta, 1.5 * A)
    # amplitude relation of §16 on the displayed run's first swing
    first = t <= (2 * math.pi / modes["frequency"])
    ratio = float((v[first].max() - v[first].min()) / (2 * alpha * max(np.abs(eta[first]).max(), 1e-300)))
    Vo = modes["osc_vector"]
    ratio_linear = float(abs(Vo[0]) / abs(Vo[1]))
    b_lunar = alpha * scale
    eta_e, v_e = sz.euler_oscillation(alpha, A, t, side)
    metrics = {
        "syzygy_distance_lunar_units": b_lunar,
        "syzygy_distance_lunar_units_euler": (sz.EULER_N_SQUARED / 3.0) ** (1.0 / 3.0),
        "alpha_sun_distance": alpha,
        "alpha_euler_sun_distance": alpha_e,
        "reduced_mass": mu,
        "oscillation_frequency": w_meas,
        "oscillation_frequency_euler": sz.HILL_FREQUENCY,
        "oscillation_frequency_linear": modes["frequency"],
        "oscillation_frequency_run": w_run,
        "escape_exponent": lam_meas,
        "escape_exponent_linear": modes["escape_exponent"],
        "escape_exponent_hill": sz.HILL_ESCAPE_EXPONENT,
        "amplitude_ratio": ratio,
        "amplitude_ratio_euler": sz.AMPLITUDE_COEFFICIENT,
        "amplitude_ratio_linear": ratio_linear,
        "fit_rms_residual_rel": fit_res,
        "escape_time_yr": float(t[-1] / (2 * math.pi)) if left else float("nan"),
        "swings_before_escape": float(n_half_run) / 2.0,
    }
    comps = [
        Comparison("syzygy distance", (sz.EULER_N_SQUARED / 3.0) ** (1.0 / 3.0), b_lunar, None, "b",
                   "Euler: v ≈ c·∛(n²/3) (his c: the Moon's distance) with n² = 175, 'about four'; simulated: "
                   "root of §7/§9 with today's n, m"),
        Comparison("α = v/a: Euler's §7 equation vs the restricted problem's quintic", alpha_e, alpha, None, "",
                   "Euler pulls the Moon toward the Sun with a³ = G(M☉ + M⊕) where the Sun alone gives "
                   "a³(1 − μ); simulated: the collinear point (quintic) the run sits at"),
        Comparison("α = v/a: Euler's 4-term series vs the root of his §7 equation", series_e, alpha_e, series_c, "",
                   "his m = n²c³/a³ = μ; modern column: the series with the 4th coefficient corrected (4/243, not 1/81)"),
        Comparison("oscillation frequency (Sun's mean motion = 1)", sz.HILL_FREQUENCY, w_meas, modes["frequency"], "",
                   "Euler/Hill √(√28 − 1) (α⁴ + 2α² = 27); simulated: fit of η on the restricted problem; "
                   "modern: its linearisation, ω² = (2 − c₂ + √(9c₂² − 8c₂))/2"),
        Comparison("v = b(1 − k·A cos ω): k", sz.AMPLITUDE_COEFFICIENT, ratio, ratio_linear, "",
                   "half the swing of v/b over the η amplitude on the first swing; modern: centre eigenvector"),
        Comparison("escape exponent (real root Euler missed)", None, lam_meas, modes["escape_exponent"], "",
                   f"Hill limit √(√28 + 1) = {sz.HILL_ESCAPE_EXPONENT:.4f}; e-folding every "
                   f"{1 / lam_meas / (2 * math.pi) * SIDEREAL_YEAR_DAYS:.1f} days"),
    ]
    notes = [
        "Euler linearised about syzygy and assumed an oscillation; the same characteristic equation "
        "λ⁴ − 2λ² − 27 = 0 has the real root λ² = 1 + √28: the Moon leaves after a few swings.",
        "§7's substitution '2 − α = x' should read x = 1 − α; §9 prints (1−α)³ for (1+α)³; the 4th term of "
        "the series (§8, §9) should be 4mε/243, not mε/81.",
        f"Sun drawn at {min(3.0, scale / b_lunar):.3g} syzygy distances along its true direction (true distance "
        f"{scale:.0f} lunar distances).",
    ]
    if values["start"] == "euler":
        notes.append("Euler's start (his first-order solution at ω = 0, Hill's approximation) differs from the true "
                     "centre mode by terms of order v/u ≈ 1%: that small share of the unstable mode is enough for "
                     "the Moon to leave within about one swing.")
    # bodies: Earth-centred inertial frame, lunar distances (the Sun turns at rate 1)
    sgn = 1.0 if side == "conjunction" else -1.0
    c, s = np.cos(t), np.sin(t)
    xr, yr = S[:, 0] * scale, S[:, 1] * scale
    moon = np.stack([c * xr - s * yr, s * xr + c * yr, np.zeros_like(t)], axis=1)
    sun = min(3.0 * b_lunar, scale) * np.stack([c, s, np.zeros_like(t)], axis=1)
    traj = orbit_trajectory(t / (2 * math.pi), {"sun": sun, "earth": np.zeros_like(moon), "moon": moon}, "yr",
                            series={"moon_corotating_x": xr, "moon_corotating_y": yr,
                                    "eta_deg": np.degrees(eta), "distance_over_b": v / alpha,
                                    "frame_angle_rad": t})  # the Sun's direction turns at rate 1
    warnings = []
    if left:
        warnings.append(
            f"The Moon left the syzygy at t = {t[-1] / (2 * math.pi):.3g} yr, "
            + (f"after {n_half_run / 2:g} swings" if n_half_run >= 2 else "within its first swing") + ": the "
            f"line-up is unstable (the real root λ = {modes['escape_exponent']:.4f} of the linearised equations, "
            "the one Euler's assumed oscillation misses), so his η = A sin αζ and v = b(1 − kA cos αζ) describe "
            "only the part of the run before it.")
    elif A > 0 and np.max(np.abs(eta)) > SWING_GROWN * A:
        # still near the line-up, but the unstable direction, seeded by the swing's own second-order
        # terms (∝ A²) and growing by e^(λ·2π) a year, has taken over from the small swing
        warnings.append(
            f"The swing grew from A = {values['amplitude_deg']:g}° to {math.degrees(np.max(np.abs(eta))):.3g}° "
            f"within the run: the start's departure from the exact small swing (its second-order terms, or "
            f"Euler's first-order start) seeds the unstable direction (λ = {modes['escape_exponent']:.4f}), "
            "which outgrows the swing, so its frequency and Euler's k = 0.3117 describe only the start. "
            "The exact small-swing start with A = 3e-4° stays small for 0.8 of a year.")
    elif A > 0 and _distance_left(t, v, v_e) is not None:
        # η can stay within the swing while the distance, the unstable direction's larger share, has
        # left it: the former year-long default ended 6 swings off Euler's v (2 swings from 0.92 yr)
        t_off = _distance_left(t, v, v_e)
        warnings.append(
            f"From t ≈ {t_off / (2 * math.pi):.2g} yr the Moon's distance leaves the small swing (it moves more than "
            f"{SWING_GROWN:g} swings from Euler's v = b(1 − kA cos αζ)): the line-up is unstable (λ = "
            f"{modes['escape_exponent']:.4f}), and the start's tiny share of the unstable direction has grown "
            "e^(λ·2π) ≈ 10⁷-fold a year; his curves describe the run before that.")
    return Run("syzygy", values, traj, metrics, comps, notes, warnings=warnings, plot_series={
        "η simulated (deg)": np.degrees(eta), "η Euler A sin αζ (deg)": np.degrees(eta_e),
        "v/b simulated": v / alpha, "v/b Euler 1 − 0.3117 A cos αζ": v_e / alpha},
        extras={"syzygy_point_lunar": (sgn * b_lunar, 0.0, 0.0)})



def _syzygy_params():
    from ..physics.three_body import syzygy as sz

    return (
        Param("side", "conjunction", kind="choice", choices=("conjunction", "opposition"),
              help="Moon between Earth and Sun (§7) or beyond the Earth (§9)",
              label="Side",
              choice_labels=("conjunction: Moon between Earth and Sun", "opposition: Moon beyond the Earth")),
        Param("amplitude_deg", 3e-4, 0.0, 20.0, "deg", "A: amplitude of η, the Moon's angle from the Sun line",
              label="Swing amplitude A"),
        Param("start", "linear-mode", kind="choice", choices=("euler", "linear-mode"),
              help="Euler's first-order solution at ω = 0, or the exact linear centre mode",
              label="Start", choice_labels=("Euler's first-order start", "exact small-swing mode")),
        Param("escape_seed", 0.0, 0.0, 0.1, "b", "extra displacement along the unstable direction",
              label="Push along the escape direction"),
        Param("duration_yr", 0.8, 0.1, 20.0, "yr", "run length (the run stops when the Moon has left)",
              label="Length of the run"),
        Param("mass_ratio", sz.EARTH_SUN_MASS_RATIO, 1e-9, 1.0, "1",
              "m = M⊕/M☉ (IAU 2009: 3.0035e-6); Euler's n²c³/a³ is m/(1 + m)",
              label="Earth/Sun mass ratio m", advanced=True),
        Param("moon_revolutions_per_year", sz.MOON_REVOLUTIONS_PER_YEAR, 1.0, 100.0, "1/yr",
              "n: sidereal months per sidereal year (13.369; Euler: √175 = 13.23); sets the lunar unit",
              label="Months per year n", advanced=True),
    )


# ---- the scene ---------------------------------------------------------------------------------

OPTIONS = {**tbd.corotating_option(True, "co-rotating frame (Sun fixed on +x)"),
           "inset": Option("magnified swing about the syzygy point (inset)", True),
           "plot_per_amplitude": Option("plot in units of the amplitude A (Euler's curve visible)", True)}
PLOT_CLIP = 4.0  # |η/A| plotted up to this (the escape is read in the scene)
INSET_OFFSET = (0.0, 0.75, 0.0)  # scene units from the syzygy point
INSET_AMPLITUDE = 0.18  # the first swing drawn this large (scene units)
INSET_CLIP = 0.55  # the magnified path is drawn while within this radius
INSET_COLOR = (190, 120, 255)
READOUT_AT = np.array([-1.7, 2.6, 0.0])  # top left, above the Sun's circle in the inertial view
_PLOT_KEYS = ("η simulated (deg)", "η Euler A sin αζ (deg)", "v/b simulated", "v/b Euler 1 − 0.3117 A cos αζ")


def _plot(run: Run, per_amplitude: bool) -> dict:
    """η/A and (v/b − 1)/A beside Euler's sin αζ and −0.3117 cos αζ (§16), clipped at ±PLOT_CLIP:
    in degrees the escape (tens of degrees) flattens the first swings of 0.05°. Without the
    option (or without an amplitude): the run's own series."""
    ps = run.plot_series
    A = float(run.params.get("amplitude_deg", 0.0))
    if not per_amplitude or A <= 0 or not all(k in ps for k in _PLOT_KEYS):
        return dict(ps)
    Ar, c = np.radians(A), PLOT_CLIP
    return {  # Euler's curve first, the simulation drawn over it
        "η/A Euler: sin αζ": np.asarray(ps[_PLOT_KEYS[1]]) / A,
        f"η/A simulated (clipped at ±{c:g})": np.clip(np.asarray(ps[_PLOT_KEYS[0]]) / A, -c, c),
        "(v/b − 1)/A Euler: −0.3117 cos αζ": (np.asarray(ps[_PLOT_KEYS[3]]) - 1) / Ar,
        f"(v/b − 1)/A simulated (clipped at ±{c:g})": np.clip((np.asarray(ps[_PLOT_KEYS[2]]) - 1) / Ar, -c, c),
    }


def _inset(d: Drawing, run: Run, k: float, p: np.ndarray) -> None:
    """The Moon's offset from the syzygy point, magnified M times so that the first swing (η
    amplitude A) is INSET_AMPLITUDE long, drawn beside the point while it stays within INSET_CLIP:
    Euler's small oscillation (a retrograde ellipse, radial/transverse = 0.31) and its growth into
    the escape. A dot follows the Moon's offset while it is inside the ring."""
    s = run.trajectory.series
    if "moon_corotating_x" not in s or "moon_corotating_y" not in s:
        return
    rel = np.stack([np.asarray(s["moon_corotating_x"], float) - p[0], np.asarray(s["moon_corotating_y"], float) - p[1],
                    np.zeros(len(s["moon_corotating_x"]))], 1)
    A = np.radians(float(run.params.get("amplitude_deg", 0.0)))
    amp0 = abs(p[0]) * A if A > 0 else float(np.linalg.norm(rel[min(len(rel) - 1, 5)]))
    if not amp0 > 0:
        return
    M = INSET_AMPLITUDE / (k * amp0)
    centre = k * p + np.asarray(INSET_OFFSET)
    with np.errstate(over="ignore", invalid="ignore"):
        pts = centre + k * M * rel
    if not np.all(np.isfinite(pts)):  # a swing too small to magnify (amplitude 1e-311°)
        return
    inside = np.linalg.norm(pts - centre, axis=1) <= INSET_CLIP
    last = int(np.argmin(inside)) if not inside.all() else len(inside)  # first sample outside the ring
    tbd.growing_path(d, "inset/path", pts[:last], np.arange(last), INSET_COLOR, 0.008)
    r = INSET_CLIP
    d.add(Segments(name="inset/ring", points=segments(centre + circle(r, 65)), colors=(110, 110, 125), thickness=0.003))
    tbd.line(d, "inset/sun_line", centre - (r, 0, 0), centre + (r, 0, 0), color=tbd.SUN_LINE_COLOR, thickness=0.004)
    d.add(Label(name="inset/label", text=f"swing about the Sun line ×{M:.0f}", position=centre + (-r, r + 0.05, 0)))
    f = d.frames
    if last > 0:
        d.add(Sphere(name="inset/moon", radius=0.03, color=INSET_COLOR, position=pts[np.minimum(f, last - 1)],
                     visible=f < last))


def _draw(run: Run, spec: Scenario, view: View) -> Drawing:
    """The Sun–Earth line and the syzygy point (Sun–Earth L1 or L2); in the co-rotating frame
    (default) the Moon swings about the line and then leaves, with a magnified inset of the swing;
    an η and v/b read-out; the plot in units of the amplitude."""
    d = new_drawing(run, spec)
    tr, f = run.trajectory, d.frames
    corot = tbd.corotating(run, spec, view)
    d.plot = _plot(run, view.option("plot_per_amplitude", spec))
    bodies = tbd.body_positions(run, turn=corot)
    # inertial: the Sun goes round the whole circle, which the camera (aimed at the co-rotating
    # picture, Sun on +x) sees whole when drawn smaller
    k = tbd.draw_bodies(d, run, bodies, tbd.largest_distance(bodies) * (1.0 if corot else 1.3))
    tbd.turning_frame(d, run, corot)
    sun_d = float(np.linalg.norm(np.asarray(tr.bodies["sun"], float)[0])) if "sun" in tr.bodies else \
        tbd.largest_distance(bodies)
    tbd.line(d, f"{tbd.TURNING}/sun_line", (-0.5 * k * sun_d, 0, 0), (k * sun_d, 0, 0), color=tbd.SUN_LINE_COLOR)
    p = run.extras.get("syzygy_point_lunar")
    if p is not None:
        p = np.asarray(p, float)
        tbd.marker(d, f"{tbd.TURNING}/syzygy_point", k * p, radius=0.04)
        side = "L1" if p[0] > 0 else "L2"
        if corot:  # below and toward the Earth: the Moon's swing and its escape stay on the point's other side
            d.add(Label(name=f"{tbd.TURNING}/syzygy_point/label", text=f"syzygy point ({side})",
                        position=(-0.62, -0.1, 0.0)))
            if view.option("inset", spec):
                _inset(d, run, k, p)
        else:  # turning with the Sun line, a name beside it would pass over the Earth's and the Moon's
            d.add(Label(name="syzygy_point_key", text=f"white dot on the Sun line: syzygy point ({side})",
                        position=READOUT_AT + np.array([0.0, -0.16, 0.0])))
    t = np.asarray(tr.t, float)[f]
    eta, v = tr.series.get("eta_deg"), tr.series.get("distance_over_b")
    texts = [(f"η = {eta[i]:+.3g}°  v/b = {v[i]:.4f}  t = {t[j]:.3f} {tr.time_unit}"
              if eta is not None and v is not None else f"t = {t[j]:.3g} {tr.time_unit}") for j, i in enumerate(f)]
    tbd.readout(d, texts, READOUT_AT)
    return d


def _cost(values):
    """The displayed run and the 2-year measurement (DOP853); kept: up to N_SAMPLES states with the
    Sun, the Earth and the Moon, five series and four plotted curves."""
    steps = STEPS_PER_YEAR * (values["duration_yr"] + 2.0)
    return Cost(steps, N_SAMPLES, trajectory_bytes(N_SAMPLES, bodies=3, series=9))


register(Scenario(
    series_units={"(earth|moon|moon_corotating|sun)_[xyz]": "LD", "distance_over_b": "",
                  "v/b .*": ""},  # lunar distances; the Sun's direction drawn at 3 of them
    name="syzygy",
    title="The Moon kept in syzygy with the Sun",
    section="Euler 1766, §5–§16",
    group=GROUP,
    summary=("Four times farther out than it is, the Moon could stay lined up with the Sun and the "
            "Earth (today's Sun–Earth Lagrange points L1 and L2). Euler found its small swing about "
            "that line, at √(√28 − 1) ≈ 2.07 times the Sun's motion: Hill's result, a century early. "
            "The same equation shows that the line-up is unstable: nudge the Moon along the unstable "
            "direction and watch it leave after a few swings."),
    params=_syzygy_params(),
    camera=Camera((0.4, -0.8, 3.1), (0.4, 0.0, 0.0)),  # co-rotating: Sun on +x, both syzygy points in view
    simulate_fn=_syzygy,
    draw=_draw,
    options=OPTIONS,
    cost_fn=_cost,
    preview={"duration_yr": 0.8},  # the first 0.8 yr while a run of many is computed
    euler_formula=("m(1 − α)² = α² − α²(1 − α)³ (§7)\n"
                   "η = A sin ω, v = b(1 − 0.3117 A cos ω), ω = αζ, α⁴ + 2α² = 27 (§16)"),
    kind="orbit",
    presets=(
        ("Syzygy: the small swing (Hill)", {}),
        ("Syzygy: Euler's own start, and the Moon leaves", {"start": "euler", "amplitude_deg": 0.05}),
        ("Syzygy: beyond the Earth (opposition)", {"side": "opposition"}),
        ("Syzygy: the Moon leaves", {"escape_seed": 0.01, "duration_yr": 6.0}),
    ),
    # the Sun's mean motion is the unit of rate (time in years/2π); distances in the Moon's b
    metric_units={"syzygy_distance_lunar_units_euler": "b", "alpha_sun_distance": "", "alpha_euler_sun_distance": "",
                  "reduced_mass": "",
                  r"oscillation_frequency(_euler|_linear|_run)?": "n_sun", r"escape_exponent(_linear|_hill)?": "n_sun",
                  r"amplitude_ratio(_euler|_linear)?": "", "fit_rms_residual_rel": "", "swings_before_escape": ""},
))


@register_check("E12", "Moon swinging about syzygy: frequency vs Euler's √(√28 − 1)", "Euler 1766 §12–§16")
def e12():
    m = sz.EARTH_SUN_MASS_RATIO
    A = 1e-6
    window = 20.0
    t, S, _ = sz.integrate(m, sz.initial_state(m, A, "conjunction", "linear-mode", 1e-9), 4 * math.pi, n_samples=8000)
    eta, _ = sz.eta_and_distance(S)
    w, lam, _ = sz.fit_swing_and_escape(t, eta, A, window=window)
    modern = sz.linear_modes(m)["frequency"]
    alpha = sz.equilibrium_conjunction(m)
    # (a) simulated vs the modern linearised frequency: the fit runs on the nonlinear equations
    # while |η| ≤ window·A; the nonlinear terms are of relative size |η| (order-one coefficient;
    # measured: the offset scales with A, 1.26e-6 / 1.26e-5 / 1.26e-4 at A = 1e-7 / 1e-6 / 1e-5),
    # the integration (rtol 1e-12) is far smaller; the linearisation is in closed form.
    rel_sim = abs(w / modern - 1)
    tol_sim = 2 * window * A  # 4e-5
    # (b) Euler vs modern: Euler's u ≫ v drops the O(α) parts of the stiffnesses (Kxx = 9 + 12α,
    # Kyy = −3 − 6α), which shift ω by c₁α (c₁ = 0.70735, derived in hill_first_order_coefficient);
    # what is left after that term must be O(α²) (coefficient ≈ 0.9): allow 2α².
    c1 = sz.hill_first_order_coefficient("conjunction")
    euler_off = modern / sz.HILL_FREQUENCY - 1
    remainder = euler_off - c1 * alpha
    ok_euler = abs(remainder) <= 2 * alpha**2
    return dict(euler=sz.HILL_FREQUENCY, simulated=w, modern=modern, rel_error=rel_sim,
                tolerance=tol_sim, passed=rel_sim <= tol_sim and ok_euler, unit="× Sun's mean motion",
                note=f"rel_error = |simulated/modern − 1| (fit on the full equations while |η| ≤ 20A, A = 1e-6; "
                     f"tolerance 2·20A: the nonlinear terms are of relative size |η|); and Euler: modern/Euler − 1 = "
                     f"{euler_off:.5f} = c₁α = {c1 * alpha:.5f} (the O(v/u) terms Euler drops, α = {alpha:.5f}) + "
                     f"{remainder:.1e} (must be ≤ 2α² = {2 * alpha**2:.1e}); escape exponent {lam:.4f} "
                     f"(Hill limit {sz.HILL_ESCAPE_EXPONENT:.4f}) — the real root Euler did not see")


@register_check("E12.distance", "syzygy distance: the restricted problem's collinear point (quintic) vs Euler's 'about four'", "Euler 1766 §7–§8")
def e12_distance():
    m = sz.EARTH_SUN_MASS_RATIO
    b = sz.equilibrium_conjunction(m) * sz.lunar_units_per_sun_distance(m, sz.MOON_REVOLUTIONS_PER_YEAR)
    eu = (sz.EULER_N_SQUARED / 3) ** (1 / 3)
    # modern: Sun–Earth L1 at 1.4915e6 km (from the CR3BP root, = 0.99 of 1 AU inward)
    rel = abs(eu / b - 1)
    return dict(euler=eu, simulated=b, modern=None, rel_error=rel, tolerance=sz.equilibrium_conjunction(m) + 0.01,
                unit="lunar distances",
                note="Euler's first approximation ∛(n²/3) with n² = 175 against the root with today's m, n; "
                     "tolerance: the neglected α (1%) plus his n² = 175 vs 178.7 (0.7% in the cube root)")


@register_check("E12.escape", "escape exponent measured vs the real root of λ⁴ − 2λ² − 27 = 0", "Euler 1766 §16")
def e12_escape():
    m = sz.EARTH_SUN_MASS_RATIO
    lam = sz.measured_escape_exponent(m)
    lin = sz.linear_modes(m)["escape_exponent"]
    rel = abs(lam / lin - 1)
    return dict(euler=sz.HILL_ESCAPE_EXPONENT, simulated=lam, modern=lin, rel_error=rel, tolerance=1e-3,
                unit="× Sun's mean motion",
                note="growth of a displacement from 1e-7 to 1e-3 b; Euler's own equation has this root, he took only λ = iα")


@register_check("E12.mass_ratio", "syzygy at m = 0.01: frequencies of the restricted problem (1 + m in the mean "
                "motion), both sides, Euler's √(√28 − 1) beside", "Euler 1766 §12–§16, modern")
def e12_mass_ratio():
    """The frequency measured on the restricted problem at a mass ratio where Euler's frame (the
    Sun's pull a³ on the Moon, or a frame turning at rate 1 with G·M_sun = 1) is visibly off:
    2.3157 (conjunction) and 1.8755 (opposition), where the rate-1 model gave 2.3248 and 1.8814."""
    m, A = 0.01, 1e-6
    out, worst = [], 0.0
    for side in ("conjunction", "opposition"):
        modes = sz.linear_modes(m, side)
        t, S, _ = sz.integrate(m, sz.initial_state(m, A, side, "linear-mode", 1e-9), 4 * math.pi, n_samples=8000)
        eta, _ = sz.eta_and_distance(S, side)
        w, _, _ = sz.fit_swing_and_escape(t, eta, A, guess=(modes["frequency"], modes["escape_exponent"]))
        worst = max(worst, abs(w / modes["frequency"] - 1))
        out.append((side, w, modes["frequency"]))
    (_, wc, lc), (_, wo, lo) = out
    return dict(euler=sz.HILL_FREQUENCY, simulated=wc, modern=lc, rel_error=worst, tolerance=4e-5,
                unit="× Sun's mean motion",
                note=f"conjunction {wc:.5f} (linearised {lc:.5f}), opposition {wo:.5f} (linearised {lo:.5f}); "
                     "rel_error: the larger of |fit/linearised − 1| on the two sides (fit while |η| ≤ 20A, A = 1e-6: "
                     "tolerance 2·20A, the nonlinear terms). Euler/Hill: 2.07159 on both sides (m → 0)")


@register_check("E12.richardson", "Sun–Earth L1: distance and in-plane frequency vs Richardson (1980)", "modern")
def e12_richardson():
    """Richardson 1980 (Celest. Mech. 22, 241), Sun–(Earth + Moon), μ = 3.040357143e-6:
    γ₁ = 0.01001090475 (distance of L1 from the Earth in AU), c₂ = 4.061073566, in-plane
    frequency ω_p = 2.086453455 (units of the mean motion)."""
    mu = 3.040357143e-6
    m = mu / (1.0 - mu)  # the mass ratio whose μ = m/(1 + m) is Richardson's
    g = sz.equilibrium_conjunction(m)
    c2 = sz.stiffness_c2(m)
    w = sz.linear_modes(m)["frequency"]
    rel = max(abs(g / 0.01001090475 - 1), abs(c2 / 4.061073566 - 1), abs(w / 2.086453455 - 1))
    return dict(euler=sz.HILL_FREQUENCY, simulated=w, modern=2.086453455, rel_error=rel, tolerance=1e-9,
                unit="× mean motion",
                note=f"γ₁ = {g:.11f} (published 0.01001090475), c₂ = {c2:.10f} (4.061073566); rel_error: the largest "
                     "of the three; tolerance 1e-9: about one unit in the last (tenth) published digit")
