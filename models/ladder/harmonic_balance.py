"""Multi-harmonic balance of the base-excited contact oscillator (ladder rung 4).

Equation (models/ladder/oscillator.py, theta = Omega tau):

    Omega^2 q_thth + (g(1 + q, Omega q_th) - 1)/s + E Omega^2 sin(theta) = 0,

q(theta) = c0 + sum_{k=1..H} a_k cos(k theta) + b_k sin(k theta); unknowns
X = [c0, a1, b1, ..., aH, bH]. Alternating frequency-time (AFT): q and q_th are
synthesised on N equispaced samples, the contact force is evaluated there (contact
loss included) and projected back by a real FFT; the Galerkin residual R(X, Omega, E)
has 2H + 1 components. Newton with the Jacobian from forward-mode AD.

* :func:`sweep`: stepped frequency sweep (natural continuation, each solve starting
  from the previous frequency's solution) as an analyser would see it, up or down.
* :func:`frf`: pseudo-arclength continuation (Keller) in Omega through the folds:
  the whole frequency-response curve, the peak, and the fold (jump) frequencies.
* :func:`solve`, :func:`peak_at_drive`, :func:`peak_at_amplitude`: single solves with
  implicit-function-theorem gradients (``jax.lax.custom_root``) w.r.t. every parameter
  of the contact law, the drive and the frequency.
* :func:`backbone` / :func:`backbone_shift`: the conservative free vibration
  (cosine series, amplitude fixed, Omega unknown), to check against the exact
  energy-integral backbone of models/ladder/backbone.py.

Amplitude: x = sqrt(a1^2 + b1^2), the first harmonic of q = (delta - delta0)/delta0.
Reference: Krack & Gross, *Harmonic Balance for Nonlinear Vibration Problems*
(Springer 2019), Ch. 2-4 (AFT, Newton, arclength continuation).
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.ladder.oscillator import ContactLaw

__all__ = [
    "default_time_samples",
    "fourier_bases",
    "newton",
    "residual",
    "amplitude",
    "solve",
    "sweep",
    "FRC",
    "frf",
    "peak_at_drive",
    "peak_at_amplitude",
    "backbone",
    "backbone_shift",
]


def default_time_samples(harmonics: int) -> int:
    """N = smallest power of two >= max(64, 16 H): the force is only C^1 at contact loss,
    so its spectrum decays slowly and aliasing needs a generous N."""
    return int(2 ** np.ceil(np.log2(max(64, 16 * harmonics))))


def fourier_bases(h: int, n: int) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """AFT bases on n time samples theta_j = 2 pi j/n for X = [c0, a1, b1, ..., aH, bH]:
    B (n, 2H+1) with q(theta) = B @ X, dB/dtheta, and the harmonic index of each column."""
    th = 2.0 * np.pi * np.arange(n) / n
    k = np.arange(1, h + 1)
    b = np.ones((n, 2 * h + 1))
    db = np.zeros((n, 2 * h + 1))
    b[:, 1::2], b[:, 2::2] = np.cos(np.outer(th, k)), np.sin(np.outer(th, k))
    db[:, 1::2], db[:, 2::2] = -k * np.sin(np.outer(th, k)), k * np.cos(np.outer(th, k))
    return jnp.asarray(b), jnp.asarray(db), jnp.asarray(np.repeat(np.r_[0, k], [1] + [2] * h))


def _project(f: jnp.ndarray, h: int) -> jnp.ndarray:
    """Fourier coefficients [c0, a1, b1, ...] of real samples f (AFT time -> frequency)."""
    n = f.shape[-1]
    c = jnp.fft.rfft(f) / n
    ab = jnp.stack([2.0 * c[1:h + 1].real, -2.0 * c[1:h + 1].imag], axis=-1).reshape(-1)
    return jnp.concatenate([c[:1].real, ab])


def residual(x: jnp.ndarray, omega: ArrayLike, drive: ArrayLike, law: ContactLaw,
             harmonics: int, n_time: int | None = None) -> jnp.ndarray:
    """Galerkin residual R(X, Omega, E) [-] of length 2H + 1."""
    h = harmonics
    n = n_time or default_time_samples(h)
    b, db, kk = fourier_bases(h, n)
    q, qd = b @ x, db @ x
    fnl = (law.force(1.0 + q, omega * qd) - 1.0) / law.slope
    r = -(omega * kk) ** 2 * x + _project(fnl, h)
    return r.at[2].add(drive * omega**2)


def amplitude(x: jnp.ndarray) -> jnp.ndarray:
    """First-harmonic amplitude sqrt(a1^2 + b1^2) [-]."""
    return jnp.sqrt(x[..., 1] ** 2 + x[..., 2] ** 2)


def newton(fun, x0, iters: int, tol: float = 1e-11):
    """Newton on fun(x) = 0, each step capped at 0.5 in max-norm; returns (x, converged).

    No line search on |fun|: where a branch has just ended (a fold) |fun| has a local
    minimum that a descent safeguard gets stuck in, while capped full steps escape.
    """

    def cond(c):
        _, i, err = c
        return (i < iters) & (err > tol)

    def body(c):
        x, i, _ = c
        r, jac = fun(x), jax.jacfwd(fun)(x)
        dx = jnp.linalg.solve(jac, -r)
        scale = jnp.minimum(1.0, 0.5 / jnp.maximum(jnp.max(jnp.abs(dx)), 1e-300))
        return x + scale * dx, i + 1, jnp.max(jnp.abs(dx)) + jnp.max(jnp.abs(r))

    x, _, err = jax.lax.while_loop(cond, body, (x0, 0, jnp.inf))
    ok = jnp.all(jnp.isfinite(x)) & (jnp.max(jnp.abs(fun(x))) < 1e-8)
    return x, ok


def _implicit(fun, x0, iters):
    """Root of fun with implicit-function-theorem derivatives (custom_root)."""
    def solver(f, guess):
        return newton(f, guess, iters)[0]

    def tangent_solve(g, y):
        return jnp.linalg.solve(jax.jacfwd(g)(y), y)

    return jax.lax.custom_root(fun, x0, solver, tangent_solve)


@partial(jax.jit, static_argnames=("harmonics", "n_time", "iters"))
def solve(law: ContactLaw, drive: ArrayLike, omega: ArrayLike, x0: jnp.ndarray | None = None,
          *, harmonics: int = 3, n_time: int | None = None, iters: int = 40) -> jnp.ndarray:
    """Harmonic coefficients X at one frequency [-] (IFT-differentiable)."""
    x0 = jnp.zeros(2 * harmonics + 1) if x0 is None else x0
    return _implicit(lambda x: residual(x, omega, drive, law, harmonics, n_time), x0, iters)


@partial(jax.jit, static_argnames=("harmonics", "n_time", "iters"))
def sweep(law: ContactLaw, drive: ArrayLike, omegas: ArrayLike, *, harmonics: int = 3,
          n_time: int | None = None, iters: int = 40) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Stepped sweep over ``omegas`` in the given order (reverse it for a down sweep).

    Each frequency starts from the previous solution, so the sweep stays on a branch
    until it ends at a fold and then falls to the other one, as a measured sweep does.
    Returns (X per frequency (F, 2H+1), converged flags (F,)).
    """
    def step(x, om):
        fun = lambda z: residual(z, om, drive, law, harmonics, n_time)
        xn, ok = newton(fun, x, iters)
        # the branch ended (fold): land on the other one, as the analyser's sweep does,
        # by restarting from rest (jump down) or from a larger orbit (jump up)
        for guess in (x, jnp.zeros_like(x), 2.0 * x):
            xn, ok = jax.lax.cond(ok, lambda xn=xn, ok=ok: (xn, ok),
                                  lambda g=guess: newton(fun, g, 5 * iters))
        return xn, (xn, ok)

    _, (xs, ok) = jax.lax.scan(step, jnp.zeros(2 * harmonics + 1), jnp.asarray(omegas))
    return xs, ok


