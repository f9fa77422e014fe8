"""The loss-against-shift table (inference.evidence.loss_shift) and the law each observable
prefers (inference.evidence.observables), against references computed independently: the
Masing loop integrated numerically, the mechanisms' small-amplitude limits of
docs/damping.md, and toys whose answer is known."""

from __future__ import annotations

import math

import arviz as az
import numpy as np
import pytest
from scipy import integrate, stats

from beadrod import data as bd
from beadrod.inference.evidence import loss_shift, observables
from beadrod.inference.evidence.ranking import DataHashMismatch
from beadrod.inference.model.amplitude import LossPoints, eq31, loss_points
from beadrod.inference.model.likelihood import model_inputs
from beadrod.inference.model.numpyro_models import ModelSpec
from beadrod.models.laws import masing, viscoelastic


@pytest.fixture(scope="module")
def embedded():
    ds = bd.load_default()
    return ds, model_inputs(ds)


def _idata(**draws):
    """A posterior of 2 chains x 3 draws holding each given value (and the shift noise
    every fit has)."""
    draws = {"sigma_shift": 1e-3, **draws}
    return az.from_dict(posterior={k: np.full((2, 3), float(v)) for k, v in draws.items()})


def _loop_ratio(m: float) -> float:
    """2 q/|dk| of a Masing loop (a = 1, U = 1) by quadrature of its force, the closed
    forms left aside: dk = (1/pi) Int f cos, q = -(1/pi) Int f sin."""
    f = lambda t: float(masing.loop_force(t, amplitude=1.0, a=1.0, m=m))  # noqa: E731
    kw = {"points": [np.pi], "epsabs": 1e-13, "epsrel": 1e-12, "limit": 200}
    dk = integrate.quad(lambda t: f(t) * np.cos(t), 0, 2 * np.pi, **kw)[0] / np.pi
    q = -integrate.quad(lambda t: f(t) * np.sin(t), 0, 2 * np.pi, **kw)[0] / np.pi
    return 2.0 * q / abs(dk)


def test_masing_loop_ratio_is_eight_over_three_pi():
    assert _loop_ratio(2.0) == pytest.approx(8.0 / (3.0 * np.pi), rel=1e-9)


@pytest.mark.parametrize("m", [2.0, 1.6])
def test_hysteretic_law_row_has_the_loops_ratio_and_exponent(embedded, m):
    _, inputs = embedded
    spec = ModelSpec(law="hertz_hysteretic", rung="backbone")
    idata = _idata(young=2e11, strength=0.05, exponent=m, loss_exponent=0.0)
    row = loss_shift.model_row(spec, idata, 1e-4, inputs)
    # at x = 1e-4 Hertz's x^2 is 1e-4 of the loops' shift: the ratio is the loop's rho(m)
    assert row["ratio"][1] == pytest.approx(_loop_ratio(m), rel=2e-3)
    assert row["shift_exponent"][1] == pytest.approx(m - 1.0, abs=2e-3)
    assert row["loss_exponent"][1] == pytest.approx(m - 1.0, abs=1e-9)
    assert row["sign"] == "widens" and row["p_widens"] == 1.0
    assert row["q_ref_source"] == "data" and row["beta_source"] == "fitted"
    # Eq. 31 adds the base excitation: + 2/Q0 (the loss constant, beta = 0), and
    # 2 rho |shift| (the loss change read through Omega^-2)
    assert row["ratio_eq31"][1] - row["ratio"][1] == pytest.approx(2.0 / row["q_ref"],
                                                                   rel=1e-2)


@pytest.mark.parametrize("beta", [0.0, 1.0, 3.0])
def test_elastic_law_with_a_background_loss(embedded, beta):
    _, inputs = embedded
    spec = ModelSpec(law="hertz", rung="backbone")
    row = loss_shift.model_row(spec, _idata(young=2e11, loss_exponent=beta), 0.01, inputs)
    q0 = float(np.median(np.asarray(inputs["q_plugin"])))
    assert row["q_ref"] == pytest.approx(q0)
    assert row["shift_exponent"][1] == pytest.approx(2.0, abs=1e-3)  # Hertz: x^2
    if beta == 0.0:  # a constant loss factor: the loss does not change at all
        assert row["sign"] == "none" and row["loss_exponent"] is None
        assert row["ratio"][1] == 0.0
        return
    # L0 Omega^beta: Delta(1/Q) = beta L0 Delta f/f0 to first order, narrowing
    assert row["ratio"][1] == pytest.approx(-beta / q0, rel=2e-3)
    assert row["sign"] == "narrows" and row["loss_exponent"][1] == pytest.approx(2.0, abs=1e-3)


