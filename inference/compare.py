"""Model comparison tables: LOO (``arviz.compare``) and evidence (two estimators).

Both tables are only meaningful across models fitted to the same data, so every entry
carries the data hash (``idata.posterior.attrs['data_hash']`` or given explicitly) and
mixing hashes raises :class:`DataHashMismatch`. Runs whose diagnostics failed stay in
the tables, flagged in a 'diagnostics' column.
"""

from __future__ import annotations

from collections.abc import Mapping

import arviz as az
import numpy as np
import pandas as pd

from .evidence import EvidenceResult, combined_agreement

__all__ = ["DataHashMismatch", "loo_table", "evidence_table", "log_bayes_factor"]


class DataHashMismatch(ValueError):
    """Models fitted to different data were put in one comparison."""


def _one_hash(hashes: Mapping[str, str | None]) -> str:
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
    h = _one_hash({k: v.posterior.attrs.get("data_hash", data_hash) for k, v in idatas.items()})
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
    h = _one_hash({k: data_hashes.get(k) for k in results})
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


def log_bayes_factor(a: EvidenceResult, b: EvidenceResult) -> tuple[float, float]:
    """log B_ab = log Z_a - log Z_b and its 1-sigma error (independent errors)."""
    return a.log_z - b.log_z, float(np.hypot(a.log_z_err, b.log_z_err))