class FRC(NamedTuple):
    """A frequency-response curve from arclength continuation (padded arrays)."""

    omega: jnp.ndarray        # (S,) Omega along the arc [-]
    coeffs: jnp.ndarray       # (S, 2H+1) harmonic coefficients
    amplitude: jnp.ndarray    # (S,) first-harmonic amplitude x [-]
    valid: jnp.ndarray        # (S,) accepted points inside [omega_lo, omega_hi]
    peak_omega: jnp.ndarray   # Omega at the amplitude maximum [-]
    peak_amplitude: jnp.ndarray
    up_jump_omega: jnp.ndarray    # fold where an up sweep leaves its branch (NaN if none)
    down_jump_omega: jnp.ndarray  # fold where a down sweep leaves its branch (NaN if none)
    complete: jnp.ndarray         # the arc reached omega_hi within n_steps


def _tangent(jz, t_prev):
    """Unit tangent of the branch: null vector of jz with t . t_prev > 0 (bordered solve)."""
    m = jnp.concatenate([jz, t_prev[None, :]], axis=0)
    t = jnp.linalg.solve(m, jnp.zeros(jz.shape[1]).at[-1].set(1.0))
    return t / jnp.linalg.norm(t)


@partial(jax.jit, static_argnames=("harmonics", "n_time", "n_steps", "max_turn",
                                   "corrector_iters"))
