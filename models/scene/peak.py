"""Resonance peak of the scene simulator at a given first-harmonic amplitude.

Continuation in amplitude of the peak's stationarity equations (:func:`_peak_path`) while
the orbit stays in contact; from the first step that fails or nears separation on, the
least drive over frequency (:func:`_least_drive_peak`), which needs no Jacobian of the
contact force and so survives the jumps and kinks contact loss puts into it.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.ladder.harmonic_balance import fourier_bases, newton
from beadrod.models.scene.sweep_kernels import Dyn, hb_amplitudes, hb_residual

__all__ = ["min_overlap", "peaks_along"]

# Past contact loss the sampled contact force has a jump at y = 0 (the in-contact dashpot of
# JKR/DMT/linear losses, DMT's adhesion) or an unbounded slope there (Kuwabara-Kono's
# y^(1/2) y'): the AFT Jacobian then misses the moving jump's contribution or spikes as a
# sample nears y = 0, so the stationarity equation of _peak_path jumps sign without a root
# (Newton 2-cycles with |R| ~ 1e-3) or has spurious roots off the peak. Orbits that come
# this close to separation (y = 1 + q, over delta0) are solved by the least drive instead.
_NEAR_LOSS = 0.02
_GRID = 33          # Omega points per window of the least-drive search
_MOVES = 8          # window shifts while the minimum sits on its edge
_ZOOMS = 8          # refinements by (_GRID - 1)/2: Omega to ~1e-13 (1e-9 where E is smooth)


@partial(jax.jit, static_argnames=("h", "n", "bead"))
def _peak_path(dyn: Dyn, amps: jnp.ndarray, om0: ArrayLike, e0: ArrayLike, h: int, n: int,
               bead: bool = True) -> tuple[jnp.ndarray, ...]:
    """Resonance peak (max amplitude over Omega) at each amplitude in ``amps`` (ascending,
    continuation): unknowns (X, Omega, E); R = 0, dA/dOmega along the branch = 0, A = a."""
    def amp(x, om, e):
        return hb_amplitudes(x, om, e, dyn, h, n)[0 if bead else 1]

    def fun(zz, a):
        x, om, e = zz[:-2], zz[-2], zz[-1]
        res = lambda xx, oo: hb_residual(xx, oo, e, dyn, h, n)  # noqa: E731
        rx = jax.jacfwd(res)(x, om)
        ro = jax.jacfwd(res, argnums=1)(x, om)
        ga, go = jax.grad(amp, argnums=(0, 1))(x, om, e)
        # det(R_X) keeps the condition finite at folds; dividing by the (off-resonant)
        # mean and higher-harmonic block keeps it O(1) whatever H
        sub = np.r_[0, 3:2 * h + 1]
        scale = jnp.linalg.det(rx[np.ix_(sub, sub)]) if h > 1 else rx[0, 0]
        peak = jnp.linalg.det(rx) / scale * (go - jnp.dot(ga, jnp.linalg.solve(rx, ro)))
        return jnp.concatenate([res(x, om), peak[None], (amp(x, om, e) - a)[None]])

    z0 = jnp.zeros(2 * h + 3).at[1].set(amps[0]).at[-2].set(om0).at[-1].set(e0 * amps[0])

    def step(zz, a):
        zn, ok = newton(lambda v: fun(v, a), zz, 60)
        return zn, (zn, ok)

    _, (zs, ok) = jax.lax.scan(step, z0, amps)
    return zs[:, -2], zs[:, -1], zs[:, :-2], ok


def min_overlap(x: np.ndarray, h: int, samples: int = 512) -> np.ndarray:
    """Smallest overlap 1 + q over the cycle [-] of each row of X (..., 2H+1)."""
    basis = np.asarray(fourier_bases(h, samples)[0])  # (samples, 2H+1): q(theta) = basis @ X
    return 1.0 + (x @ basis.T).min(-1)


@partial(jax.jit, static_argnames=("h", "n", "bead"))
def _drive_for_amplitude(dyn: Dyn, a: ArrayLike, omegas: jnp.ndarray, v0: jnp.ndarray,
                         h: int, n: int, bead: bool = True) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(X, E) with R = 0 and first-harmonic amplitude ``a`` at each Omega, each solved from
    ``v0``; and the converged flags. Needs R only, never its Jacobian's accuracy."""
    def one(om):
        def fun(v):
            x, e = v[:-1], v[-1]
            amp = hb_amplitudes(x, om, e, dyn, h, n)[0 if bead else 1]
            return jnp.concatenate([hb_residual(x, om, e, dyn, h, n), (amp - a)[None]])
        return newton(fun, v0, 60)

    return jax.vmap(one)(omegas)


def _least_drive_peak(dyn: Dyn, a: float, v0: np.ndarray, om_guess: float, half: float,
                      h: int, n: int, bead: bool) -> np.ndarray | None:
    """[X, Omega, E] of the resonance peak of amplitude ``a``, or None if not found.

    The peak at drive E has amplitude a exactly where E(Omega), the drive that reaches a at
    Omega, is least: a grid search, zoomed in, needs no derivative of the force, so it
    holds across the jumps and kinks that contact loss puts into the sampled force.
    """
    def least(lo, hi, v0):
        oms = np.linspace(lo, hi, _GRID)
        v, ok = (np.asarray(t) for t in
                 _drive_for_amplitude(dyn, a, jnp.asarray(oms), jnp.asarray(v0), h, n, bead))
        e = np.where(ok & (v[:, -1] > 0), v[:, -1], np.inf)
        return oms, v, int(np.argmin(e)), bool(np.isfinite(e).any())

    lo = om_guess - half
    for _ in range(_MOVES):
        oms, v, j, found = least(lo, lo + 2 * half, v0)
        if not found:
            return None
        v0 = v[j]
        if 0 < j < _GRID - 1:
            break
        lo = oms[j] - half
    else:
        return None             # the least drive is not bracketed: no peak near here
    for _ in range(_ZOOMS):
        oms, v, j, found = least(oms[max(j - 1, 0)], oms[min(j + 1, _GRID - 1)], v0)
        if not found:
            return None
        v0 = v[j]
    return np.concatenate([v[j][:-1], [oms[j], v[j][-1]]])


def peaks_along(dyn: Dyn, amps: np.ndarray, om0: float, e0: float, h: int, n: int,
                bead: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Resonance peak (Omega, E, X, found) at each amplitude of ``amps`` (ascending):
    continuation of the stationarity equations while the orbit stays in contact, then
    the least drive from the first step that fails or comes near separation."""
    out = _peak_path(dyn, jnp.asarray(amps, float), om0, e0, h, n, bead)
    om, e, x, ok = (np.array(t) for t in out)
    rough = ~ok | (min_overlap(x, h) < _NEAR_LOSS)
    if not rough.any() or rough[0]:
        return om, e, x, ok
    for i in range(int(np.argmax(rough)), len(amps)):
        step = om[i - 1] - om[i - 2] if i > 1 else 0.0
        z = _least_drive_peak(dyn, float(amps[i]), np.r_[x[i - 1], e[i - 1]],
                              om[i - 1] + step, max(0.01, 2 * abs(step)), h, n, bead)
        if z is None:
            ok[i:] = False
            break
        x[i], om[i], e[i], ok[i] = z[:-2], z[-2], z[-1], True
    return om, e, x, ok
