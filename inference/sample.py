"""NUTS sampling in float64 with fixed seeds, ArviZ InferenceData, atomic netCDF I/O.

Entry points call :func:`configure` before anything initialises JAX (host devices
cannot be added afterwards; importing jaxns initialises the backend, so configure
comes first). Chains run with ``chain_method='parallel'`` when there are as many
devices as chains, else 'sequential' (still deterministic for a given seed).
"""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import arviz as az
import jax
import numpyro
from numpyro.infer import MCMC, NUTS, Predictive, init_to_median

from .likelihood import without_observations

__all__ = ["configure", "FitResult", "run_nuts", "save_idata", "load_idata"]


def configure(n_devices: int = 4, *, x64: bool = True) -> None:
    """Set the host device count (for parallel chains) and float64. Call before JAX runs."""
    numpyro.set_host_device_count(int(n_devices))
    if x64:
        jax.config.update("jax_enable_x64", True)
    if jax.local_device_count() < n_devices:
        # the backend started before the flag was set (importing this package starts it):
        # set XLA_FLAGS first, as workflows.cli.host_devices does
        warnings.warn(f"only {jax.local_device_count()} JAX host device(s): NUTS chains will "
                      "run sequentially (slower, same numbers)", RuntimeWarning, stacklevel=2)


@dataclass
class FitResult:
    """A NUTS run: the InferenceData and its cost (compile time is reported apart)."""

    idata: az.InferenceData
    mcmc: MCMC
    timings: dict[str, float] = field(default_factory=dict)


def _chain_method(num_chains: int, chain_method: str | None) -> str:
    if chain_method is not None:
        return chain_method
    return "parallel" if jax.local_device_count() >= num_chains else "sequential"


def run_nuts(
    model: Callable,
    data: dict[str, Any],
    *,
    num_warmup: int = 500,
    num_samples: int = 500,
    num_chains: int = 4,
    seed: int = 0,
    chain_method: str | None = None,
    target_accept: float = 0.9,
    max_tree_depth: int = 10,
    dense_mass: bool = True,
    prior_draws: int = 200,
    predictive: bool = True,
    prior_data: dict[str, Any] | None = None,
    data_hash: str | None = None,
    extra_attrs: dict[str, Any] | None = None,
    measure_compile: bool = False,
) -> FitResult:
    """NUTS on ``model(data)``; returns InferenceData with posterior, sample_stats,
    log_likelihood, observed_data and (``predictive``) prior and posterior predictive.

    Same ``seed`` -> bit-identical draws. ``prior_data`` is ``data`` without the
    observations (see :func:`inference.likelihood.without_observations`); both
    predictives are simulated from it. Timings: 'nuts_s' (compile + warmup + sampling,
    one compilation), 'predictive_s', and with ``measure_compile`` 'compile_s', the
    cost of a 1-warmup/1-sample run of the same kernel (compilation alone, measured on a
    second call; every run() recompiles with progress_bar=False, so nuts_s - compile_s
    is the sampling cost) and 'sampling_s'.
    """
    # start at the prior median: numpyro's default (uniform in (-2, 2) unconstrained)
    # puts log delta0 [m] near 0, i.e. a metre-sized overlap, where a chain can stall
    def make_kernel():
        return NUTS(model, target_accept_prob=target_accept, max_tree_depth=max_tree_depth,
                    dense_mass=dense_mass, init_strategy=init_to_median(num_samples=15))

    kernel = make_kernel()
    method = _chain_method(num_chains, chain_method)
    mcmc = MCMC(kernel, num_warmup=num_warmup, num_samples=num_samples,
                num_chains=num_chains, chain_method=method, progress_bar=False)
    key = jax.random.PRNGKey(seed)
    k_run, k_prior, k_post = jax.random.split(key, 3)
    compile_s = float("nan")
    if measure_compile:
        # a 1+1-iteration run costs the compilation of the same loop and nothing else
        # (run twice: the first call also pays one-off tracing of the model's pieces,
        # which the main run below does not pay again)
        costs = []
        for _ in range(2):
            # a fresh MCMC and kernel each time: re-running one MCMC object, or a kernel
            # another MCMC initialised, breaks 'vectorized' chains (numpyro 0.22)
            probe = MCMC(make_kernel(), num_warmup=1, num_samples=1, num_chains=num_chains,
                         chain_method=method, progress_bar=False)
            tc = time.perf_counter()
            probe.run(k_run, data, extra_fields=("diverging", "energy"))
            jax.block_until_ready(probe.get_samples())
            costs.append(time.perf_counter() - tc)
        compile_s = min(costs)
    t0 = time.perf_counter()
    mcmc.run(k_run, data, extra_fields=("diverging", "energy"))
    jax.block_until_ready(mcmc.get_samples())
    t2 = time.perf_counter()
    prior = post_pred = None
    pdata = prior_data if prior_data is not None else without_observations(data)
    if predictive:
        prior = Predictive(model, num_samples=prior_draws)(
            k_prior, pdata)
        samples = mcmc.get_samples()
        post_pred = Predictive(model, posterior_samples=samples)(
            k_post, pdata)
        obs_names = [k for k in ("f0_obs", "shift_obs", "q_obs") if k in post_pred]
        post_pred = {k: post_pred[k] for k in obs_names}
        prior_pred = {k: prior[k] for k in obs_names if k in prior}
        prior = {k: v for k, v in prior.items() if k not in obs_names}
    t3 = time.perf_counter()
    kw: dict[str, Any] = {"log_likelihood": True}
    if predictive:
        kw.update(prior=prior, posterior_predictive=post_pred)
    idata = az.from_numpyro(mcmc, **kw)
    if predictive and prior_pred:
        # from_numpyro puts observed-site draws of `prior` into prior_predictive only
        # when given together; add them explicitly (shapes: 1 chain x draws).
        pp = az.from_dict(prior_predictive={k: v[None] for k, v in prior_pred.items()})
        idata.extend(pp)
    timings = {"nuts_s": t2 - t0, "predictive_s": t3 - t2}
    if measure_compile:  # absent otherwise (not NaN: NaN is not JSON)
        timings.update(compile_s=compile_s, sampling_s=t2 - t0 - compile_s)
    attrs = {"seed": seed, "num_chains": num_chains, "num_warmup": num_warmup,
             "num_samples": num_samples, "chain_method": method, **timings}
    if data_hash is not None:
        attrs["data_hash"] = data_hash
    spec = getattr(model, "spec", None)
    if spec is not None:
        attrs["model"] = spec.name
    attrs.update(extra_attrs or {})
    for k, v in attrs.items():
        idata.posterior.attrs[k] = v
    return FitResult(idata, mcmc, timings)


def save_idata(idata: az.InferenceData, path: str | os.PathLike) -> Path:
    """Write ``idata`` to netCDF atomically (temporary file in the folder, then rename)."""
    from workflows._io import atomic_path

    with atomic_path(path) as tmp:
        idata.to_netcdf(str(tmp))
    return Path(path)


def load_idata(path: str | os.PathLike) -> az.InferenceData:
    """Read an InferenceData written by :func:`save_idata` (fully loaded, file closed)."""
    idata = az.from_netcdf(str(path))
    idata.load()
    return idata
