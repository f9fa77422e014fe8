"""NUTS sampling in float64 with fixed seeds, returned as ArviZ InferenceData.

The InferenceData has named dimensions (``protocol`` with the dataset's protocol ids,
``protocol_q``, ``sweep``; :mod:`inference.model.variables`), units and descriptions as
variable attributes, and numpyro's full sample statistics (lp, step size, tree depth,
acceptance rate, divergences, energy). Nothing here writes files: workflows.pipeline.idata_io
persists the result.

Entry points call :func:`configure` before anything initialises JAX (host devices
cannot be added afterwards; importing jaxns initialises the backend, so configure
comes first). Chains run with ``chain_method='parallel'`` when there are as many
devices as chains, else 'sequential' (still deterministic for a given seed).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import arviz as az
import jax
import numpy as np
import numpyro
from numpyro.infer import MCMC, NUTS, init_to_median

from beadrod.inference.evidence.log_z import latent_site_names
from beadrod.inference.model.likelihood import without_observations
from beadrod.inference.model.variables import SAMPLE_STATS, SITE_DIMS, VARIABLES
from beadrod.inference.sampling.draws import fit_draws, observed_data, sample_stats
from beadrod.models.law import sampler_site

# unconstrained units: a fraction of a typical posterior width, enough that the chains'
# starts differ, far less than any basin the mode search separates
_INIT_JITTER = 0.02

__all__ = ["configure", "FitResult", "run_nuts", "nuts_kernel", "draw_program", "draw_cost",
           "idata_coords", "describe", "EXTRA_FIELDS"]

# everything arviz turns into sample_stats: lp (from potential_energy), step_size,
# n_steps and tree_depth (from num_steps), acceptance_rate, diverging, energy
EXTRA_FIELDS = ("diverging", "energy", "potential_energy", "num_steps", "accept_prob",
                "adapt_state.step_size")


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
    modes: Any = None  # inference.sampling.modes.ModeSearch when the chains started at a mode


def _chain_method(num_chains: int, chain_method: str | None) -> str:
    if chain_method is not None:
        return chain_method
    return "parallel" if jax.local_device_count() >= num_chains else "sequential"


def idata_coords(data: dict[str, Any],
                 protocol_ids: Sequence[Any] | None = None) -> dict[str, np.ndarray]:
    """Coordinates of the named dimensions for model inputs ``data``.

    ``protocol``: ``protocol_ids`` (the dataset's ids, in the order of ``data['f0']``),
    default 0..P-1; ``protocol_q``: the ids of the protocols with a reference Q
    (``data['q_idx']``); ``sweep``: 0..S-1 over the included drive sweeps.
    """
    if data.get("f0") is not None:
        n_p = int(np.shape(data["f0"])[0])
    else:
        n_p = int(data["n_protocols"])
    ids = np.arange(n_p) if protocol_ids is None else np.asarray(list(protocol_ids))
    if ids.shape != (n_p,):
        raise ValueError(f"{ids.size} protocol ids for {n_p} protocols")
    return {"protocol": ids, "protocol_q": ids[np.asarray(data["q_idx"], int)],
            "sweep": np.arange(int(np.shape(data["amplitude"])[0]))}


def _sweep_coords(data: dict[str, Any], protocols: np.ndarray) -> dict[str, Any]:
    # non-index coordinates: each sweep names its protocol, direction and amplitude
    proto = np.asarray(data["proto"], int)
    direction = np.where(np.asarray(data["direction"]) > 0.5, "down", "up")
    return {"sweep_protocol": ("sweep", protocols[proto]),
            "sweep_direction": ("sweep", direction),
            "drive_amplitude": ("sweep", np.asarray(data["amplitude"], float),
                                {"units": "m", "description": "displacement amplitude "
                                 "delta_a at resonance of the drive sweep"})}


def describe(idata: az.InferenceData) -> az.InferenceData:
    """Set ``units`` and ``description`` attributes on every variable that
    :mod:`inference.model.variables` knows, in every group (in place; returns ``idata``)."""
    for group in idata.groups():
        ds = idata[group]
        table = SAMPLE_STATS if group == "sample_stats" else VARIABLES
        for name in ds.data_vars:
            info = table.get(str(name)) or _sampler_info(str(name), table)
            if info is None:
                continue
            if group == "log_likelihood":
                # a log density has no unit of its own: describe, do not give units
                ds[name].attrs["description"] = f"pointwise log-likelihood of: {info.description}"
            else:
                ds[name].attrs["description"] = info.description
                if info.units:
                    ds[name].attrs["units"] = info.units
    return idata


def _sampler_info(name: str, table: dict) -> Any:
    # the sample site of a parameter with a sampler scale (models.law.sampler_site)
    base = next((k for k in table if sampler_site(k) == name), None)
    if base is None:
        return None
    return type(table[base])("", f"{base} times its law's sampler scale: the coordinate "
                                 f"NUTS moves in ({table[base].description})")


def nuts_kernel(model: Callable, *, target_accept: float = 0.9, max_tree_depth: int = 10,
                dense_mass: bool = True) -> NUTS:
    """The NUTS kernel every fit uses (:func:`run_nuts`'s defaults)."""
    # start at the prior median: numpyro's default (uniform in (-2, 2) unconstrained)
    # puts log delta0 [m] near 0, i.e. a metre-sized overlap, where a chain can stall
    return NUTS(model, target_accept_prob=target_accept, max_tree_depth=max_tree_depth,
                dense_mass=dense_mass, init_strategy=init_to_median(num_samples=15))


def _extend(mcmc: MCMC, data: dict[str, Any], samples: dict, extra: dict,
            ess_target: float | None, max_extensions: int) -> tuple[dict, dict, int]:
    # run_nuts's extensions: the draws and extra fields of every run, appended along the
    # draw axis
    from beadrod.inference.sampling.diagnostics import ess_minima

    done = 0
    while ess_target is not None and done < max_extensions:
        if min(ess_minima({k: np.asarray(v) for k, v in samples.items()})) >= ess_target:
            break
        mcmc.post_warmup_state = mcmc.last_state
        mcmc.run(mcmc.post_warmup_state.rng_key, data, extra_fields=EXTRA_FIELDS)
        more, more_extra = (mcmc.get_samples(group_by_chain=True),
                            mcmc.get_extra_fields(group_by_chain=True))
        samples = {k: np.concatenate([v, more[k]], axis=1) for k, v in samples.items()}
        extra = {k: np.concatenate([v, more_extra[k]], axis=1) for k, v in extra.items()}
        done += 1
    return samples, extra, done


def draw_program(model: Callable, data: dict[str, Any], *, init_params: dict | None = None,
                 num_warmup: int = 200, num_draws: int = 200,
                 seed: int = 0) -> tuple[Callable[[], float], float]:
    """(run, leapfrog steps per draw): ``run()`` runs one NUTS chain's ``num_draws``
    post-warmup draws of :func:`nuts_kernel` as one compiled loop (compiled here) and
    returns its wall time [s]. :func:`draw_cost` times it; a benchmark that compares laws
    times theirs in turns (machines here drift by tens of percent within minutes).

    Why not the NUTS run's wall time: it holds the compilation, whose noise can exceed a
    fast law's whole sampling. Why not a gradient timed call by call from Python: NUTS
    takes its leapfrog steps inside one XLA program, so a per-call dispatch is not part of
    their cost, while
    the sampler's own work per step (tree building, the mass matrix) is, and both are
    what this loop times. The chain runs on one thread; ``init_params`` (unconstrained)
    as :func:`run_nuts` takes them.
    """
    kernel = nuts_kernel(model)
    mcmc = MCMC(kernel, num_warmup=num_warmup, num_samples=num_draws, num_chains=1,
                progress_bar=False)
    mcmc.warmup(jax.random.PRNGKey(seed), data=data, init_params=init_params)
    state = mcmc.last_state

    # the data closed over, as MCMC.run holds them (jit_model_args=False): constants of the
    # program, so XLA folds what depends on them alone, as it does in a fit
    @jax.jit
    def draws(state):
        def body(s, _):
            s = kernel.sample(s, (), {"data": data})
            return s, s.num_steps
        return jax.lax.scan(body, state, None, length=num_draws)

    _, steps = jax.block_until_ready(draws(state))

    def run() -> float:
        t0 = time.perf_counter()
        jax.block_until_ready(draws(state))
        return time.perf_counter() - t0

    return run, float(np.mean(np.asarray(steps)))


def draw_cost(model: Callable, data: dict[str, Any], *, init_params: dict | None = None,
              num_warmup: int = 200, num_draws: int = 200, seed: int = 0,
              repeats: int = 3) -> tuple[float, float]:
    """(seconds per post-warmup draw, leapfrog steps per draw) of one NUTS chain: the
    :func:`draw_program` loop timed after a call to compile (best of ``repeats``)."""
    run, steps = draw_program(model, data, init_params=init_params, num_warmup=num_warmup,
                              num_draws=num_draws, seed=seed)
    return min(run() for _ in range(repeats)) / num_draws, steps


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
    coords: dict[str, Sequence[Any]] | None = None,
    dims: dict[str, list[str]] | None = None,
    init: str = "modes",
    ess_target: float | None = None,
    max_extensions: int = 0,
) -> FitResult:
    """NUTS on ``model(data)``; returns InferenceData with posterior, sample_stats,
    log_likelihood, observed_data and (``predictive``) prior and posterior predictive.

    Same ``seed`` -> bit-identical draws. ``prior_data`` is ``data`` without the
    observations (see :func:`inference.model.likelihood.without_observations`); both
    predictives are simulated from it. Timings: 'nuts_s' (compile + warmup + sampling,
    one compilation), 'predictive_s', and with ``measure_compile`` 'compile_s', the
    cost of a 1-warmup/1-sample run of the same kernel (compilation alone, measured on a
    second call; every run() recompiles with progress_bar=False, so nuts_s - compile_s
    is the sampling cost) and 'sampling_s'.

    ``coords`` overrides the coordinates of :func:`idata_coords` (pass
    ``{"protocol": dataset.protocol_ids}``; ``protocol_q`` then follows from it);
    ``dims`` adds to or overrides :data:`inference.model.variables.SITE_DIMS`.

    ``init``: 'modes' (default) starts every chain near the deepest mode of a multi-start
    search (:func:`inference.sampling.modes.find_modes`; its cost is 'mode_search_s', its modes
    are ``FitResult.modes`` and the posterior's attrs 'modes_found', 'mode_gap');
    'median' starts them at the prior median, as numpyro's init_to_median.

    ``ess_target``: where the smallest bulk or tail ESS of the draws (every variable, as
    :func:`inference.sampling.diagnostics.check` counts them) is below it, the chains go on from
    where they stopped, with the same adaptation, for ``num_samples`` more draws each, up
    to ``max_extensions`` times (Vehtari et al. 2021: too few effective draws, run
    longer). Why: a chain that wanders into a tail it leaves slowly (an exponential tail in
    the unconstrained space, as a parameter's posterior near its prior's bound has: one
    chain of four at E -> 250 GPa for 43 draws, Maugis-Dugdale on the embedded
    hertz_dynamics data) leaves too few effective draws in an otherwise sound run; more
    draws give its excursion its due weight. The posterior's attrs say how many extensions
    were drawn ('extensions'; 'num_samples' counts all draws); the timings their cost
    ('extension_s', in 'nuts_s').
    """
    if init not in ("modes", "median"):
        raise ValueError(f"init must be 'modes' or 'median', not {init!r}")
    def make_kernel():
        return nuts_kernel(model, target_accept=target_accept, max_tree_depth=max_tree_depth,
                           dense_mass=dense_mass)

    kernel = make_kernel()
    method = _chain_method(num_chains, chain_method)
    key = jax.random.PRNGKey(seed)
    k_run, k_prior, k_post = jax.random.split(key, 3)
    modes, init_params, search_s = None, None, 0.0
    if init == "modes":
        from beadrod.inference.sampling.modes import find_modes

        tm = time.perf_counter()
        modes = find_modes(model, data, seed=seed)
        # a small spread between the chains' starts, so that R-hat still tests mixing
        rng = np.random.default_rng(seed)
        init_params = {k: v + _INIT_JITTER * rng.standard_normal((num_chains, *np.shape(v)))
                       for k, v in modes.best.items()}
        if num_chains == 1:
            init_params = {k: v[0] for k, v in init_params.items()}
        search_s = time.perf_counter() - tm
    mcmc = MCMC(kernel, num_warmup=num_warmup, num_samples=num_samples,
                num_chains=num_chains, chain_method=method, progress_bar=False)
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
            probe.run(k_run, data, extra_fields=EXTRA_FIELDS, init_params=init_params)
            jax.block_until_ready(probe.get_samples())
            costs.append(time.perf_counter() - tc)
        compile_s = min(costs)
    t0 = time.perf_counter()
    mcmc.run(k_run, data, extra_fields=EXTRA_FIELDS, init_params=init_params)
    samples = mcmc.get_samples(group_by_chain=True)
    extra = mcmc.get_extra_fields(group_by_chain=True)
    jax.block_until_ready(samples)
    t1 = time.perf_counter()
    samples, extra, extensions = _extend(mcmc, data, samples, extra, ess_target, max_extensions)
    t2 = time.perf_counter()
    pdata = prior_data if prior_data is not None else without_observations(data)
    latents = latent_site_names(model, {"data": data})
    groups = fit_draws(model, data, pdata, samples, latents, key_post=k_post,
                       key_prior=k_prior, prior_draws=prior_draws, predictive=predictive)
    t3 = time.perf_counter()
    user = dict(coords or {})
    all_coords = idata_coords(data, user.get("protocol"))
    all_coords.update({k: np.asarray(list(v)) for k, v in user.items()})
    all_dims = {**SITE_DIMS, **(dims or {})}
    # built here, not by az.from_numpyro: that one runs the model eagerly (slow for the
    # table laws) and counts the law-domain factor as an observation
    idata = az.from_dict(
        posterior={k: np.asarray(v) for k, v in samples.items()},
        sample_stats=sample_stats(extra),
        observed_data=observed_data(data, groups["log_likelihood"]),
        coords=all_coords, dims=all_dims,
        **{g: v for g, v in groups.items() if v})
    extra = _sweep_coords(data, all_coords["protocol"])
    amp_extra = ({"amp_sweep_protocol": ("amp_sweep", all_coords["protocol"][
        np.asarray(data["amp_proto"], int)])} if "amp_proto" in data else {})
    for group in idata.groups():
        ds = idata[group]
        for dim, coords in (("sweep", extra), ("amp_sweep", amp_extra)):
            if dim in ds.dims:
                for name, coord in coords.items():  # in place: the group keeps its identity
                    ds.coords[name] = coord
    describe(idata)
    timings = {"nuts_s": t2 - t0, "predictive_s": t3 - t2}
    if extensions:
        timings["extension_s"] = t2 - t1
    if modes is not None:
        timings["mode_search_s"] = search_s
    if measure_compile:  # absent otherwise (not NaN: NaN is not JSON)
        timings.update(compile_s=compile_s, sampling_s=t2 - t0 - compile_s)
    attrs = {"seed": seed, "num_chains": num_chains, "num_warmup": num_warmup,
             "num_samples": num_samples * (1 + extensions), "extensions": extensions,
             "chain_method": method, **timings}
    if data_hash is not None:
        attrs["data_hash"] = data_hash
    spec = getattr(model, "spec", None)
    if spec is not None:
        attrs["model"] = spec.name
    if modes is not None:
        attrs["modes_found"] = len(modes.log_density)
        if modes.gap is not None:
            attrs["mode_gap"] = modes.gap
    attrs.update(extra_attrs or {})
    for k, v in attrs.items():
        idata.posterior.attrs[k] = v
    return FitResult(idata, mcmc, timings, modes)
