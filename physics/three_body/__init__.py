"""Euler's three papers on three bodies (seed 003, Bistafa's translations).

- `collinear`: 1767, *De motu rectilineo trium corporum* — the quintic, homothetic and rotating
  collinear motions, the collinear points L1, L2, L3 of the restricted problem.
- `syzygy`: 1766, *Considerationes de motu corporum coelestium* — the Moon kept in conjunction
  or opposition with the Sun, its oscillation about that line and the instability Euler missed.
- `lunar_elements`: 1768, *Methodus facilis* — the Moon's motion as equations for its orbital
  elements, integrated numerically.
- `nbody`: small direct integrators used as the independent reference.
"""
