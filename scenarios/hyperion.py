"""Spin–orbit chaos: Hyperion (Wisdom, Peale & Mignard 1984, Icarus 58, 137).

Beyond Euler: his Problem 94 equation (§833) without the small-ζ and small-e approximations,
    θ̈ = −(ω₀²/2)(a/r)³ sin 2(θ − f),   ω₀² = 3(B − A)/C,  time in 1/n,
(θ the angle of the long axis, f the true anomaly; ζ = f − θ). Hyperion: e = 0.1, ω₀ ≈ 0.89
(WPM 1984). The surface of section plots θ mod π against θ̇/n at every periapse passage.
Resonance half-widths (Goldreich & Peale 1966) ω₀√|H(p,e)|, H exact by quadrature over one
orbit (`physics.hansen`; Goldreich & Peale's truncated series beside it): the 1:1 and 3:2 zones
overlap for Hyperion, hence the large chaotic sea.
"""
from __future__ import annotations

import numpy as np
from ..physics import hansen
from ..physics import libration as lib
from ..physics import quaternion as quat
from ..physics.integrator import PointMass, integrate
from ..physics.kept import kept
from ..physics.orbits import KeplerOrbit
from ..physics.trajectory import Trajectory
from ..physics.params import SUPERSCRIPT, Param
from ..physics.spin_orbit_batch import planar_batch
from .drawing import Camera
from .base import Batch, Comparison, Run, Scenario, register
from .checks import register_check
from . import _validity
from .budget import Cost, trajectory_bytes
from ._libration import planar_moments, zeta_of
from .drawing import Label, Option, Points, Segments
from ._ch16_drawing import (ORBIT_OPTION, PANEL_COLOR, ZETA_OPTION, Panel, body_scene, camera_basis, centre_of_force,
                            f_and_zeta, frame_with_panel)


def _series_off(series: float, exact: float) -> str:
    """How far the series' half-width is from the exact one, in words a class reads: "+1.2 %",
    "−0.0056 %" (it read "−0.01%" and "−0.00%")."""
    rel = series / exact - 1
    if abs(rel) < 1e-12:
        return "the same"
    return f"{100 * rel:+.2g} %".replace("-", "−")


RESONANCES = (0.5, 1.0, 1.5, 2.0, 2.5)