def test_viscoelastic_law_narrows_by_three_over_its_own_q(embedded):
    _, inputs = embedded
    spec = ModelSpec(law="viscoelastic", rung="backbone")
    row = loss_shift.model_row(spec, _idata(young=2e11, eta=1e5), 0.01, inputs)
    f0 = float(np.median(np.asarray(inputs["f0"])))
    a = viscoelastic.damping_constant(eta1=1e5, young=2e11, poisson=inputs["scene"]["poisson"])
    q = float(viscoelastic.linear_q(damping_constant=a, omega0=2 * np.pi * f0))
    assert row["q_ref_source"] == "law" and row["q_ref"] == pytest.approx(q, rel=1e-9)
    assert row["beta"][1] == 3.0 and row["beta_source"] == "own"
    assert row["ratio"][1] == pytest.approx(-3.0 / q, rel=3e-3)
    assert row["sign"] == "narrows"


def test_a_law_without_a_fitted_background_has_no_loss_row(embedded):
    _, inputs = embedded
    row = loss_shift.model_row(ModelSpec(law="hertz", rung="backbone"),
                               _idata(young=2e11), 0.01, inputs)
    assert "not fitted" in row["note"] and "ratio" not in row
    assert row["shift_exponent"][1] == pytest.approx(2.0, abs=1e-3)


def test_baseline_row_is_its_law_free_loss(embedded):
    _, inputs = embedded
    spec = ModelSpec(law="baseline")
    idata = _idata(amp=1e-3, power=1.5, loss_exponent=0.0, loss_gain=0.02, loss_power=1.5)
    row = loss_shift.model_row(spec, idata, 0.05, inputs)
    assert row["shift_exponent"][1] == pytest.approx(1.5, abs=1e-9)
    # ln L - ln L0 = g (xs/xs_ref)^p at beta = 0: widening as x^p for a small change
    assert row["sign"] == "widens" and row["loss_exponent"][1] == pytest.approx(1.5, abs=1e-2)
    assert row["rung"] is None


def _points(rng, ratio, n=400, noise=2e-4):
    x = np.geomspace(0.02, 1.0, n)
    shift = -0.05 * x**1.5 + rng.normal(0, 1e-4, n)
    loss = ratio * np.abs(-0.05 * x**1.5) + rng.normal(0, noise, n)
    q = np.full(n, 50.0)
    return LossPoints(x=x, shift=shift, eq31=loss - 2 * shift / q, loss_change=loss,
                      q_ref=q, direction=np.zeros(n, int))


def test_data_row_recovers_the_ratio_and_exponents():
    rng = np.random.default_rng(1)
    d = loss_shift.data_row(_points(rng, -0.04), 0.05)
    assert abs(d["ratio"][0] + 0.04) < 3 * d["ratio"][1]
    assert abs(d["shift_exponent"][0] - 1.5) < 3 * d["shift_exponent"][1]
    assert d["sign"] == "narrows" and abs(d["loss_exponent"][0] - 1.5) < 0.2
    assert d["ratio_eq31"][0] > d["ratio"][0]  # Eq. 31 reads + 2|shift|/Q more
    flat = loss_shift.data_row(_points(rng, 0.0), 0.05)
    assert flat["sign"] == "either" and flat["loss_exponent"] is None


