"""The multi-start mode search that places NUTS (inference.sampling.modes), on a toy with two
modes of known depth, and the zero likelihood outside a law's domain."""

import jax.numpy as jnp
import numpy as np
import numpyro
import numpyro.distributions as dist
import pytest
from jax.scipy.special import logsumexp

from beadrod.inference.sampling.modes import find_modes
from beadrod.inference.sampling.sample import run_nuts

# prior N(0, 1); likelihood: two narrow bumps (width W) at A (near the prior median) and B,
# B's 12 nats taller. Peak log densities, closed form: log N(m; 0, 1) + log bump height
A, B, W, LIFT = 0.5, 2.5, 0.05, 12.0


def _toy(data):
    x = numpyro.sample("x", dist.Normal(0.0, 1.0))
    numpyro.factor("bumps", logsumexp(jnp.stack([
        -0.5 * ((x - A) / W) ** 2, LIFT - 0.5 * ((x - B) / W) ** 2])))


def _peak(m, lift):
    return -0.5 * m**2 - 0.5 * np.log(2 * np.pi) + lift


def test_finds_both_modes_deepest_first():
    ms = find_modes(_toy, {}, starts=32, steps=400, seed=0)
    assert len(ms.log_density) == 2
    assert float(ms.best["x"]) == pytest.approx(B, abs=0.01)
    assert ms.log_density[0] == pytest.approx(_peak(B, LIFT), abs=0.05)
    assert ms.gap == pytest.approx(_peak(B, LIFT) - _peak(A, 0.0), abs=0.1)


def test_chains_start_in_the_deepest_mode_not_the_nearest():
    # run_nuts labels its output by the data's protocols and sweeps: one of each
    one = {"f0": np.ones(1), "q_idx": np.zeros(0, int), "amplitude": np.ones(1),
           "proto": np.zeros(1, int), "direction": np.zeros(1)}
    kw = dict(num_warmup=100, num_samples=100, num_chains=1, predictive=False)
    near = run_nuts(_toy, one, init="median", **kw)
    deep = run_nuts(_toy, one, **kw)
    # from the prior median the chain stays in the bump it starts next to (the barrier
    # between them is hundreds of nats deep); from the mode search, in the deeper one
    assert abs(float(near.idata.posterior["x"].mean()) - A) < 0.05
    assert abs(float(deep.idata.posterior["x"].mean()) - B) < 0.05
    assert deep.idata.posterior.attrs["modes_found"] == 2
    assert "mode_search_s" in deep.timings


def test_no_finite_start_is_a_clear_error():
    def nowhere(data):
        numpyro.sample("x", dist.Normal(0.0, 1.0))
        numpyro.factor("wall", -jnp.inf)

    with pytest.raises(RuntimeError, match="none of 16 starts"):
        find_modes(nowhere, {}, starts=16, steps=10)


@pytest.fixture(scope="module")
def paper_inputs():
    from beadrod import data as bd
    from beadrod.inference.model.likelihood import model_inputs

    return model_inputs(bd.process(bd.load_dataset(bd.default_path())))


def test_law_domain_gives_zero_likelihood_outside(paper_inputs):
    # Hertz's backbone table holds beyond x = 2: a sweep driven past it makes every
    # parameter point impossible, where the held value would have been fitted silently
    from numpyro.infer.util import log_density

    from beadrod.inference.model.numpyro_models import build_model

    model = build_model("hertz", rung="backbone")
    params = {"young": 200e9, "delta0_scatter": 0.1, "offset_down": -0.005,
              "sigma_shift": 0.01, "kappa_shift": 0.1, "tau_shift": 1e-3, "mu_logq": 4.0,
              "tau_logq": 0.4, "loss_exponent": 1.0, "sigma_amp": 0.02, "tau_amp": 0.01,
              "offset_amp_down": 0.0}
    inside, _ = log_density(model, (paper_inputs,), {}, params)
    assert np.isfinite(float(inside))
    far = dict(paper_inputs)
    far["amplitude"] = jnp.asarray(paper_inputs["amplitude"]).at[0].set(1e-5)  # x ~ 200
    outside, _ = log_density(model, (far,), {}, params)
    assert float(outside) == -np.inf
