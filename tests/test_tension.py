"""Tension statistics against closed forms, the one tension path on hand-made fits, and
(slow) the full analysis on synthetic data with two viscosities."""

import arviz as az
import numpy as np
import pytest
from scipy import stats

from beadrod.inference.evidence.tension import analyse_tension, log10_gap, ppc_failure, prob_greater


def test_prob_greater_closed_form():
    rng = np.random.default_rng(1)
    a, b = rng.normal(1.0, 1.0, 100_000), rng.normal(0.0, 1.0, 100_000)
    assert prob_greater(a, b) == pytest.approx(stats.norm.cdf(1 / np.sqrt(2)), abs=0.01)


def test_log10_gap_closed_form():
    # log10 a ~ N(1, 0.1), log10 b ~ N(0, 0.2): the gap is N(1, sqrt(0.1^2 + 0.2^2))
    rng = np.random.default_rng(3)
    a = 10.0 ** rng.normal(1.0, 0.1, 200_000)
    b = 10.0 ** rng.normal(0.0, 0.2, 200_000)
    q05, q50, q95 = log10_gap(a, b)
    sd = np.hypot(0.1, 0.2)
    assert q50 == pytest.approx(1.0, abs=0.005)
    assert q05 == pytest.approx(1.0 - stats.norm.ppf(0.95) * sd, abs=0.01)
    assert q95 == pytest.approx(1.0 + stats.norm.ppf(0.95) * sd, abs=0.01)


def _idata(obs_shift):
    rng = np.random.default_rng(2)
    rep = rng.normal(0.0, 1.0, size=(2, 500, 30))
    return az.from_dict(posterior_predictive={"shift_obs": rep},
                        observed_data={"shift_obs": rng.normal(obs_shift, 1.0, 30)})


def test_ppc_failure_flags_misfit_only():
    ok = ppc_failure(_idata(0.0), "shift_obs")
    bad = ppc_failure(_idata(2.0), "shift_obs")
    assert ok["p_value"] > 0.01 and abs(ok["mean_std_residual"]) < 0.6
    assert bad["p_value"] < 0.001 and bad["mean_std_residual"] > 1.4


def _fits(seed=0):
    """Shared and split fits whose shift fits and whose Q misses by a factor e^1.5."""
    rng = np.random.default_rng(seed)
    shape = (2, 400)
    shift_rep = rng.normal(0.0, 1.0, size=shape + (40,))
    q_rep = np.exp(rng.normal(np.log(50.0), 0.1, size=shape + (10,)))
    shared = az.from_dict(
        posterior={"eta": 10.0 ** rng.normal(5.0, 0.05, shape)},
        posterior_predictive={"shift_obs": shift_rep, "q_obs": q_rep},
        observed_data={"shift_obs": rng.normal(0.0, 1.0, 40),
                       "q_obs": np.full(10, 50.0 * np.exp(1.5))})
    split = az.from_dict(posterior={"eta_shift": 10.0 ** rng.normal(6.0, 0.05, shape),
                                    "eta_q": 10.0 ** rng.normal(4.8, 0.05, shape)})
    return shared, split, rng


def test_analyse_tension_where_eta_enters_the_shift():
    shared, split, rng = _fits()
    eta_shift = 10.0 ** rng.normal(6.0, 0.05, 800)
    eta_q = 10.0 ** rng.normal(4.8, 0.05, 800)
    t = analyse_tension(rung="paper_eq25", eta_q=eta_q, eta_shift=eta_shift, shared=shared,
                        split=split, log_z_shared=(-100.0, 0.3), log_z_split=(-88.0, 0.4))
    assert t["eta_in_shift"] is True
    assert t["eta_shift_q05_q50_q95"][1] == pytest.approx(1e6, rel=0.02)
    assert t["eta_q_q05_q50_q95"][1] == pytest.approx(10.0 ** 4.8, rel=0.02)
    gap = t["log10_gap_q05_q50_q95"]
    assert gap[1] == pytest.approx(1.2, abs=0.01) and gap[0] > 1.0  # excludes 0: tension
    assert t["p_shift_gt_q"] == 1.0
    assert t["log_bf_split_vs_shared"] == pytest.approx(12.0)
    assert t["log_bf_err"] == pytest.approx(0.5)
    assert t["ppc"]["missed"] == "q" and t["ppc"]["q_p"] < 0.01 < t["ppc"]["shift_p"]
    assert "bhattacharyya" not in t and "overlap" not in t


