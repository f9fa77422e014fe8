"""Where NUTS starts: a multi-start search for the posterior's modes.

Why. NUTS explores the basin it starts in, and bridge sampling (the default evidence)
fits one Normal to those draws, so a run started at the prior median reports the nearest
mode as if it were the only one, and bridge sampling misses a mode that nested sampling
sees. The search finds the deepest mode to start from, and reports the others.

Method. ``starts`` points are drawn from the prior, mapped to numpyro's unconstrained
space and spread about their coordinate-wise median by ``spread`` (overdispersed starts,
Gelman & Rubin 1992, so that a basin in the prior's tail is reached); Adam then descends
the potential (minus log joint density) from all of them at once (one compiled, vmapped
scan). Two optima are one mode unless the log density on the straight line between them
dips more than ``barrier`` nats below the lower one. The chains start at the deepest.
What is reported (:class:`ModeSearch`): every distinct mode's log density at its optimum,
so a caller can say when a second mode comes close (its mass is then missing from the
evidence of a one-mode sampler).

Cost: ``starts x steps`` gradient evaluations, vectorised, in one program whose tracing
and compilation dominate. The prior draws, the unconstrained layout and both density
evaluations are inside that program: each apart would trace the model again.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from numpyro import handlers
from numpyro.infer.util import potential_energy

from beadrod.inference.evidence.log_z import latent_site_names
from beadrod.inference.model.unconstrained import flatten_unconstrained

__all__ = ["ModeSearch", "find_modes"]

_SEGMENT = 6  # interior points of the barrier test between two optima


@dataclass(frozen=True)
class ModeSearch:
    """The distinct optima found, deepest first.

    ``log_density``: log joint density (numpyro's -potential, unconstrained space) at each
    optimum; ``points``: each optimum as a dict of unconstrained site values;
    ``starts_converged``: how many starts ended at a finite density.
    """

    log_density: tuple[float, ...]
    points: tuple[dict[str, np.ndarray], ...] = field(repr=False)
    starts: int = 0
    starts_converged: int = 0

    @property
    def best(self) -> dict[str, np.ndarray]:
        return self.points[0]

    @property
    def gap(self) -> float | None:
        """log density of the deepest mode minus the second's [nat] (None: one mode)."""
        return None if len(self.log_density) < 2 else self.log_density[0] - self.log_density[1]

    def to_dict(self) -> dict[str, Any]:
        return {"modes": len(self.log_density), "log_density": list(self.log_density),
                "gap": self.gap, "starts": self.starts,
                "starts_converged": self.starts_converged}


def _adam(grad_fn: Callable, u0: jnp.ndarray, steps: int, lr: float) -> jnp.ndarray:
    b1, b2, eps = 0.9, 0.999, 1e-8

    def step(carry, k):
        u, m, v = carry
        g = grad_fn(u)
        g = jnp.where(jnp.isfinite(g), g, 0.0)  # a start outside the support: no push
        m = b1 * m + (1 - b1) * g
        v = b2 * v + (1 - b2) * g * g
        # the step size decays tenfold over the run: coarse basin-finding, then settling
        rate = lr * 0.1 ** (k / steps)
        mh, vh = m / (1 - b1 ** (k + 1)), v / (1 - b2 ** (k + 1))
        return (u - rate * mh / (jnp.sqrt(vh) + eps), m, v), None

    z = jnp.zeros_like(u0)
    (u, _, _), _ = jax.lax.scan(step, (u0, z, z), jnp.arange(steps, dtype=u0.dtype))
    return u


def find_modes(model: Callable, data: dict[str, Any], *, starts: int = 16,
               steps: int = 200, lr: float = 0.05, spread: float = 2.0,
               barrier: float = 1.0, seed: int = 0) -> ModeSearch:
    """Multi-start search of ``model(data)``'s posterior modes (module doc).

    Raises RuntimeError when no start reaches a finite log density.
    """
    kw = {"data": data}
    latents = latent_site_names(model, kw)
    layout: list[Callable] = []  # the unravel of the unconstrained layout, set while tracing

    def pot(x):
        return potential_energy(model, (), kw, layout[0](x))

    def prior_draw(key):
        tr = handlers.trace(handlers.seed(model, key)).get_trace(**kw)
        return {k: tr[k]["value"] for k in latents}

    t = jnp.linspace(0.0, 1.0, _SEGMENT + 2)[1:-1]

    @jax.jit
    def run(key):
        # prior draws -> unconstrained, spread about their median: all in the one program,
        # which traces the model fewer times than the draws (Predictive), the layout
        # (eval_shape) and the two density calls would apart
        draws = jax.vmap(prior_draw)(jax.random.split(key, starts))
        x0, unravel = flatten_unconstrained(model, kw, draws)
        layout.append(unravel)
        centre = jnp.median(x0, axis=0)
        x0 = centre + spread * (x0 - centre)
        xs = jax.vmap(lambda x: _adam(jax.grad(pot), x, steps, lr))(x0)
        # the highest potential on the segment between every pair of optima, in the same
        # program (one compilation): segments of one basin stay near its floor
        seg = xs[None, :, None, :] + t[None, None, :, None] * (xs[:, None, None, :]
                                                               - xs[None, :, None, :])
        pts = jnp.concatenate([xs, seg.reshape(-1, seg.shape[-1])])
        pe_all = jax.vmap(pot)(pts)
        return xs, pe_all[:starts], jnp.max(pe_all[starts:].reshape(seg.shape[:3]), axis=-1)

    # optimised, though it runs once: compiled without LLVM's passes
    # (inference.speed.light_compile),
    # its Adam steps run slower, which costs more than the compile saves once the
    # compilation cache is warm
    xs, pe, ridge = (np.asarray(a) for a in run(jax.random.PRNGKey(seed)))
    unravel = layout[-1]
    ok = np.isfinite(pe)
    if not ok.any():
        raise RuntimeError(f"mode search: none of {starts} starts reached a finite "
                           "log density (the prior may put no mass where the law is defined)")
    order = np.argsort(np.where(ok, pe, np.inf))[: int(ok.sum())]
    # Adam stops short of the optimum along flat directions, so two starts in one basin
    # end apart: they are one mode unless the density between them dips by more than
    # `barrier` nats below the lower end (a straight-line barrier test)
    modes: list[int] = []
    for i in order:
        if not any(ridge[i, j] <= pe[i] + barrier for j in modes):
            modes.append(int(i))
    points = tuple({k: np.asarray(v) for k, v in unravel(jnp.asarray(xs[i])).items()}
                   for i in modes)
    return ModeSearch(tuple(float(-pe[i]) for i in modes), points, starts, int(ok.sum()))
