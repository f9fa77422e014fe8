"""The law-free baseline model: any smooth monotone softening, no contact law.

Delta f/f0 = -a_ref (xs/xs_ref)^power = -amp xs^power with xs = delta_a omega0_p^2 / g
(the overlap scale g/omega0^2 of a linear spring; any other scale is absorbed into the
prefactor) and xs_ref a pivot fixed by the sweeps' amplitudes and f0
(:func:`reference_scale`), f0_obs ~ Normal(mu_f0, tau_f0), and the law-free nuisance
model of Q. A contact law that loses to it is missing
the data's shape. Its priors are in :mod:`inference.model.priors` (``a_ref``, ``power``,
``mu_f0``, ``tau_f0``); ``amp`` = a_ref xs_ref^-power is derived.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpyro
import numpyro.distributions as dist

from beadrod.inference.model.amplitude import has_amplitudes, observe_amplitude
from beadrod.inference.model.likelihood import observe_logq, observe_shift
from beadrod.inference.model.priors import prior
from beadrod.inference.model.shift_noise import ProtocolNormal, noise_variance
from beadrod.inference.speed.residual_fold import POINTWISE
from beadrod.inference.speed.residual_fold import log_likelihood as residual_log_likelihood
from beadrod.models.scene import materials

__all__ = ["baseline_curve", "baseline_model", "observe_drive", "nuisance_q",
           "reference_scale", "amplitude_scale", "log_loss_change", "PIVOT_POWER",
           "BASELINE_PARAMS"]

BASELINE_PARAMS = ("amp", "power")
"""The baseline's curve parameters (posterior curve draws use them)."""


def baseline_curve(amp, power, amplitude, f0):
    """-amp (delta_a (2 pi f0)^2 / g)^power [-] (amplitude [m], f0 [Hz])."""
    return -amp * jnp.power(amplitude_scale(amplitude, f0), power)


def nuisance_q(spec: Any, data: dict) -> None:
    """log Q ~ Normal(mu_logq, tau_logq): the Q model of every law that predicts none."""
    mu = numpyro.sample("mu_logq", prior("mu_logq", spec.overrides))
    tau = numpyro.sample("tau_logq", prior("tau_logq", spec.overrides))
    nq = data["q_idx"].shape[0]
    observe_logq(jnp.full((nq,), mu), tau, data["q_obs"], likelihood=spec.likelihood,
                 df=spec.student_df)


def observe_drive(spec: Any, curve: jnp.ndarray, data: dict,
                  sums: jnp.ndarray | None = None) -> None:
    """The measured shifts around s = curve + offset_down * direction.

    ``spec.shift_noise == "protocol"`` (:mod:`inference.model.shift_noise`): a floor
    ``sigma_shift``, a part ``kappa_shift`` |s| and an offset ``tau_shift`` shared by a
    protocol's sweeps (Normal; with the Student-t option the sweeps are independent
    Student-t of scale sqrt(sigma^2 + (kappa s)^2) and there is no shared offset).
    ``"constant"``: shift_obs ~ Normal|StudentT(s, sigma_shift). With ``sums`` (constant
    Normal noise only), the residual sums (S0, S1) of the curve
    (:mod:`inference.speed.residual_fold`): the same log density as one factor
    ('shift_obs_folded') instead of a site per sweep; ``curve`` then enters only the
    deterministic 'shift_pred'."""
    offset = numpyro.sample("offset_down", prior("offset_down", spec.overrides))
    sigma = numpyro.sample("sigma_shift", prior("sigma_shift", spec.overrides))
    pred = numpyro.deterministic("shift_pred", curve + offset * data["direction"])
    if spec.shift_noise == "protocol":
        kappa = numpyro.sample("kappa_shift", prior("kappa_shift", spec.overrides))
        var = noise_variance(pred, sigma=sigma, kappa=kappa)
        if spec.likelihood == "normal":
            tau = numpyro.sample("tau_shift", prior("tau_shift", spec.overrides))
            with numpyro.plate("sweeps", pred.shape[0]):
                numpyro.sample("shift_obs", ProtocolNormal(
                    pred, var, tau, data["proto"], data["n_protocols"],
                    pointwise=bool(data.get(POINTWISE))), obs=data["shift"])
            return
        observe_shift(pred, jnp.sqrt(var), data["shift"], likelihood=spec.likelihood,
                      df=spec.student_df)
        return
    if sums is None:
        observe_shift(pred, sigma, data["shift"], likelihood=spec.likelihood,
                      df=spec.student_df)
        return
    d = jnp.asarray(data["direction"], float)
    numpyro.factor("shift_obs_folded", residual_log_likelihood(
        sums, offset, sigma, int(d.shape[0]), jnp.sum(d * d)))


def amplitude_scale(amplitude, f0):
    """xs = delta_a (2 pi f0)^2 / g [-] (amplitude [m], f0 [Hz]): the baseline's amplitude
    scale, delta_a over the overlap g/omega0^2 of a linear spring."""
    return amplitude * jnp.square(2.0 * jnp.pi * jnp.abs(f0)) / materials.G_STANDARD


