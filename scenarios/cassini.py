"""The Moon's Cassini state (Peale 1969; Colombo's and Cassini's laws): the spin axis, the orbit
normal and the ecliptic normal stay in one plane while the orbit's node regresses in 18.6 years,
and the spin axis keeps ~1.54° from the ecliptic pole.

The rigid Moon (LLR moments) is integrated under the Earth, which moves on a Kepler ellipse of the
Moon's mean elements whose node regresses and whose perigee advances at their observed sidereal
rates, and under the Sun on its circle in the ecliptic. It starts in the Cassini state Peale's
equation gives (physics.cassini) and turns synchronously; the run measures the obliquity of its
figure axis (mean over whole node cycles), how far the axis leaves the plane of the other two
normals, and on which side of the ecliptic pole it stays.

Check row E8.moon-cassini: the equilibrium obliquity from Peale's equation and from the run
against the observed 1.543° (IAU: the mean lunar equator's inclination 1.54242°).
"""
from __future__ import annotations

import functools
import math

import numpy as np

from ..physics import cassini as CS
from ..physics import constants as C
from ..physics import kepler
from ..physics import moon
from ..physics import quaternion as quat
from ..physics.constants import ARCSEC_RAD, JULIAN_YEAR_DAYS
from ..physics.integrator import PointMass, integrate, samples_kept, step_count
from ..physics.params import Param, ParameterError
from ..physics.trajectory import Trajectory
from .base import Comparison, Run, Scenario, get, register
from .budget import Cost, trajectory_bytes
from .checks import register_check
from .drawing import Arrows, Camera, Label, Option, Path, Segments, unit
from ._ch16_drawing import body_scene

GM_SUN_KM3_DAY2 = C.GM_SUN_KM3_S2 * C.SECONDS_PER_DAY**2
# the mean motions against the fixed ecliptic (rad/day): month, node, perigee, year
N_MONTH = 2 * math.pi / C.SIDEREAL_MONTH_DAYS
G_NODE = -2 * math.pi / C.NODE_PERIOD_SIDEREAL_DAYS
W_APSE = 2 * math.pi / C.APSE_PERIOD_SIDEREAL_DAYS
N_YEAR = 2 * math.pi / C.SIDEREAL_YEAR_DAYS


def orbit(values):
    """The Moon's mean orbit about the Earth (functions of t in days): geocentric position (km) of
    the Moon and its orbit normal; the node, the argument of latitude F and the mean longitude.
    a is the Moon's mean distance and n its sidereal mean motion, as observed (with the Sun's
    perturbation they are not Kepler's pair: only the positions are taken from the ellipse)."""
    a, e = C.EARTH_MOON_DISTANCE_KM, C.MOON_MEAN_ECCENTRICITY
    inc = math.radians(values["inclination_deg"])
    g = -2 * math.pi / (values["node_period_yr"] * JULIAN_YEAR_DAYS)
    L0, node0, varpi0 = (math.radians(x) for x in (C.MOON_MEAN_LONGITUDE[0], C.MOON_NODE[0], C.MOON_PERIGEE_J2000_DEG))

    def angles(t):
        t = np.asarray(t, float)
        L = L0 + N_MONTH * t
        node = node0 + g * t
        varpi = varpi0 + W_APSE * t
        return L, node, varpi

    def position(t):
        L, node, varpi = angles(t)
        return kepler.position(L - varpi, a, e, inc, node, varpi - node)

    def normal(t):
        _, node, _ = angles(t)
        return np.stack([math.sin(inc) * np.sin(node), -math.sin(inc) * np.cos(node),
                         np.full_like(node, math.cos(inc))], -1)

    return position, normal, angles, inc, g, a, e


def sun_from_earth(t):
    """The Sun on a circle of 1 AU in the ecliptic at its mean longitude (km)."""
    L = math.radians(C.SUN_MEAN_LONGITUDE_J2000_DEG) + N_YEAR * np.asarray(t, float)
    return C.AU_KM * np.stack([np.cos(L), np.sin(L), 0 * L], -1)


