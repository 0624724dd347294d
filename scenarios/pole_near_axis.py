"""The pole of rotation near a principal axis (Problem 95, §840–843): its momentary motion
under a central force, and with two equal moments the spin unchanged.

Check rows E9 and E9.equal-moments.
"""
from __future__ import annotations

import numpy as np
from ..physics.inertia import validate_moments
from ..physics.integrator import PointMass, integrate, samples_kept, step_count
from ..physics.params import Param
from ..physics.precession import (TYPOS_840_843, equal_moments_841, pole_rates_840)
from ..physics.trajectory import Trajectory
from .drawing import Camera
from .base import Comparison, Run, Scenario, register
from . import _validity
from .budget import Cost, trajectory_bytes
from .base import get
from .checks import register_check
from ._precession import MAX_SAMPLES
from .drawing import Label, Option, Path, Segments, Sphere, segments, unit, wire_sphere
from ._ch16_drawing import (WIGGLE_COLOR, body_scene, centre_line, centre_of_force, magnified_about_start, nice_step,
                            path_samples)


def _stride(n_steps):
    return max(1, int(np.ceil(n_steps / MAX_SAMPLES)))


def _fixed_direction(u):
    u = np.asarray(u, float)

    def pos(t):
        return np.broadcast_to(u, (np.size(t), 3)).copy()

    return pos


def measure_pole_rates(t, omega_body):
    """dγ'/dt, dβ/dt, dγ/dt at t = 0 from a short simulated run: β, γ = arccos(ω_B/|ω|),
    arccos(ω_C/|ω|); a quartic fitted by least squares, its slope at t = 0."""
    w = np.linalg.norm(omega_body, axis=1)
    beta = np.arccos(np.clip(omega_body[:, 1] / w, -1, 1))
    gamma = np.arccos(np.clip(omega_body[:, 2] / w, -1, 1))
    out = []
    for y in (w, beta, gamma):
        c = np.polynomial.polynomial.polyfit(t - t[0], y, 4)
        out.append(float(c[1]))
    return out