def log_loss_change(omega, xs_rel, *, beta, gain, power):
    """ln L(x) - ln L0 = beta ln Omega + g (xs/xs_ref)^p [-]: the baseline's law-free loss
    change, with ``omega`` = f_res/f0 and ``xs_rel`` = xs/xs_ref (:func:`amplitude_scale`,
    :func:`reference_scale`)."""
    return beta * jnp.log(omega) + gain * jnp.power(xs_rel, power)


def _baseline_amplitude(spec: Any, curve: jnp.ndarray, xs_ref: jnp.ndarray, f0: jnp.ndarray,
                        data: dict) -> None:
    """Law-free amplitude ratios: ln L(x) - ln L0 = beta ln Omega + g (xs/xs_ref)^p
    (inference.model.amplitude), the pivot the shift's."""
    beta = numpyro.sample("loss_exponent", prior("loss_exponent", spec.overrides))
    gain = numpyro.sample("loss_gain", prior("loss_gain", spec.overrides))
    power = numpyro.sample("loss_power", prior("loss_power", spec.overrides))
    idx, p_i = data["amp_idx"], data["amp_proto"]
    omega = jnp.maximum(1.0 + curve[idx], 1e-3)
    ln_loss = log_loss_change(omega, amplitude_scale(data["amplitude"][idx], f0[p_i]) / xs_ref,
                              beta=beta, gain=gain, power=power)
    ln_loss_ref = log_loss_change(1.0, amplitude_scale(data["ref_amplitude"], f0) / xs_ref,
                                  beta=beta, gain=gain, power=power)[p_i]
    # predicted_ratio's 2 ln Omega - ln L(x) + ln L(x_ref), with L0 cancelled
    ratio = 2.0 * jnp.log(omega) - ln_loss + ln_loss_ref
    observe_amplitude(spec, ratio, data)


PIVOT_POWER = 2.0
"""The softening exponent p0 the pivot is tuned to: a smooth contact softens as x^2 at
small amplitude (the Lindstedt order of Hertz and of every F ~ delta^n)."""


def reference_scale(amplitude, f0):
    """Pivot xs_ref [-] of the baseline: ln xs_ref = sum_i w_i ln xs_i / sum_i w_i with
    w_i = xs_i^(2 p0), xs_i = delta_a,i omega0_i^2 / g (amplitude [m], f0 [Hz] per sweep).

    With a constant shift noise the Fisher information of (ln a_ref, power) in
    Delta f/f0 = -a_ref (xs/xs_ref)^power has the off-diagonal sum_i s_i^2 ln(xs_i/xs_ref),
    s_i ~ xs_i^power: it vanishes at this xs_ref when power = p0 (:data:`PIVOT_POWER`).
    The geometric mean of xs does not decorrelate them (the large sweeps carry the
    information): Fisher correlation -0.98 on both embedded worlds, against 0.00
    (hertz_dynamics) and 0.20 (paper_like) here."""
    ln_xs = jnp.log(amplitude_scale(amplitude, f0))
    w = jnp.exp(2.0 * PIVOT_POWER * (ln_xs - jnp.max(ln_xs)))  # xs^(2 p0), rescaled
    return jnp.exp(jnp.sum(w * ln_xs) / jnp.sum(w))


def baseline_model(spec: Any, data: dict) -> None:
    """f0_obs ~ Normal(mu_f0, tau_f0); Delta f/f0 = -a_ref (xs/xs_ref)^power, pivoted at
    xs_ref = :func:`reference_scale`, where ln a_ref and power are nearly uncorrelated
    (posterior correlation of ln amp, the prefactor at xs = 1, and power: 0.95 on
    hertz_dynamics). ``amp`` = a_ref xs_ref^-power is kept as a deterministic site
    (:func:`baseline_curve` takes it)."""
    mu = numpyro.sample("mu_f0", prior("mu_f0", spec.overrides))
    tau = numpyro.sample("tau_f0", prior("tau_f0", spec.overrides))
    with numpyro.plate("protocols", data["n_protocols"]):
        f0 = numpyro.sample("f0_obs", dist.Normal(mu, tau), obs=data["f0"])
    if spec.use_shift:
        a_ref = numpyro.sample("a_ref", prior("a_ref", spec.overrides))
        power = numpyro.sample("power", prior("power", spec.overrides))
        f0_sweep = f0[data["proto"]]
        # fixed by the measured f0 when observed; with f0 simulated (prior predictive) the
        # pivot moves with the draw, and a_ref keeps its meaning: the shift at xs_ref
        xs_ref = reference_scale(data["amplitude"], f0_sweep)
        amp = numpyro.deterministic("amp", a_ref * jnp.power(xs_ref, -power))
        curve = baseline_curve(amp, power, data["amplitude"], f0_sweep)
        observe_drive(spec, curve, data)
        if spec.use_amplitude and has_amplitudes(data):
            _baseline_amplitude(spec, curve, xs_ref, f0, data)
    if spec.use_q:
        nuisance_q(spec, data)
