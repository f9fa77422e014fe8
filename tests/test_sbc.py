"""Simulation-based calibration of the viscoelastic model."""

import os
import types
from pathlib import Path

import numpy as np
import pytest

from inference.likelihood import design_inputs
from inference.numpyro_models import ModelSpec
from inference.sbc import SBCResult, plot_ecdf, run_sbc, uniformity_pvalue
from models import materials

R = 7.938e-3
ST = materials.STAINLESS_STEEL
SCENE = types.SimpleNamespace(mass=float(materials.bead_mass(R, ST.density)),
                              load=float(materials.bead_weight(R, ST.density)),
                              radius=R, bead_material=ST, rod_material=ST)
SPEC = ModelSpec("viscoelastic", rung="paper_eq25")


def test_uniformity_test_accepts_uniform_and_rejects_biased_ranks():
    rng = np.random.default_rng(0)
    assert uniformity_pvalue(rng.integers(0, 101, 200), 100) > 0.01
    assert uniformity_pvalue(np.zeros(50, int), 100) < 1e-6  # truth always below the posterior
    assert uniformity_pvalue(rng.integers(40, 61, 200), 100) < 1e-6  # overdispersed posterior


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


@pytest.mark.slow
def test_sbc_full_viscoelastic_ranks_uniform(tmp_path):
    des = design_inputs(SCENE, n_protocols=4, amplitudes=np.linspace(8e-9, 40e-9, 4))
    res = run_sbc(SPEC, des, n_replicates=100, num_warmup=300, num_samples=100, thin=3,
                  seed=1, params=("eta", "young", "delta0_scatter", "sigma_shift"))
    out_dir = Path(os.environ.get("BEADROD_ARTIFACTS", tmp_path))
    plot_ecdf(res, out_dir / "sbc_viscoelastic.png")
    # 4 tests: Bonferroni at 1 %
    assert res.min_pvalue() > 0.01 / 4, res.pvalues