def ensemble_starts(n_starts, max_rate=3.0):
    """Starts at periapse: half at θ = 0, half at θ = π/2, θ̇/n evenly in (0, max_rate]."""
    k = max(1, n_starts // 2)
    w = np.linspace(max_rate / k, max_rate, k)
    th = np.concatenate([np.zeros(k), np.full(n_starts - k, 0.5 * np.pi)])
    wd = np.concatenate([w, np.linspace(max_rate / (n_starts - k), max_rate, n_starts - k)])
    return th, wd


def probe_lyapunov(theta_deg, rate, e, omega0, n_orbits, steps_per_orbit, progress=None):
    """Largest Lyapunov exponent (per unit time, n = 1) of starts at periapse (θ in degrees, θ̇/n),
    each with its own ω₀, on one orbit: the batched planar kernel (physics.spin_orbit_batch,
    Blanes & Moan's 4th-order scheme, the tangent map renormalised every orbit). A body's result
    does not depend on the rest of the batch: a sweep's map and a single run agree bit for bit."""
    orb = KeplerOrbit(a=1.0, e=e, n=1.0)
    w0 = np.asarray(omega0, float)
    out = planar_batch(np.radians(np.asarray(theta_deg, float)), rate, 0.5 * w0**2, orb, 2 * np.pi / steps_per_orbit,
                       int(n_orbits) * int(steps_per_orbit), scheme="blanes-moan4", lyapunov=True,
                       renorm=int(steps_per_orbit), progress=progress)
    return out["lyapunov"]


@kept(4)  # moving the drawn body's sliders (θ, θ̇/n, orbits drawn) reuses the section
def _ensemble_section(e, w0, n_starts, n_orbits, steps_per_orbit, progress=None):
    """The ensemble's surface of section: starts (θ, θ̇/n), then per start θ and θ̇/n at each
    periapse and the Lyapunov exponent (per unit time); read-only, as it is shared."""
    th0, wd0 = ensemble_starts(n_starts)
    T, W, lyap = lib.spin_orbit_section(th0, wd0, e, w0, n_orbits, steps_per_orbit=steps_per_orbit, lyapunov=True,
                                        progress=progress)
    out = tuple(np.asarray(a, float) for a in (th0, wd0, T, W, lyap))
    for a in out:
        a.flags.writeable = False
    return out


# steps per orbit of the drawn body (4th-order Yoshida; every periapse passage is a stored sample).
# Its start in the chaotic sea (θ̇/n = 1.4) loses an e-fold of accuracy per orbit at any step: at
# 256 it follows a run 32× finer to 0.01 rad for 12 orbits (128: 9, 512: 15, 900: 19, measured);
# over 20 orbits the synchronous start (θ̇/n = 1) stays within 3e-6 rad, θ̇/n = 2 within 0.013.
DRAWN_STEPS_PER_ORBIT = 256


def _hyperion(values, progress=None):
    e, w0 = values["eccentricity"], values["omega0"]
    ns, no = values["n_starts"], values["n_orbits"]
    part = (lambda a, b: None if progress is None else (lambda f: progress(a + (b - a) * f)))
    th0, wd0, T, W, lyap = _ensemble_section(e, w0, ns, no, values["steps_per_orbit"], progress=part(0.0, 0.6))
    # the probe start, as a full rigid body (the integrator of physics.integrator)
    gamma = w0**2 / 3.0
    I = planar_moments(gamma)
    orbit = KeplerOrbit(a=1.0, e=e, n=1.0)
    P = 2 * np.pi
    probe_orbits = values["probe_orbits"]
    n_steps = max(1, round(DRAWN_STEPS_PER_ORBIT * probe_orbits))
    t, L, q = integrate(I, [0, 0, values["probe_rate"]], probe_orbits * P, probe_orbits * P / n_steps,
                        q0=quat.from_axis_angle([0, 0, 1], values["probe_theta_deg"] * np.pi / 180),
                        masses=[PointMass(1.0, orbit.position)], scheme="yoshida4", progress=part(0.6, 0.8))
    pos = orbit.position(t)
    traj = Trajectory(t, q, L, I, time_unit="1/n·rad", bodies={"attractor": pos}, moment_unit="C")
    zeta = zeta_of(q, pos)
    lp = probe_lyapunov([values["probe_theta_deg"]], [values["probe_rate"]], e, [w0], max(no, 100),
                        values["steps_per_orbit"], progress=part(0.8, 0.9))
    m = {
        "lyapunov_probe_per_unit_time": float(lp[0]),
        "lyapunov_probe_per_orbit": float(lp[0] * P),
        "chaotic_fraction": float(np.mean(lyap * P > 0.05)),
        "lyapunov_max_per_orbit": float(np.max(lyap) * P),
    }
    for p in RESONANCES:
        m[f"gp_half_width_{p:g}"] = float(lib.resonance_half_width(p, e, w0))
        m[f"gp_series_half_width_{p:g}"] = float(w0 * np.sqrt(abs(hansen.goldreich_peale_series(p, e))))
    m["overlap_1_and_1.5"] = float((m["gp_half_width_1"] + m["gp_half_width_1.5"]) / 0.5)
    # the islands at these values: each resonance's periodic orbit followed from small ω₀
    islands = []
    for p in (RESONANCES[:4] if values["islands"] == "on" else ()):
        try:
            th_i, wd_i, tr = lib.continue_resonance(p, e, w0)
        except Exception as exc:  # noqa: BLE001 — a lost branch is reported as NaN, and in words
            th_i, wd_i, tr = np.nan, np.nan, np.nan
            islands.append(f"{p:g}: not followed to this ω₀ ({getattr(exc, 'allowed', exc)})")
        m[f"island_rate_{p:g}"] = float(wd_i)
        m[f"island_angle_{p:g}_rad"] = float(th_i)
        m[f"island_trace_{p:g}"] = float(tr)
        if np.isfinite(tr):
            islands.append(f"{p:g}: θ̇/n = {wd_i:.3f} at θ = {th_i:.2f} ({'stable island' if abs(tr) < 2 else 'unstable (no island)'})")
    # Euler's §833 first-order forced libration ζ = 2e/(1 − ω₀²)·sin M (fails here: ω₀ ~ 1, e = 0.1);
    # at ω₀ = 1 (his resonance A² = 2N) the formula has no value: the curve is left out, not NaN
    euler_applies = abs(1 - w0**2) > 1e-9
    series = {"zeta_rad": zeta}
    if euler_applies:
        series["zeta_euler_rad"] = 2 * e / (1 - w0**2) * np.sin(t)
    # the surface of section is a point cloud, not a time series: per start (n_starts, n_orbits)
    # arrays in extras, which the scene draws
    theta_mod_pi = np.remainder(T, np.pi)
    extras = {"section": {
        "theta_mod_pi": theta_mod_pi, "theta_dot": np.asarray(W, float),
        "lyapunov_per_orbit": np.asarray(lyap * P, float),
        "start_theta": np.asarray(th0, float), "start_theta_dot": np.asarray(wd0, float),
    }}
    traj.series.update({"zeta_rad": zeta})
    comps = [Comparison(f"resonance θ̇/n = {p:g}: half-width ω₀√|H(p,e)|", None, None,
                        m[f"gp_half_width_{p:g}"], "n",
                        f"H exact (quadrature over one orbit); Goldreich–Peale's series (1966, to "
                        f"e{str(hansen.GP_SERIES_NEXT_ORDER[p] - 2).translate(SUPERSCRIPT)}): {m[f'gp_series_half_width_{p:g}']:.5g}"
                        + (f", {_series_off(m[f'gp_series_half_width_{p:g}'], m[f'gp_half_width_{p:g}'])}"
                           if m[f"gp_half_width_{p:g}"] > 0 else ""))
             for p in RESONANCES]
    comps.append(Comparison("Lyapunov exponent of the probe start", None, m["lyapunov_probe_per_orbit"], None,
                            "1/orbit", "nearby starts in the chaotic sea separate by a factor e every 1/λ orbits"))
    notes = (["Periodic orbits followed from Goldreich & Peale's centres (small ω₀) to these values — " + "; ".join(islands)]
             if values["islands"] == "on" else [])
    notes.append("The surface of section is a point cloud, not a time series: extras['section'] holds "
                 "theta_mod_pi and theta_dot as (n_starts, n_orbits) arrays (one row per start, periapse "
                 "passages in order) and lyapunov_per_orbit (n_starts,); plot theta_dot against theta_mod_pi, "
                 "coloured by lyapunov_per_orbit. Draw the resonance zones θ̇/n = p ± gp_half_width_p.")
    if euler_applies:
        notes.append("Euler's linear forced libration (§833) is drawn as zeta_euler_rad: for Hyperion it fails "
                     "completely (ω₀ ≈ 1 is near his resonance A² = 2N, and ζ is not small).")
    else:
        notes.append("ω₀ = 1 is Euler's resonance A² = 2N: his forced libration 2e/(1 − ω₀²)·sin M is "
                     "infinite there, so no Euler curve is drawn.")
    return Run("hyperion", values, traj, m, comps, notes, plot_series=series, extras=extras,
               warnings=_warnings(values))


def _warnings(values) -> list[str]:
    """What a run with these values cannot be read as (a single run's and a sweep's alike): the
    step against the fastest period, the torque ∝ sin 2(θ − f) turning at 2|θ̇ − ḟ| (starts up to
    θ̇/n = 3, the probe's rate, f fastest at periapse), and the periapse passage itself."""
    e = values["eccentricity"]
    fdot_max, fdot_min = (1 + e) ** 2 / (1 - e * e) ** 1.5, (1 - e) ** 2 / (1 - e * e) ** 1.5
    hi, lo = max(3.0, values["probe_rate"]), min(0.0, values["probe_rate"])
    T_fast = min(np.pi / max(hi - fdot_min, fdot_max - lo), 2 * np.pi / fdot_max)
    return _validity.add([], _validity.coarse_step(2 * np.pi / values["steps_per_orbit"], T_fast,
                                                   "the torque on the spinning body, sin 2(θ − f)", "1/n",
                                                   "steps_per_orbit"))


CHAOTIC_PER_ORBIT = 0.05  # Lyapunov exponent per orbit above which a start counts as chaotic (chaotic_fraction)
RESONANCE_NAMES = {0.5: "1:2", 1.0: "1:1", 1.5: "3:2", 2.0: "2:1", 2.5: "5:2"}


def _draw(run, spec, view):
    """The probe body with F and ζ, and beside it the surface of section (θ mod π, θ̇/n at each
    periapse) of the ensemble, chaotic starts red and regular ones blue, with the Goldreich–Peale
    zones p ± half-width (the run's metrics gp_half_width_p) as green lines."""
    d, _ = body_scene(run, spec, view, bodies={"F": centre_of_force(run)})
    f_and_zeta(d, run, spec, view)
    if view.option("section", spec) and "section" in run.extras:
        frame_with_panel(d, _section(d, run))
    return d


def _section(d, run):
    sec = run.extras["section"]
    th = np.asarray(sec["theta_mod_pi"], float).ravel()  # start by start, periapse passages in order
    w = np.asarray(sec["theta_dot"], float).ravel()
    ly = np.repeat(np.asarray(sec["lyapunov_per_orbit"], float), np.shape(sec["theta_mod_pi"])[1])
    ok = np.isfinite(th) & np.isfinite(w)
    th, w, ly = th[ok], w[ok], ly[ok]
    widths = {float(k[len("gp_half_width_"):]): float(v) for k, v in run.metrics.items()
              if k.startswith("gp_half_width_") and np.isfinite(v)}
    y0 = min(float(np.min(w)) if len(w) else 0.0, 0.0)
    y1 = max(float(np.max(w)) if len(w) else 3.0, max((p + h for p, h in widths.items()), default=0.0))
    pad = 0.05 * (y1 - y0)
    right, up, look = camera_basis(d.camera)
    p = Panel(look - 4.5 * right + 0.1 * up, right, up, (0.0, np.pi), (y0 - pad, y1 + pad), size=3.2)
    col = np.where((ly > CHAOTIC_PER_ORBIT)[:, None], np.array([215, 60, 40]), np.array([40, 90, 200])).astype(np.uint8)
    d.add(Segments(name="section/frame", points=p.frame(), colors=PANEL_COLOR, thickness=0.01),
          Points(name="section/points", points=p.map(th, w), colors=col, size=0.028))
    lines, labels = [], []
    for q, h in sorted(widths.items()):
        lines += [p.hline(y) for y in (q - h, q + h) if y0 - pad <= y <= y1 + pad]
        if y0 - pad <= q <= y1 + pad:
            labels.append((q, h))
    if lines:  # a little toward the camera, so the zones are drawn over the points
        d.add(Segments(name="section/resonance_zones", points=np.concatenate(lines) + 0.03 * p.normal,
                       colors=(20, 150, 60), thickness=0.016))
    for q, h in labels:
        d.add(Label(name=f"section/res_{q:g}", text=f"{RESONANCE_NAMES.get(q, f'{q:g}')} ± {h:.2f}",
                    position=p.map(np.pi, q) + 0.25 * right))
    # title above and axes below, from the panel's left edge (a label starts at its point)
    d.add(Label(name="section/title", text="surface of section at periapse: red chaotic, blue regular, "
                "green Goldreich–Peale zones", position=p.map(0.0, y1 + 2.5 * pad)),
          Label(name="section/axes_label", text=f"across: θ mod π, 0 … π; up: θ̇/n, {y0:.1f} … {y1:.1f}",
                position=p.map(0.0, y0 - 2.5 * pad)))
    return p


BATCH_METRICS = ("lyapunov_probe_per_unit_time", "lyapunov_probe_per_orbit") + tuple(
    f"gp_half_width_{p:g}" for p in RESONANCES) + tuple(f"gp_series_half_width_{p:g}" for p in RESONANCES) + (
    "overlap_1_and_1.5",)


def _batch(values, swept):
    """A chaos map: the probe's Lyapunov exponent for every point, the points sharing an orbit
    (eccentricity, steps per orbit, passages) integrated together. The ensemble's surface of
    section and the islands of a single run are not recomputed per point (ask for those metrics
    and the sweep maps single runs)."""
    n = len(next(iter(swept.values())))
    pts = [{**values, **{k: (v[i].item() if hasattr(v[i], "item") else v[i]) for k, v in swept.items()}} for i in range(n)]
    out = {k: np.full(n, np.nan) for k in BATCH_METRICS}
    groups: dict[tuple, list[int]] = {}
    for i, v in enumerate(pts):
        groups.setdefault((v["eccentricity"], v["steps_per_orbit"], max(v["n_orbits"], 100)), []).append(i)
    for (e, spo, no), idx in groups.items():
        lp = probe_lyapunov([pts[i]["probe_theta_deg"] for i in idx], [pts[i]["probe_rate"] for i in idx], e,
                            [pts[i]["omega0"] for i in idx], no, spo)
        for j, i in enumerate(idx):
            out["lyapunov_probe_per_unit_time"][i] = float(lp[j])
            out["lyapunov_probe_per_orbit"][i] = float(lp[j] * 2 * np.pi)
    widths: dict[tuple, float] = {}  # the same numbers as a single run's, computed once per (p, e, ω₀)
    for i, v in enumerate(pts):
        e, w0 = v["eccentricity"], v["omega0"]
        for p in RESONANCES:
            key = (p, e, w0)
            if key not in widths:
                widths[key] = (float(lib.resonance_half_width(p, e, w0)),
                               float(w0 * np.sqrt(abs(hansen.goldreich_peale_series(p, e)))))
            out[f"gp_half_width_{p:g}"][i], out[f"gp_series_half_width_{p:g}"][i] = widths[key]
        out["overlap_1_and_1.5"][i] = (out["gp_half_width_1"][i] + out["gp_half_width_1.5"][i]) / 0.5
    from ..app.sweep import ok_with_warnings

    out["_messages"] = {i: ok_with_warnings(w) for i, w in ((i, _warnings(v)) for i, v in enumerate(pts)) if w}
    return out


# the periodic orbits followed from small ω₀: per resonance and per ω₀ step of 0.05, Newton on the
# one-orbit map at 128 steps per orbit (1 + 4 runs per iteration) and the map's trace; measured
# 2850 steps per resonance and ω₀ step on the defaults and presets
ISLAND_STEPS_PER_W0_STEP = 2900


def _cost(values):
    """The ensemble (n_starts × n_orbits × steps_per_orbit member-steps), the drawn probe and its
    Lyapunov run, the islands' continuation; kept: every step of the probe with F's position and
    ζ, the section (θ mod π and θ̇ per point, the starts and an exponent per start)."""
    ns, no, spo = values["n_starts"], values["n_orbits"], values["steps_per_orbit"]
    S = ns * no
    probe = max(1, round(DRAWN_STEPS_PER_ORBIT * values["probe_orbits"]))
    lyap = max(no, 100) * spo
    islands = len(RESONANCES[:4]) * (len(np.arange(0.05, values["omega0"], 0.05)) + 1) * ISLAND_STEPS_PER_W0_STEP \
        if values["islands"] == "on" else 0
    samples = probe + 1
    euler_curve = 1 if abs(1 - values["omega0"] ** 2) > 1e-9 else 0
    return Cost(float(S * spo + probe + lyap + islands), samples,
                trajectory_bytes(samples, bodies=1, series=1 + euler_curve, extra=2 * 8 * S + 3 * 8 * ns))


register(Scenario(
    series_units={"attractor_[xyz]": "a"},  # the orbit's semi-major axis
    name="hyperion",
    title="Hyperion: chaotic tumbling (spin–orbit surface of section)",
    section="§833 (beyond Euler)",
    group="ch. 16",
    summary=("Euler's libration equation with none of his approximations, for an elongated moon on an "
            "eccentric orbit (like Saturn's moon Hyperion). The plot is a surface of section: each of "
            "many starts is marked once per orbit, at periapse, by its angle and spin rate. Smooth "
            "curves and closed islands (the synchronous, 1:2, 3:2 and 2:1 spin–orbit resonances) are "
            "regular motion; the scattered sea of dots is chaos (Wisdom, Peale & Mignard 1984). The "
            "body drawn follows one start, the probe."),
    params=(
        Param("eccentricity", 0.1, 0.0, 0.5, "", "orbital eccentricity (Hyperion 0.1)", label="Orbital eccentricity"),
        Param("omega0", 0.89, 0.0, 1.5, "", "ω₀ = √(3(B−A)/C) (Hyperion ≈ 0.89, WPM 1984)", exclusive_min=True,
              label="Out-of-roundness ω₀ = √(3(B − A)/C)"),
        Param("n_starts", 60, 2, 400, "", "starts in the ensemble", kind="int",
              label="Starts in the section", advanced=True),
        Param("n_orbits", 300, 10, 3000, "", "periapse passages per start", kind="int",
              label="Orbits per start", advanced=True),
        Param("steps_per_orbit", 48, 16, 2048, "", "integrator steps per orbit (4th-order Blanes–Moan)", kind="int",
              label="Integrator steps per orbit", advanced=True),
        Param("probe_theta_deg", 0.0, -90.0, 90.0, "deg", "the drawn body: θ at periapse",
              label="Drawn body: angle θ at periapse"),
        Param("probe_rate", 1.4, -1.0, 4.0, "n", "the drawn body: θ̇/n at periapse",
              label="Drawn body: spin θ̇/n at periapse"),
        Param("probe_orbits", 20.0, 1.0, 200.0, "", "orbits drawn", label="Orbits drawn"),
        # the islands' periodic orbits, each followed from small ω₀ (two thirds of the quick
        # preview's CPU when e or ω₀ is new): the preview leaves them out, and so can a sweep
        Param("islands", "on", kind="choice", choices=("on", "off"),
              help="the resonances' periodic orbits (island centres and their stability), followed from small ω₀",
              label="Island centres (periodic orbits)", choice_labels=("on", "off"), advanced=True),
    ),
    camera=Camera((0.8, -2.0, 5.2), (0.0, 0.0, 0.0)),
    preview={'n_starts': 12, 'n_orbits': 60, 'islands': 'off'},
    simulate_fn=_hyperion,
    draw=_draw,
    options={**ZETA_OPTION, **ORBIT_OPTION, "section": Option("surface of section + resonance zones")},
    cost_fn=_cost,
    chaotic=True,
    euler_formula=("θ̈ = −(ω₀²/2) (a/r)³ sin 2(θ − f)\n"
                   "θ: the body's long axis, f: the moon's direction seen from the planet, r: its distance"),
    presets=(
        ("Hyperion: chaotic tumbling", {}),
        ("Nearly circular orbit: mostly regular", {"eccentricity": 0.01}),
        ("Hyperion: a probe in the synchronous island", {"probe_rate": 1.0}),
    ),
    batch=Batch(_batch, sweepable=("eccentricity", "omega0", "steps_per_orbit", "n_orbits", "probe_theta_deg",
                                   "probe_rate", "n_starts", "probe_orbits"), metrics=BATCH_METRICS, chunk=2048),
    # rates as multiples of the mean motion n (the time unit is 1/n)
    metric_units={"lyapunov_probe_per_unit_time": "n", "chaotic_fraction": "", r"gp_(series_)?half_width_[\d.]+": "n",
                  r"overlap_[\d.]+_and_[\d.]+": "", r"island_rate_[\d.]+": "n", r"island_trace_[\d.]+": ""},
))


def _mean_anomaly_average_H(p, e, n=1 << 18):
    """H(p, e) the slow way, for the check row: the average of (a/r)³ cos(2f − 2pM) over n equally
    spaced mean anomalies (midpoints), Kepler's equation solved by Newton at each."""
    M = (np.arange(n) + 0.5) * (2.0 * np.pi / n)
    E = np.where(M < np.pi, M + e, M - e)
    for _ in range(60):
        E -= (E - e * np.sin(E) - M) / (1.0 - e * np.cos(E))
    f = 2.0 * np.arctan2(np.sqrt(1.0 + e) * np.sin(0.5 * E), np.sqrt(1.0 - e) * np.cos(0.5 * E))
    return float(np.mean(np.cos(2.0 * f - 2.0 * p * M) / (1.0 - e * np.cos(E)) ** 3))


@register_check("E8.hyperion-widths", "spin–orbit resonance half-widths ω₀√|H(p,e)| at e = 0.5: quadrature vs "
                "the mean-anomaly average; Goldreich–Peale's series beside", "§833 (beyond Euler)")
def e8_hyperion_widths():
    e, w0 = 0.5, 0.89
    rows, worst = [], 0.0
    for p in RESONANCES:
        exact = float(lib.resonance_half_width(p, e, w0))
        brute = w0 * np.sqrt(abs(_mean_anomaly_average_H(p, e)))
        series = w0 * np.sqrt(abs(hansen.goldreich_peale_series(p, e)))
        worst = max(worst, abs(exact / brute - 1))
        rows.append(f"{p:g}: {exact:.5f} (series {series / exact - 1:+.1%})")
    p = 2.5
    exact = float(lib.resonance_half_width(p, e, w0))
    return dict(euler=float(w0 * np.sqrt(abs(hansen.goldreich_peale_series(p, e)))), simulated=exact,
                modern=float(w0 * np.sqrt(abs(_mean_anomaly_average_H(p, e)))), rel_error=worst, tolerance=1e-10,
                unit="n", note="row values for p = 5/2; Euler column: Goldreich–Peale's series (1966, Table I); "
                "simulated: H by the trapezoid rule in E (physics.hansen); modern: the plain average over 2¹⁸ mean "
                "anomalies (Kepler by Newton). rel_error: the largest over p = 1/2 … 5/2 of quadrature vs average; both "
                "converge geometrically, so they must agree to rounding (tolerance 1e-10; the issue asked 0.1 %). "
                "Half-widths (ω₀ = 0.89): " + "; ".join(rows))