def peale(values) -> float:
    """Peale's equilibrium obliquity (deg) for the run's moments, orbit and Sun."""
    _, _, _, inc, g, a, e = orbit(values)
    I = moon.moments(values["beta"], values["gamma"])
    k_e = CS.torque_coefficient(moon.GM_EARTH_KM3_DAY2, 1.0 / (a ** 3 * (1 - e * e) ** 1.5), N_MONTH)
    k_s = CS.torque_coefficient(GM_SUN_KM3_DAY2, C.AU_KM ** -3.0, N_MONTH) if values["sun_torque"] == "on" else 0.0
    I_state = CS.peale_obliquity(inc, g, k_e, k_s, I)
    if I_state is None:
        raise ParameterError("beta", values["beta"], "large enough for a Cassini state 2 at this node period "
                             f"({values['node_period_yr']:g} yr) and inclination (raise beta or gamma, or "
                             "lengthen node_period_yr)")
    return math.degrees(I_state)


def _cassini(values, progress=None):
    position, normal, angles, inc, g, a, e = orbit(values)
    I_peale = peale(values)
    obl0 = math.radians(I_peale + values["start_offset_deg"])
    I = moon.moments(values["beta"], values["gamma"])
    duration = values["years"] * JULIAN_YEAR_DAYS

    def frame(t):
        L, node, _ = angles(t)
        return CS.cassini_frame(node, L - node, obl0)

    eps = 1e-3
    qs = frame(np.array([-eps, 0.0, eps]))
    q0 = qs[1]
    w0 = 2 * quat.multiply(quat.conjugate(q0), (qs[2] - qs[0]) / (2 * eps))[1:]
    earth = lambda t: -position(t)  # noqa: E731  (the Earth seen from the Moon)
    masses = [PointMass(moon.GM_EARTH_KM3_DAY2, earth)]
    if values["sun_torque"] == "on":
        masses.append(PointMass(GM_SUN_KM3_DAY2, lambda t: sun_from_earth(t) + earth(t)))
    h = values["step_days"]
    n_steps = int(math.ceil(duration / h))
    t, L, q = integrate(I, w0, duration, h, q0=q0, masses=masses, scheme="yoshida4",
                        stride=max(1, int(math.ceil(n_steps / 8000))), progress=progress)
    k = np.array([0.0, 0.0, 1.0])
    spin = quat.rotate(q, np.array([0.0, 0.0, 1.0]))  # the figure (C) axis
    nrm = normal(t)
    obl = np.arccos(np.clip(spin[:, 2], -1, 1))
    theta = np.arccos(np.clip(np.sum(spin * nrm, axis=1), -1, 1))
    off = CS.out_of_plane(spin, nrm, k)
    side = CS.side_of_pole(spin, nrm, k)
    # mean over whole node cycles (the free precession about the state and the monthly forced terms
    # average out with them; a shorter run takes the whole run)
    P = 2 * math.pi / abs(g)
    whole = int(t[-1] // P)
    sel = t <= whole * P if whole >= 1 else np.ones_like(t, bool)
    mean_obl = float(np.degrees(np.mean(obl[sel])))
    m = {
        "obliquity_mean_deg": mean_obl,
        "obliquity_peale_deg": I_peale,
        "obliquity_observed_deg": C.MOON_EQUATOR_INCLINATION_DEG,
        "obliquity_min_deg": float(np.degrees(obl.min())), "obliquity_max_deg": float(np.degrees(obl.max())),
        "spin_to_orbit_normal_mean_deg": float(np.degrees(np.mean(theta[sel]))),
        "out_of_plane_max_arcsec": float(np.max(np.abs(off)) / ARCSEC_RAD),
        "out_of_plane_rms_arcsec": float(np.sqrt(np.mean(off ** 2)) / ARCSEC_RAD),
        "opposite_side_fraction": float(np.mean(side > 0)),
        "node_period_yr": values["node_period_yr"],
        "node_cycles_averaged": float(whole),
    }
    comps = [
        Comparison("obliquity of the spin axis to the ecliptic (°)", I_peale, mean_obl, C.MOON_EQUATOR_INCLINATION_DEG,
                   "deg", "Euler column: Peale's equation; modern: IAU mean lunar equator", observed="the real Moon"),
        Comparison("spin axis out of the plane (ecliptic pole, orbit normal), rms (″)", 0.0,
                   m["out_of_plane_rms_arcsec"], None, "arcsec",
                   "Cassini's third law: 0; the monthly nod of the axis (forced libration in latitude)"),
        Comparison("spin–orbit normal angle θ = i + I (°)", math.degrees(inc) + I_peale, m["spin_to_orbit_normal_mean_deg"],
                   C.MOON_MEAN_INCLINATION_DEG + C.MOON_EQUATOR_INCLINATION_DEG, "deg",
                   "state 2: the ecliptic pole between the spin axis and the orbit normal", observed="the real Moon"),
    ]
    notes_rows = ("Obliquity: simulated is the figure axis's mean angle to the ecliptic pole over whole node cycles; "
                  "Euler's column is Peale's equation, modern the IAU mean lunar equator. The axis "
                  "leaves the plane of the other two normals by its monthly nod, the forced physical libration in "
                  "latitude (DE421's own axis nods by ±0.06°).")
    notes = [
        f"Started {values['start_offset_deg']:+g}° from Peale's state ({I_peale:.4f}°); the axis then circles the "
        "state (free precession) while following the node. "
        f"The node regresses in {values['node_period_yr']:g} yr; the spin axis stays on the far side of the ecliptic "
        f"pole from the orbit normal in {100 * m['opposite_side_fraction']:.0f}% of the samples.",
        "Moments from lunar laser ranging (β, γ); the Earth on a Kepler ellipse with the Moon's mean distance, "
        "eccentricity and inclination, its node and perigee turning at the observed sidereal rates (Meeus ch. 47); "
        "the Sun on a circle in the ecliptic. A rigid Moon without the degree-3 field or a core (Peale's setting).",
        notes_rows,
    ]
    node_line = unit(np.cross(k, nrm))
    traj = Trajectory(t, q, L, I, time_unit="day", bodies={"earth": earth(t)}, moment_unit="C")
    extras = {"orbit_normal": nrm, "spin_axis": spin, "node_line": node_line, "ecliptic_pole": k}
    plot = {"obliquity (deg)": np.degrees(obl), "obliquity, Peale (deg)": np.full_like(obl, I_peale),
            "out of plane (arcsec)": off / ARCSEC_RAD}
    # the mean over less than a node cycle still carries the free precession about the state
    warnings = [] if whole >= 1 else [
        f"The run ({t[-1] / JULIAN_YEAR_DAYS:.3g} yr) is shorter than one regression of the node "
        f"({values['node_period_yr']:g} yr): the mean obliquity is over part of a cycle, so the axis's circling "
        "about Cassini's state is not averaged out. Run at least one node period."]
    return Run("cassini", values, traj, m, comps, notes, plot_series=plot, extras=extras, warnings=warnings)


def _cost(values):
    """One run over `years` at step_days (yoshida4, the Earth and the Sun), ~8,000 states kept;
    per state the Earth's position, three directions (orbit normal, spin axis, node line) and
    three plotted series."""
    n = step_count(values["years"] * JULIAN_YEAR_DAYS, values["step_days"])
    samples = samples_kept(n, max(1, int(math.ceil(n / 8000)))) if math.isfinite(n) else 8001
    return Cost(n, samples, trajectory_bytes(samples, bodies=4, series=3))


ECLIPTIC_COLOR, ORBIT_COLOR, SPIN_COLOR, NODE_COLOR = (200, 160, 0), (40, 120, 220), (220, 50, 47), (90, 90, 90)
NORMAL_LENGTH = 1.9


def _magnified(v, k):
    """Directions with their angle from the ecliptic pole (+z) multiplied by k (same azimuth)."""
    v = unit(np.asarray(v, float))
    p = np.arccos(np.clip(v[..., 2], -1, 1)) * k
    az = np.arctan2(v[..., 1], v[..., 0])
    return np.stack([np.sin(p) * np.cos(az), np.sin(p) * np.sin(az), np.cos(p)], -1)


def _draw(run, spec, view):
    """The Moon, and the three normals from its centre: the ecliptic pole (yellow, fixed), the orbit
    normal (blue) and the spin axis (red), with the cones their tips trace and the node line (grey)
    turning in 18.6 years; the normals' angles from the ecliptic pole magnified so that the plane
    they share shows (the factor is written on the scene)."""
    d, semi = body_scene(run, spec, view, bodies={})
    f = d.frames
    k_mag = MAGNIFY if view.option("magnify", spec) else 1.0
    ex = run.extras
    nrm = _magnified(ex["orbit_normal"], k_mag)
    spin = _magnified(ex["spin_axis"], k_mag)
    Lk = NORMAL_LENGTH
    d.add(Arrows(name="normals/ecliptic", origins=np.zeros((1, 3)), vectors=np.array([[0.0, 0.0, Lk]]),
                 colors=(ECLIPTIC_COLOR,), shaft_radius=0.02, head_radius=0.05, head_length=0.1),
          Arrows(name="normals/orbit", origins=np.zeros((1, 3)), vectors=(Lk * nrm[f])[:, None, :],
                 colors=(ORBIT_COLOR,), shaft_radius=0.02, head_radius=0.05, head_length=0.1,
                 labels=("orbit normal",)),
          Arrows(name="normals/spin", origins=np.zeros((1, 3)), vectors=(Lk * spin[f])[:, None, :],
                 colors=(SPIN_COLOR,), shaft_radius=0.02, head_radius=0.05, head_length=0.1,
                 labels=("spin axis",)))
    at = np.arange(len(f), dtype=float)
    d.add(Path(name="normals/orbit_cone", points=Lk * nrm[f], color=ORBIT_COLOR, thickness=0.01, at=at),
          Path(name="normals/spin_cone", points=Lk * spin[f], color=SPIN_COLOR, thickness=0.01, at=at))
    nl = np.asarray(ex["node_line"], float)[f]
    d.add(Segments(name="node_line", points=np.stack([-1.6 * nl, 1.6 * nl], 1)[:, None], colors=NODE_COLOR,
                   thickness=0.015),
          Segments(name="normals/plane", points=np.stack([Lk * nrm[f], Lk * spin[f]], 1)[:, None], colors=(120, 120, 120),
                   thickness=0.006),
          Label(name="node_line_label", text="node line", position=1.75 * nl),
          # named above its tip, not at it: the spin axis's tip stays within a few degrees of it
          Label(name="normals/magnified", text="ecliptic pole (yellow): " + (
              f"angles from it ×{k_mag:g}" if k_mag != 1 else "angles true to scale"), position=(0.0, 0.0, Lk + 0.35)))
    th = np.linspace(0, 2 * np.pi, 181)
    ring = np.stack([np.cos(th), np.sin(th), 0 * th], 1)
    d.add(Segments(name="ecliptic", points=np.stack([1.5 * ring[:-1], 1.5 * ring[1:]], 1), colors=ECLIPTIC_COLOR,
                   thickness=0.01))
    ps = run.plot_series
    d.plot = {k: ps[k] for k in ("obliquity (deg)", "obliquity, Peale (deg)")}
    return d


MAGNIFY = 5.0


@functools.lru_cache(maxsize=1)
def _check_run():
    return get("cassini").simulate({})


@register_check("E8.moon-cassini", "Moon: Cassini state obliquity, Peale's equation and the run vs 1.543°",
                "Cassini's laws; Peale 1969")
def e8_moon_cassini():
    r = _check_run()
    m = r.metrics
    obs = C.MOON_EQUATOR_INCLINATION_DEG
    err = abs(m["obliquity_mean_deg"] - obs)
    err_p = abs(m["obliquity_peale_deg"] - obs)
    return dict(euler=m["obliquity_peale_deg"], simulated=m["obliquity_mean_deg"], modern=obs, rel_error=err,
                tolerance=0.02, unit="deg", passed=bool(err <= 0.02 and err_p <= 0.02),
                note=(f"error and tolerance in degrees (both the run and Peale's equation must be within 0.02° of the "
                      f"observed {obs}°): run {m['obliquity_mean_deg']:.4f}° (mean over "
                      f"{m['node_cycles_averaged']:.0f} node cycles), Peale {m['obliquity_peale_deg']:.4f}° "
                      f"(run − Peale {3600 * (m['obliquity_mean_deg'] - m['obliquity_peale_deg']):+.1f}″). The axis "
                      f"stays within {m['out_of_plane_max_arcsec']:.0f}″ of the plane of the other two normals "
                      f"(Cassini's third law), on the far side of the ecliptic pole. What the rigid quadrupole Moon "
                      "leaves out: the fluid core (0.07% of C: +~5″), the degree-3 field (it tilts DE421's principal "
                      "axes by ~79″ from the mean-Earth pole), tides; the mean orbit leaves out the inclination's "
                      "oscillation (5.0–5.3°)"))


register(Scenario(
    series_units={"earth_[xyz]": "km"},
    name="cassini",
    real_params=("beta", "gamma", "inclination_deg", "node_period_yr", "sun_torque"),
    title="The Moon's Cassini state: three normals in one plane",
    section="Cassini's laws; Peale 1969 (beyond Euler, with §815)",
    group="ch. 16",
    summary=("The Moon's orbit is tilted 5.1° to the ecliptic, and its node slides backwards around the "
            "ecliptic once in 18.6 years. The Moon's spin axis follows: it stays 1.54° from the ecliptic "
            "pole, on the far side from the orbit's normal, and all three axes stay in one plane that turns "
            "with the node line (Cassini's laws, 1693). The Earth's pull on the Moon's bulge is what keeps "
            "it there: Peale's equation gives the angle from the Moon's moments, and the run shows it."),
    params=(
        Param("years", 74.4, 0.5, 200.0, "yr", "time span (4 node cycles of 18.6 yr ≈ 3 turns of the free "
              "precession about the state, 24 yr in the node's frame)", label="Time span"),
        # 2 days, 14 steps a month: the monthly torque is the fastest thing the kicks sample (the free
        # turn itself is exact). Over the default 74.4 years the mean obliquity differs from a run at
        # 0.5 d by 3e-5° (1 d: 7e-6°; the check's tolerance is 0.02°), the out-of-plane peak by 0.06 %,
        # for 0.13 CPU-s a run against 0.29 s at 1 d (tests/test_cassini.py)
        Param("step_days", 2.0, 0.01, 2.0, "day", "integrator step", label="Integrator step", advanced=True),
        Param("beta", C.MOON_BETA_LLR, 1e-5, 0.01, "", "(C−A)/B (lunar laser ranging: 631.0 × 10⁻⁶)", label="β = (C − A)/B"),
        Param("gamma", C.MOON_GAMMA_LLR, 1e-6, 0.01, "", "(B−A)/C (lunar laser ranging: 227.7 × 10⁻⁶)", label="γ = (B − A)/C"),
        Param("inclination_deg", C.MOON_MEAN_INCLINATION_DEG, 0.5, 30.0, "deg", "orbit to ecliptic (5.145°)",
              label="Orbit to ecliptic"),
        Param("node_period_yr", C.NODE_PERIOD_SIDEREAL_DAYS / JULIAN_YEAR_DAYS, 2.0, 200.0, "yr",
              "regression period of the node against the stars (18.60 yr)", label="Node regression period"),
        Param("sun_torque", "on", kind="choice", choices=("on", "off"), help="the Sun's torque on the Moon's figure",
              label="The Sun's torque", choice_labels=("on", "off")),
        Param("start_offset_deg", 0.0, -3.0, 3.0, "deg", "start this far from Peale's obliquity (a free precession "
              "about the state)", label="Start away from Peale's obliquity"),
    ),
    camera=Camera((3.2, -3.4, 2.6), (0.0, 0.0, 0.5)),
    preview={"years": 19.0},
    simulate_fn=_cassini,
    cost_fn=_cost,
    draw=_draw,
    options={"magnify": Option(f"magnify the normals' angles ×{MAGNIFY:g}")},
    overlays={"axes": False, "vectors": False, "axis_trail": False, "polhode": False},
    euler_formula=("(|g| − K☉(C − A′)/(Cω) cos I) sin I = K⊕/(Cω) [(C − A) cos θ + (B − A)(1 − cos θ)/4] sin θ, "
                   "θ = i + I, K = 3GM⟨r⁻³⟩/2 (Peale 1969; from §815's torque averaged over the month)"),
    presets=(
        ("Moon: the Cassini state over four node cycles", {}),
        ("Moon: started 1° off, the axis circles the state", {"start_offset_deg": 1.0, "years": 80.0}),
        ("Moon: a node twice as slow", {"node_period_yr": 37.2, "years": 80.0}),
    ),
    metric_units={"opposite_side_fraction": "", "node_cycles_averaged": ""},
))
