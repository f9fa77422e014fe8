"""The Q-versus-shift tension of the viscoelastic law, quantified.

On one dataset and one rung, four viscoelastic fits:
  shift-only (``use_q=False``), Q-only (``use_shift=False``), joint with one shared eta,
  and joint with eta split into eta_shift and eta_q.
Reported:
  * eta posteriors (log10 quantiles) of the shift-only, Q-only and joint fits;
  * overlap of the shift-only and Q-only eta posteriors: the Bhattacharyya coefficient
    BC = sum_bins sqrt(p_i q_i) of log10 eta histograms on common bins (1 = identical,
    0 = disjoint), and P(log eta_shift > log eta_Q) from the split fit (and from
    pairing the two single-source fits' draws);
  * log Bayes factor shared vs split eta from the evidences (both estimators, when
    requested: negative means the data prefer two different viscosities);
  * posterior predictive failure of the joint fit: for shift and for Q, the mean
    standardised residual (obs - E[rep]) / sd[rep] and the posterior predictive p-value
    of the discrepancy T = sum ((y - E[rep]) / sd[rep])^2, p = P(T(rep) >= T(obs)).
    The source with the smaller p (and larger residuals) is the one the joint fit misses.

Under the 'first_order' or 'backbone' rungs the shift does not depend on eta at all, so
the shift-only eta posterior is the prior (BC near the prior's overlap with the Q-only
posterior): the tension exists only under the paper's Eq. 25 ('paper_eq25').
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import arviz as az
import numpy as np

from .evidence import nested_sampling_log_z, smc_log_z
from .numpyro_models import ModelSpec, build_model
from .sample import run_nuts

__all__ = ["TensionReport", "bhattacharyya", "prob_greater", "ppc_failure", "analyse_tension"]


def bhattacharyya(a: np.ndarray, b: np.ndarray, bins: int = 60) -> float:
    """Bhattacharyya coefficient of two samples on common histogram bins [0, 1]."""
    a = np.asarray(a, float).ravel()
    b = np.asarray(b, float).ravel()
    lo, hi = min(a.min(), b.min()), max(a.max(), b.max())
    if hi <= lo:
        return 1.0
    edges = np.linspace(lo, hi, bins + 1)
    p = np.histogram(a, edges)[0] / a.size
    q = np.histogram(b, edges)[0] / b.size
    return float(np.sum(np.sqrt(p * q)))


def prob_greater(a: np.ndarray, b: np.ndarray, seed: int = 0) -> float:
    """P(a > b) for independent posteriors, by randomly pairing draws."""
    a = np.asarray(a, float).ravel()
    b = np.asarray(b, float).ravel()
    rng = np.random.default_rng(seed)
    n = min(a.size, b.size)
    return float(np.mean(rng.choice(a, n, replace=False) > rng.choice(b, n, replace=False)))


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


@dataclass
class TensionReport:
    """Everything :func:`analyse_tension` measures (plain numbers, JSON-ready)."""

    rung: str
    data_hash: str | None
    eta_quantiles: dict[str, dict[str, float]]
    bhattacharyya: float
    p_shift_gt_q_split: float
    p_shift_gt_q_independent: float
    log_bf_shared_vs_split: dict[str, tuple[float, float]] = field(default_factory=dict)
    ppc_joint: dict[str, dict[str, float]] = field(default_factory=dict)
    missed_by_joint: str = ""
    diagnostics: dict[str, str] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _q(x: np.ndarray) -> dict[str, float]:
    x = np.log10(np.asarray(x).ravel())
    p = np.percentile(x, [5, 50, 95])
    return {"log10_q05": float(p[0]), "log10_median": float(p[1]), "log10_q95": float(p[2])}


def analyse_tension(
    data: dict[str, Any],
    *,
    rung: str = "paper_eq25",
    data_hash: str | None = None,
    num_warmup: int = 500,
    num_samples: int = 500,
    num_chains: int = 4,
    seed: int = 0,
    evidence: bool = True,
    ns_live_points: int | None = None,
    smc_particles: int = 1000,
    smc_seeds: tuple[int, ...] = (0, 1, 2, 3),
    likelihood: str = "normal",
) -> TensionReport:
    """Run the four viscoelastic fits on ``data`` (model inputs) and measure the tension."""
    from .diagnostics import check

    base = dict(law="viscoelastic", rung=rung, likelihood=likelihood)
    specs = {
        "shift_only": ModelSpec(**base, use_q=False),
        "q_only": ModelSpec(**base, use_shift=False),
        "joint_shared": ModelSpec(**base),
        "joint_split": ModelSpec(**base, eta_mode="split"),
    }
    fits = {}
    diag = {}
    for i, (name, spec) in enumerate(specs.items()):
        fit = run_nuts(build_model(spec), data, num_warmup=num_warmup, num_samples=num_samples,
                       num_chains=num_chains, seed=seed + i, data_hash=data_hash)
        fits[name] = fit.idata
        diag[name] = check(fit.idata, ess_min=min(400.0, 0.4 * num_samples * num_chains)).status
    eta_s = np.asarray(fits["shift_only"].posterior["eta"])
    eta_q = np.asarray(fits["q_only"].posterior["eta"])
    split = fits["joint_split"].posterior
    quant = {"shift_only": _q(eta_s), "q_only": _q(eta_q),
             "joint_shared": _q(fits["joint_shared"].posterior["eta"]),
             "split_eta_shift": _q(split["eta_shift"]), "split_eta_q": _q(split["eta_q"])}
    bc = bhattacharyya(np.log10(eta_s), np.log10(eta_q))
    p_split = float(np.mean(np.asarray(split["eta_shift"]) > np.asarray(split["eta_q"])))
    p_ind = prob_greater(np.log10(eta_s), np.log10(eta_q), seed)
    ppc = {"shift": ppc_failure(fits["joint_shared"], "shift_obs"),
           "q": ppc_failure(fits["joint_shared"], "q_obs", log=True)}
    missed = min(ppc, key=lambda k: (ppc[k]["p_value"], -ppc[k]["rms_std_residual"]))
    bfs: dict[str, tuple[float, float]] = {}
    if evidence:
        shared, splitm = build_model(specs["joint_shared"]), build_model(specs["joint_split"])
        for label, fn in (("nested_sampling", lambda m: nested_sampling_log_z(
                m, {"data": data}, num_live_points=ns_live_points, seed=seed)),
                          ("tempered_smc", lambda m: smc_log_z(
                m, {"data": data}, num_particles=smc_particles, seeds=smc_seeds))):
            a, b = fn(shared), fn(splitm)
            bfs[label] = (a.log_z - b.log_z, float(np.hypot(a.log_z_err, b.log_z_err)))
    return TensionReport(rung, data_hash, quant, bc, p_split, p_ind, bfs, ppc, missed, diag)
