"""Tidal despinning and capture into spin–orbit resonance (beyond Euler: why Mercury turns three
times in two orbits and the Moon shows one face).

Euler's §833 libration equation without his approximations, θ̈ = −(ω₀²/2)(a/r)³ sin 2(θ − f),
plus the tidal torque of a constant time lag, −c (a/r)⁶ (θ̇ − ḟ) (physics.tides: Mignard 1979,
Hut 1981). A body starts spinning fast; the tide slows it toward the pseudo-synchronous rate
q(e) > 1; on the way it meets the resonances θ̇ = p n (p = 2, 3/2, 1, …) and is either captured or
passes through — which, depends on its phase at the encounter. Goldreich & Peale (1966) give the
probability for this torque: P = 2/(1 + π(p − q)/(2ω₀√H(p, e))) (derived in physics.tides).

Check rows tides.capture-3:2 and tides.capture-1:1: the fraction of 400 starts (the initial angle
swept over half a turn, all else equal) that end in each resonance, against Goldreich & Peale,
with the binomial error of 400 draws as the tolerance.
"""
from __future__ import annotations

import math

import numpy as np

from ..physics import tides
from ..physics.orbits import KeplerOrbit
from ..physics.params import Param
from ..physics.spin_orbit_batch import planar_batch
from ..physics.trajectory import Trajectory
from .budget import Cost, trajectory_bytes
from .base import Batch, Comparison, Run, Scenario, get, register
from .checks import register_check
from .drawing import Camera
from ._libration import planar_moments

MAX_SAMPLES = 6000  # orbit-mean spin rates kept for the plot
FINAL_ORBITS = 50  # the final spin is the mean over the last this many orbits
CAPTURE_TOL = 0.01  # |final spin − p| below this (in n): captured into p
RESONANCES = (3.0, 2.5, 2.0, 1.5, 1.0, 0.5)  # first-order spin–orbit resonances θ̇ = p n
SCHEME = "blanes-moan4"


def _stride_orbits(orbits):
    return max(1, int(np.ceil(orbits / MAX_SAMPLES)))


def _integrate(values_list):
    """All the runs of `values_list` (same eccentricity, orbits and steps per orbit) in one batch:
    per run the periapse angle θ every `k` orbits (k = _stride_orbits), unwrapped."""
    v0 = values_list[0]
    e, spo, orbits = v0["eccentricity"], int(v0["steps_per_orbit"]), int(round(v0["orbits"]))
    k = _stride_orbits(orbits)
    orb = KeplerOrbit(a=1.0, e=e, n=1.0)
    th0 = np.radians([v["initial_angle_deg"] for v in values_list])
    out = planar_batch(th0, [v["spin_rate"] for v in values_list], [0.5 * v["omega0"] ** 2 for v in values_list],
                       orb, 2 * np.pi / spo, orbits * spo, scheme=SCHEME,
                       tide_rate=[v["tide_rate"] for v in values_list], stride=k * spo)
    return orb, k, th0, out


def _cost(values):
    """orbits × steps_per_orbit steps of the planar kernel; kept: a state every k orbits and the last,
    with the attractor's position and four series (the orbit-mean spin, shared with the trajectory's series,
    and the three lines of the plot)."""
    orbits = int(round(values["orbits"]))
    k = _stride_orbits(orbits)
    samples = 1 + orbits // k + (1 if orbits % k else 0)  # and the last state, after the last whole stride
    return Cost(float(orbits * int(values["steps_per_orbit"])), samples,
                trajectory_bytes(samples, bodies=1, series=4))