def frf(law: ContactLaw, drive: ArrayLike, omega_lo: float = 0.8, omega_hi: float = 1.2, *,
        harmonics: int = 3, n_time: int | None = None, n_steps: int = 200,
        ds_max: float | None = None, max_turn: float = 0.15,
        corrector_iters: int = 8) -> FRC:
    """Pseudo-arclength continuation from omega_lo to omega_hi, through folds.

    Fixed number of predictor-corrector steps (``n_steps``); the step length adapts
    (x1.3 after a success, x0.5 and retry after a failed corrector or a tangent that
    turned by more than ``max_turn`` rad), capped at ``ds_max`` (default: 1.5 x an
    arc-length estimate / n_steps); ``complete`` tells whether omega_hi was reached.
    The peak is refined by a Newton solve of R = 0, dA/ds = 0 from the best point on
    the arc (kept only if it stays beside it). Folds are the sign changes of dOmega/ds:
    an up sweep leaves the branch where Omega turns back (a local maximum of Omega
    along the arc), a down sweep where it turns forward.
    """
    h = harmonics
    dim = 2 * h + 2
    res = lambda z: residual(z[:-1], z[-1], drive, law, h, n_time)
    x0, _ = newton(lambda x: residual(x, omega_lo, drive, law, h, n_time),
                   jnp.zeros(2 * h + 1), 40)
    z0 = jnp.concatenate([x0, jnp.array([omega_lo], dtype=x0.dtype)])
    t0 = _tangent(jax.jacfwd(res)(z0), jnp.zeros(dim).at[-1].set(1.0))
    if ds_max is None:
        # arc length ~ frequency span + up and down the resonance peak (linear estimate)
        a_lin = jnp.minimum(drive / _damping_guess(law), 2.0)
        ds_max = 1.5 * ((omega_hi - omega_lo) + 3.0 * a_lin) / n_steps
    ds0 = 0.5 * ds_max
    cos_turn = float(np.cos(max_turn))

    def step(c, _):
        z, t, ds, done = c
        zp = z + ds * t

        def corr(w):
            return jnp.concatenate([res(w), jnp.dot(t, w - zp)[None]])

        def body(_, w):
            return w + jnp.linalg.solve(jax.jacfwd(corr)(w), -corr(w))

        w = jax.lax.fori_loop(0, corrector_iters, body, zp)
        ok = jnp.all(jnp.isfinite(w)) & (jnp.max(jnp.abs(corr(w))) < 1e-9)
        ok = ok & (jnp.linalg.norm(w - z) < 2.0 * ds + 1e-12)
        tn = _tangent(jax.jacfwd(res)(jnp.where(ok, w, z)), t)
        ok = ok & (jnp.dot(tn, t) > cos_turn)
        accept = ok & ~done
        z_new = jnp.where(accept, w, z)
        t_new = jnp.where(accept, tn, t)
        ds_new = jnp.where(ok, jnp.minimum(1.3 * ds, ds_max), 0.5 * ds)
        done_new = done | (accept & ((w[-1] > omega_hi) | (w[-1] < omega_lo)))
        return (z_new, t_new, ds_new, done_new), (w, t_new[-1], accept)

    init = (z0, t0, ds0, jnp.array(False))
    (_, _, _, complete), (zs, dom, acc) = jax.lax.scan(step, init, None, length=n_steps)
    zs = jnp.concatenate([z0[None], zs])
    dom = jnp.concatenate([t0[-1:], dom])
    valid = jnp.concatenate([jnp.array([True]), acc])
    valid = valid & (zs[:, -1] >= omega_lo) & (zs[:, -1] <= omega_hi)
    amp = amplitude(zs[:, :-1])
    am = jnp.where(valid, amp, -jnp.inf)
    i = jnp.argmax(am)
    # folds: sign change of dOmega/ds between consecutive valid points
    idx = jnp.arange(zs.shape[0])
    last = jax.lax.associative_scan(jnp.maximum, jnp.where(valid, idx, -1))
    prev = jnp.concatenate([jnp.array([-1]), last[:-1]])
    has_prev = valid & (prev >= 0)
    dprev = dom[jnp.maximum(prev, 0)]
    right = has_prev & (dprev > 0) & (dom < 0)
    left = has_prev & (dprev < 0) & (dom > 0)
    om = zs[:, -1]
    up = jnp.where(jnp.any(right), om[jnp.argmax(right)], jnp.nan)
    down = jnp.where(jnp.any(left), om[zs.shape[0] - 1 - jnp.argmax(left[::-1])], jnp.nan)

    def peak_fun(z):
        x, o = z[:-1], z[-1]
        return jnp.concatenate([residual(x, o, drive, law, h, n_time),
                                _peak_condition(x, o, drive, law, h, n_time)[None]])

    zpk, okpk = newton(peak_fun, zs[i], 30)
    # accept the refined peak only if it stays beside the best arc point (near a fold
    # the peak system is nearly singular and Newton may wander)
    okpk = okpk & (jnp.abs(zpk[-1] - zs[i, -1]) < 2.0 * ds_max) & (amplitude(zpk[:-1]) >= amp[i])
    zpk = jnp.where(okpk, zpk, zs[i])
    return FRC(om, zs[:, :-1], amp, valid, zpk[-1], amplitude(zpk[:-1]), up, down,
               complete)


