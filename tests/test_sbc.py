"""Simulation-based calibration of the viscoelastic model and of Hertz with hysteresis;
its ECDF band and files."""

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from beadrod.inference.evidence.sbc import (
    SBCResult,
    dkw_halfwidth,
    ecdf_difference,
    run_sbc,
    uniformity_pvalue,
)
from beadrod.inference.model.likelihood import design_inputs
from beadrod.inference.model.numpyro_models import ModelSpec
from beadrod.models.scene import builtin_scene
from beadrod.workflows.pipeline.sbc_outputs import plot_ecdf, write_sbc_json

SCENE = builtin_scene("paper")  # the paper's bead on its rod
SPEC = ModelSpec("viscoelastic", rung="paper_eq25")


def test_uniformity_test_accepts_uniform_and_rejects_biased_ranks():
    rng = np.random.default_rng(0)
    assert uniformity_pvalue(rng.integers(0, 101, 200), 100) > 0.01
    assert uniformity_pvalue(np.zeros(50, int), 100) < 1e-6  # truth always below the posterior
    assert uniformity_pvalue(rng.integers(40, 61, 200), 100) < 1e-6  # overdispersed posterior


@pytest.mark.slow  # in `-m slow`, run before an issue is resolved (keeps CI under 12 min)
def test_sbc_small_runs_and_plots(tmp_path):
    des = design_inputs(SCENE, n_protocols=3, amplitudes=np.linspace(8e-9, 40e-9, 3))
    res = run_sbc(SPEC, des, n_replicates=4, num_warmup=150, num_samples=100, thin=1,
                  seed=0, params=("eta", "young"))
    assert isinstance(res, SBCResult) and set(res.ranks) == {"eta", "young"}
    for r in res.ranks.values():
        assert r.shape == (4,) and np.all((r >= 0) & (r <= 100))
    assert all(0.0 <= p <= 1.0 for p in res.pvalues.values())
    out = plot_ecdf(res, tmp_path / "sbc.png")
    assert out.exists() and out.stat().st_size > 1000
    back = json.loads(write_sbc_json(res, tmp_path / "sbc.json").read_text())
    assert back["ranks"] == {k: v.tolist() for k, v in res.ranks.items()}
    assert back["n_draws"] == 100 and len(back["divergences"]) == 4
    assert not list(tmp_path.glob(".*part*"))  # atomic writes leave no temporary


def test_dkw_band_matches_massart_bound_and_covers_uniform_ranks():
    # Massart (1990): P(sup|F_n - F| > eps) <= 2 exp(-2 n eps^2) = alpha
    eps = dkw_halfwidth(100, 0.05)
    assert 2 * math.exp(-2 * 100 * eps**2) == pytest.approx(0.05, rel=1e-12)
    assert eps == pytest.approx(0.13581, abs=1e-5)
    with pytest.raises(ValueError):
        dkw_halfwidth(0)
    rng = np.random.default_rng(3)
    n_draws = 99
    good = SBCResult({"a": rng.integers(0, n_draws + 1, 400)}, n_draws, {"a": 1.0}, 0.0)
    grid, diff, eps = ecdf_difference(good)
    assert grid[0] == 0.0 and grid[-1] == 1.0 and diff["a"].shape == grid.shape
    assert np.max(np.abs(diff["a"])) < eps  # uniform ranks stay inside the band
    # a posterior biased high puts the truth low: every rank in the bottom fifth
    biased = SBCResult({"a": rng.integers(0, 20, 400)}, n_draws, {"a": 0.0}, 0.0)
    _, diff, eps = ecdf_difference(biased)
    assert diff["a"][np.searchsorted(grid, 0.2)] == pytest.approx(0.8, abs=0.01)
    assert np.max(diff["a"]) > eps


def _full_sbc(n_replicates: int = 100, spec: ModelSpec = SPEC,
              params: tuple[str, ...] = ("eta", "young", "delta0_scatter", "sigma_shift"),
              **design: object) -> SBCResult:
    import jax

    jax.config.update("jax_enable_x64", True)  # a fresh process: conftest did not run
    des = design_inputs(SCENE, n_protocols=4, amplitudes=np.linspace(8e-9, 40e-9, 4),
                        **design)
    return run_sbc(spec, des, n_replicates=n_replicates, num_warmup=300, num_samples=100,
                   thin=3, seed=1, params=params)


def _in_own_process(*args: object, **kwargs: object) -> SBCResult:
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        return pool.submit(_full_sbc, *args, **kwargs).result(timeout=3000)


@pytest.mark.slow
def test_sbc_full_viscoelastic_ranks_uniform(tmp_path):
    # The SBC runs in a Python process of its own. In three slow-suite runs out of three
    # XLA crashed (segfault or abort in deserialize_executable, at the first replicate)
    # when it ran late in a long pytest worker; run alone it passed against the same
    # cache. The cause is not established (README); a fresh process lacks the history.
    res = _in_own_process()
    out_dir = Path(os.environ.get("BEADROD_ARTIFACTS", tmp_path))
    plot_ecdf(res, out_dir / "sbc_viscoelastic.png")
    # 4 tests: Bonferroni at 1 %
    assert res.min_pvalue() > 0.01 / 4, res.pvalues


@pytest.mark.slow
def test_sbc_hertz_hysteretic_ranks_uniform(tmp_path):
    """The hysteretic law's strength and exponent, read from the shift and the amplitude
    ratios together (design with amplitude_ratios), calibrated at the first-order rung."""
    spec = ModelSpec("hertz_hysteretic", rung="first_order")
    params = ("strength", "exponent", "young", "loss_exponent", "sigma_amp")
    res = _in_own_process(100, spec, params, amplitude_ratios=True)
    out_dir = Path(os.environ.get("BEADROD_ARTIFACTS", tmp_path))
    plot_ecdf(res, out_dir / "sbc_hertz_hysteretic.png")
    print({k: round(v, 4) for k, v in res.pvalues.items()}, "divergences",
          int(np.sum(res.divergences)))
    assert res.min_pvalue() > 0.01 / len(params), res.pvalues  # Bonferroni at 1 %