def test_loss_points_are_the_figures_eq31_and_its_base_excitation(embedded):
    ds, inputs = embedded
    p = loss_points(ds)
    usable = np.isfinite(ds.drive_inv_q_shift)
    np.testing.assert_array_equal(p.eq31, ds.drive_inv_q_shift[usable])
    q = p.q_ref
    np.testing.assert_allclose(p.loss_change,
                               ((1 + p.shift) ** 2 * (1 + q * p.eq31) - 1) / q, rtol=1e-9,
                               atol=1e-15)
    # the model's observed ratios read back through Eq. 31
    np.testing.assert_allclose(eq31(np.asarray(inputs["amp_obs"]), 1.0)[:5] / q[:5],
                               p.eq31[:5], rtol=1e-9)
    assert 0.0 < loss_shift.small_amplitude(p.x) < np.median(p.x)


# ------------------------------------------------------------------ the law each prefers
def _toy(means: dict[str, float], sites=("shift_obs", "amp_obs"), n=200, seed=0):
    """log-likelihoods of y ~ N(0, 1) under N(mu + small draw noise, 1) per site."""
    rng = np.random.default_rng(seed)
    y = rng.normal(0, 1, n)
    ll = {}
    for site in sites:
        mu = means[site] + rng.normal(0, 0.02, (2, 200, 1))
        ll[site] = stats.norm.logpdf(y, mu, 1.0)
    return az.from_dict(posterior={"a": rng.normal(size=(2, 200))}, log_likelihood=ll,
                        attrs={"data_hash": "h"})


def test_each_observable_names_the_law_that_predicts_it_best():
    idatas = {"A": _toy({"shift_obs": 0.0, "amp_obs": 1.0}),
              "B": _toy({"shift_obs": 1.0, "amp_obs": 0.0}),
              "C": _toy({"shift_obs": 0.6}, sites=("shift_obs",)),
              "base": _toy({"shift_obs": -0.01, "amp_obs": 1.5}),
              "broken": _toy({"shift_obs": 0.0, "amp_obs": 0.0})}
    loos = {k: observables.site_loos(v) for k, v in idatas.items()}
    evidence = {"best": "A", "runner_up": "B", "gap": 3.0, "gap_err": 0.1}
    out = observables.preference_by_observable(
        loos, evidence, eligible=["A", "B", "C", "base"], baselines=["base"],
        data_hashes={k: "h" for k in loos})
    by = {c["site"]: c for c in out["observables"]}
    assert [c["site"] for c in out["observables"]] == ["shift_obs", "amp_obs"]
    shift, amp = by["shift_obs"], by["amp_obs"]
    assert shift["preferred"] == "A" and shift["runner_up"] == "C" and shift["resolved"]
    assert amp["preferred"] == "B" and amp["runner_up"] == "A" and amp["absent"] == ["C"]
    # the failed fit ranks but never wins; the baseline ranks but is never preferred
    assert "broken" in shift["elpd"] and shift["baseline"] == "base"
    exact = {k: float(loos[k]["amp_obs"].elpd_loo) for k in ("A", "B")}
    assert amp["delta_elpd"] == pytest.approx(exact["B"] - exact["A"])
    assert amp["delta_elpd"] > 2 * amp["delta_se"] > 0
    assert out["all"]["preferred"] == "A" and out["all"]["delta_log_z"] == 3.0
    assert all(e["k_bad"] == 0 and e["n"] == 200 for e in shift["elpd"].values())


def test_fits_of_other_data_are_refused():
    loos = {k: observables.site_loos(_toy({"shift_obs": 0.0, "amp_obs": 0.0}))
            for k in ("A", "B")}
    with pytest.raises(DataHashMismatch):
        observables.preference_by_observable(loos, {}, data_hashes={"A": "h", "B": "g"})


def test_a_site_no_model_read_is_left_out_and_a_lone_law_wins_alone():
    loos = {"A": observables.site_loos(_toy({"shift_obs": 0.0}, sites=("shift_obs",)))}
    out = observables.preference_by_observable(loos, {})
    assert [c["site"] for c in out["observables"]] == ["shift_obs"]
    assert out["unread"] == ["f0", "reference Q", "amplitude per volt"]
    c = out["observables"][0]
    assert c["preferred"] == "A" and c["runner_up"] is None and c["resolved"] is None
    assert math.isfinite(c["elpd"]["A"]["elpd_loo"])
