"""The Q-versus-shift tension of the viscoelastic law, quantified from finished fits.

The one place where the tension statistics are computed. The fits are the caller's
(``workflows.pipeline.outputs`` runs them in its worker pool; a test can run them with
:func:`inference.sampling.sample.run_nuts`), all on one dataset and one rung:

  shift-only (``use_q=False``), Q-only (``use_shift=False``), joint with one shared eta,
  and joint with eta split into eta_shift (shift) and eta_q (Q).

:func:`analyse_tension` returns, each with the meaning the report states:

* eta quantiles (5, 50, 95 %) [Pa s] of the shift-only, Q-only and joint fits;
* the gap g = log10 eta_shift - log10 eta_Q [decades] between the two single-source
  posteriors, its 5/50/95 % quantiles by randomly pairing their independent draws: a 90 %
  interval that excludes 0 says the shift and Q need different viscosities;
* P(eta_shift > eta_Q) in the split model's one joint posterior;
* the log Bayes factor of split over shared eta, log Z_split - log Z_shared [nats], with
  the two evidence errors in quadrature: > 0 favours two viscosities (Kass & Raftery
  1995, in nats: 1-3 positive, 3-5 strong, > 5 very strong);
* the posterior predictive check of the joint fit, per observable (shift, log Q): the
  standardised residuals z = (y - E[rep]) / sd[rep] and the p-value of the discrepancy
  T = sum z^2, p = P(T(rep) >= T(obs)); p < 0.05 says the joint fit cannot reproduce it.

Under the 'first_order' and 'backbone' rungs eta does not enter the shift (models.laws.viscoelastic:
damping moves the damping, not the stiffness): the shift alone says nothing about eta,
so there is no shift-only eta, no gap and no P(eta_shift > eta_Q) (eta_shift of the split
model is its prior there), and the split-vs-shared Bayes factor is 0 up to its error by
construction. The tension exists only under the paper's Eq. 25 ('paper_eq25').
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import arviz as az
import numpy as np

from beadrod.inference.evidence.ranking import log_bayes_factor

__all__ = ["ETA_IN_SHIFT", "prob_greater", "log10_gap", "ppc_failure", "analyse_tension"]

ETA_IN_SHIFT = ("paper_eq25",)
"""Rungs on which the viscoelastic shift depends on eta."""


def prob_greater(a: np.ndarray, b: np.ndarray, seed: int = 0) -> float:
    """P(a > b) for independent posteriors, by randomly pairing draws."""
    a = np.asarray(a, float).ravel()
    b = np.asarray(b, float).ravel()
    rng = np.random.default_rng(seed)
    n = min(a.size, b.size)
    return float(np.mean(rng.choice(a, n, replace=False) > rng.choice(b, n, replace=False)))


def log10_gap(a: np.ndarray, b: np.ndarray, seed: int = 0) -> list[float]:
    """5/50/95 % quantiles of log10 a - log10 b [decades] for independent posteriors of
    positive quantities, by randomly pairing draws."""
    a = np.log10(np.asarray(a, float).ravel())
    b = np.log10(np.asarray(b, float).ravel())
    rng = np.random.default_rng(seed)
    n = min(a.size, b.size)
    d = rng.choice(a, n, replace=False) - rng.choice(b, n, replace=False)
    return [float(v) for v in np.percentile(d, [5, 50, 95])]


def _flat(x) -> np.ndarray:
    x = np.asarray(x)
    return x.reshape(-1, *x.shape[2:])


def ppc_failure(idata: az.InferenceData, site: str, *, log: bool = False) -> dict[str, float]:
    """Standardised residuals and the discrepancy p-value of one observed site."""
    rep = _flat(idata.posterior_predictive[site])
    obs = np.asarray(idata.observed_data[site])
    if log:
        rep, obs = np.log(rep), np.log(obs)
    mu, sd = rep.mean(0), rep.std(0) + 1e-300
    z = (obs - mu) / sd
    t_obs = float(np.sum(z**2))
    t_rep = np.sum(((rep - mu) / sd) ** 2, axis=1)
    return {"mean_std_residual": float(z.mean()), "rms_std_residual": float(np.sqrt(np.mean(z**2))),
            "max_abs_std_residual": float(np.max(np.abs(z))), "T_obs": t_obs,
            "p_value": float(np.mean(t_rep >= t_obs)), "n": int(obs.size)}


def _triple(x) -> list[float]:
    return [float(v) for v in np.percentile(np.asarray(x, float).ravel(), [5, 50, 95])]


def analyse_tension(
    *,
    rung: str,
    eta_q: np.ndarray,
    shared: az.InferenceData,
    split: az.InferenceData,
    eta_shift: np.ndarray | None = None,
    log_z_shared: Sequence[float] | None = None,
    log_z_split: Sequence[float] | None = None,
    seed: int = 0,
    param: str = "eta",
) -> dict[str, Any]:
    """The tension statistics (module docstring) from the four fits' results.

    ``eta_q`` and ``eta_shift`` [Pa s] are the draws of the Q-only and shift-only fits
    (``eta_shift`` is ignored, and may be None, on a rung where eta does not enter the
    shift); ``shared`` and ``split`` the joint fits' InferenceData (with posterior
    predictive draws); ``log_z_*`` their (log Z, error) [nats] when computed. ``param``:
    the loss parameter's name in the shared fit (models.law.Presentation.tension_param);
    the split fit carries it as ``<param>_shift`` and ``<param>_q``. The keys say eta
    whatever ``param`` is called. JSON-ready.
    """
    in_shift = rung in ETA_IN_SHIFT
    if in_shift and eta_shift is None:
        raise ValueError(f"rung {rung!r}: eta enters the shift, the shift-only draws are needed")
    post_split = split.posterior
    e_shift, e_q = f"{param}_shift", f"{param}_q"
    ppc = {"shift": ppc_failure(shared, "shift_obs"), "q": ppc_failure(shared, "q_obs", log=True)}
    log_bf = log_bf_err = None
    if log_z_shared is not None and log_z_split is not None:
        log_bf, log_bf_err = log_bayes_factor(tuple(log_z_split), tuple(log_z_shared))
    return {
        "rung": rung, "eta_in_shift": in_shift,
        "eta_shift_q05_q50_q95": _triple(eta_shift) if in_shift else None,
        "eta_q_q05_q50_q95": _triple(eta_q),
        "eta_joint_q05_q50_q95": _triple(shared.posterior[param]),
        "eta_split_shift_q05_q50_q95": _triple(post_split[e_shift]),
        "eta_split_q_q05_q50_q95": _triple(post_split[e_q]),
        "log10_gap_q05_q50_q95": log10_gap(eta_shift, eta_q, seed) if in_shift else None,
        "p_shift_gt_q": (float(np.mean(np.asarray(post_split[e_shift])
                                       > np.asarray(post_split[e_q]))) if in_shift else None),
        "log_bf_split_vs_shared": log_bf, "log_bf_err": log_bf_err,
        "ppc": {"shift_p": ppc["shift"]["p_value"], "q_p": ppc["q"]["p_value"],
                "missed": min(ppc, key=lambda k: (ppc[k]["p_value"],
                                                  -ppc[k]["rms_std_residual"])),
                "detail": ppc},
    }
