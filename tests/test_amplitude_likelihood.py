"""The amplitude observable (inference.model.amplitude) against hand computations: the
observed log ratios from the table, each law's predicted ratio at a fixed parameter point
from independent formulas (scipy quadrature of the first-order Hertz shift, the Masing
loss ratio from Gamma functions), the joint density against scipy's multivariate normal,
and the sweeps a missing cell leaves out."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from numpyro import handlers
from scipy import integrate, special, stats

from beadrod.data.load import load_dataset
from beadrod.data.process import load_default, process
from beadrod.inference.model.likelihood import model_inputs, simulate, without_observations
from beadrod.inference.model.numpyro_models import build_model
from tests.test_data_validation import replace, write

COMMON = {"delta0_scatter": 0.1, "sigma_shift": 1e-3, "kappa_shift": 0.1, "tau_shift": 1e-3,
          "offset_down": 0.0, "mu_logq": math.log(50.0), "tau_logq": 0.5,
          "sigma_amp": 0.02, "tau_amp": 0.01, "offset_amp_down": 0.003}


@pytest.fixture(scope="module")
def ds():
    return load_default()


@pytest.fixture(scope="module")
def inputs(ds):
    return model_inputs(ds)


def _first_order_hertz(x):
    # paper Eq. 23 by adaptive quadrature: (1/4 pi) Int (1 + x sin t)^(1/2) dt - 1/2
    val, _ = integrate.quad(lambda t: math.sqrt(max(1 + x * math.sin(t), 0.0)), 0, 2 * math.pi,
                            epsabs=1e-13, epsrel=1e-12, limit=200)
    return val / (4 * math.pi) - 0.5


def _trace(law, inputs, values):
    model = build_model(law, rung="first_order")
    return handlers.trace(handlers.substitute(handlers.seed(model, jax.random.PRNGKey(0)),
                                              data=values)).get_trace(inputs)


def _omega(ds, inputs, idx):
    f0 = np.asarray(ds.f0)[np.asarray(ds.drive_protocol)][idx]
    d0 = 3 * ds.scene.load / (2 * ds.scene.mass * (2 * np.pi * f0) ** 2)
    x = np.asarray(ds.drive_amplitude)[idx] / d0
    return 1 + np.array([_first_order_hertz(v) for v in x]), x, d0


def test_observed_ratios_are_read_from_the_table(ds, inputs):
    idx = np.asarray(inputs["amp_idx"])
    p = np.asarray(ds.drive_protocol)[idx]
    want = (np.log(ds.drive_amplitude[idx] / ds.drive_voltage[idx])
            - np.log(ds.ref_amplitude[p] / ds.ref_voltage[p]))
    np.testing.assert_allclose(np.asarray(inputs["amp_obs"]), want, rtol=1e-12)
    assert idx.size == ds.n_drive  # every sweep of the embedded world has both cells


def test_elastic_law_ratio_is_the_background_exponent(ds, inputs):
    beta = 1.3
    tr = _trace("hertz", inputs, {"young": 200e9, "loss_exponent": beta, **COMMON})
    idx = np.asarray(inputs["amp_idx"])[:40]
    om, _, _ = _omega(ds, inputs, idx)
    want = (2 - beta) * np.log(om) + COMMON["offset_amp_down"] * ds.drive_direction[idx]
    np.testing.assert_allclose(np.asarray(tr["amp_pred"]["value"])[:40], want, rtol=1e-8,
                               atol=1e-12)


def test_viscoelastic_loss_scales_as_omega_cubed(ds, inputs):
    tr = _trace("viscoelastic", inputs, {"young": 200e9, "eta": 1e5, "sigma_logq": 0.3,
                                         **COMMON})
    assert "loss_exponent" not in tr  # its loss is its own
    idx = np.asarray(inputs["amp_idx"])[:40]
    om, _, _ = _omega(ds, inputs, idx)
    want = -np.log(om) + COMMON["offset_amp_down"] * ds.drive_direction[idx]
    np.testing.assert_allclose(np.asarray(tr["amp_pred"]["value"])[:40], want, rtol=1e-8,
                               atol=1e-12)


def test_hysteretic_loss_adds_to_the_measured_linear_loss(ds, inputs):
    h, m, beta = 0.02, 1.7, 1.0
    tr = _trace("hertz_hysteretic", inputs, {"young": 200e9, "strength": h, "exponent": m,
                                             "loss_exponent": beta, **COMMON})
    idx = np.asarray(inputs["amp_idx"])[:40]
    om_h, x, d0 = _omega(ds, inputs, idx)
    om = om_h - h * x ** (m - 1)        # first order: Hertz's shift plus the element's
    rho = 2 * (m - 1) * special.gamma(m + 1) / (math.sqrt(math.pi) * m * special.gamma(m + 0.5))
    p = np.asarray(ds.drive_protocol)[idx]
    lin = 1 / np.asarray(ds.q_ref)[p]                  # every protocol here has a Q
    x_ref = np.asarray(ds.ref_amplitude)[p] / d0
    loss = lin * om**beta + h * rho * x ** (m - 1)
    loss_ref = lin + h * rho * x_ref ** (m - 1)
    want = (2 * np.log(om) - np.log(loss) + np.log(loss_ref)
            + COMMON["offset_amp_down"] * ds.drive_direction[idx])
    np.testing.assert_allclose(np.asarray(tr["amp_pred"]["value"])[:40], want, rtol=1e-8)


def test_joint_density_is_the_protocols_multivariate_normal(ds, inputs):
    tr = _trace("hertz", inputs, {"young": 200e9, "loss_exponent": 1.0, **COMMON})
    site = tr["amp_obs"]
    got = float(jnp.sum(site["fn"].log_prob(site["value"])))
    pred, y = np.asarray(tr["amp_pred"]["value"]), np.asarray(inputs["amp_obs"])
    proto = np.asarray(inputs["amp_proto"])
    want = 0.0
    for q in np.unique(proto):
        sel = proto == q
        cov = COMMON["sigma_amp"] ** 2 * np.eye(sel.sum()) + COMMON["tau_amp"] ** 2
        want += stats.multivariate_normal(pred[sel], cov).logpdf(y[sel])
    assert got == pytest.approx(want, rel=1e-10)


def test_simulated_and_prior_predictive_inputs(inputs):
    model = build_model("hertz", rung="first_order")
    assert without_observations(inputs)["amp_obs"] is None
    sim, values = simulate(model, without_observations(inputs),
                           {"young": 200e9, "loss_exponent": 2.0, **COMMON}, seed=1)
    assert np.shape(sim["amp_obs"]) == np.shape(inputs["amp_obs"])
    resid = np.asarray(sim["amp_obs"]) - np.asarray(values["amp_pred"])
    assert 0.5 * 0.022 < np.std(resid) < 2 * 0.022   # sqrt(0.02^2 + 0.01^2)


def test_a_design_with_amplitude_ratios_simulates_them():
    """design_inputs(amplitude_ratios=True): every sweep's ratio against a reference at
    ref_amplitude, drawn by simulate (what the SBC and recovery designs fit)."""
    from beadrod.inference.model.likelihood import design_inputs
    from beadrod.models.scene import builtin_scene

    des = design_inputs(builtin_scene("paper"), n_protocols=3,
                        amplitudes=np.geomspace(3e-9, 40e-9, 4), amplitude_ratios=True)
    model = build_model("hertz", rung="first_order")
    truth = {"young": 200e9, "loss_exponent": 1.0, **COMMON}
    sim, values = simulate(model, des, truth, seed=2)
    assert np.shape(sim["amp_obs"]) == (3 * 2 * 4,)
    assert np.all(np.isfinite(sim["amp_obs"]))
    # (2 - beta) ln Omega with Omega falling: the ratio falls along each sweep
    pred = np.asarray(values["amp_pred"]).reshape(3, 2, 4)
    assert np.all(np.diff(pred, axis=-1) < 0)
    assert "amp_obs" not in design_inputs(builtin_scene("paper"), n_protocols=1,
                                          amplitudes=[1e-8])


def test_a_sweep_without_voltage_is_left_out_of_the_ratios_only(tmp_path):
    from beadrod.data.load import dump_toml
    from beadrod.models import scene

    text = dump_toml(scene.scene_to_dict(scene.builtin_scene("paper")))
    ds = process(load_dataset(write(tmp_path, text, replace(2, "drive_voltage_V", ""))))
    inp = model_inputs(ds)
    assert inp["shift"].shape[0] == 3 and list(np.asarray(inp["amp_idx"])) == [0, 2]
