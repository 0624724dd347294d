"""Counts the integrator steps a run really takes, for tests of the cost estimates
(scenarios.budget): every integrator theoria uses is wrapped where it is called.

- the rigid-body splitting (physics.integrator._run): its `n_steps` per chunk;
- the lunar RK4 (physics.three_body.lunar_elements._rk4): its `nsteps` times the systems it advances;
- the spin–orbit ensemble (physics.libration._section_run): members × orbits × steps per orbit;
- scipy's Runge–Kutta methods (DOP853, RK45: `RungeKutta._step_impl`): one per accepted step;
- REBOUND (`Simulation.integrate`): the growth of `steps_done`.
"""
from __future__ import annotations

import contextlib

import numpy as np


@contextlib.contextmanager
def count_steps():
    """Yields a dict {integrator: steps} filled while the block runs."""
    import rebound
    from scipy.integrate._ivp.rk import RungeKutta

    from theoria.physics import integrator, libration
    from theoria.physics.three_body import lunar_elements

    from theoria.physics import spin_orbit_batch
    from theoria.scenarios import hyperion, tidal_capture

    counts = {"rigid": 0, "rk4": 0, "ensemble": 0, "scipy": 0, "rebound": 0, "planar": 0}
    saved = [(integrator, "_run", integrator._run), (lunar_elements, "_rk4", lunar_elements._rk4),
             (libration, "_section_run", libration._section_run), (RungeKutta, "_step_impl", RungeKutta._step_impl),
             (rebound.Simulation, "integrate", rebound.Simulation.integrate)]
    # the planar batch, wherever a module took its name
    batch_owners = [m for m in (spin_orbit_batch, hyperion, tidal_capture) if hasattr(m, "planar_batch")]
    saved += [(m, "planar_batch", m.planar_batch) for m in batch_owners]
    run, rk4, section, step_impl, reb = (s[2] for s in saved[:5])
    planar = spin_orbit_batch.planar_batch

    def planar_(theta0, thetadot0, strength, orbit, h, n_steps, *a, **kw):
        counts["planar"] += int(np.atleast_1d(theta0).shape[0]) * int(n_steps)
        return planar(theta0, thetadot0, strength, orbit, h, n_steps, *a, **kw)


    def run_(L, q, I, h, n, *a):
        counts["rigid"] += int(n)
        return run(L, q, I, h, n, *a)

    def rk4_(which, y0, i0, h, nsteps, *a):
        counts["rk4"] += int(nsteps) * len(which)  # the systems advanced side by side
        return rk4(which, y0, i0, h, nsteps, *a)

    def section_(theta, thetadot, k, s2f, c2f, h, n_orbits, *a):
        counts["ensemble"] += int(theta.shape[0]) * int(n_orbits) * int(s2f.shape[0])
        return section(theta, thetadot, k, s2f, c2f, h, n_orbits, *a)

    def step_impl_(self):
        counts["scipy"] += 1
        return step_impl(self)

    def reb_(self, *a, **kw):
        before = self.steps_done
        try:
            return reb(self, *a, **kw)
        finally:
            counts["rebound"] += int(self.steps_done - before)

    integrator._run, lunar_elements._rk4, libration._section_run = run_, rk4_, section_
    RungeKutta._step_impl, rebound.Simulation.integrate = step_impl_, reb_
    for m in batch_owners:
        m.planar_batch = planar_
    try:
        yield counts
    finally:
        for owner, name, value in saved:
            setattr(owner, name, value)
