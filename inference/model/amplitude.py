"""The amplitude observable: each drive sweep's resonance amplitude per volt, relative to
its protocol's first reference sweep.

What is observed, per drive sweep i of protocol p whose ratio is defined
(``ProcessedDataset.drive_amplitude_usable``)::

    a_i = ln(delta_i / V_i) - ln(delta_ref,p / V_ref,p)                       [-]

What a model predicts. The rod end moves by Y = d V and drives the bead with the force
m omega^2 Y (base excitation); at the peak of the resonance curve the amplitude is
x = E Omega^2 / L(x) (docs/damping.md: exact for one harmonic), with E = Y/delta0,
Omega = f_res/f0 and L = q/k0 the loss at that amplitude. The unknown transduction d and
delta0 cancel in the ratio::

    a_i = 2 ln Omega_i - ln L_p(x_i) + ln L_p(x_ref,p) + o_a d_i,

with Omega_i = 1 + s(x_i) the model's own resonance ratio at the sweep's amplitude (its
up-sweep curve), Omega = 1 at the reference (which defines f0), x_ref,p the reference's
amplitude, and o_a an offset of down sweeps (d_i = 1) as for the shift. L_p(x) is the law's
(:meth:`models.law.ContactLaw.loss`): its linear loss L0,p scaled as Omega^beta, with beta
the law's own (Kuwabara-Kono: 3) or, for a law with no loss of its own, the fitted
background exponent ``loss_exponent`` ~ Uniform(0, 3) (0: a constant loss factor; 1: a
constant dashpot; 3: radiation into the rod); plus the law's loss increment (hysteresis).
L0,p is the law's predicted 1/Q where it predicts one; else the protocol's measured
reference 1/Q (a plug-in: it matters only where the law adds a loss increment, since
L0,p cancels otherwise), the median measured one where the protocol has none.

The law-free baseline: ln L(x) - ln L0 = beta ln Omega + g (xs/xs_ref)^p, a law-free
change of the loss with the amplitude scale xs of its shift, either sign.

Noise: ln delta is measured with a relative error; the reference's error is shared by the
protocol's ratios, so each protocol's a_i are jointly Normal with covariance
sigma_a^2 I + tau_a^2 1 1^T (:class:`inference.model.shift_noise.ProtocolNormal`; tau_a the
reference's error, sigma_a the sweep's). Their priors are in :mod:`inference.model.priors`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax.numpy as jnp
import numpy as np
import numpyro

from beadrod.inference.model.priors import prior
from beadrod.inference.model.shift_noise import ProtocolNormal
from beadrod.inference.speed.residual_fold import POINTWISE

__all__ = ["AMPLITUDE_KEYS", "amplitude_inputs", "has_amplitudes", "linear_loss_plugin",
           "predicted_ratio", "observe_amplitude", "eq31", "loss_change_from_ratio",
           "LossPoints", "loss_points"]

AMPLITUDE_KEYS = ("amp_obs", "amp_idx", "amp_proto", "ref_amplitude", "q_plugin")
"""The model inputs of the amplitude observable (:func:`amplitude_inputs`)."""


def linear_loss_plugin(q_ref: Any) -> np.ndarray:
    """L0,p = 1/Q_ref,p (P,) [-]: the measured reference Q, the median of the measured
    ones where a protocol has none, 1/50 (a typical bead-rod Q) where none has one."""
    q = np.asarray(q_ref, float)
    ok = np.isfinite(q) & (q > 0)
    fill = float(np.median(q[ok])) if ok.any() else 50.0
    return 1.0 / np.where(ok, q, fill)


def amplitude_inputs(ds: Any) -> dict[str, Any]:
    """The amplitude observable's model inputs from a processed dataset: ``amp_obs`` (the
    observed a_i of the usable sweeps), ``amp_idx`` (their sweep indices), ``amp_proto``
    (their protocols), ``ref_amplitude`` (P,) [m] and ``q_plugin`` (P,) (1/L0,p)."""
    usable = getattr(ds, "drive_amplitude_usable", None)
    usable = np.ones(len(ds.drive_shift), bool) if usable is None else np.asarray(usable, bool)
    idx = np.flatnonzero(usable)
    proto = np.asarray(ds.drive_protocol, int)
    a_ref = np.asarray(ds.ref_amplitude, float)
    v_ref = np.asarray(ds.ref_voltage, float)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = (np.log(np.asarray(ds.drive_amplitude, float)[idx]
                        / np.asarray(ds.drive_voltage, float)[idx])
                 - np.log(a_ref / v_ref)[proto[idx]])
    if not np.all(np.isfinite(ratio)):
        raise ValueError("amplitude ratios must be finite where drive_amplitude_usable")
    return {"amp_obs": jnp.asarray(ratio), "amp_idx": jnp.asarray(idx, dtype=jnp.int32),
            "amp_proto": jnp.asarray(proto[idx], dtype=jnp.int32),
            "ref_amplitude": jnp.asarray(np.where(np.isfinite(a_ref), a_ref, 1.0)),
            "q_plugin": jnp.asarray(1.0 / linear_loss_plugin(ds.q_ref))}


def has_amplitudes(data: dict) -> bool:
    """True where the inputs carry at least one amplitude ratio to fit (or to simulate)."""
    return "amp_idx" in data and int(np.shape(data["amp_idx"])[0]) > 0


def predicted_ratio(*, omega_ratio: Any, loss: Any, loss_ref: Any) -> jnp.ndarray:
    """2 ln Omega - ln L(x) + ln L(x_ref) [-]: the predicted a_i before the offset."""
    return 2.0 * jnp.log(omega_ratio) - jnp.log(loss) + jnp.log(loss_ref)


def eq31(a: Any, q_ref: Any) -> np.ndarray:
    """Delta(1/Q) = (1/Q_ref)(exp(-a) - 1) [-] of log amplitude ratios ``a`` (paper Eq. 31:
    (1/Q_ref)(V delta_ref/(V_ref delta) - 1)), with the reference's Q_ref [-]."""
    return np.expm1(-np.asarray(a, float)) / np.asarray(q_ref, float)


