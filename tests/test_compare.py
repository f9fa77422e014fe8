"""The evidence ranking and the LOO-PIT check of inference.evidence.ranking."""

import math

import arviz as az
import numpy as np
import pytest
from scipy import stats

from beadrod.inference.evidence.ranking import log_bayes_factor, loo_pit_summary, rank_evidence


def _e(name, z, err, ok=True, baseline=False):
    return {"name": name, "log_z": z, "log_z_err": err, "ok": ok, "baseline": baseline}


def test_rank_evidence_best_gap_and_baseline_lead():
    r = rank_evidence([_e("hertz", -512.3, 0.3), _e("visco", -480.1, 0.4),
                       _e("jkr", -400.0, 0.1, ok=False), _e("base", -470.0, 0.5, baseline=True),
                       _e("none", None, None)])
    assert r["best"] == "visco" and r["runner_up"] == "hertz"  # failed jkr never wins
    assert r["gap"] == pytest.approx(32.2) and r["gap_err"] == pytest.approx(0.5)
    assert r["baseline"] == "base"
    assert r["baseline_lead"] == pytest.approx(10.1)
    assert r["baseline_lead_err"] == pytest.approx(math.hypot(0.5, 0.4))
    assert r["reference"] == "visco" and r["delta"]["visco"] == (0.0, 0.0)
    assert r["delta"]["jkr"][0] == pytest.approx(80.1)
    assert "none" not in r["delta"]


def test_rank_evidence_without_a_passing_law():
    r = rank_evidence([_e("a", -10.0, 0.1, ok=False), _e("b", -12.0, 0.1, ok=False),
                       _e("base", -1.0, 0.1, baseline=True)])
    assert r["best"] is None and r["baseline_lead"] is None
    assert r["reference"] == "a" and r["delta"]["b"][0] == pytest.approx(-2.0)


def test_log_bayes_factor_of_pairs():
    bf, err = log_bayes_factor((-10.0, 0.3), (-12.0, 0.4))
    assert bf == pytest.approx(2.0) and err == pytest.approx(0.5)


def _normal_idata(sigma_model: float, seed: int = 0, n: int = 200, draws: int = 1000):
    """Data y ~ N(0, 1); a model with known noise sigma_model and a flat-prior mean."""
    rng = np.random.default_rng(seed)
    y = rng.normal(0.0, 1.0, n)
    mu = y.mean() + sigma_model / np.sqrt(n) * rng.normal(size=(2, draws))
    rep = mu[..., None] + sigma_model * rng.normal(size=(2, draws, n))
    ll = stats.norm.logpdf(y, loc=mu[..., None], scale=sigma_model)
    return az.from_dict(posterior={"mu": mu}, posterior_predictive={"y": rep},
                        log_likelihood={"y": ll}, observed_data={"y": y})


def test_loo_pit_calibrated_model_passes():
    s = loo_pit_summary(_normal_idata(1.0), "y")
    assert s["calibrated"] and s["n"] == 200
    assert s["tails"] == pytest.approx(0.10, abs=0.06) and s["mean"] == pytest.approx(0.5,
                                                                                      abs=0.06)


def test_loo_pit_overconfident_model_fails():
    # noise three times too small: the PIT piles at 0 and 1; a PIT value lies in the outer
    # 5 % tails when |y - mu| > 1.645 sigma_model = 1.645 / 3, probability 0.58
    s = loo_pit_summary(_normal_idata(1.0 / 3.0), "y")
    assert not s["calibrated"] and s["ks_p"] < 1e-6
    assert s["tails"] == pytest.approx(2 * stats.norm.sf(stats.norm.ppf(0.95) / 3), abs=0.1)