def _pole_near_axis(values, progress=None):
    I = validate_moments(values["moments"], "moments")
    spin = values["spin"]
    zeta = np.radians(values["zeta_deg"])
    az = np.radians(values["azimuth_deg"])
    a0 = np.radians(values["offset_deg"])
    # direction of F on the body axes A, B, C (body x, y, z): cos ζ, cos η, cos θ
    cz, ce, ct = np.cos(zeta), np.sin(zeta) * np.cos(az), np.sin(zeta) * np.sin(az)
    u = np.array([cz, ce, ct])
    tidal = values["tidal"]
    w0 = spin * np.array([np.cos(a0), np.sin(a0), 0.0])  # O at α from A, toward B
    T = 2 * np.pi / spin
    dur = values["duration_turns"] * T
    step = T / values["steps_per_turn"]
    n = int(np.ceil(dur / step))
    t, L, q = integrate(I, w0, dur, step, masses=[PointMass(tidal, _fixed_direction(u))],
                        scheme="yoshida4", stride=_stride(n), progress=progress)
    # F is fixed in space, the body turns: F's inertial position (initial body frame = space)
    traj = Trajectory(t, q, L, I, time_unit="s", bodies={"centre": np.tile(u, (len(t), 1))},
                      figure_axis_index=0)
    # the momentary rates: a separate short run, finely sampled, over 1/200 turn or less: short
    # against the time the pull takes to turn the pole (1/√(3·tidal·ΔI/I)); at tidal = 10⁶ the pole
    # swung in 1/200 turn, the quartic through it gave |Oo|/dt 20× too slow and §841's 0 as 87.6
    pull = np.sqrt(3.0 * tidal * np.ptp(I) / np.min(I))
    # and short against the time the pole takes to move 0.01 rad (|τ|/(I γ′): at a spin of 10⁻⁶
    # rad/s the pole ran off A within the window, and dβ/dt came out −53 against −147,721)
    pole_rate = 3.0 * tidal * np.linalg.norm(np.cross(u, I * u)) / (np.min(I) * spin)
    window = min(T / 200, 0.02 / pull if pull > 0 else np.inf, 0.01 / pole_rate if pole_rate > 0 else np.inf)
    ts, Ls, qs = integrate(I, w0, window, window / 100, masses=[PointMass(tidal, _fixed_direction(u))],
                           scheme="yoshida4")
    dspin, dbeta, dgamma = measure_pole_rates(ts, Ls / I)
    e = pole_rates_840(I, spin, (cz, ce, ct), tidal)
    m = dict(dspin_dt=dspin, dspin_dt_euler=e.dspin_dt, dbeta_dt=dbeta, dbeta_dt_euler=e.dbeta_dt,
             dgamma_dt=dgamma, dgamma_dt_euler=e.dgamma_dt, pole_speed=float(np.hypot(dbeta, dgamma)),
             pole_speed_euler=e.pole_speed)
    comps = [Comparison("how fast the spin changes, dγ'/dt (γ' = |ω|)", e.dspin_dt, dspin, None, "rad/s²", "§840"),
             Comparison("dβ/dt (pole toward/away from B)", e.dbeta_dt, dbeta, None, "rad/s",
                        "§840 (the printed formula lacks the minus sign)"),
             Comparison("dγ/dt (pole toward/away from C)", e.dgamma_dt, dgamma, None, "rad/s", "§840")]
    notes = ["Text: " + t for t in TYPOS_840_843]
    if a0 > 0:
        notes.append(f"the pole starts {values['offset_deg']:g}° from A: Euler's rates drop the free "
                     f"wobble (aa−bb)/cc·γ′ sin α cos α, of size {spin * abs(I[0] - I[1]) / I[2] * np.sin(a0) * np.cos(a0):.3g} "
                     "rad/s in dγ/dt (the pole, off A toward B, turns toward C at that rate without any pull)")
    if np.isclose(I[1], I[2], rtol=1e-12):
        q841 = equal_moments_841(I, spin, (cz, ce, ct), tidal)
        ang = np.arctan2(-dgamma, -dbeta)  # displacement of O on (B, C) is (−dβ, −dγ)
        ang_e = np.arctan2(q841["direction_BC"][1], q841["direction_BC"][0])
        m.update(N_843=q841["N"], pole_speed_euler_842=q841["pole_speed"],
                 pole_direction_deg=float(np.degrees(ang)), pole_direction_deg_euler=float(np.degrees(ang_e)),
                 perpendicularity_841=float(dbeta * ce + dgamma * ct))
        comps.append(Comparison("speed of the pole O across the body, |Oo|/dt = 2N cos ζ sin ζ (B = C)", q841["pole_speed"],
                                m["pole_speed"], None, "rad/s", "§842"))
        comps.append(Comparison("direction of Oo on (B, C)", float(np.degrees(ang_e)),
                                float(np.degrees(ang)), None, "deg",
                                "§843: at right angles to FA, around A in the sense C→B when aa > cc"))
        comps.append(Comparison("the pole's motion toward F, dβ cos η + dγ cos θ (Euler: none)", 0.0, m["perpendicularity_841"], None, "rad/s", "§841"))
    ob = traj.omega_body / np.linalg.norm(traj.omega_body, axis=1, keepdims=True)
    # the step against the fastest period: F's pull on the turning body repeats twice a turn
    warnings = _validity.add([], _validity.coarse_step(step, T / 2, "half a turn of the body under F (the pull "
                                                       "repeats twice a turn)", "s", "steps_per_turn"))
    return Run("pole-near-axis", values, traj, m, comps, notes, warnings=warnings,
                  plot_series={"β − 90° (deg)": np.degrees(np.arccos(np.clip(ob[:, 1], -1, 1))) - 90,
                               "γ − 90° (deg)": np.degrees(np.arccos(np.clip(ob[:, 2], -1, 1))) - 90,
                               "spin γ' (rad/s)": np.linalg.norm(traj.omega_body, axis=1)})


POLE_RADIUS = 1.6  # the pole's path is drawn on a body-fixed sphere beyond the A axis (semi-axis 1)


def _draw(run, spec, view):
    """The spinning body with the direction to F, and on the body (turning with it) the path of
    the rotation pole O (the direction of ω in the body, beyond the A axis), its departure from
    the start magnified by the factor in its label: in a few turns O moves by a fraction of a
    degree (§840), at right angles to the arc AF (§841). Around the start, a body-fixed scale:
    the directions toward B and C and rings at round true angles from the start, drawn with the
    same magnification as the path."""
    d, _ = body_scene(run, spec, view, bodies={"F": centre_of_force(run)})
    if view.option("pole_path", spec):
        tr = run.trajectory
        u = unit(tr.omega_body)
        path, k = magnified_about_start(u, target_deg=16.0)
        path = POLE_RADIUS * path
        idx, at = path_samples(d, len(path))
        d.add(Path(name="body/pole_path", points=path[idx], color=WIGGLE_COLOR, thickness=0.02, at=at),
              Sphere(name="body/pole_now", radius=0.04, color=WIGGLE_COLOR, position=path[d.frames]))
        _pole_scale(d, u[0], float(np.degrees(np.max(np.arccos(np.clip(u @ u[0], -1, 1))))), k)
        # the sphere the path is drawn on, fixed in the body: parallels about A and meridians through it,
        # so that the path is seen on the turning body rather than floating in space
        grid = wire_sphere(POLE_RADIUS, n_lat=5, n_lon=6)[..., [2, 0, 1]]
        d.add(Segments(name="body/pole_sphere", points=grid, colors=(175, 175, 190), thickness=0.003))
    centre_line(d, run, spec, view)
    return d


