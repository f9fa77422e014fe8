"""Model comparison: the evidence ranking, LOO (``arviz.compare``), LOO-PIT calibration.

:func:`rank_evidence` is the one ranking of laws by log evidence: the report's headline,
its comparison table and the Bayes factors of the tension read it. Delta log Z of two
independent runs carries their errors in quadrature (:func:`log_bayes_factor`).

The tables are only meaningful across models fitted to the same data, so every entry
carries the data hash (``idata.posterior.attrs['data_hash']`` or given explicitly) and
mixing hashes raises :class:`DataHashMismatch`. Runs whose diagnostics failed stay in
the tables, flagged in a 'diagnostics' column.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import arviz as az
import numpy as np
import pandas as pd

from beadrod.inference.evidence.log_z import EvidenceResult, combined_agreement

__all__ = ["DataHashMismatch", "one_data_hash", "loo_table", "evidence_table",
           "log_bayes_factor", "rank_evidence", "loo_pit_summary", "loo_pit_values",
           "LOO_PIT_P_MIN"]

LOO_PIT_P_MIN = 0.01
"""Kolmogorov-Smirnov p-value below which LOO-PIT values count as non-uniform."""


class DataHashMismatch(ValueError):
    """Models fitted to different data were put in one comparison."""


def one_data_hash(hashes: Mapping[str, str | None]) -> str:
    """The one data hash of ``hashes`` (model -> hash of the data it was fitted to);
    :class:`DataHashMismatch` where one is missing or two differ."""
    missing = [k for k, h in hashes.items() if not h]
    if missing:
        raise DataHashMismatch(f"no data hash recorded for {missing}: cannot compare safely")
    uniq = set(hashes.values())
    if len(uniq) != 1:
        detail = ", ".join(f"{k}: {h[:12]}" for k, h in hashes.items())
        raise DataHashMismatch(f"models were fitted to different data ({detail})")
    return uniq.pop()


def loo_table(idatas: Mapping[str, az.InferenceData], *, var_name: str = "shift_obs",
              data_hash: str | None = None) -> pd.DataFrame:
    """``arviz.compare`` (PSIS-LOO on ``var_name``) plus data hash and diagnostics flags."""
    h = one_data_hash({k: v.posterior.attrs.get("data_hash", data_hash)
                       for k, v in idatas.items()})
    table = az.compare(dict(idatas), ic="loo", var_name=var_name)
    table["diagnostics"] = [idatas[k].posterior.attrs.get("diagnostics", "unchecked")
                            for k in table.index]
    table["data_hash"] = h
    return table


def evidence_table(results: Mapping[str, Mapping[str, EvidenceResult]],
                   data_hashes: Mapping[str, str], *, n_sigma: float = 3.0,
                   diagnostics: Mapping[str, str] | None = None) -> pd.DataFrame:
    """One row per model: log Z +- error from each estimator, their agreement, and
    log Bayes factors against the best model (by the nested-sampling value).

    ``results[model]`` maps estimator name ('nested_sampling', 'tempered_smc') to its
    result; ``data_hashes[model]`` the hash of the data that model was fitted to.
    """
    h = one_data_hash({k: data_hashes.get(k) for k in results})
    rows = []
    for model, est in results.items():
        row: dict[str, object] = {"model": model}
        for name, r in est.items():
            row[f"log_z_{name}"] = r.log_z
            row[f"err_{name}"] = r.log_z_err
            row[f"time_s_{name}"] = r.wall_s
        if len(est) >= 2:
            a, b = list(est.values())[:2]
            ok, z = combined_agreement(a, b, n_sigma)
            row["agree"] = ok
            row["disagreement_sigma"] = z
        else:
            row["agree"] = None
        vals = np.array([r.log_z for r in est.values()])
        errs = np.array([r.log_z_err for r in est.values()])
        w = 1.0 / np.maximum(errs, 1e-3) ** 2
        row["log_z"] = float(np.sum(w * vals) / np.sum(w))
        row["log_z_err"] = float(np.sqrt(1.0 / np.sum(w)))
        row["diagnostics"] = (diagnostics or {}).get(model, "n/a")
        rows.append(row)
    table = pd.DataFrame(rows).set_index("model")
    best = table["log_z"].max()
    table["log_bf_vs_best"] = table["log_z"] - best
    table["data_hash"] = h
    return table.sort_values("log_z", ascending=False)


def _z_err(e: EvidenceResult | Sequence[float]) -> tuple[float, float]:
    if isinstance(e, EvidenceResult):
        return float(e.log_z), float(e.log_z_err)
    z, err = e
    return float(z), float(err)


def log_bayes_factor(a: EvidenceResult | Sequence[float],
                     b: EvidenceResult | Sequence[float]) -> tuple[float, float]:
    """log B_ab = log Z_a - log Z_b [nats] and its 1-sigma error (independent errors).

    ``a`` and ``b`` are :class:`EvidenceResult` or (log Z, error) pairs."""
    (za, ea), (zb, eb) = _z_err(a), _z_err(b)
    return za - zb, float(np.hypot(ea, eb))


def _finite(v: Any) -> bool:
    try:
        return math.isfinite(float(v))
    except (TypeError, ValueError):
        return False


def rank_evidence(entries: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Rank laws by log evidence [nats].

    Each entry has ``name``, ``log_z``, ``log_z_err``, ``ok`` (passed its sampling gate)
    and ``baseline`` (a law-free reference model, never 'preferred'). Returns

    * ``best``: the passing non-baseline law with the highest log Z (None if none),
      ``runner_up`` the next one, ``gap`` = log Z_best - log Z_runner_up ± ``gap_err``;
    * ``baseline``: the best passing baseline, ``baseline_lead`` = log Z_baseline -
      log Z_best ± ``baseline_lead_err`` (> 0: the baseline beats every law);
    * ``reference``: the entry every ``delta`` is measured against (``best``, else the
      highest finite non-baseline log Z among failed runs, else any), and
      ``delta[name]`` = (log Z - log Z_reference, error); the reference's own is (0, 0).

    Errors of two runs add in quadrature (independent estimates).
    """
    finite = [e for e in entries if _finite(e.get("log_z"))]

    def top(pool):
        return sorted(pool, key=lambda e: -float(e["log_z"]))

    laws = top([e for e in finite if e.get("ok") and not e.get("baseline")])
    bases = top([e for e in finite if e.get("ok") and e.get("baseline")])
    ref_pool = laws or top([e for e in finite if not e.get("baseline")]) or top(finite)
    ref = ref_pool[0] if ref_pool else None
    out: dict[str, Any] = {"best": None, "runner_up": None, "gap": None, "gap_err": None,
                           "baseline": None, "baseline_lead": None, "baseline_lead_err": None,
                           "reference": ref["name"] if ref else None, "delta": {}}

    def pair(e):
        err = e.get("log_z_err")
        return float(e["log_z"]), float(err) if _finite(err) else math.nan

    if laws:
        out["best"] = laws[0]["name"]
        if len(laws) > 1:
            out["runner_up"] = laws[1]["name"]
            out["gap"], out["gap_err"] = log_bayes_factor(pair(laws[0]), pair(laws[1]))
        if bases:
            out["baseline"] = bases[0]["name"]
            out["baseline_lead"], out["baseline_lead_err"] = log_bayes_factor(pair(bases[0]),
                                                                              pair(laws[0]))
    for e in finite:
        out["delta"][e["name"]] = ((0.0, 0.0) if e is ref else log_bayes_factor(pair(e), pair(ref)))
    return out