def _classify(values, theta, theta0, k):
    """Metrics of one run from its periapse angles every k orbits."""
    e, w0 = values["eccentricity"], values["omega0"]
    th = np.concatenate([[theta0], theta])
    rate = np.diff(th) / (2 * np.pi * k)  # mean spin over each k orbits, in units of n
    last = max(1, min(len(theta) // 2, int(np.ceil(FINAL_ORBITS / k))))  # the last 50 orbits (half a short run)
    final = float((th[-1] - th[-1 - last]) / (2 * np.pi * k * last))
    q = float(tides.pseudo_synchronous_rate(e))
    captured = next((p for p in RESONANCES if abs(final - p) < CAPTURE_TOL), 0.0)
    # Goldreich & Peale along the way to q: each resonance between the start and q is met in turn
    # (from above for a body despinning, from below for one spun up), and a body reaches p only if
    # it was not held by one met before it
    start = values["spin_rate"]
    down = start > q
    p_reach, gp = 1.0, {}
    for p in sorted((p for p in RESONANCES if (p < start if down else p > start)), reverse=down):
        P = tides.capture_probability(p, e, w0, q, from_above=down)
        gp[p] = p_reach * P
        p_reach *= 1.0 - P
    # decided: held in a resonance, or settled at q, or already past p (passed through); a spin on
    # its way to p is undecided for p (NaN: a sweep's mean over starts leaves it out)
    # held anywhere (also in a higher-order resonance such as 5:4): over the last two windows the
    # spin changed by less than a fifth of what the tide alone would have changed it
    before = (th[-1 - last] - th[-1 - 2 * last]) / (2 * np.pi * k * last) if len(th) > 2 * last else np.nan
    expected = values["tide_rate"] * float(tides.hut_omega(e)) * abs(final - q) * 2 * np.pi * k * last
    held = bool(np.isfinite(before) and abs(final - before) < 0.2 * expected)
    settled = captured != 0.0 or abs(final - q) < 0.02 or held

    def outcome(p):
        if captured == p:
            return 1.0
        if settled or (final < p - CAPTURE_TOL if down else final > p + CAPTURE_TOL):  # passed through it
            return 0.0
        return float("nan")

    m = {
        "final_spin_rate_n": final,
        "captured_resonance": float(captured),
        "captured_3_2": outcome(1.5),
        "captured_1_1": outcome(1.0),
        "pseudo_synchronous_rate_n": q,
        "gp_capture_probability_3_2": gp.get(1.5, 0.0),
        "gp_capture_probability_1_1": gp.get(1.0, 0.0),
    }
    return m, rate


def _higher_order(final, q, max_denominator: int = 8):
    """(a, b) when the final mean spin sits on a resonance θ̇ = (a/b) n of higher order (5:4, 7:4,
    …) far closer than to q: held there, not settled at q (Mercury's orbit: 5:4 at 1.25 against
    q = 1.2558, the held runs' mean spin within 3e-4 of 1.25). None otherwise."""
    best = None
    for b in range(1, max_denominator + 1):
        a = int(round(final * b))
        if a <= 0 or math.gcd(a, b) != 1 or (2 * a) % b == 0:  # half-integers are first order
            continue
        d = abs(final - a / b)
        if d < min(2e-3, 0.15 * abs(final - q)) and (best is None or d < best[0]):
            best = (d, a, b)
    return None if best is None else best[1:]


def _warnings(values, m) -> list[str]:
    """What a run's metrics `m` cannot be read as (a single run's and a sweep's alike); adds the
    tides' strength against the 3:2 resonance to `m`."""
    e, w0, q = values["eccentricity"], values["omega0"], m["pseudo_synchronous_rate_n"]
    final, cap = m["final_spin_rate_n"], m["captured_resonance"]
    warnings = []
    if cap == 0.0 and abs(final - q) > 0.02:
        warnings.append(f"the run ended with the spin still changing or held elsewhere (θ̇/n = {final:.4f}, not a "
                        f"first-order resonance, and the tidal end state is {q:.4f}): run more orbits, or it sits in a "
                        "higher-order resonance that Goldreich & Peale's first-order theory leaves out")
    # Goldreich & Peale's result is the limit of weak tides: the energy lost along the separatrix must be small
    # against the separatrix's own energy
    for p in (1.5,):
        H = abs(tides.resonance_strength(p, e))
        A = values["tide_rate"] * float(tides.hut_omega(e))
        depth = 0.5 * w0**2 * H  # 0 for a round body (ω₀² underflows below 1e-154): no resonance to hold it
        ratio = A * (np.pi * abs(p - q) + 2 * w0 * np.sqrt(H)) / depth if depth > 0 else np.inf
        m[f"tide_to_resonance_ratio_{p:g}"] = float(ratio)
        if ratio > 0.1 and depth > 0:  # no resonance at all (e = 0, a round body): nothing to be strong against
            warnings.append(f"tides strong against the {p:g} resonance (energy lost per libration {ratio:.2f} × its "
                            "depth): Goldreich & Peale's probability is the weak-tide limit")
    return warnings


def _simulate(values, progress=None):
    orb, k, th0, out = _integrate([values])
    m, rate = _classify(values, out["theta_samples"][0], th0[0], k)
    w0 = values["omega0"]
    t = np.concatenate([[0.0], out["t"]])
    th = np.concatenate([th0, out["theta_samples"][0]])
    wd = np.concatenate([[values["spin_rate"]], out["thetadot_samples"][0]])
    orbits = int(round(values["orbits"]))
    rest = orbits - k * (len(t) - 1)  # the orbits after the last whole stride: the run ends where it was asked to
    if rest > 0:
        t = np.append(t, 2 * np.pi * orbits)
        th = np.append(th, out["theta"][0])
        wd = np.append(wd, out["thetadot"][0])
        rate = np.append(rate, (th[-1] - th[-2]) / (2 * np.pi * rest))
    I = planar_moments(w0**2 / 3.0)
    z = np.zeros_like(th)
    traj = Trajectory(t, np.stack([np.cos(th / 2), z, z, np.sin(th / 2)], 1), np.stack([z, z, I[2] * wd], 1), I,
                      time_unit="1/n·rad", bodies={"attractor": orb.position(t)}, moment_unit="C")
    q = m["pseudo_synchronous_rate_n"]
    final, cap = m["final_spin_rate_n"], m["captured_resonance"]
    warnings = _warnings(values, m)
    held_in = _higher_order(final, q) if cap == 0.0 else None
    what = {1.5: "captured into the 3:2 resonance (Mercury's state)", 1.0: "captured into synchronous rotation (the Moon's state)",
            0.0: f"not in a first-order resonance at the end (θ̇/n = {final:.4f})"}.get(cap, f"captured into θ̇/n = {cap:g}")
    if held_in is not None:
        what = (f"held in the {held_in[0]}:{held_in[1]} resonance (θ̇/n = {final:.4f}), a higher-order one that "
                f"Goldreich & Peale's first-order theory leaves out; the tidal end state q = {q:.4f} is not reached")
    comps = [Comparison("pseudo-synchronous spin N(e)/Ω(e) (Hut 1981)", None,
                        final if (cap == 0.0 and held_in is None) else None, q, "n",
                        "where the orbit-averaged tide vanishes"),
             Comparison("probability of capture into 3:2 (Goldreich & Peale 1966)", None, m["captured_3_2"],
                        m["gp_capture_probability_3_2"], "", "one run is captured (1) or not (0); a sweep over the "
                        "initial angle measures the probability (as the check of this result does)"),
             Comparison("probability of ending in 1:1", None, m["captured_1_1"], m["gp_capture_probability_1_1"], "",
                        "passes 3:2 (and 2:1 if above it), then captured if q lies inside the 1:1 zone"
                        if values["spin_rate"] > q else
                        "spun up from below toward q: captured on the way, or carried through 1:1 to q")]
    notes = [f"This run: {what}.",
             "The tidal rate c is exaggerated so that despinning takes thousands of orbits rather than millions of "
             "years; the capture probability does not depend on it as long as it is weak (see the warning).",
             "The plot: the spin averaged over each orbit (exact: the periapse-to-periapse turn / 2π), with the "
             "resonances and the pseudo-synchronous rate as lines."]
    n = len(t)
    mean_spin = np.concatenate([[values["spin_rate"]], rate])
    series = {"spin rate, mean over each orbit (n)": mean_spin,
              "3:2 resonance (n)": np.full(n, 1.5), "1:1 resonance (n)": np.full(n, 1.0),
              "pseudo-synchronous rate (n)": np.full(n, q)}
    traj.series.update({"spin_rate_orbit_mean_n": mean_spin})
    return Run("tidal-capture", values, traj, m, comps, notes, plot_series=series, warnings=warnings)


BATCH_METRICS = ("final_spin_rate_n", "captured_resonance", "captured_3_2", "captured_1_1",
                 "pseudo_synchronous_rate_n", "gp_capture_probability_3_2", "gp_capture_probability_1_1")


def _batch(values, swept):
    """All points sharing an orbit (eccentricity, orbits, steps per orbit) in one kernel call; each
    body's arithmetic is independent of the batch, so the metrics are those of single runs, bit for bit."""
    from ..app.sweep import ok_with_warnings

    n = len(next(iter(swept.values())))
    pts = [{**values, **{k: (v[i].item() if hasattr(v[i], "item") else v[i]) for k, v in swept.items()}} for i in range(n)]
    out = {k: np.full(n, np.nan) for k in BATCH_METRICS}
    groups: dict[tuple, list[int]] = {}
    for i, v in enumerate(pts):
        groups.setdefault((v["eccentricity"], v["orbits"], v["steps_per_orbit"]), []).append(i)
    messages = {}
    for idx in groups.values():
        _, k, th0, res = _integrate([pts[i] for i in idx])
        for j, i in enumerate(idx):
            m, _ = _classify(pts[i], res["theta_samples"][j], th0[j], k)
            for name in BATCH_METRICS:
                out[name][i] = m[name]
            warned = _warnings(pts[i], m)
            if warned:  # as a single run's: what its numbers cannot be read as
                messages[i] = ok_with_warnings(warned)
    out["_messages"] = messages
    return out


register(Scenario(
    series_units={"attractor_[xyz]": "a"},  # the orbit's semi-major axis
    name="tidal-capture",
    title="Tidal despinning and capture into resonance (Mercury's 3:2, the Moon's 1:1)",
    section="§833 (beyond Euler)",
    group="ch. 16",
    summary=("A body on an eccentric orbit starts spinning fast. Tides raised on it by the planet act as a "
            "brake (a constant time lag): the spin slows toward a rate a little faster than the orbit. On the "
            "way down it meets the spin–orbit resonances — the 3:2 where Mercury turns three times in two "
            "orbits, then the 1:1 where the Moon always shows one face. At each it is either captured, held "
            "for good by the pull on its long axis (Euler's §833 torque), or passes through: which, depends "
            "on the body's orientation when it arrives. Change the initial angle and watch the outcome flip; "
            "Goldreich & Peale (1966) give the odds."),
    params=(
        Param("eccentricity", 0.07, 0.0, 0.5, "", "orbital eccentricity e (Mercury 0.2056)", label="Orbital eccentricity"),
        Param("omega0", 0.1, 0.0, 1.0, "", "ω₀ = √(3(B−A)/C), the body's out-of-roundness (Mercury ≈ 0.019)",
              exclusive_min=True, label="Out-of-roundness ω₀ = √(3(B − A)/C)"),
        Param("tide_rate", 2e-5, 0.0, 1e-3, "n", "tidal rate c in θ̈ = −c (a/r)⁶ (θ̇ − ḟ) (exaggerated)",
              exclusive_min=True, label="Tidal rate c (exaggerated)"),
        Param("spin_rate", 1.8, 0.2, 4.0, "n", "initial spin θ̇/n at periapse", label="Starting spin θ̇"),
        Param("initial_angle_deg", 0.0, -180.0, 180.0, "deg", "initial angle of the long axis from the periapse line",
              label="Starting angle of the long axis from periapse"),
        Param("orbits", 50000.0, 10.0, 2e5, "", "orbits to simulate", label="Orbits to follow"),
        Param("steps_per_orbit", 48, 16, 512, "", "integrator steps per orbit (4th-order Blanes–Moan)", kind="int",
              label="Integrator steps per orbit", advanced=True),
    ),
    camera=Camera((0.8, -2.0, 5.2), (0.0, 0.0, 0.0)),
    simulate_fn=_simulate,
    cost_fn=_cost,
    euler_formula=("θ̈ = −(ω₀²/2) (a/r)³ sin 2(θ − f) − c (a/r)⁶ (θ̇ − ḟ)\n"
                   "capture into θ̇ = p n: P = 2 / (1 + π(p − q) / (2ω₀√H(p, e)))  (Goldreich & Peale 1966)"),
    presets=(
        ("Tides: through 3:2, then synchronous (the Moon's way)", {"initial_angle_deg": 0.0}),
        ("Tides: captured into 3:2 on the way down (Mercury's way)", {"initial_angle_deg": 15.0}),
        ("Mercury-like orbit (e = 0.2056): never synchronous", {"eccentricity": 0.2056, "spin_rate": 1.7}),
    ),
    preview={"orbits": 2000.0},
    batch=Batch(_batch, sweepable=("eccentricity", "omega0", "tide_rate", "spin_rate", "initial_angle_deg", "orbits",
                                   "steps_per_orbit"), metrics=BATCH_METRICS, chunk=256),
    metric_units={"captured_resonance": "n", r"captured_\d+_\d+": "", r"gp_capture_probability_\d+_\d+": "",
                  r"tide_to_resonance_ratio_[\d.]+": ""},
))


N_PHASES = 400  # starts in the check's sweep over the initial angle


def _capture_sweep():
    sc = get("tidal-capture")
    values = sc.defaults
    angles = np.linspace(0.0, 180.0, N_PHASES, endpoint=False)
    return values, sc.batch.fn(values, {"initial_angle_deg": angles})


_SWEEP_CACHE: dict = {}


def _row(p, metric, gp_metric):
    if "r" not in _SWEEP_CACHE:
        _SWEEP_CACHE["r"] = _capture_sweep()
    values, out = _SWEEP_CACHE["r"]
    assert np.all(np.isfinite(out[metric])), "every start must be decided: run more orbits"
    P_sim = float(np.mean(out[metric]))
    P_gp = float(out[gp_metric][0])
    sigma = float(np.sqrt(max(P_gp * (1 - P_gp), 1e-12) / N_PHASES))
    other = float(np.mean(out["captured_resonance"] == 0))
    return {"euler": None, "simulated": P_sim, "modern": P_gp, "rel_error": abs(P_sim - P_gp) / P_gp,
            "tolerance": 3 * sigma / P_gp, "unit": "",
            "note": (f"e = {values['eccentricity']}, ω₀ = {values['omega0']}, tide c = {values['tide_rate']:g}, "
                     f"start θ̇ = {values['spin_rate']} n; {N_PHASES} initial angles over half a turn; binomial σ = "
                     f"{sigma:.3f}, tolerance 3σ; {other:.1%} of the starts end outside the first-order resonances "
                     "(higher-order ones, absent from Goldreich & Peale's theory)")}


@register_check("tides.capture-3:2", "capture into the 3:2 spin–orbit resonance: Goldreich & Peale's probability",
                "§833 (beyond Euler)")
def capture_3_2():
    return _row(1.5, "captured_3_2", "gp_capture_probability_3_2")


@register_check("tides.capture-1:1", "ending in synchronous rotation after passing 3:2: (1 − P₃:₂) · P₁:₁",
                "§833 (beyond Euler)")
def capture_1_1():
    return _row(1.0, "captured_1_1", "gp_capture_probability_1_1")