def _damping_guess(law: ContactLaw) -> jnp.ndarray:
    """2 zeta_eff = (dg/dy')(1, 0)/s: the linearised damping, for initial guesses."""
    return jax.grad(lambda v: law.force(1.0, v))(0.0) / law.slope


def _peak_condition(x, omega, drive, law, h, n_time):
    """grad(A) . dX/ds along the branch, scaled by det(R_X) so it stays finite at folds."""
    rx = jax.jacfwd(lambda z: residual(z, omega, drive, law, h, n_time))(x)
    ro = jax.jacfwd(lambda o: residual(x, o, drive, law, h, n_time))(omega)
    ga = jax.grad(amplitude)(x)
    return -jnp.linalg.det(rx) * jnp.dot(ga, jnp.linalg.solve(rx, ro))


def _x_guess(h, amp, dtype=float):
    return jnp.zeros(2 * h + 1, dtype=dtype).at[1].set(amp)


def peak_at_drive(law: ContactLaw, drive: ArrayLike, *, omega_guess: ArrayLike = 1.0,
                  amplitude_guess: ArrayLike | None = None, harmonics: int = 3,
                  n_time: int | None = None, iters: int = 60) -> tuple[jnp.ndarray, ...]:
    """Resonance peak (max first-harmonic amplitude over Omega) at drive E.

    Solves R = 0 together with dA/ds = 0 along the branch (unknowns X, Omega);
    IFT-differentiable. Needs a good initial guess: near a fold (hysteretic curves,
    contact loss) the system is nearly singular; :func:`frf` gives a robust peak.
    Returns (Omega_peak, x_peak, X).
    """
    h = harmonics
    amp0 = drive / _damping_guess(law) if amplitude_guess is None else amplitude_guess

    def fun(z):
        x, om = z[:-1], z[-1]
        return jnp.concatenate([residual(x, om, drive, law, h, n_time),
                                _peak_condition(x, om, drive, law, h, n_time)[None]])

    z0 = jnp.concatenate([_x_guess(h, amp0), jnp.atleast_1d(jnp.asarray(omega_guess, float))])
    z = _implicit(fun, z0, iters)
    return z[-1], amplitude(z[:-1]), z[:-1]


