"""A NUTS run short of its ESS target goes on from where it stopped
(inference.sampling.sample.run_nuts ``ess_target``, ``max_extensions``; the comparison's
``sampling.extensions``), on a toy posterior N(0, 1)."""

import numpy as np
import numpyro
import numpyro.distributions as dist

from beadrod.inference.sampling.sample import run_nuts

# run_nuts labels its output by the data's protocols and sweeps: one of each
ONE = {"f0": np.ones(1), "q_idx": np.zeros(0, int), "amplitude": np.ones(1),
       "proto": np.zeros(1, int), "direction": np.zeros(1)}
KW = dict(num_warmup=50, num_samples=30, num_chains=2, predictive=False, seed=3,
          init="median", max_extensions=2)


def _toy(data):
    numpyro.sample("x", dist.Normal(0.0, 1.0))


def test_a_run_short_of_its_target_goes_on_and_keeps_its_first_draws():
    # a target met: no extension
    met = run_nuts(_toy, ONE, ess_target=1.0, **KW)
    assert met.idata.posterior.attrs["extensions"] == 0
    assert met.idata.posterior.sizes["draw"] == 30 and "extension_s" not in met.timings
    # an unreachable target: every extension is drawn
    longer = run_nuts(_toy, ONE, ess_target=1e9, **KW)
    post = longer.idata.posterior
    assert post.sizes["draw"] == 90 and post.attrs["num_samples"] == 90
    assert post.attrs["extensions"] == 2 and longer.timings["extension_s"] > 0
    assert longer.idata.sample_stats.sizes["draw"] == 90
    x = np.asarray(post["x"])
    # the first draws are the run's without extensions, bit for bit
    np.testing.assert_array_equal(x[:, :30], np.asarray(met.idata.posterior["x"]))
    # the chains went on: neither restarted nor repeated
    assert not np.array_equal(x[:, 30:60], x[:, :30])
    assert not np.array_equal(x[:, 60:], x[:, 30:60])
    # ... with the first run's adaptation, from its last state: the extensions' draws are
    # the same posterior's (N(0, 1): 120 draws, ESS >= 60 at worst)
    later = x[:, 30:].ravel()
    assert abs(later.mean()) < 4.0 / np.sqrt(later.size / 2) and 0.6 < later.std() < 1.5