def test_analyse_tension_where_eta_does_not_enter_the_shift():
    shared, split, rng = _fits(1)
    t = analyse_tension(rung="backbone", eta_q=10.0 ** rng.normal(4.8, 0.05, 800),
                        shared=shared, split=split)
    assert t["eta_in_shift"] is False
    for key in ("eta_shift_q05_q50_q95", "log10_gap_q05_q50_q95", "p_shift_gt_q",
                "log_bf_split_vs_shared"):
        assert t[key] is None, key
    with pytest.raises(ValueError, match="shift-only draws"):
        analyse_tension(rung="paper_eq25", eta_q=np.ones(3), shared=shared, split=split)


def test_workflow_uses_the_inference_tension_path():
    """compare_outputs keeps no statistics of its own: it calls analyse_tension."""
    import inspect

    from beadrod.workflows.pipeline import outputs

    src = inspect.getsource(outputs)
    assert "analyse_tension(" in src
    for dup in ("def ppc_failure", "def prob_greater", "bhattacharyya", "p_value"):
        assert dup not in src, dup


@pytest.mark.slow
def test_tension_on_synthetic_paper_like_data():
    """Data built with a shift-eta of 1e6 Pa s (paper Eq. 25) but Q from 1e5 Pa s: the
    analysis must see two viscosities (gap excluding 0, split preferred)."""
    from beadrod.inference.evidence.bridge import bridge_sampling_log_z
    from beadrod.inference.model.likelihood import design_inputs, simulate
    from beadrod.inference.model.numpyro_models import ModelSpec, build_model
    from beadrod.inference.sampling.sample import run_nuts
    from beadrod.models.scene import builtin_scene

    des = design_inputs(builtin_scene("paper"), n_protocols=6, amplitudes=np.linspace(5e-9, 40e-9, 6))
    base = {"law": "viscoelastic", "rung": "paper_eq25"}
    split_model = build_model(ModelSpec(**base, eta_mode="split"))
    data, _ = simulate(split_model, des, {"young": 200e9, "eta_shift": 1e6, "eta_q": 1e5,
                                          "delta0_scatter": 0.05, "sigma_shift": 0.002,
                                          "offset_down": 0.0, "sigma_logq": 0.2}, seed=0)
    specs = {"shift": ModelSpec(**base, use_q=False), "q": ModelSpec(**base, use_shift=False),
             "shared": ModelSpec(**base), "split": ModelSpec(**base, eta_mode="split")}
    fits, log_z = {}, {}
    for i, (name, spec) in enumerate(specs.items()):
        model = build_model(spec)
        fits[name] = run_nuts(model, data, num_warmup=300, num_samples=300, num_chains=2,
                              seed=i).idata
        if name in ("shared", "split"):
            ev = bridge_sampling_log_z(model, {"data": data}, fits[name].posterior, seed=0)
            log_z[name] = (ev.log_z, ev.log_z_err)
    t = analyse_tension(rung="paper_eq25", eta_q=np.asarray(fits["q"].posterior["eta"]),
                        eta_shift=np.asarray(fits["shift"].posterior["eta"]),
                        shared=fits["shared"], split=fits["split"],
                        log_z_shared=log_z["shared"], log_z_split=log_z["split"])
    assert t["log10_gap_q05_q50_q95"][0] > 0.3  # ten times apart, the interval excludes 0
    assert t["p_shift_gt_q"] > 0.99
    assert t["log_bf_split_vs_shared"] - 3 * t["log_bf_err"] > 0
    assert t["ppc"]["missed"] in ("shift", "q")
    for p in t["ppc"]["detail"].values():
        assert 0.0 <= p["p_value"] <= 1.0 and np.isfinite(p["rms_std_residual"])


def test_analyse_tension_reads_the_laws_loss_parameter_by_name():
    """A law whose loss parameter is not called eta (models.law.Presentation.tension_param):
    the same draws under other names give the same block, keys unchanged."""
    shared, split, rng = _fits(2)
    eta_q, eta_shift = 10.0 ** rng.normal(4.8, 0.05, 800), 10.0 ** rng.normal(6.0, 0.05, 800)
    renamed_shared = shared.rename_vars({"eta": "zeta"}, groups="posterior")
    renamed_split = split.rename_vars({"eta_shift": "zeta_shift", "eta_q": "zeta_q"},
                                      groups="posterior")
    kw = {"rung": "paper_eq25", "eta_q": eta_q, "eta_shift": eta_shift}
    want = analyse_tension(shared=shared, split=split, **kw)
    got = analyse_tension(shared=renamed_shared, split=renamed_split, param="zeta", **kw)
    assert got == want and got["p_shift_gt_q"] == 1.0
