"""A campaign's summary, rebuilt from its task records whenever the campaign runs:
``campaign.csv``, ``summary.md`` and ``figures/*.png``.

SBC (this module): a row per replicate; per parameter and for the log-likelihood test
quantity the uniformity p-value of the ranks (inference.evidence.sbc.uniformity_pvalue)
over every replicate that ran and over those that passed their gate, the ECDF-difference
plot with its simultaneous band (workflows.pipeline.sbc_outputs.plot_ecdf) and rank
histograms with the replicates that failed their gate stacked in their own colour: the
failures are counted and shown, never dropped. Recovery and datasets:
workflows.campaign.summary_compare.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from beadrod.workflows.campaign.execute import DONE  # noqa: E402
from beadrod.workflows.campaign.tables import (  # noqa: E402
    CAMPAIGN_CSV,
    FIGURES,
    SUMMARY_MD,
    fmt,
    status_lines,
    write_table,
)
from beadrod.workflows.campaign.tasks import Task  # noqa: E402

__all__ = ["write_summary", "sbc_statistics", "SUMMARY_MD", "CAMPAIGN_CSV", "FIGURES"]

ALPHA = 0.01  # a p-value below this (Bonferroni over the parameters) flags a parameter


def sbc_statistics(done: list[dict[str, Any]]) -> tuple[dict[str, dict[str, Any]], int]:
    """Per ranked quantity: the number of replicates, the uniformity p-value over all of
    them and over those that passed their gate; and the draws per replicate."""
    from beadrod.inference.evidence.sbc import uniformity_pvalue

    if not done:
        return {}, 0
    n_draws = int(done[0]["n_draws"])
    ok = [r["gate"]["status"] == "ok" for r in done]
    stats = {}
    for k in done[0]["ranks"]:
        ranks = np.array([r["ranks"][k] for r in done])
        passed = ranks[np.array(ok)]
        stats[k] = {"n": len(ranks), "p_all": uniformity_pvalue(ranks, n_draws),
                    "n_passed": len(passed),
                    "p_passed": uniformity_pvalue(passed, n_draws) if len(passed) else None}
    return stats, n_draws


def _reason(failure: str) -> str:
    # a gate failure's kind (inference.sampling.diagnostics.check's wording)
    for kind in ("R-hat", "bulk ESS", "tail ESS", "divergent", "E-BFMI"):
        if kind in failure:
            return "divergences" if kind == "divergent" else kind
    return failure


def _rank_histograms(done: list[dict[str, Any]], n_draws: int, path: Path) -> Path:
    from scipy import stats as st

    from beadrod.data.io import atomic_path

    names = list(done[0]["ranks"])
    ok = np.array([r["gate"]["status"] == "ok" for r in done])
    n = len(done)
    bins = int(min(20, max(4, n // 5)))
    edges = np.linspace(0.0, 1.0, bins + 1)
    lo, hi = st.binom.ppf([0.005, 0.995], n, 1.0 / bins)
    cols = min(4, len(names))
    rows = -(-len(names) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.0 * cols, 2.6 * rows), squeeze=False)
    for ax, k in zip(axes.ravel(), names):
        u = (np.array([r["ranks"][k] for r in done]) + 0.5) / (n_draws + 1)
        ax.axhspan(lo, hi, color="0.88", label="99 % band, uniform ranks")
        ax.hist([u[ok], u[~ok]], bins=edges, stacked=True, color=["C0", "C3"],
                label=["gate passed", "gate FAILED"])
        ax.set_title(k, fontsize=9)
        ax.set_xlabel("fractional rank", fontsize=8)
    for ax in axes.ravel()[len(names):]:
        ax.axis("off")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle(f"SBC rank histograms: {n} replicates, {n_draws} draws each", fontsize=9)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
    return path


def _sbc(tasks: list[Task], records: dict[str, dict[str, Any]], out: Path) -> list[Path]:
    from beadrod.data.io import write_text
    from beadrod.inference.evidence.sbc import SBCResult
    from beadrod.workflows.campaign.sbc_task import LOGLIK
    from beadrod.workflows.pipeline.sbc_outputs import plot_ecdf

    rows = []
    for t in tasks:
        r = records.get(t.name)
        row = {"task": t.name, "replicate": t.inputs["replicate"], "seed": t.inputs["seed"],
               "status": r.get("status") if r else "not run"}
        if r and r.get("status") == DONE:
            g = r["gate"]
            row.update({"gate": g["status"], "gate_failures": "; ".join(g["failures"]),
                        "divergences": g["divergences"], "rhat_max": g["rhat_max"],
                        "ess_bulk_min": g["ess_bulk_min"], "n_draws": r["n_draws"],
                        "wall_s": r.get("wall_s"), "fit_s": r["timings"]["fit_s"]})
            row.update({f"rank_{k}": v for k, v in r["ranks"].items()})
            row.update({f"truth_{k}": v for k, v in r["truth"].items()})
        elif r:
            row["error"] = r.get("error")
        rows.append(row)
    files = [write_table(rows, out / CAMPAIGN_CSV)]
    done = [records[t.name] for t in tasks if records.get(t.name, {}).get("status") == DONE]
    spec = tasks[0].inputs["spec"] if tasks else {}
    s = tasks[0].inputs["sampling"] if tasks else {}
    md = [f"# SBC campaign: {spec.get('law')} at rung {spec.get('rung')}", "",
          f"Each replicate draws its parameters from the prior, simulates a dataset on the "
          f"fixed design ({tasks[0].inputs['design'] if tasks else ''}), fits it by NUTS "
          f"({s.get('chains')} chains x {s.get('warmup')} warmup + {s.get('samples')} draws, "
          f"every {tasks[0].inputs['thin'] if tasks else 1}. kept) and ranks the truth "
          f"among the draws. `{LOGLIK}` is the rank of the data's log-likelihood at the "
          "truth among its values at the draws (Modrák et al. 2023).", ""]
    md += status_lines(tasks, records)
    stats, n_draws = sbc_statistics(done)
    if stats:
        gate_bad = [r for r in done if r["gate"]["status"] != "ok"]
        reasons = Counter(_reason(f) for r in gate_bad for f in r["gate"]["failures"])
        md += ["", f"## Ranks ({len(done)} replicates, {n_draws} draws each)", "",
               f"Replicates that FAILED their sampling gate: {len(gate_bad)} of {len(done)}"
               + (" (" + ", ".join(f"{k}: {v}" for k, v in reasons.most_common()) + ")"
                  if reasons else "") + "; they are in every statistic below that says "
               "'all', and shown in red in the histograms.", "",
               "| quantity | replicates | KS p (all) | passed gate | KS p (passed) | ranks |",
               "|---|---|---|---|---|---|"]
        alpha = ALPHA / max(len(stats), 1)
        for k, v in stats.items():
            verdict = "not uniform" if v["p_all"] < alpha else "uniform"
            md.append(f"| {k} | {v['n']} | {fmt(v['p_all'])} | {v['n_passed']} | "
                      f"{fmt(v['p_passed'])} | {verdict} |")
        md += ["", f"'not uniform': KS p below {ALPHA} / {len(stats)} (Bonferroni over the "
               "quantities) on the randomised PIT of the ranks "
               "(inference.evidence.sbc.uniformity_pvalue). With few replicates the test "
               "sees only gross miscalibration.", ""]
        figs = out / FIGURES
        ranks = {k: np.array([r["ranks"][k] for r in done]) for k in stats}
        res = SBCResult(ranks, n_draws, {k: v["p_all"] for k, v in stats.items()}, 0.0)
        files.append(plot_ecdf(res, figs / "sbc_ecdf.png"))
        files.append(_rank_histograms(done, n_draws, figs / "sbc_ranks.png"))
        md += ["![ECDF difference](figures/sbc_ecdf.png)", "",
               "![rank histograms](figures/sbc_ranks.png)", ""]
    files.append(write_text(out / SUMMARY_MD, "\n".join(md) + "\n"))
    return files


def write_summary(kind: str, tasks: list[Task], records: dict[str, dict[str, Any]],
                  out: Path) -> list[Path]:
    """Write ``campaign.csv``, ``summary.md`` and the figures of a campaign of ``kind``
    from its ``records``; return the files written."""
    out = Path(out)
    if kind == "sbc":
        return _sbc(tasks, records, out)
    from beadrod.workflows.campaign import summary_compare

    return summary_compare.write(kind, tasks, records, out, status_lines(tasks, records))
