"""The noise model of the measured shifts: a floor, a part that grows with the shift, and
an offset shared by the sweeps of one protocol.

Every shift of a protocol is read against the same first reference sweep,
Delta f/f0 = f_res/f_ref - 1, so the reference's own error (its peak-picking noise, a few
Hz at 2.7 kHz, and any drift of the contact before the first drive) enters all of them
alike; and what scatters the drive sweeps themselves (the up/down difference of a bent
peak, the contact's slow wear between steps) grows with the shift. So (``"protocol"``)::

    y_i = s_i + b_p(i) + e_i,   e_i ~ Normal(0, d_i),   d_i = sigma^2 + (kappa s_i)^2,
    b_p ~ Normal(0, tau^2),

with s_i the predicted shift (the law's curve plus the down-sweep offset), sigma the floor
(``sigma_shift``), kappa the relative part (``kappa_shift``) and tau the protocol's offset
(``tau_shift``). b_p is integrated out in closed form: a protocol's sweeps are jointly
Normal with covariance D + tau^2 1 1^T, whose inverse and determinant follow from the
Sherman-Morrison formula and the matrix determinant lemma. With W_p = sum 1/d_i and
S_p = sum r_i/d_i over the protocol (r = y - s)::

    log p(y_p) = -1/2 sum r_i^2/d_i + tau^2 S_p^2 / (2 (1 + tau^2 W_p))
                 - 1/2 sum log(2 pi d_i) - 1/2 log(1 + tau^2 W_p).

No latent offset per protocol is sampled (28 fewer dimensions than the equivalent
hierarchical model) and every form stays finite at tau = 0, where it is the independent
heteroscedastic Normal.

Leave-one-out. The sweeps of a protocol are not independent given the parameters, so
the point-wise log-likelihood that PSIS-LOO needs is the conditional density
p(y_i | y_-i, theta) (Buerkner, Gabry & Vehtari, Comput. Stat. 36, 1243 (2021),
"Efficient leave-one-out cross-validation for Bayesian non-factorized normal and Student-t
models"). Here it is Normal: b_p given the other sweeps has precision
1/tau^2 + W_p - 1/d_i, so r_i | r_-i ~ Normal(m_i, v_i) with::

    m_i = tau^2 (S_p - r_i/d_i) / (1 + tau^2 (W_p - 1/d_i)),
    v_i = d_i + tau^2 / (1 + tau^2 (W_p - 1/d_i)).

The LOO-PIT of the shifts uses the same conditional (:func:`loo_pit`).

``"constant"`` is the model before this one, y_i ~ Normal(s_i, sigma): kept to show
what the noise model changes (docs/damping.md) and because the two-parameter residual
fold (:mod:`inference.speed.residual_fold`) reads only its sums.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import numpyro.distributions as dist
from jax.scipy.special import ndtr
from numpyro.distributions import constraints

__all__ = ["SHIFT_NOISES", "DEFAULT_SHIFT_NOISE", "noise_variance", "protocol_sums",
           "joint_log_density", "loo_conditional", "ProtocolNormal", "loo_pit"]

SHIFT_NOISES = ("protocol", "constant")
"""The shift's noise models: ``protocol`` (floor, growth, protocol offset), ``constant``."""
DEFAULT_SHIFT_NOISE = "protocol"


def noise_variance(pred: Any, *, sigma: Any, kappa: Any) -> jnp.ndarray:
    """d_i = sigma^2 + (kappa s_i)^2 [-]: the sweep's own noise variance around s_i."""
    return jnp.square(sigma) + jnp.square(kappa * pred)


def protocol_sums(values: Any, proto: Any, n_protocols: int) -> jnp.ndarray:
    """Sum of ``values`` over the sweeps of each protocol, gathered back per sweep."""
    totals = jax.ops.segment_sum(values, proto, num_segments=n_protocols)
    return totals[proto]


def _per_protocol(resid, var, proto, n_protocols):
    w = protocol_sums(1.0 / var, proto, n_protocols)
    s = protocol_sums(resid / var, proto, n_protocols)
    n = protocol_sums(jnp.ones_like(resid), proto, n_protocols)
    return w, s, n


