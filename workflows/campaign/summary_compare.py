"""The summary of a campaign of comparisons, rebuilt from its records.

- **datasets**: log Z of every law on every dataset (a law that failed its gate marked),
  the preferred law per dataset and a flag where it differs from the majority's, and a
  forest plot per parameter of the majority's law across the datasets (mean and 90 %
  interval).
- **recovery**: the confusion table of the preferred law against the generating law,
  the coverage of each parameter's 90 % interval where the world defines a truth
  (workflows.report.truth.world_truth), and the distribution of Δ log Z, the generating
  law's log Z minus the best other law's.

``campaign.csv`` has one row per (task, law).
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
from beadrod.workflows.campaign.tasks import Task, point_label  # noqa: E402

__all__ = ["write", "law_rows", "delta_log_z"]


def _fmt(x: Any) -> str:
    return "–" if x is None else f"{x:.2f}"


def law_rows(task: Task, rec: dict[str, Any] | None) -> list[dict[str, Any]]:
    """One CSV row per law of a task's record (one row with the status when it has none)."""
    base = {"task": task.name, "status": rec.get("status") if rec else "not run"}
    if task.kind == "recovery":
        base.update({"world": task.inputs["world"], "world_seed": task.inputs["world_seed"],
                     "overrides": point_label(task.inputs.get("overrides") or {}),
                     "generating_law": task.inputs["law"]})
    else:
        base["dataset"] = task.inputs["dataset"]
    if not rec or rec.get("status") != DONE:
        return [{**base, "error": (rec or {}).get("error")}]
    return [{**base, "law": r["name"], "log_z": r["log_z"], "log_z_err": r["log_z_err"],
             "gate": r["status"], "preferred": rec["preferred"]} for r in rec["laws"]]


def delta_log_z(rec: dict[str, Any], law: str) -> float | None:
    """log Z of ``law`` minus the highest other log Z of the record (None if missing)."""
    z = {r["name"]: r["log_z"] for r in rec["laws"] if r.get("log_z") is not None}
    others = [v for k, v in z.items() if k != law]
    return None if law not in z or not others else float(z[law] - max(others))


def _save(fig: Any, path: Path) -> Path:
    from beadrod.data.io import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
    return path


def _forest(done: dict[str, dict[str, Any]], law: str, path: Path) -> Path | None:
    """Each parameter of ``law``: mean and 90 % interval per dataset."""
    per: dict[str, list[tuple[str, dict[str, Any]]]] = {}
    for name, rec in done.items():
        row = next((r for r in rec["laws"] if r["name"] == law), None)
        for p in (row or {}).get("params", []):
            per.setdefault(p["name"], []).append((name, p))
    shared = {k: v for k, v in per.items() if len(v) >= 2}
    if not shared:
        return None
    names = sorted(done)
    cols = min(4, len(shared))
    rows = -(-len(shared) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, (1.2 + 0.3 * len(names)) * rows),
                             squeeze=False)
    for ax, (param, items) in zip(axes.ravel(), shared.items()):
        for name, p in items:
            y = names.index(name)
            ax.plot([p["q05"], p["q95"]], [y, y], color="C0", lw=1.5)
            ax.plot(p["mean"], y, "o", color="C0", ms=4)
        ax.set_title(f"{param} [{items[0][1].get('unit') or '-'}]", fontsize=9)
        ax.set_yticks(range(len(names)), names, fontsize=7)
        ax.set_ylim(-0.6, len(names) - 0.4)
        ax.tick_params(axis="x", labelsize=7)
    for ax in axes.ravel()[len(shared):]:
        ax.axis("off")
    fig.suptitle(f"{law}: mean and 90 % interval per dataset", fontsize=9)
    fig.tight_layout()
    return _save(fig, path)


