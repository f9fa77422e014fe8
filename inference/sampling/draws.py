"""Everything a fit adds to its NUTS draws, in one compiled program: the pointwise
log-likelihood, the posterior predictive and the prior (with its predictive).

Why one program. Evaluated draw by draw outside ``jit`` (``Predictive``,
``az.from_numpyro``'s log-likelihood and the eager model run it makes to find the
observations), most of the time goes to dispatching single operations (a law's root
solves, say); traced once and mapped over the draws in batches, they compile into one
program.

Only the observation sites count (``inference.model.likelihood.OBSERVED_SITES``): a
``numpyro.factor`` (the law's domain) is an observed site to numpyro, but it is no
observation and has no predictive.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from numpyro import handlers

from beadrod.inference.model.likelihood import OBSERVED_DATA_KEYS, OBSERVED_SITES
from beadrod.inference.speed.residual_fold import POINTWISE

__all__ = ["fit_draws", "sample_stats", "observed_data", "BATCH"]

BATCH = 250
"""Draws evaluated side by side (vmapped) in one step of the map over draws: large enough
to amortise a step's overhead, small enough that a table law's batch stays in cache."""


def _trace(model: Callable, data: dict[str, Any], values: dict[str, Any] | None,
           key: jax.Array | None) -> dict[str, Any]:
    fn = model if values is None else handlers.substitute(model, data=values)
    if key is not None:
        fn = handlers.seed(fn, key)
    return handlers.trace(fn).get_trace(data)


def fit_draws(model: Callable, data: dict[str, Any], pdata: dict[str, Any],
              samples: dict[str, Any], latents: list[str], *, key_post: jax.Array,
              key_prior: jax.Array, prior_draws: int, predictive: bool = True
              ) -> dict[str, dict[str, np.ndarray]]:
    """log_likelihood, posterior_predictive, prior and prior_predictive of ``model``.

    ``samples``: the NUTS draws, each array (chains, draws, ...); only the ``latents``
    are substituted. ``data`` holds the observations, ``pdata`` is ``data`` without them
    (:func:`inference.model.likelihood.without_observations`). Arrays come back with a leading
    (chains, draws) shape; the prior's chain axis has length 1. Without ``predictive``
    only the log-likelihood is computed.
    """
    lead = np.shape(samples[latents[0]])[:2] if latents else (1, 1)
    n = int(np.prod(lead))
    # through host memory: draws of parallel chains are sharded over the host devices,
    # and a program fed sharded arrays runs partitioned, far slower
    flat = {k: jnp.asarray(np.reshape(np.asarray(samples[k]), (n, *np.shape(samples[k])[2:])))
            for k in latents}

    with_prior = predictive and prior_draws > 0
    n_all, batch = n, min(BATCH, n)
    if with_prior:
        # whole batches only: a remainder would be a second copy of the model's program;
        # the spare prior draws are made and dropped
        batch = min(BATCH, n + prior_draws)
        n_all = -(-(n + prior_draws) // batch) * batch

    def latents_one(key):
        tr = _trace(model, pdata, None, key)
        return {k: tr[k]["value"] for k in latents}

    # the point-wise likelihood needs the curve at every sweep: a model whose sweeps'
    # likelihood is folded (inference.speed.residual_fold) evaluates it for this trace
    data_pw = {**data, POINTWISE: True}

    def one(args):
        values, key = args
        tr = _trace(model, data_pw, values, None)
        out = {f"ll:{k}": tr[k]["fn"].log_prob(tr[k]["value"])
               for k in OBSERVED_SITES if k in tr}
        if predictive:
            sim = _trace(model, pdata, values, key)
            out.update({f"pp:{k}": s["value"] for k, s in sim.items() if _kept(k, s)})
        return out

    @jax.jit
    def program(flat, k_post, k_prior):
        # the prior's draws go through the posterior's function (its predictive trace, given
        # latents drawn from the prior, is the prior trace): one copy of the model's
        # predictive in the program, not two (a map of its own for the prior would double
        # the compilation)
        keys = jax.random.split(k_post, n)
        if with_prior:
            k_lat, k_prior = jax.random.split(k_prior)
            extra = jax.vmap(latents_one)(jax.random.split(k_lat, n_all - n))
            flat = {k: jnp.concatenate([flat[k], extra[k]]) for k in latents}
            keys = jnp.concatenate([keys, jax.random.split(k_prior, n_all - n)])
        return jax.lax.map(one, (flat, keys), batch_size=batch)

    res = jax.device_get(program(flat, key_post, key_prior))
    post = {k: v[:n] for k, v in res.items()
            if k.startswith("ll:") or k.split(":", 1)[1] in OBSERVED_SITES}
    prior = {k.split(":", 1)[1]: v[n:n + prior_draws] for k, v in res.items()
             if k.startswith("pp:")} if with_prior else {}
    groups: dict[str, dict[str, np.ndarray]] = {"log_likelihood": {},
                                                "posterior_predictive": {},
                                                "prior": {}, "prior_predictive": {}}
    for k, v in post.items():
        tag, name = k.split(":", 1)
        group = "log_likelihood" if tag == "ll" else "posterior_predictive"
        groups[group][name] = np.reshape(np.asarray(v), (*lead, *np.shape(v)[1:]))
    for k, v in prior.items():
        group = "prior_predictive" if k in OBSERVED_SITES else "prior"
        groups[group][k] = np.asarray(v)[None]
    return groups


def _kept(name: str, site: dict[str, Any]) -> bool:
    # what a predictive trace returns: the observations, and (for the prior's draws) the
    # latents and deterministic sites; not a factor (an observed site to numpyro)
    return (site["type"] == "deterministic"
            or (site["type"] == "sample" and (name in OBSERVED_SITES or not site["is_observed"])))


# numpyro's names -> arviz's; lp is minus the potential energy, tree_depth from n_steps
_STAT_NAMES = {"potential_energy": "lp", "adapt_state.step_size": "step_size",
               "num_steps": "n_steps", "accept_prob": "acceptance_rate"}


def sample_stats(extra: dict[str, Any]) -> dict[str, np.ndarray]:
    """arviz's sample_stats from numpyro's extra fields (grouped by chain), with arviz's
    names and conventions (as ``az.from_numpyro`` makes them)."""
    out: dict[str, np.ndarray] = {}
    for stat, value in extra.items():
        if isinstance(value, (dict, tuple)):
            continue
        value = np.asarray(value)
        name = _STAT_NAMES.get(stat, stat)
        out[name] = -value if stat == "potential_energy" else value.copy()
        if stat == "num_steps":
            out["tree_depth"] = np.log2(value).astype(int) + 1
    return out


def observed_data(data: dict[str, Any], sites: Any) -> dict[str, np.ndarray]:
    """The observed values of ``sites`` (observation site names) in model inputs ``data``."""
    return {k: np.asarray(data[OBSERVED_DATA_KEYS[k]]) for k in sites
            if k in OBSERVED_DATA_KEYS and data.get(OBSERVED_DATA_KEYS[k]) is not None}
