"""The islands' periodic orbits against an independent solve (scipy, no theoria kernel): the
symmetric period-one orbit of the p resonance starts at periapse on its symmetry line θ_c (0 or
π/2) and reaches the line again at apoapse after exactly p half-turns: θ(π) = θ_c + pπ, one
equation in θ̇(0) (Kepler's f integrated alongside)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from theoria.physics import libration as lib


def _flow(th0, wd0, e, w0, T, var=False):
    q = 1 - e * e

    def rhs(t, y):
        ar = (1 + e * np.cos(y[2])) / q
        out = [y[1], -0.5 * w0**2 * ar**3 * np.sin(2 * (y[0] - y[2])), (1 + e * np.cos(y[2]))**2 / q**1.5]
        if var:
            k = -w0**2 * ar**3 * np.cos(2 * (y[0] - y[2]))
            out += [y[5], y[6], k * y[3], k * y[4]]
        return out
    y0 = [th0, wd0, 0.0] + ([1.0, 0.0, 0.0, 1.0] if var else [])
    return solve_ivp(rhs, (0, T), y0, method="DOP853", rtol=1e-11, atol=1e-12).y[:, -1]


@pytest.mark.parametrize("e, w0", [(0.5, 1.5), (0.1, 1.0), (0.3, 1.25)])
@pytest.mark.parametrize("p", [0.5, 1.0, 1.5, 2.0])
def test_island_is_the_p_resonance_orbit(p, e, w0):
    th, wd, tr = lib.continue_resonance(p, e, w0)
    th_c = abs(lib.resonance_centre_angle(p, e))
    assert abs(np.remainder(th - th_c + np.pi / 2, np.pi) - np.pi / 2) < 1e-8
    g = lambda w: _flow(th_c, w, e, w0, np.pi)[0] - th_c - p * np.pi  # noqa: E731
    root = brentq(g, wd - 0.01, wd + 0.01, xtol=1e-13)  # raises if no orbit of winding 2p is there
    assert abs(wd - root) < 1e-6
    y = _flow(th_c, root, e, w0, 2 * np.pi, var=True)
    assert abs(y[0] - th_c - 2 * np.pi * p) < 1e-8 and abs(y[1] - root) < 1e-8  # closes after one orbit
    assert abs(tr - (y[3] + y[6])) < 1e-5 * max(1.0, abs(tr))  # the monodromy's trace


def test_hyperion_reports_every_island_at_the_corner_of_its_range():
    """At the largest eccentricity and out-of-roundness the scene offers, the four islands'
    orbits exist (the solve above) and are all unstable: the run says so for each, where it gave NaN
    for three of them (Newton followed a winding of the wrong resonance, then lost it)."""
    import theoria

    spec = theoria.scenario("hyperion")
    e, w0 = spec.param("eccentricity").maximum, spec.param("omega0").maximum
    run = spec.simulate(eccentricity=e, omega0=w0, islands="on", n_starts=4, n_orbits=20)
    for p in (0.5, 1, 1.5, 2):
        assert np.isfinite(run.metrics[f"island_rate_{p:g}"]) and abs(run.metrics[f"island_trace_{p:g}"]) > 2
    note = next(n for n in run.notes if "Periodic orbits" in n)
    assert note.count("unstable (no island)") == 4, note
