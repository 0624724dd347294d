"""Tidal despinning and capture into spin–orbit resonance (beyond Euler).

Torque (constant time lag, planar, zero obliquity). A body of mass m, radius R, Love number k₂
and moment C about its spin axis, raised into a tide by a mass M at distance r, with the tide
lagging by a fixed time Δt, feels about its spin axis (Mignard 1979, Moon & Planets 20, 301,
eq. 13 for zero obliquity; Hut 1981, A&A 99, 126, eq. 9 before averaging; the "viscous" model of
Goldreich & Peale 1966, AJ 71, 425, and Correia & Laskar 2004, Nature 429, 848):

    C θ̈ = −3 k₂ G M² R⁵ Δt / r⁶ · (θ̇ − ḟ),

(the tidal bulge leads or lags by 2(θ̇ − ḟ)Δt; the torque is the bulge's quadrupole k₂R⁵GM/r³
times its misalignment, times GM/r³). With C = αmR² and GM = n²a³ (m ≪ M):

    θ̈ = −c (a/r)⁶ (θ̇ − ḟ),   c = 3 k₂ (nΔt) n (M/m) (R/a)³ / α.

Averaged over one orbit at a fixed spin θ̇ (f the true anomaly, M the mean anomaly):

    ⟨θ̈⟩ = −c [Ω(e) θ̇ − N(e) n],
    Ω(e) = ⟨(a/r)⁶⟩ = (1 + 3e² + 3e⁴/8)/(1 − e²)^{9/2},
    N(e) = ⟨(a/r)⁶ ḟ⟩/n = (1 + 15e²/2 + 45e⁴/8 + 5e⁶/16)/(1 − e²)⁶,

(Hut 1981, eq. 11, his f₂ and f₅; derived by writing dM = (1 − e²)^{3/2}/(1 + e cos f)² df and
integrating powers of cos f). The torque vanishes at the pseudo-synchronous rate q = N/Ω
(1.257 n for Mercury's e = 0.2056), above the 1:1.

Capture (Goldreich & Peale 1966, §III; rederived here for this torque). Near the resonance
θ̇ = p n put γ = θ − pM; averaging the gravitational torque −(ω₀²/2)(a/r)³ sin 2(θ − f) over the
orbit leaves −(ω₀²/2) H(p, e) sin 2γ (H the Goldreich–Peale coefficient, `resonance_strength`),
and the tide −A(γ̇ + p − q), A = cΩ(e) (time unit 1/n). The pendulum energy E = γ̇²/2 −
(ω₀²H/4) cos 2γ changes by dE/dt = −A(p − q)γ̇ − Aγ̇². Along the separatrix γ̇ = ±ω₀√H cos γ
(γ from −π/2 to π/2 and back) the losses are

    δ₊ = A[π(p − q) + 2ω₀√H]  on the upper branch (γ̇ > 0),
    δ₋ = A[−π(p − q) + 2ω₀√H] on the lower one.

A body coming from above crosses the separatrix during an upper passage with its energy below
it by an amount uniformly spread over (0, δ₊) (the phase at the encounter is random); it stays
if the lower passage cannot lift it back, i.e. with probability

    P(p) = (δ₊ + δ₋)/δ₊ = 2 / (1 + π(p − q)/(2ω₀√H)),

1 when δ₋ ≥ 0 (q within 2ω₀√H/π of p: certain capture) and 0 when δ₊ ≤ 0 (the tide stops the
spin above the resonance: it is never reached). A body spun up from below (q above p: a slow
rotator on an eccentric orbit) crosses during a lower passage, by an amount spread over (0, δ₋),
and stays if the upper passage cannot lift it back: the same argument with the branches
exchanged, P(p) = (δ₋ + δ₊)/δ₋ = 2 / (1 + π(q − p)/(2ω₀√H)); it is 0 when δ₋ ≤ 0 (q below p).
The tidal strength A cancels: the result holds in the limit of weak tides (δ₊ ≪ the separatrix's
energy ω₀²H/2). Mercury, with (B − A)/C ≈ 1.2e-4:
P(3/2) ≈ 0.07 (Goldreich & Peale's 7 %; Correia & Laskar 2004).
"""
from __future__ import annotations

import numpy as np



def hut_omega(e):
    """Ω(e) = ⟨(a/r)⁶⟩ over the mean anomaly (Hut 1981, f₅(e)/(1 − e²)^{9/2})."""
    e2 = np.asarray(e, float) ** 2
    return (1 + 3 * e2 + 3 * e2**2 / 8) / (1 - e2) ** 4.5


def hut_N(e):
    """N(e) = ⟨(a/r)⁶ ḟ⟩/n (Hut 1981, f₂(e)/(1 − e²)⁶)."""
    e2 = np.asarray(e, float) ** 2
    return (1 + 15 * e2 / 2 + 45 * e2**2 / 8 + 5 * e2**3 / 16) / (1 - e2) ** 6


def pseudo_synchronous_rate(e):
    """q = N(e)/Ω(e), the spin (in units of n) at which the orbit-averaged tidal torque vanishes."""
    return hut_N(e) / hut_omega(e)


def resonance_strength(p, e):
    """Goldreich & Peale's H(p, e) = ⟨(a/r)³ cos(2f − 2pM)⟩ over the mean anomaly, exact (the
    Hansen coefficient X^{−3,2}_{2p}(e) by quadrature: `physics.hansen.hansen_H`)."""
    from .hansen import hansen_H

    return float(hansen_H(p, e))


def capture_probability(p, e, omega0, q=None, from_above: bool = True):
    """Goldreich & Peale's (1966) probability that a body despinning from above (or, with
    `from_above=False`, spun up from below) is captured into the resonance θ̇ = p n, for the
    constant-time-lag torque (module docstring): 2/(1 + π|p − q|/(2ω₀√|H|)), clipped to 1 (certain
    capture) and 0 (never reached: q on the side the body comes from). ω₀² = 3(B − A)/C."""
    if q is None:
        q = float(pseudo_synchronous_rate(e))
    H = abs(resonance_strength(p, e))
    w = omega0 * np.sqrt(H)
    up = np.pi * (p - q) + 2 * w  # δ₊/A: lost on the passage the body crosses in
    down = -np.pi * (p - q) + 2 * w  # δ₋/A: lost on the passage that may lift it back out
    if not from_above:
        up, down = down, up
    if up <= 0:
        return 0.0
    if down >= 0:
        return 1.0
    return float((up + down) / up)
