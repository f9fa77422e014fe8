"""Convergence gate for NUTS runs and LOO with Pareto-k reporting.

Gate (Vehtari et al. 2021, "Rank-normalization, folding, and localization"; Betancourt
2016 for E-BFMI): max R-hat < 1.01, min bulk and tail ESS >= 400 (total over chains; 40 %
of the draws for a run of fewer than 1000, :func:`gate_ess`), no divergent transition,
E-BFMI > 0.3 in every chain. A run that fails is marked failed: the verdict says so, a
warning is logged, and ``idata.posterior.attrs`` records it, so every table built from
the run can show it.
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import asdict, dataclass, field
from typing import Any

import arviz as az
import numpy as np

from beadrod.inference.sampling import mcmc_stats

__all__ = ["Verdict", "check", "gate_ess", "ess_minima", "loo_report", "relative_efficiency",
           "DiagnosticsFailed"]

log = logging.getLogger("beadrod.inference")


class DiagnosticsFailed(RuntimeError):
    """Raised by :func:`check` with ``strict=True`` when the gate fails."""


@dataclass(frozen=True)
class Verdict:
    """Outcome of the gate; ``failures`` lists every violated criterion in words."""

    passed: bool
    rhat_max: float
    ess_bulk_min: float
    ess_tail_min: float
    divergences: int
    bfmi_min: float
    failures: tuple[str, ...] = field(default_factory=tuple)
    thresholds: dict[str, float] = field(default_factory=dict)

    @property
    def status(self) -> str:
        return "ok" if self.passed else "FAILED"

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["failures"] = list(self.failures)
        d["status"] = self.status
        return d

    def __str__(self) -> str:
        head = (f"diagnostics {self.status}: R-hat max {self.rhat_max:.4f}, ESS bulk min "
                f"{self.ess_bulk_min:.0f}, tail min {self.ess_tail_min:.0f}, divergences "
                f"{self.divergences}, E-BFMI min {self.bfmi_min:.3f}")
        return head if self.passed else head + "\n  - " + "\n  - ".join(self.failures)


def _varying(post, var_names) -> dict[str, np.ndarray]:
    """Per variable, the mask of elements that vary over the draws (a constant element,
    e.g. a deterministic fixed by the data, has undefined R-hat and ESS)."""
    out = {}
    for v in var_names:
        a = np.asarray(post[v], float)
        # relative: rounding jitter (1e-16) of a data-fixed deterministic is "constant"
        scale = np.abs(a).mean(axis=(0, 1)) + 1e-300
        out[v] = (a.std(axis=(0, 1)) > 1e-10 * scale).ravel()
    return out


def _min_over_vars(ds, masks=None) -> float:
    vals = [np.ravel(ds[v])[masks[v]] if masks else np.ravel(ds[v]) for v in ds]
    vals = np.concatenate(vals) if vals else np.array([np.nan])
    return float(np.nanmin(vals)) if np.any(np.isfinite(vals)) else float("nan")


def gate_ess(num_samples: int, num_chains: int) -> float:
    """The ESS the gate asks of a run of ``num_chains`` x ``num_samples`` draws: 400, or
    40 % of the draws where there are fewer than 1000 (a smoke run's counts)."""
    return min(400.0, 0.4 * num_samples * num_chains)


def _gate_stats(post: Any, var_names: list[str] | None):
    # per variable: the mask of varying elements and (R-hat, bulk ESS, tail ESS); every
    # variable that varies anywhere unless var_names says which
    if var_names is None:
        var_names = [v for v, m in _varying(post, list(post)).items() if m.any()]
    # vectorised (inference.sampling.mcmc_stats; arviz's definitions): az.rhat / az.ess loop over
    # the ~500 elements of a posterior in Python
    masks = _varying(post, var_names)
    return masks, {v: mcmc_stats.gate_stats(np.asarray(post[v], float)) for v in var_names}


def _ess_minima(masks: dict, stats: dict) -> tuple[float, float]:
    return (_min_over_vars({v: st[1] for v, st in stats.items()}, masks),
            _min_over_vars({v: st[2] for v, st in stats.items()}, masks))


def ess_minima(post: Any, var_names: list[str] | None = None) -> tuple[float, float]:
    """(min bulk ESS, min tail ESS) of the draws ``post`` (a posterior dataset, or a dict
    of arrays (chain, draw, ...)) as :func:`check` counts them: every variable, constant
    elements left out."""
    return _ess_minima(*_gate_stats(post, var_names))


def check(idata: az.InferenceData, *, rhat_max: float = 1.01, ess_min: float = 400.0,
          max_divergences: int = 0, bfmi_min: float = 0.3, var_names: list[str] | None = None,
          strict: bool = False) -> Verdict:
    """Apply the gate to ``idata`` (posterior + sample_stats); mark and warn on failure.

    R-hat and ESS are taken over every posterior variable (deterministics included,
    except constant elements, whose R-hat is undefined: e.g. the up-sweep predictions
    of a law with no shape parameter). NaN R-hat counts as a failure.
    """
    post = idata.posterior
    masks, stats = _gate_stats(post, var_names)
    r_all = np.concatenate([np.ravel(st[0])[masks[v]] for v, st in stats.items()])
    r_max = float(np.max(r_all)) if np.all(np.isfinite(r_all)) else float("nan")
    eb, et = _ess_minima(masks, stats)
    ss = idata.sample_stats
    div = int(np.asarray(ss["diverging"]).sum()) if "diverging" in ss else 0
    bfmi = float(np.min(az.bfmi(idata))) if "energy" in ss else float("nan")
    fails = []
    if not np.isfinite(r_max) or r_max >= rhat_max:
        fails.append(f"R-hat max {r_max:.4f} >= {rhat_max}")
    if not eb >= ess_min:
        fails.append(f"bulk ESS min {eb:.0f} < {ess_min:.0f}")
    if not et >= ess_min:
        fails.append(f"tail ESS min {et:.0f} < {ess_min:.0f}")
    if div > max_divergences:
        fails.append(f"{div} divergent transitions > {max_divergences}")
    if not bfmi > bfmi_min:
        fails.append(f"E-BFMI min {bfmi:.3f} <= {bfmi_min}")
    verdict = Verdict(not fails, r_max, eb, et, div, bfmi, tuple(fails),
                      {"rhat_max": rhat_max, "ess_min": ess_min,
                       "max_divergences": max_divergences, "bfmi_min": bfmi_min})
    post.attrs["diagnostics"] = verdict.status
    post.attrs["diagnostics_failures"] = "; ".join(fails)
    if fails:
        msg = f"NUTS run {post.attrs.get('model', '')} FAILED its diagnostics:\n{verdict}"
        log.error(msg)
        warnings.warn(msg, RuntimeWarning, stacklevel=2)
        if strict:
            raise DiagnosticsFailed(msg)
    return verdict


def relative_efficiency(idata: az.InferenceData) -> float:
    """PSIS's relative efficiency r_eff, as ``az.loo`` computes it when not given one: the
    mean ESS ("mean" method) over every posterior variable, per draw; 1 for one chain.
    It depends on the posterior alone, so one value serves every observed site's LOO
    (computing it is most of a LOO's cost: the ESS of every deterministic element)."""
    post = idata.posterior
    n = post.sizes["chain"] * post.sizes["draw"]
    if post.sizes["chain"] == 1:
        return 1.0
    ess = az.ess(post, method="mean")
    return float(np.hstack([np.ravel(ess[v].values) for v in ess.data_vars]).mean() / n)


def loo_report(idata: az.InferenceData, var_name: str | None = None,
               reff: float | None = None) -> dict[str, Any]:
    """PSIS-LOO with Pareto-k counts (k <= 0.7 good, 0.7-1 bad, > 1 very bad).

    With several observed sites, ``var_name`` picks one (arviz needs a single
    pointwise log-likelihood); default: the drive sweeps ('shift_obs') if present.
    ``reff``: :func:`relative_efficiency` of ``idata``, when the caller has it already.
    """
    ll = idata.log_likelihood
    if var_name is None:
        var_name = "shift_obs" if "shift_obs" in ll else next(iter(ll.data_vars))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        loo = az.loo(idata, var_name=var_name, pointwise=True, reff=reff)
    k = np.asarray(loo.pareto_k)
    return {
        "var_name": var_name,
        "elpd_loo": float(loo.elpd_loo),
        "se": float(loo.se),
        "p_loo": float(loo.p_loo),
        "n_points": int(k.size),
        "k_good": int(np.sum(k <= 0.7)),
        "k_bad": int(np.sum((k > 0.7) & (k <= 1.0))),
        "k_very_bad": int(np.sum(k > 1.0)),
        "k_max": float(np.max(k)),
        "reliable": bool(np.all(k <= 0.7)),
    }