def peak_at_amplitude(law: ContactLaw, x_peak: ArrayLike, *, omega_guess: ArrayLike = 1.0,
                      x_guess: jnp.ndarray | None = None, harmonics: int = 3,
                      n_time: int | None = None, iters: int = 60) -> tuple[jnp.ndarray, ...]:
    """Drive E and peak Omega such that the resonance peak has amplitude ``x_peak``.

    Unknowns (X, Omega, E), equations R = 0, dA/ds = 0, A = x_peak; IFT-differentiable.
    Start it from the conservative backbone (:func:`backbone`: ``omega_guess`` and
    ``x_guess``); near contact loss the system is nearly singular, so check the
    residual of the result (models/ladder/powerlaw_ladder.py does).
    Returns (Omega_peak, E, X). The resonance shift at amplitude x is Omega_peak - 1.
    """
    h = harmonics
    e0 = _damping_guess(law) * x_peak

    def fun(z):
        x, om, e = z[:-2], z[-2], z[-1]
        return jnp.concatenate([residual(x, om, e, law, h, n_time),
                                _peak_condition(x, om, e, law, h, n_time)[None],
                                (amplitude(x) - x_peak)[None]])

    xg = _x_guess(h, x_peak) if x_guess is None else x_guess
    z0 = jnp.concatenate([xg, jnp.stack([jnp.asarray(omega_guess, float),
                                                          jnp.asarray(e0, float)])])
    z = _implicit(fun, z0, iters)
    return z[-2], z[-1], z[:-2]


def backbone(law: ContactLaw, x: ArrayLike, *, omega_guess: ArrayLike = 1.0,
             harmonics: int = 3, n_time: int | None = None,
             iters: int = 60) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Conservative free vibration by harmonic balance at first-harmonic amplitude x.

    Only for laws without dissipation (the orbit is even in time: cosine series).
    Unknowns (c0, a2..aH, Omega) with a1 = x fixed; IFT-differentiable.
    Returns (Omega, X).
    """
    h = harmonics
    cos_idx = np.r_[0, 1 + 2 * np.arange(h)]     # c0, a1, ..., aH
    free = np.r_[0, 1 + 2 * np.arange(1, h)]     # c0, a2, ..., aH

    def full(z):
        return jnp.zeros(2 * h + 1, z.dtype).at[free].set(z[:-1]).at[1].set(x)

    def fun(z):
        return residual(full(z), z[-1], 0.0, law, h, n_time)[cos_idx]

    z0 = jnp.zeros(h + 1).at[-1].set(omega_guess)
    z = _implicit(fun, z0, iters)
    return z[-1], full(z)


def backbone_shift(law: ContactLaw, x: ArrayLike, *, harmonics: int = 3,
                   n_time: int | None = None) -> jnp.ndarray:
    """HBM backbone Delta f/f0 = Omega - 1 at first-harmonic amplitude x [-]."""
    return backbone(law, x, harmonics=harmonics, n_time=n_time)[0] - 1.0
