"""A full simulation-based calibration of every model of the default comparison, each a
``beadrod campaign sbc`` on a 2-worker LocalCluster (slow:
``pytest -m slow tests/test_campaign_sbc_full.py``; issue 50).

Per model (workflows.pipeline.fits.default_model_names: every law in the default
comparison, then the baseline) N replicates: a truth drawn from the prior, a dataset
simulated from the model on the campaign's fixed design with the amplitude ratios
(``--amplitude-ratios``: the amplitude likelihood ``compare`` fits where the data have
amplitudes, so the model calibrated is the one the comparison fits), a NUTS fit, and the
rank of every scalar parameter's truth and of the data's log-likelihood at the truth
(Modrák et al. 2023) among the kept draws. The ranks must be uniform: a Kolmogorov-Smirnov
test on the randomised PIT (inference.evidence.sbc.uniformity_pvalue) per quantity, at
1 % Bonferroni-corrected over every quantity of every model (a false alarm somewhere in
the whole SBC has chance 1 %). A model whose ranks are not uniform fails its own case,
which prints the model, each quantity below the threshold with its p-value (over all
replicates and over those that passed their gate), how many replicates failed their gate
and why, and where the summary and figures are.

**The rung.** A law is calibrated at ``first_order`` where it has a fast path there, and
at ``backbone`` (the comparison's default) where its first order would run the generic
quadrature at every NUTS step (``ContactLaw.too_slow_for_nuts``: the rough sphere and
Maugis-Dugdale; hours per replicate). SBC checks the inference machinery (priors,
likelihood, noise sites, sampler) against the model it simulates from; the rung changes
the shift function inside it, not that machinery, and the first order costs a fraction
of the backbone's table look-ups per step. The baseline has no rung.

**The size.** ``BEADROD_SBC_N`` replicates per model (default :data:`N_DEFAULT`), 2
chains x (``BEADROD_SBC_WARMUP``, default 200) warmup + 50 kept draws, every 2nd kept
(100 draws per replicate; the gate's R-hat needs two chains). ``BEADROD_SBC_LAWS``
(comma-separated) runs some models only; ``BEADROD_SBC_DRAWS`` sets the kept draws per
chain and ``BEADROD_SBC_WORKERS`` the workers (for a check of the plumbing).

The estimate behind the default, from two small runs of this test on the 2-core machine under other load (load average about 6; one worker,
2 chains x 70 steps per replicate): Hertz at first order compiled in about 50 s and then
fitted a replicate in 1.7 s, about 12 ms per step; Maugis-Dugdale at the backbone
compiled in about 85 s and fitted one in 12 s, about 90 ms per step. At this size (2 x
300 steps) that is ~7 s per first-order replicate and ~55 s per backbone one. On 2
workers: a first-order law ~3-5 min with its compilation (more for the costlier ones:
adhesion, the split viscosity, hysteresis), a backbone law ~20 min; seven first-order
laws, two backbone laws and the baseline: ~70-80 min under that load, less on a quiet
machine, under the 90 the issue allows. The first full run must confirm it
(``campaign.csv`` holds each replicate's ``fit_s``): lower ``BEADROD_SBC_N`` if it does
not fit. The estimate holds for this file run alone (``-n 0``): each case starts
its own 2 workers, and the project's ``--dist loadscope`` keeps the cases on one pytest
worker, one after another, but beside other modules' slow tests. With 40 replicates the test sees gross miscalibration only (a bias of about a
third of a posterior sd).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

pytest.importorskip("distributed")

from beadrod.models.registry import get_law  # noqa: E402
from beadrod.workflows.campaign.execute import DONE  # noqa: E402
from beadrod.workflows.campaign.summary import sbc_statistics  # noqa: E402
from beadrod.workflows.cli import main  # noqa: E402
from beadrod.workflows.pipeline.fits import default_model_names  # noqa: E402

N_DEFAULT = 40
ALPHA = 0.01
FIRST = "first_order"
FALLBACK = "backbone"


def _models() -> list[str]:
    names = default_model_names()
    only = os.environ.get("BEADROD_SBC_LAWS")
    if only:
        names = [n for n in names if n in {s.strip() for s in only.split(",")}]
    return names


def rung_of(name: str) -> str:
    """first_order where the law has a fast path there, else the backbone; the
    baseline's rung is a label only."""
    try:
        law = get_law(name)
    except (KeyError, ValueError):  # the baseline: no law, no rung
        return FIRST
    if FIRST in law.physics.rungs and not law.too_slow_for_nuts(FIRST):
        return FIRST
    return FALLBACK