def loss_change_from_ratio(a: Any, omega_ratio: Any, q_ref: Any) -> np.ndarray:
    """L(x) - L0 = (1/Q_ref)(Omega^2 exp(-a) - 1) [-]: the loss change a measured ratio
    ``a`` implies once the base excitation's Omega^2 is taken out (the inverse of
    :func:`predicted_ratio` with L(x_ref) = 1/Q_ref; ``omega_ratio`` = f_res/f0 [-]).
    Eq. 31 (:func:`eq31`) is this without the Omega^2: it reads a loss that does not change
    as a widening of 2|Delta f/f0|/Q_ref (docs/damping.md)."""
    w = np.asarray(omega_ratio, float)
    return (np.square(w) * np.exp(-np.asarray(a, float)) - 1.0) / np.asarray(q_ref, float)


@dataclass(frozen=True)
class LossPoints:
    """The usable drive sweeps' loss against shift, from the data alone (N usable,):
    ``x`` = delta_a/delta0,p with delta0,p the Hertz overlap the measured f0_p implies [-];
    ``shift`` Delta f/f0 [-]; ``eq31`` the paper's Delta(1/Q) (:func:`eq31`) [-];
    ``loss_change`` the same with the base excitation taken out
    (:func:`loss_change_from_ratio`) [-]; ``q_ref`` the protocol's measured reference Q
    [-]; ``direction`` 0 up, 1 down."""

    x: np.ndarray
    shift: np.ndarray
    eq31: np.ndarray
    loss_change: np.ndarray
    q_ref: np.ndarray
    direction: np.ndarray


def loss_points(ds: Any) -> LossPoints:
    """:class:`LossPoints` of a processed dataset: the drive sweeps whose amplitude ratio is
    defined and whose protocol has a measured reference Q (the sweeps the paper's Fig. 10
    shows)."""
    proto = np.asarray(ds.drive_protocol, int)
    q = np.asarray(ds.q_ref, float)[proto]
    inv_q = np.asarray(ds.drive_inv_q_shift, float)
    ok = np.isfinite(inv_q) & np.isfinite(q) & (q > 0)
    a = -np.log1p(inv_q[ok] * q[ok])  # the ratio behind Eq. 31, read back
    shift = np.asarray(ds.drive_shift, float)[ok]
    x = np.asarray(ds.normalized_amplitude("f0"), float)[ok]
    return LossPoints(x=x, shift=shift, eq31=inv_q[ok],
                      loss_change=loss_change_from_ratio(a, 1.0 + shift, q[ok]), q_ref=q[ok],
                      direction=np.asarray(ds.drive_direction, int)[ok])


def observe_amplitude(spec: Any, ratio: jnp.ndarray, data: dict) -> None:
    """amp_obs ~ the protocols' jointly Normal ratios around ``ratio`` (the usable sweeps'
    predicted a_i) plus ``offset_amp_down`` on down sweeps."""
    sigma = numpyro.sample("sigma_amp", prior("sigma_amp", spec.overrides))
    tau = numpyro.sample("tau_amp", prior("tau_amp", spec.overrides))
    offset = numpyro.sample("offset_amp_down", prior("offset_amp_down", spec.overrides))
    idx = data["amp_idx"]
    pred = numpyro.deterministic("amp_pred", ratio + offset * data["direction"][idx])
    var = jnp.full(pred.shape, jnp.square(sigma))
    with numpyro.plate("amp_sweeps", pred.shape[0]):
        numpyro.sample("amp_obs", ProtocolNormal(pred, var, tau, data["amp_proto"],
                                                 data["n_protocols"],
                                                 pointwise=bool(data.get(POINTWISE))),
                       obs=data.get("amp_obs"))