def _pole_scale(d, c, dev_deg, k):
    """Rings about the start c at round true angles θ, drawn where the magnified path puts a pole
    θ from c (c + k·(u − c), normalised: at atan2(k sin θ, 1 + k(cos θ − 1))), and the arcs
    through c toward the body's B and C axes."""
    tb = unit(np.array([0.0, 1.0, 0.0]) - c[1] * c)
    tb = tb if np.linalg.norm(tb) > 0.5 else unit(np.array([0.0, 0.0, 1.0]) - c[2] * c)
    tc = np.cross(c, tb)
    step = nice_step(max(dev_deg, 1e-12) / 2)
    rings = step * np.arange(1, 4)
    drawn = np.arctan2(k * np.sin(np.radians(rings)), 1 + k * (np.cos(np.radians(rings)) - 1))
    th = np.linspace(0, 2 * np.pi, 73)[:, None]
    segs = [segments(POLE_RADIUS * (np.cos(a) * c + np.sin(a) * (np.cos(th) * tb + np.sin(th) * tc))) for a in drawn]
    reach = np.linspace(-drawn[-1], drawn[-1], 25)[:, None]
    for t in (tb, tc):
        segs.append(segments(POLE_RADIUS * (np.cos(reach) * c + np.sin(reach) * t)))
    edge = 1.08 * POLE_RADIUS
    d.add(Segments(name="body/pole_scale", points=np.concatenate(segs), colors=(150, 150, 160), thickness=0.004),
          Label(name="body/pole_scale/B", text="toward B", position=edge * (np.cos(drawn[-1]) * c + np.sin(drawn[-1]) * tb)),
          Label(name="body/pole_scale/C", text="toward C", position=edge * (np.cos(drawn[-1]) * c + np.sin(drawn[-1]) * tc)),
          Label(name="body/pole_label", text=f"pole O, departure ×{k:g}; rings {step:g}° apart (true)",
                position=edge * (np.cos(drawn[-1]) * c - np.sin(drawn[-1]) * tc)))


def _cost(values):
    """duration_turns × steps_per_turn steps (yoshida4), the 100-step run that measures the rates
    at t = 0, and the centre's direction and three series kept per sample."""
    T = 2 * np.pi / values["spin"]
    dur, step = values["duration_turns"] * T, T / values["steps_per_turn"]
    n = step_count(dur, step)
    samples = samples_kept(n, _stride(n)) if np.isfinite(n) else MAX_SAMPLES + 1
    return Cost(n + step_count(T / 200, T / 20000), samples, trajectory_bytes(samples, bodies=1, series=3))


