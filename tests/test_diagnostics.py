"""Convergence gate, LOO report and comparison tables on hand-made InferenceData."""

import arviz as az
import numpy as np
import pytest

from beadrod.inference.evidence.log_z import EvidenceResult
from beadrod.inference.evidence.ranking import (
    DataHashMismatch,
    evidence_table,
    log_bayes_factor,
    loo_table,
)
from beadrod.inference.sampling.diagnostics import DiagnosticsFailed, check, loo_report


def make_idata(shift=0.0, divergences=0, n_chains=4, n_draws=500, seed=0, data_hash="h1",
               energy_ar=0.0):
    rng = np.random.default_rng(seed)
    y = rng.normal(size=20)
    # the exact posterior of a normal mean (unit noise, flat prior); `shift` separates chains
    sd = 1 / np.sqrt(20)
    mu = y.mean() + sd * (rng.normal(size=(n_chains, n_draws)) + shift * np.arange(n_chains)[:, None])
    div = np.zeros((n_chains, n_draws), bool)
    div.flat[:divergences] = True
    e = rng.normal(size=(n_chains, n_draws))
    energy = np.zeros_like(e)
    for t in range(n_draws):  # AR(1) energy: a large coefficient gives a small E-BFMI
        energy[:, t] = (energy_ar * energy[:, t - 1] if t else 0.0) + e[:, t]
    ll = -0.5 * (y[None, None, :] - mu[..., None]) ** 2 - 0.5 * np.log(2 * np.pi)
    idata = az.from_dict(posterior={"mu": mu}, sample_stats={"diverging": div, "energy": energy},
                         log_likelihood={"shift_obs": ll}, observed_data={"shift_obs": y})
    idata.posterior.attrs["data_hash"] = data_hash
    return idata


def test_good_run_passes():
    v = check(make_idata())
    assert v.passed and v.status == "ok" and v.rhat_max < 1.01 and v.divergences == 0
    assert v.ess_bulk_min > 1000 and v.bfmi_min > 0.3


def test_constant_elements_raise_no_warning():
    """A deterministic with constant elements (up-sweep predictions at x = 0) is masked
    out of the gate, and arviz's 0/0 on it is not reported as a warning."""
    import warnings

    idata = make_idata()
    mu = idata.posterior["mu"].values
    pred = np.stack([mu, np.zeros_like(mu)], axis=-1)
    idata.posterior["pred"] = (("chain", "draw", "pred_dim_0"), pred)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        v = check(idata)
    assert v.passed and np.isfinite(v.rhat_max)


def test_bad_mixing_fails_loudly_and_is_marked():
    idata = make_idata(shift=1.0)
    with pytest.warns(RuntimeWarning, match="FAILED"):
        v = check(idata)
    assert not v.passed and any("R-hat" in f for f in v.failures)
    assert idata.posterior.attrs["diagnostics"] == "FAILED"
    with pytest.raises(DiagnosticsFailed), pytest.warns(RuntimeWarning):
        check(idata, strict=True)


def test_divergences_low_ess_and_bfmi_fail():
    with pytest.warns(RuntimeWarning):
        v = check(make_idata(divergences=3))
    assert v.failures == ("3 divergent transitions > 0",)
    with pytest.warns(RuntimeWarning):
        v = check(make_idata(n_draws=60))
    assert any("bulk ESS" in f for f in v.failures)
    with pytest.warns(RuntimeWarning):
        v = check(make_idata(energy_ar=0.97))
    assert any("E-BFMI" in f for f in v.failures)


def test_loo_report_counts_pareto_k():
    r = loo_report(make_idata())
    assert r["n_points"] == 20 and r["k_good"] + r["k_bad"] + r["k_very_bad"] == 20
    assert r["reliable"] and np.isfinite(r["elpd_loo"])


def test_loo_table_refuses_mixed_data():
    a, b = make_idata(seed=1), make_idata(seed=2, data_hash="h2")
    with pytest.raises(DataHashMismatch, match="different data"):
        loo_table({"a": a, "b": b})
    t = loo_table({"a": a, "b": make_idata(seed=3)})
    assert set(t.index) == {"a", "b"} and (t["data_hash"] == "h1").all()


def test_evidence_table_and_agreement_flags():
    ns = lambda v, e: EvidenceResult("nested_sampling", v, e, 1.0)
    smc = lambda v, e: EvidenceResult("tempered_smc", v, e, 1.0)
    res = {"m1": {"nested_sampling": ns(-10.0, 0.1), "tempered_smc": smc(-10.1, 0.05)},
           "m2": {"nested_sampling": ns(-14.0, 0.1), "tempered_smc": smc(-16.0, 0.05)}}
    t = evidence_table(res, {"m1": "h", "m2": "h"})
    assert list(t.index) == ["m1", "m2"]
    assert bool(t.loc["m1", "agree"]) and not bool(t.loc["m2", "agree"])
    assert t.loc["m1", "log_bf_vs_best"] == 0.0 and t.loc["m2", "log_bf_vs_best"] < -3
    with pytest.raises(DataHashMismatch):
        evidence_table(res, {"m1": "h", "m2": "other"})
    with pytest.raises(DataHashMismatch, match="no data hash"):
        evidence_table(res, {"m1": "h"})
    bf, err = log_bayes_factor(ns(-10.0, 0.3), ns(-12.0, 0.4))
    assert bf == pytest.approx(2.0) and err == pytest.approx(0.5)
