"""Many planar spin–orbit bodies advanced together on one shared orbit (sweeps, maps, Monte Carlo).

The equation is Euler's §825/§833 libration equation without his approximations, plus an
optional tidal torque (constant time lag, `physics.tides`):

    θ̈ = −k (a/r)³ sin 2(θ − f) − c (a/r)⁶ (θ̇ − ḟ),

θ the angle of the body's A (long) axis in the orbital plane, f the true anomaly of the centre
of force F, r its distance, k = (3/2)(GM/a³)(B − A)/C (= ω₀²n²/2) and c the tidal rate
constant. Every body has its own k and c; the orbit (f, r, ḟ at every kick time) is tabulated
once and shared by the whole batch — that is what makes the batch cheap.

Scheme: a symmetric kick–drift composition (Yoshida's triple jump by default, the same
coefficients and kick times as the rigid-body integrator of `physics.integrator`, so a batch
reproduces a single 3-D run of the libration scenarios to round-off). A kick is the exact flow
of θ̈ with θ and t frozen: with tides the velocity relaxes exponentially,
w ← w + (F − c(a/r)⁶(w − ḟ))·Δ·φ(x), φ(x) = (1 − e^{−x})/x, x = c(a/r)⁶Δ, so the composition
keeps its order with the dissipation in it. The last kick of a step and the first of the next act
at the same time on the same θ and are merged.

Speed: the bodies are processed in blocks of `BLOCK` held in local arrays, the block's loop
innermost so that the compiler vectorises it (AVX2: 4 bodies per instruction), blocks in
parallel over the cores (numba `prange`). sin 2(θ − f) is a branch-free polynomial (fdlibm's
minimax kernels on [−π/4, π/4] after a Cody–Waite reduction by π/2, error below 1 ulp of the
result's scale), and θ is kept reduced modulo π (with the count of half turns beside it) so the
phase keeps full precision over millions of turns. A body's arithmetic never depends on the
other bodies of the batch: a batch of one and a batch of a thousand give bit-identical results
(a batch is padded to whole blocks; a single body without the Lyapunov exponent runs as a block of
one, which takes 0.38 s of CPU where a padded block of sixteen took 0.67 s for tidal-capture's run,
with the same bits: tests/test_spin_orbit_batch.py, also with the kernel loaded from numba's
cache). The compiled loop releases the GIL, so a Dask worker stays responsive (heartbeats)
through a long chunk.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from .errors import ParameterError

# bodies per vector block of a batch (the block's length is an argument of the compiled loop; at 16
# it is vectorised: a 160-body batch takes the same CPU as when the length was a constant, 0.137
# against 0.140 s with tides)
BLOCK = 16

# fdlibm's __kernel_sin / __kernel_cos minimax coefficients on [−π/4, π/4] (Sun Microsystems,
# freely redistributable): |error| < 2⁻⁵⁸ relative
_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11
# π/2 in two parts (fdlibm pio2_1, pio2_1t): k·PIO2_HI is exact for |k| < 2²⁰
_PIO2_HI = 1.57079632673412561417e+00
_PIO2_LO = 6.07710050650619224932e-11
_INV_PIO2 = 6.36619772367581382433e-01
# π in two parts for keeping θ reduced: n·PI_HI exact for |n| < 2²⁰
_PI_HI = 2.0 * _PIO2_HI
_PI_LO = 2.0 * _PIO2_LO

# kick / drift coefficients of the symmetric compositions (last drift 0); the same numbers as
# physics.integrator.SCHEMES and physics.libration.SCHEMES
_W1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
_W0 = -(2.0 ** (1.0 / 3.0)) * _W1
_BM_B = (0.0829844064174052, 0.396309801498368, -0.0390563049223486)
_BM_A = (0.245298957184271, 0.604872665711080)
SCHEMES = {
    "strang": (np.array([0.5, 0.5]), np.array([1.0, 0.0])),
    # Yoshida (1990) triple jump of leapfrog: order 4, 3 force evaluations per step (merged)
    "yoshida4": (np.array([_W1 / 2, (_W1 + _W0) / 2, (_W0 + _W1) / 2, _W1 / 2]), np.array([_W1, _W0, _W1, 0.0])),
    # Blanes & Moan (2002) SRKN_6^b: order 4, 6 evaluations per step, error constant ~100× smaller
    "blanes-moan4": (np.array([_BM_B[0], _BM_B[1], _BM_B[2], 1 - 2 * sum(_BM_B), _BM_B[2], _BM_B[1], _BM_B[0]]),
                     np.array([_BM_A[0], _BM_A[1], 0.5 - sum(_BM_A), 0.5 - sum(_BM_A), _BM_A[1], _BM_A[0], 0.0])),
}


def kick_times(scheme: str) -> np.ndarray:
    """Times of the kicks within a step, in units of the step (0 … 1)."""
    _, dk = SCHEMES[scheme]
    return np.concatenate([[0.0], np.cumsum(dk)[:-1]])


@nb.njit(inline="always", fastmath=True)
def _sincos(y):
    """sin y, cos y for |y| ≲ 10⁵ without branches: y = kπ/2 + r, |r| ≤ π/4, polynomials for
    sin r and cos r, then the quadrant k mod 4 picks and signs them."""
    k = np.floor(y * _INV_PIO2 + 0.5)
    r = (y - k * _PIO2_HI) - k * _PIO2_LO
    z = r * r
    s = r + r * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
    c = 1.0 - 0.5 * z + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
    q = k - 4.0 * np.floor(0.25 * k)  # 0, 1, 2, 3
    odd = q - 2.0 * np.floor(0.5 * q)  # 0 or 1
    sgn = 1.0 - 2.0 * np.floor(0.5 * q)  # +1 for q = 0, 1; −1 for q = 2, 3
    sn = s if odd == 0.0 else c
    cs = c if odd == 0.0 else -s
    return sgn * sn, sgn * cs


@nb.njit(inline="always", fastmath=True)
def _stage(tw, wv, kb, tf, g, dl, d):
    """Kick by dl (θ frozen) then drift by d, for one block: the conservative case."""
    for i in range(tw.shape[0]):
        sn, cs = _sincos(2.0 * tw[i] - tf)
        wv[i] -= dl * kb[i] * g * sn
        tw[i] += d * wv[i]


@nb.njit(inline="always", fastmath=True)
def _stage_lyap(tw, wv, a, bb, kb, tf, g, dl, d):
    """The same with the tangent map (δθ, δθ̇) carried along."""
    for i in range(tw.shape[0]):
        sn, cs = _sincos(2.0 * tw[i] - tf)
        bb[i] -= 2.0 * dl * kb[i] * g * cs * a[i]
        a[i] += d * bb[i]
        wv[i] -= dl * kb[i] * g * sn
        tw[i] += d * wv[i]


@nb.njit(inline="always", fastmath=True)
def _stage_tide(tw, wv, a, bb, kb, cb, tf, g, g6, fd, dl, d, lyap_on):
    """With the tidal torque: the kick is the exact exponential relaxation of θ̇ toward ḟ at
    frozen θ and t, w ← w + (F − c(a/r)⁶(w − ḟ))·Δ·φ(x), φ(x) = (1 − e^{−x})/x by its series
    (x ≤ 0.01: six terms are exact to round-off)."""
    for i in range(tw.shape[0]):
        sn, cs = _sincos(2.0 * tw[i] - tf)
        x = cb[i] * g6 * dl
        phi = 1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 - x * (1.0 / 720.0)))))
        acc = -kb[i] * g * sn - cb[i] * g6 * (wv[i] - fd)
        if lyap_on:
            bb[i] += dl * phi * (-2.0 * kb[i] * g * cs * a[i] - cb[i] * g6 * bb[i])
            a[i] += d * bb[i]
        wv[i] += acc * dl * phi
        tw[i] += d * wv[i]



@nb.njit(parallel=True, fastmath=True, cache=True, nogil=True)
def _kernel(th_w, nwrap, w, kstr, ctide, two_f, r3, r6, fdot, m, s0, ck, dk, h, n_steps, k0, stride,
            out_th, out_w, lyap_on, tide_on, dth, dw, lsum, renorm, block):
    """Advance every body n_steps steps (global step numbers k0 … k0 + n_steps − 1).

    th_w ∈ [−π/2, π/2) with nwrap half turns beside it (θ = th_w + nwrap·π), w = θ̇. Table row
    (s0 + k) mod m holds the orbit at step k's kick times. Records (after the step's last kick):
    every `stride` global steps into out_th/out_w[:, row]. Lyapunov (tangent map δθ, δθ̇): its
    norm is logged into lsum and reset to 1 every `renorm` global steps."""
    N = th_w.shape[0]
    K = ck.shape[0]
    nblk = N // block
    for b in nb.prange(nblk):
        lo = b * block
        tw = np.empty(block)
        nw = np.empty(block)
        wv = np.empty(block)
        kb = np.empty(block)
        cb = np.empty(block)
        a = np.empty(block)
        bb = np.empty(block)
        ls = np.empty(block)
        for i in range(block):
            tw[i] = th_w[lo + i]
            nw[i] = nwrap[lo + i]
            wv[i] = w[lo + i]
            kb[i] = kstr[lo + i]
            cb[i] = ctide[lo + i]
            a[i] = dth[lo + i]
            bb[i] = dw[lo + i]
            ls[i] = lsum[lo + i]
        s = s0
        for k in range(n_steps):
            for j in range(K - 1):
                c = ck[j]
                if j == 0 and k > 0:
                    c += ck[K - 1]  # the previous step's last kick, same time, same θ
                dl = c * h
                tf = two_f[s, j]
                g = r3[s, j]
                d = dk[j] * h
                if tide_on:
                    _stage_tide(tw, wv, a, bb, kb, cb, tf, g, r6[s, j], fdot[s, j], dl, d, lyap_on)
                elif lyap_on:
                    _stage_lyap(tw, wv, a, bb, kb, tf, g, dl, d)
                else:
                    _stage(tw, wv, kb, tf, g, dl, d)
            # keep θ reduced modulo π (two-part π: the phase stays exact over millions of turns)
            for i in range(block):
                n = np.floor(tw[i] * (1.0 / math.pi) + 0.5)
                tw[i] = (tw[i] - n * _PI_HI) - n * _PI_LO
                nw[i] += n
            gk = k0 + k + 1
            rec = stride > 0 and gk % stride == 0
            ren = lyap_on and renorm > 0 and gk % renorm == 0
            last = k == n_steps - 1
            if rec or ren or last:
                # the step's pending last kick, applied for the record (and for good at the end)
                dl = ck[K - 1] * h
                tf = two_f[s, K - 1]
                g = r3[s, K - 1]
                g6 = r6[s, K - 1] if tide_on else 0.0
                fd = fdot[s, K - 1] if tide_on else 0.0
                for i in range(block):
                    sn, cs = _sincos(2.0 * tw[i] - tf)
                    x = cb[i] * g6 * dl
                    phi = 1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 - x * (1.0 / 720.0)))))
                    wr = wv[i] + (-kb[i] * g * sn - cb[i] * g6 * (wv[i] - fd)) * dl * phi
                    br = bb[i] + dl * phi * (-2.0 * kb[i] * g * cs * a[i] - cb[i] * g6 * bb[i])
                    if rec:
                        row = gk // stride - 1
                        out_th[lo + i, row] = tw[i] + nw[i] * math.pi
                        out_w[lo + i, row] = wr
                    if ren:
                        nrm = math.sqrt(a[i] * a[i] + br * br)
                        ls[i] += math.log(nrm)
                        a[i] /= nrm
                        bb[i] /= nrm
                        br /= nrm
                    if last:
                        wv[i] = wr
                        bb[i] = br
            s += 1
            if s == m:
                s = 0
        for i in range(block):
            th_w[lo + i] = tw[i]
            nwrap[lo + i] = nw[i]
            w[lo + i] = wv[i]
            dth[lo + i] = a[i]
            dw[lo + i] = bb[i]
            lsum[lo + i] = ls[i]


class OrbitTable:
    """The orbit at every kick time of `m` steps of length h, shared by a batch: 2f reduced to
    [−π, π), (a/r)³, and for tides (a/r)⁶ and ḟ. Periodic (m steps = one orbit) when h divides
    the orbital period; otherwise the rows run on (`rows(k0, n)` builds them for steps k0 … k0+n−1).

    `orbit` is a physics.orbits.KeplerOrbit (a, e, n, t_peri) or CircularOrbit (radius, rate, phase)."""

    def __init__(self, orbit, h, scheme="yoshida4", tides=False, t0=0.0):
        self.orbit, self.h, self.scheme, self.tides, self.t0 = orbit, float(h), scheme, bool(tides), float(t0)
        self.at = kick_times(scheme)
        rate = getattr(orbit, "n", None) or getattr(orbit, "rate", None)
        self.period = 2.0 * np.pi / abs(rate) if rate else np.inf
        m = int(round(self.period / self.h)) if np.isfinite(self.period) else 0
        self.periodic = m >= 1 and abs(m * self.h - self.period) <= 1e-12 * self.period
        self.m = m if self.periodic else 0
        self._periodic_rows = self.rows(0, m) if self.periodic else None

    def rows(self, k0, n):
        """Tables for steps k0 … k0 + n − 1: (two_f, r3, r6, fdot), each (n, K)."""
        tk = self.t0 + self.h * (k0 + np.arange(n)[:, None] + self.at[None, :])
        orb = self.orbit
        if hasattr(orb, "anomalies"):
            f, r = orb.anomalies(tk.ravel())
            ref = orb.a
        else:
            f, r = orb.longitude(tk.ravel()), orb.distance(tk.ravel())
            ref = orb.radius
        f = f.reshape(tk.shape)
        q = (ref / r.reshape(tk.shape))
        two_f = np.remainder(2.0 * f + np.pi, 2.0 * np.pi) - np.pi
        r3 = q**3
        if self.tides:
            r6 = r3 * r3
            if hasattr(orb, "true_anomaly_rate"):
                fdot = np.asarray(orb.true_anomaly_rate(tk.ravel()), float).reshape(tk.shape)
            else:
                fdot = np.full(tk.shape, float(orb.rate))
        else:
            r6 = fdot = np.zeros((1, 1))
        return (np.ascontiguousarray(two_f), np.ascontiguousarray(r3), np.ascontiguousarray(r6),
                np.ascontiguousarray(fdot))


MAX_TABLE_STEPS = 65536  # a table that does not repeat is built in pieces of this many steps


def planar_batch(theta0, thetadot0, strength, orbit, h, n_steps, scheme="yoshida4", tide_rate=None,
                 stride=0, lyapunov=False, renorm=0, threads=None, t0=0.0, progress=None):
    """Advance N planar bodies n_steps steps of length h on one orbit.

    theta0, thetadot0: (N,) starting θ and θ̇ at t0; strength: k per body (θ̈ = −k (a/r)³ sin 2(θ−f)),
    scalar or (N,); tide_rate: c per body (constant time lag, θ̈ += −c (a/r)⁶ (θ̇ − ḟ)) or None.
    Returns a dict: theta, thetadot (N,) at the end (θ unwrapped); if stride: t (rows,), theta_samples,
    thetadot_samples (N, rows) every `stride` steps; if lyapunov: lyapunov (N,) per unit time, from
    the tangent map renormalised every `renorm` steps (default: one orbit when the table is periodic).
    """
    th = np.atleast_1d(np.asarray(theta0, float)).ravel()
    N = th.shape[0]
    wd = np.broadcast_to(np.asarray(thetadot0, float), (N,)).astype(float)
    ks = np.broadcast_to(np.asarray(strength, float), (N,)).astype(float)
    tides = tide_rate is not None and bool(np.any(np.asarray(tide_rate) != 0))
    ct = np.broadcast_to(np.asarray(0.0 if tide_rate is None else tide_rate, float), (N,)).astype(float)
    for name, v in (("theta0", th), ("thetadot0", wd), ("strength", ks), ("tide_rate", ct)):
        if not np.all(np.isfinite(v)):
            raise ParameterError(name, v, "finite numbers")
    if not (np.isfinite(h) and h > 0):
        raise ParameterError("step", h, "a finite step > 0")
    n_steps = int(n_steps)
    if n_steps < 0:
        raise ParameterError("n_steps", n_steps, "at least 0")
    if tides:
        tab = OrbitTable(orbit, h, scheme, True, t0)
        worst = float(np.max(np.abs(ct))) * h * float(np.max(np.abs(SCHEMES[scheme][0]))) * (
            (orbit.a / (orbit.a * (1 - orbit.e))) ** 6 if hasattr(orbit, "e") else 1.0)
        if worst > 0.01:
            raise ParameterError("tide_rate", float(np.max(np.abs(ct))),
                                 f"below {0.01 / worst * float(np.max(np.abs(ct))):.3g} at this step "
                                 "(the spin would relax by more than 1 % within one kick)")
    else:
        tab = OrbitTable(orbit, h, scheme, False, t0)
    ck, dk = SCHEMES[scheme]
    # pad to whole blocks (copies of the last body): every body runs the same vector code
    # One body without the tangent map runs as a block of one (no fifteen copies of it to carry: the
    # same bits, tidal-capture 0.67 -> 0.38 s). With it, a block of BLOCK: the kernel as numba loads
    # it from its cache takes the logarithm in the vector loop with other bits than in the scalar
    # one (the exponent differed in its last bits for 52 of 53 bodies; freshly compiled, for none).
    block = BLOCK if N > 1 or lyapunov else 1
    Np = -(-N // block) * block if N else 0
    pad = lambda v: np.concatenate([v, np.repeat(v[-1:], Np - N)]) if N else v  # noqa: E731
    red = np.floor(th / np.pi + 0.5)
    th_w = pad(th - red * np.pi)
    nwrap = pad(red)
    w = pad(wd)
    kstr, ctide = pad(ks), pad(ct)
    rows = n_steps // stride if stride else 0
    out_th = np.zeros((Np, max(rows, 1)))
    out_w = np.zeros((Np, max(rows, 1)))
    if renorm <= 0 and lyapunov:
        renorm = tab.m if tab.periodic else max(1, int(round(tab.period / h))) if np.isfinite(tab.period) else 64
    a = np.ones(Np)
    b = np.zeros(Np)
    lsum = np.zeros(Np)
    old_threads = nb.get_num_threads()
    if threads is not None:
        nb.set_num_threads(max(1, min(int(threads), nb.config.NUMBA_NUM_THREADS)))
    try:
        done = 0
        if tab.periodic:
            two_f, r3, r6, fdot = tab._periodic_rows
            piece = max(1, min(n_steps, 200000))
        else:
            piece = MAX_TABLE_STEPS
        while done < n_steps and N:
            n = min(piece, n_steps - done)
            if tab.periodic:
                s0, m = done % tab.m, tab.m
            else:
                two_f, r3, r6, fdot = tab.rows(done, n)
                s0, m = 0, n
            _kernel(th_w, nwrap, w, kstr, ctide, two_f, r3, r6, fdot, m, s0, ck, dk, float(h), n, done,
                    int(stride), out_th, out_w, bool(lyapunov), tides, a, b, lsum, int(renorm), block)
            done += n
            if progress is not None:
                progress(done / n_steps)
    finally:
        nb.set_num_threads(old_threads)
    out = {"theta": (th_w + nwrap * np.pi)[:N], "thetadot": w[:N].copy()}
    if stride:
        out["t"] = t0 + h * stride * np.arange(1, rows + 1)
        out["theta_samples"] = out_th[:N, :rows]
        out["thetadot_samples"] = out_w[:N, :rows]
    if lyapunov:
        n_ren = (n_steps // renorm) if renorm else 0
        out["lyapunov"] = lsum[:N] / (n_ren * renorm * h) if n_ren else np.full(N, np.nan)
    return out