_PROTOCOL_SITES = {
    # observed site: (its noise-free prediction, floor sd, growth, shared sd, dimension)
    "shift_obs": ("shift_pred", "sigma_shift", "kappa_shift", "tau_shift", "sweep"),
    "amp_obs": ("amp_pred", "sigma_amp", None, "tau_amp", "amp_sweep"),
}


def loo_pit_values(idata: az.InferenceData, var_name: str = "shift_obs") -> np.ndarray:
    """LOO-PIT values of ``var_name``. Where its observations share a protocol offset
    (the shifts under the protocol noise model, the amplitude ratios), each value is the
    conditional Normal's given the protocol's other observations
    (:func:`inference.model.shift_noise.loo_pit`): the posterior predictive draws, which
    ``az.loo_pit`` reads, are the joint ones and would count the shared offset twice."""
    from beadrod.inference.model.shift_noise import loo_pit

    post = idata.posterior
    spec = _PROTOCOL_SITES.get(var_name)
    if spec is None or spec[3] not in post:
        return np.asarray(az.loo_pit(idata, y=var_name), float).ravel()
    pred_name, sigma, kappa, tau, dim = spec
    flat = post.stack(sample=("chain", "draw"))
    # only the grouping matters: protocols in order of first appearance
    _, proto = np.unique(np.asarray(post[f"{dim}_protocol"]), return_inverse=True)
    ll = idata.log_likelihood[var_name].stack(sample=("chain", "draw"))
    scale = np.asarray(flat[sigma])
    growth = np.asarray(flat[kappa]) if kappa else np.zeros_like(scale)
    return loo_pit(np.asarray(idata.observed_data[var_name]),
                   np.asarray(flat[pred_name].transpose("sample", dim)), scale, growth,
                   np.asarray(flat[tau]), proto, int(proto.max()) + 1,
                   np.asarray(ll.transpose("sample", dim)))


def loo_pit_summary(idata: az.InferenceData, var_name: str = "shift_obs") -> dict[str, Any]:
    """Calibration of the leave-one-out predictive of ``var_name`` (LOO-PIT).

    PIT_i = P(y_rep,i <= y_i | y_-i), uniform on [0, 1] for a calibrated model
    (Gelfand et al. 1992; Gabry et al. 2019), from :func:`loo_pit_values`. Returned: the
    Kolmogorov-Smirnov distance ``ks_d`` to the uniform and its p-value ``ks_p``
    (``calibrated``: p >= LOO_PIT_P_MIN); ``tails``, the share of PIT values below 0.05
    or above 0.95 (0.10 if calibrated; more: the predictive is too narrow, fewer: too
    wide); ``mean`` (0.5 if calibrated; above: the data lie above the predictions); ``n``
    values.
    """
    from scipy import stats

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pit = loo_pit_values(idata, var_name)
    pit = pit[np.isfinite(pit)]
    if pit.size == 0:
        raise ValueError(f"no finite LOO-PIT values for {var_name!r}")
    ks = stats.kstest(pit, "uniform")
    tails = float(np.mean((pit < 0.05) | (pit > 0.95)))
    return {"var_name": var_name, "n": int(pit.size), "ks_d": float(ks.statistic),
            "ks_p": float(ks.pvalue), "tails": tails, "mean": float(pit.mean()),
            "calibrated": bool(ks.pvalue >= LOO_PIT_P_MIN)}
