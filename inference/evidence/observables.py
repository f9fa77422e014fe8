"""The law each observable prefers, and the law all of them prefer together.

Every model's likelihood is a density of the same observed variables (f0, the shifts,
the reference Q, the amplitude ratios), each an observed site with its own point-wise
log-likelihood (:data:`inference.model.likelihood.OBSERVED_SITES`). Per site, the
expected log predictive density by Pareto-smoothed leave-one-out,

    elpd_loo = sum_i ln p(y_i | y_-i)                                        [nats]

(Vehtari, Gelman & Gabry 2017; :func:`site_loos`), ranks the laws that read it
(``arviz.compare``). The preferred law of a site is the eligible law (one that passed
its gate, not the law-free baseline) with the highest elpd; its lead over the runner-up
is Delta elpd +- the standard error of the point-wise differences (``dse``): a lead below
:data:`RESOLVED_SE` times that error is not resolved. PSIS is unreliable where a point's
Pareto k > 0.7 (counted per law and site, as the LOO table's). A law whose likelihood did
not read a site (``--observables shift``) is not in that site's contest, and is listed as
absent. All together: the evidence ranking
(:func:`inference.evidence.ranking.rank_evidence`), log Z of every observable jointly.
Only fits of one dataset are compared (:func:`inference.evidence.ranking.one_data_hash`).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Mapping
from typing import Any

import arviz as az
import numpy as np

from beadrod.inference.evidence.ranking import one_data_hash
from beadrod.inference.model.likelihood import OBSERVED_SITES
from beadrod.inference.sampling.diagnostics import relative_efficiency

__all__ = ["OBSERVABLE_NAMES", "RESOLVED_SE", "K_GOOD", "site_loos", "site_contest",
           "preference_by_observable"]

OBSERVABLE_NAMES = {"f0_obs": "f0", "shift_obs": "shift", "q_obs": "reference Q",
                    "amp_obs": "amplitude per volt"}
"""What each observed site holds, as the report names it."""

RESOLVED_SE = 2.0
"""A lead in elpd counts as resolved beyond this many standard errors of the difference."""

K_GOOD = 0.7
"""Pareto k above which a point's PSIS-LOO estimate is unreliable (Vehtari et al. 2024)."""


def site_loos(idata: az.InferenceData) -> dict[str, Any]:
    """PSIS-LOO (``arviz.ELPDData``, point-wise) of each observed site ``idata`` holds a
    point-wise log-likelihood of."""
    ll = getattr(idata, "log_likelihood", None)
    out = {}
    reff = None  # one relative efficiency for every site: it depends on the posterior alone
    for site in OBSERVED_SITES:
        if ll is None or site not in ll:
            continue
        if reff is None:
            reff = relative_efficiency(idata)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out[site] = az.loo(idata, var_name=site, pointwise=True, reff=reff)
    return out


def _lead(loos: Mapping[str, Any], a: str, b: str) -> tuple[float, float]:
    """elpd_a - elpd_b [nats] and the standard error of the point-wise differences."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = az.compare({a: loos[a], b: loos[b]}, ic="loo")
    return float(t.loc[a, "elpd_loo"] - t.loc[b, "elpd_loo"]), float(t["dse"].max())


def site_contest(loos: Mapping[str, Mapping[str, Any]], site: str, *,
                 eligible: Iterable[str] | None = None, baselines: Iterable[str] = ()
                 ) -> dict[str, Any]:
    """One observed site's contest (module docstring). ``loos``: model -> its
    :func:`site_loos`; ``eligible``: the models that may be preferred (default all);
    ``baselines``: law-free models, ranked but never preferred. JSON-ready: ``site``,
    ``observable``, ``elpd`` (per model: elpd_loo, se, k_bad, n, in rank order),
    ``preferred``, ``runner_up``, ``delta_elpd``, ``delta_se``, ``resolved``, ``absent``
    (models without the site), ``baseline`` and ``baseline_delta`` /
    ``baseline_delta_se`` (the best baseline's elpd minus the preferred law's: > 0, it
    predicts this observable better than every law)."""
    have = {k: v[site] for k, v in loos.items() if site in v}
    out: dict[str, Any] = {"site": site, "observable": OBSERVABLE_NAMES.get(site, site),
                           "absent": sorted(set(loos) - set(have)), "elpd": {},
                           "preferred": None, "runner_up": None, "delta_elpd": None,
                           "delta_se": None, "resolved": None, "baseline": None,
                           "baseline_delta": None, "baseline_delta_se": None}
    order = sorted(have, key=lambda k: -float(have[k].elpd_loo))
    for name in order:
        k = np.asarray(have[name].pareto_k)
        out["elpd"][name] = {"elpd_loo": float(have[name].elpd_loo),
                             "se": float(have[name].se),
                             "k_bad": int(np.sum(k > K_GOOD)), "n": int(k.size)}
    base = set(baselines)
    ok = set(have) if eligible is None else set(eligible)
    laws = [k for k in order if k in ok and k not in base]
    bases = [k for k in order if k in base]
    if not laws:
        return out
    out["preferred"] = laws[0]
    if len(laws) > 1:
        d, se = _lead(have, laws[0], laws[1])
        out.update(runner_up=laws[1], delta_elpd=d, delta_se=se,
                   resolved=bool(d > RESOLVED_SE * se))
    if bases:
        d, se = _lead(have, bases[0], laws[0])
        out.update(baseline=bases[0], baseline_delta=d, baseline_delta_se=se)
    return out


def preference_by_observable(loos: Mapping[str, Mapping[str, Any]],
                             evidence: Mapping[str, Any], *,
                             eligible: Iterable[str] | None = None,
                             baselines: Iterable[str] = (),
                             data_hashes: Mapping[str, str | None] | None = None
                             ) -> dict[str, Any]:
    """Per observed site the contest of :func:`site_contest` (sites no model read are
    left out, their names under ``unread``), and ``all``: the evidence ranking ``evidence``
    (:func:`inference.evidence.ranking.rank_evidence`'s dict) as preferred law, runner-up
    and log Z gap +- error [nats]. ``data_hashes`` (model -> data hash), where given, must
    be one hash. JSON-ready."""
    if data_hashes is not None:
        one_data_hash({k: data_hashes.get(k) for k in loos})
    eligible = None if eligible is None else list(eligible)
    sites = [site_contest(loos, s, eligible=eligible, baselines=baselines)
             for s in OBSERVED_SITES]
    return {"observables": [s for s in sites if s["elpd"]],
            "unread": [s["observable"] for s in sites if not s["elpd"]],
            "all": {"preferred": evidence.get("best"), "runner_up": evidence.get("runner_up"),
                    "delta_log_z": evidence.get("gap"),
                    "delta_log_z_err": evidence.get("gap_err"),
                    "baseline": evidence.get("baseline"),
                    "baseline_lead": evidence.get("baseline_lead"),
                    "baseline_lead_err": evidence.get("baseline_lead_err")}}