register(Scenario(
    series_units={"centre_[xyz]": "1"},  # the direction of F
    name="pole-near-axis",
    title="The pole of rotation near a principal axis",
    section="§840–843",
    group="ch. 16",
    summary=("A body spins fast about (nearly) its principal axis A while a distant mass F pulls on it. "
            "Euler computes the first instants: the spin rate changes only if the moments B and C "
            "differ, and the pole of rotation O leaves A at right angles to the arc AF, fastest when F "
            "is 45° from the axis (§842: rate 2N cos ζ sin ζ). The table compares his rates with the "
            "simulated ones."),
    params=(
        Param("moments", (1.2, 1.0, 1.0), kind="vec3", minimum=1e-6, maximum=1e6, unit="kg m^2",
              help="Euler's aa, bb, cc: moments about A (the spin axis, body x), B, C",
              label="Moments A (spin axis), B, C"),
        # at least 1e-6 rad/s (found by tests/test_fuzz.py: spin 1.6e-171 with moments 1e-6 underflowed
        # |ω|² to 0 and the rate fit got NaN)
        Param("spin", 10.0, 1e-6, 1e4, "rad/s", "spin γ' about A", label="Spin rate γ′ about A"),
        Param("tidal", 1.0, 0.0, 1e6, "1/s^2", "GM/s³ of the centre of force", exclusive_min=True,
              label="Pull of F, GM/s³"),
        Param("zeta_deg", 40.0, 0.0, 180.0, "deg", "arc AF from the spin axis to the centre",
              label="Arc AF from the spin axis"),
        Param("azimuth_deg", 30.0, -180.0, 180.0, "deg", "azimuth of F around A, from B toward C",
              label="Azimuth of F about A"),
        Param("offset_deg", 0.0, 0.0, 10.0, "deg", "initial arc AO of the pole from A (toward B)",
              label="Pole's start away from A"),
        Param("duration_turns", 5.0, 0.0, 1e4, "turns", "length of the drawn run", exclusive_min=True,
              label="Length of the run"),
        Param("steps_per_turn", 200, 4, 1e5, "1", "integrator steps per turn", kind="int",
              label="Integrator steps per turn", advanced=True),
    ),
    camera=Camera((4.6, 1.6, 1.4), (0.8, 0.0, 0.0)),  # nearly down the spin axis A (body x): the pole path beyond it face-on
    # ω and L lie within a fraction of a degree of A here: drawn true, their arrows and letters sit
    # on the A axis and hide the magnified path of the pole O, which is ω's direction in the body
    overlays={'celestial': False, 'axis_trail': False, 'polhode': False, 'vectors': False},
    simulate_fn=_pole_near_axis,
    draw=_draw,
    options={"pole_path": Option("path of the rotation pole O in the body, magnified"),
             "centre": Option("direction to the centre of force")},
    cost_fn=_cost,
    euler_formula=("dγ' = 6gee (cc − bb) dt cos η cos ϑ / (aa s³) (§840)\n"
                   "γ' dβ = −6gee (aa − cc) dt cos ζ cos ϑ / (bb s³)\n"
                   "γ' dγ = −6gee (bb − aa) dt cos ζ cos η / (cc s³)   (6gee = 3GM)\n"
                   "bb = cc: Oo = 2N cos ζ sin ζ dt, N = 3gee (aa − cc) / (γ' cc s³) (§842–843)"),
    presets=(
        ("Pole: F at 40°, B = C", {}),
        ("Pole: F at 45°, the fastest drift", {"zeta_deg": 45.0}),
        ("Pole: B ≠ C, the spin changes", {"moments": (1.2, 1.0, 0.8)}),
    ),
    metric_units={"dspin_dt": "rad/s^2", "dspin_dt_euler": "rad/s^2", r"(dbeta_dt|dgamma_dt|pole_speed)(_euler)?": "rad/s",
                  "pole_speed_euler_842": "rad/s", "N_843": "rad/s", "perpendicularity_841": "rad/s",
                  "pole_direction_deg_euler": "deg"},
))


@register_check("E9", "momentary motion of the pole near a principal axis (aa, bb, cc unequal)", "§840")
def e9():
    r = get("pole-near-axis").simulate({"moments": (1.3, 1.0, 0.8), "duration_turns": 1.0})
    m = r.metrics
    errs = [abs(m[k] - m[k + "_euler"]) / abs(m[k + "_euler"]) for k in ("dspin_dt", "dbeta_dt", "dgamma_dt")]
    return dict(euler=m["dbeta_dt_euler"], simulated=m["dbeta_dt"], modern=None, rel_error=max(errs),
                tolerance=1e-6, unit="rad/s",
                note=f"dγ'/dt, dβ/dt, dγ/dt at O = A (where Euler's dropped terms vanish); worst of the three. "
                     f"dγ'/dt {m['dspin_dt']:.6g} vs {m['dspin_dt_euler']:.6g}. §840 prints γ'dβ without its minus sign. "
                     "Tolerance: the quartic fit of a 1/200-turn run")


@register_check("E9.equal-moments", "bb = cc: spin unchanged, pole moves ⟂ FA at 2N cos ζ sin ζ, sense C→B", "§841–843")
def e9_equal():
    r = get("pole-near-axis").simulate({"moments": (1.2, 1.0, 1.0), "duration_turns": 1.0})
    m = r.metrics
    rel = abs(m["pole_speed"] - m["pole_speed_euler_842"]) / m["pole_speed_euler_842"]
    dang = abs((m["pole_direction_deg"] - m["pole_direction_deg_euler"] + 180) % 360 - 180)
    passed = rel <= 1e-6 and dang <= 1e-4 and abs(m["dspin_dt"]) <= 1e-9 * m["pole_speed"] * 10
    return dict(euler=m["pole_speed_euler_842"], simulated=m["pole_speed"], modern=None, rel_error=rel,
                tolerance=1e-6, unit="rad/s", passed=passed,
                note=f"direction of Oo {m['pole_direction_deg']:.5f}° vs Euler {m['pole_direction_deg_euler']:.5f}°; "
                     f"dγ'/dt = {m['dspin_dt']:.2g} (Euler: 0)")