def joint_log_density(resid: Any, var: Any, tau: Any, proto: Any,
                      n_protocols: int) -> jnp.ndarray:
    """The joint log density of the residuals r = y - s, spread over the sweeps: each
    protocol's coupling term is shared equally by its sweeps, so the values sum to
    sum_p log p(y_p) (module docstring) but are not point-wise densities."""
    w, s, n = _per_protocol(resid, var, proto, n_protocols)
    t2 = jnp.square(tau)
    coupling = 0.5 * t2 * jnp.square(s) / (1.0 + t2 * w) - 0.5 * jnp.log1p(t2 * w)
    return (-0.5 * jnp.square(resid) / var - 0.5 * jnp.log(2.0 * jnp.pi * var)
            + coupling / n)


def loo_conditional(resid: Any, var: Any, tau: Any, proto: Any,
                    n_protocols: int) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(m_i, v_i): mean and variance of r_i given the other sweeps' residuals."""
    w, s, _ = _per_protocol(resid, var, proto, n_protocols)
    t2 = jnp.square(tau)
    denom = 1.0 + t2 * (w - 1.0 / var)
    return t2 * (s - resid / var) / denom, var + t2 / denom


class ProtocolNormal(dist.Distribution):
    """Observations whose protocols each share one Normal offset: the measured shifts under
    the ``protocol`` noise model, and the amplitude ratios (inference.model.amplitude).

    ``sample`` draws them jointly (one offset per protocol). ``log_prob`` returns the
    joint log density spread over the sweeps (:func:`joint_log_density`), or with
    ``pointwise`` each sweep's leave-one-out conditional density (for PSIS-LOO; those
    values do not sum to the joint density)."""

    arg_constraints = {"pred": constraints.real, "var": constraints.positive}
    support = constraints.real
    pytree_data_fields = ("pred", "var", "tau", "proto")
    pytree_aux_fields = ("n_protocols", "pointwise")

    def __init__(self, pred: Any, var: Any, tau: Any, proto: Any, n_protocols: int, *,
                 pointwise: bool = False, validate_args: bool | None = None) -> None:
        self.pred, self.var = jnp.broadcast_arrays(pred, var)
        self.tau = jnp.asarray(tau)
        self.proto = jnp.asarray(proto)
        self.n_protocols = int(n_protocols)
        self.pointwise = bool(pointwise)
        super().__init__(batch_shape=jnp.shape(self.pred), validate_args=validate_args)

    def sample(self, key: jax.Array, sample_shape: tuple[int, ...] = ()) -> jnp.ndarray:
        k_e, k_b = jax.random.split(key)
        e = jax.random.normal(k_e, sample_shape + self.batch_shape)
        b = jax.random.normal(k_b, sample_shape + (self.n_protocols,))
        return self.pred + jnp.sqrt(self.var) * e + self.tau * b[..., self.proto]

    def log_prob(self, value: Any) -> jnp.ndarray:
        resid = value - self.pred
        if not self.pointwise:
            return joint_log_density(resid, self.var, self.tau, self.proto, self.n_protocols)
        m, v = loo_conditional(resid, self.var, self.tau, self.proto, self.n_protocols)
        return -0.5 * jnp.square(resid - m) / v - 0.5 * jnp.log(2.0 * jnp.pi * v)


def loo_pit(y: np.ndarray, pred: np.ndarray, sigma: np.ndarray, kappa: np.ndarray,
            tau: np.ndarray, proto: np.ndarray, n_protocols: int,
            log_lik: np.ndarray) -> np.ndarray:
    """LOO-PIT of the shifts under the ``protocol`` noise model: for each sweep,
    PIT_i = sum_s w_is Phi((r_is - m_is)/sqrt(v_is)), the conditional Normal of
    :func:`loo_conditional` at each draw s, weighted by the Pareto-smoothed leave-one-out
    importance weights w_is (from ``log_lik``, the point-wise log-likelihood, draws x
    sweeps). ``pred`` is (draws, sweeps); ``sigma``, ``kappa``, ``tau`` (draws,)."""
    import arviz as az

    resid = jnp.asarray(y)[None, :] - jnp.asarray(pred)
    var = noise_variance(jnp.asarray(pred), sigma=jnp.asarray(sigma)[:, None],
                         kappa=jnp.asarray(kappa)[:, None])
    fn = jax.vmap(lambda r, v, t: loo_conditional(r, v, t, jnp.asarray(proto), n_protocols))
    m, v = fn(resid, var, jnp.asarray(tau))
    cdf = np.asarray(ndtr((resid - m) / jnp.sqrt(v)))
    log_w, _ = az.psislw(-np.asarray(log_lik).T)       # (sweeps, draws), normalised
    return np.sum(np.exp(log_w) * cdf.T, axis=1)