def _datasets(tasks: list[Task], records: dict[str, dict[str, Any]],
              out: Path) -> tuple[list[str], list[Path]]:
    done = {t.inputs["dataset"]: records[t.name] for t in tasks
            if records.get(t.name, {}).get("status") == DONE}
    md, files = [], []
    if not done:
        return md, files
    laws = list(dict.fromkeys(r["name"] for rec in done.values() for r in rec["laws"]))
    votes = Counter(rec["preferred"] for rec in done.values())
    majority = votes.most_common(1)[0][0]
    md += ["", "## Log Z per dataset and law", "",
           f"Majority preferred law: **{majority}** ({votes[majority]} of {len(done)}). "
           "'(gate)': the fit FAILED its sampling gate and is not preferred.", "",
           "| dataset | " + " | ".join(laws) + " | preferred | differs from majority |",
           "|---" * (len(laws) + 3) + "|"]
    for name, rec in sorted(done.items()):
        z = {r["name"]: _fmt(r["log_z"]) + ("" if r["status"] == "ok" else " (gate)")
             for r in rec["laws"]}
        flag = "**yes**" if rec["preferred"] != majority else ""
        md.append(f"| {name} | " + " | ".join(z.get(k, "–") for k in laws)
                  + f" | {rec['preferred']} | {flag} |")
    shown = majority
    if shown == "none":  # no law passed its gate: the law of the highest log Z, most often
        top = Counter(max((r for r in rec["laws"] if r["name"] != "baseline"
                           and r.get("log_z") is not None),
                          key=lambda r: r["log_z"], default={"name": None})["name"]
                      for rec in done.values())
        shown = top.most_common(1)[0][0]
        md += ["", f"No law passed its gate on most datasets: the forest plot shows {shown}, "
               "the law of the highest log Z on most of them."]
    fig = _forest(done, shown, out / "figures" / f"forest_{shown}.png") if shown else None
    if fig is not None:
        files.append(fig)
        md += ["", f"![forest plot of {shown}'s parameters](figures/{fig.name})"]
    return md, files


def _recovery(tasks: list[Task], records: dict[str, dict[str, Any]],
              out: Path) -> tuple[list[str], list[Path]]:
    done = [(t, records[t.name]) for t in tasks if records.get(t.name, {}).get("status") == DONE]
    md, files = [], []
    if not done:
        return md, files
    gen = sorted({t.inputs["law"] for t, _ in done})
    pref = sorted({r["preferred"] for _, r in done})
    conf = Counter((t.inputs["law"], r["preferred"]) for t, r in done)
    md += ["", "## Preferred law against generating law", "",
           "| generating \\ preferred | " + " | ".join(pref) + " |",
           "|---" * (len(pref) + 1) + "|"]
    md += [f"| {g} | " + " | ".join(str(conf.get((g, p), 0)) for p in pref) + " |"
           for g in gen]
    cover: dict[str, list[bool]] = {}
    for t, r in done:
        row = next((x for x in r["laws"] if x["name"] == t.inputs["law"]), None)
        for p in (row or {}).get("params", []):
            v = (r.get("truth") or {}).get(p["name"])
            if v is not None and p.get("q05") is not None:
                cover.setdefault(f"{t.inputs['law']}.{p['name']}", []).append(
                    p["q05"] <= v <= p["q95"])
    md += ["", "## Coverage of the generating law's 90 % intervals", ""]
    if cover:
        md += ["| parameter | worlds | covered |", "|---|---|---|"]
        md += [f"| {k} | {len(v)} | {sum(v)} ({np.mean(v):.0%}) |" for k, v in cover.items()]
    else:
        md.append("No parameter of the generating laws has a truth in these worlds "
                  "(workflows.report.truth.world_truth says why, per world).")
    dz = [d for t, r in done if (d := delta_log_z(r, t.inputs["law"])) is not None]
    md += ["", "## Δ log Z (generating law minus the best other law)", ""]
    if dz:
        md.append(f"{len(dz)} worlds: median {np.median(dz):.2f}, min {min(dz):.2f}, "
                  f"max {max(dz):.2f}; below 0 in {sum(d < 0 for d in dz)}.")
        fig, ax = plt.subplots(figsize=(4.5, 3.0))
        ax.hist(dz, bins=min(20, max(3, len(dz))), color="C0")
        ax.axvline(0.0, color="k", lw=0.8)
        ax.set_xlabel("Δ log Z [nat]")
        ax.set_ylabel("worlds")
        fig.tight_layout()
        files.append(_save(fig, out / "figures" / "recovery_delta_log_z.png"))
        md += ["", "![Δ log Z](figures/recovery_delta_log_z.png)"]
    return md, files


def write(kind: str, tasks: list[Task], records: dict[str, dict[str, Any]], out: Path,
          status_lines: list[str]) -> list[Path]:
    """``campaign.csv``, ``summary.md`` and the figures of a recovery or datasets
    campaign; ``status_lines``: the task counts and failures (workflows.campaign.summary)."""
    from beadrod.data.io import write_text
    from beadrod.workflows.campaign.tables import CAMPAIGN_CSV, SUMMARY_MD, write_table

    rows = [row for t in tasks for row in law_rows(t, records.get(t.name))]
    files = [write_table(rows, out / CAMPAIGN_CSV)]
    title = "datasets" if kind == "datasets" else "recovery"
    md = [f"# Campaign: {title}", "", *status_lines]
    more, figs = (_datasets if kind == "datasets" else _recovery)(tasks, records, out)
    files += figs
    files.append(write_text(out / SUMMARY_MD, "\n".join(md + more) + "\n"))
    return files