def _kind(failure: str) -> str:
    # a gate failure's kind, as the campaign's summary counts them
    for kind in ("R-hat", "bulk ESS", "tail ESS", "divergent", "E-BFMI"):
        if kind in failure:
            return kind
    return failure


def test_the_rung_follows_the_laws_fast_paths():
    rungs = {n: rung_of(n) for n in default_model_names()}
    assert set(rungs.values()) <= {FIRST, FALLBACK}
    for n, r in rungs.items():
        if r == FALLBACK:
            assert get_law(n).too_slow_for_nuts(FIRST) or FIRST not in get_law(n).physics.rungs


@pytest.mark.slow
@pytest.mark.parametrize("model", _models())
def test_sbc_ranks_are_uniform(model, tmp_path):
    n = int(os.environ.get("BEADROD_SBC_N", N_DEFAULT))
    warmup = os.environ.get("BEADROD_SBC_WARMUP", "200")
    draws = os.environ.get("BEADROD_SBC_DRAWS", "50")
    root = Path(os.environ.get("BEADROD_ARTIFACTS", tmp_path))
    out = root / f"sbc-full-{model}"
    rung = rung_of(model)
    argv = ["campaign", "sbc", "--law", model, "--n", str(n), "--rung", rung,
            "--amplitude-ratios", "--chains", "2", "--warmup", warmup, "--samples", draws,
            "--thin", "2", "--seed", "50",
            "--workers", os.environ.get("BEADROD_SBC_WORKERS", "2"), "--out", str(out), "--quiet"]
    rc = main(argv)
    recs = {p.stem: json.loads(p.read_text()) for p in (out / "tasks").glob("*.json")}
    failed = {k: r.get("error") for k, r in recs.items() if r.get("status") != DONE}
    assert rc == 0 and not failed, f"{model}: tasks FAILED: {failed}"
    done = [recs[k] for k in sorted(recs)]
    stats, n_draws = sbc_statistics(done)
    # Bonferroni over every quantity of every model of the default comparison: each
    # model's own count, times the number of models
    n_tests = len(stats) * len(default_model_names())
    threshold = ALPHA / n_tests
    bad = {k: v for k, v in stats.items() if v["p_all"] < threshold}
    gate_failed = [r for r in done if r["gate"]["status"] != "ok"]
    reasons: dict[str, int] = {}
    for r in gate_failed:
        for f in r["gate"]["failures"]:
            reasons[_kind(f)] = reasons.get(_kind(f), 0) + 1
    divergences = sum(int(r["gate"]["divergences"]) for r in done)
    report = (f"{model} at {rung}: {len(done)} replicates x {n_draws} draws; gate FAILED "
              f"in {len(gate_failed)} ({reasons or 'none'}), {divergences} divergences in "
              f"all; threshold p < {threshold:.2g} (1 % / {n_tests}); summary: "
              f"{out / 'summary.md'}\n" + "\n".join(
                  f"  {k}: p = {v['p_all']:.3g} (all), "
                  f"{'-' if v['p_passed'] is None else format(v['p_passed'], '.3g')} "
                  f"(passed gate, {v['n_passed']})" for k, v in stats.items()))
    print("\n" + report)
    assert not bad, ("ranks not uniform for " + ", ".join(
        f"{model}.{k} (p = {v['p_all']:.3g})" for k, v in bad.items()) + "\n" + report)
