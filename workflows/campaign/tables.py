"""The shared pieces of a campaign's summary: its file names, its CSV writer, its task
counts and failures as Markdown lines."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

from beadrod.workflows.campaign.execute import DONE, FAILED
from beadrod.workflows.campaign.tasks import Task

__all__ = ["SUMMARY_MD", "CAMPAIGN_CSV", "FIGURES", "write_table", "fmt", "status_lines"]

SUMMARY_MD = "summary.md"
CAMPAIGN_CSV = "campaign.csv"
FIGURES = "figures"


def write_table(rows: list[dict[str, Any]], path: Path) -> Path:
    """``rows`` as CSV at ``path`` (atomically; columns in first-seen order)."""
    import pandas as pd

    from beadrod.data.io import write_text

    buf = io.StringIO()
    pd.DataFrame(rows).to_csv(buf, index=False)
    return write_text(path, buf.getvalue())


def fmt(x: Any, spec: str = ".3g") -> str:
    """A number for a Markdown table; a dash for none."""
    return "–" if x is None or (isinstance(x, float) and not np.isfinite(x)) else format(x, spec)


def status_lines(tasks: list[Task], records: dict[str, dict[str, Any]]) -> list[str]:
    """Markdown lines: the task counts, each FAILED task with its error, the tasks not
    run (a campaign stopped before its end)."""
    missing = [t.name for t in tasks if t.name not in records]
    failed = [(n, r) for n, r in records.items() if r.get("status") == FAILED]
    lines = [f"- tasks: {len(tasks)}; done {sum(r.get('status') == DONE for r in records.values())}"
             f", FAILED {len(failed)}, not run {len(missing)}"]
    if failed:
        lines += ["", "FAILED tasks (their records in `tasks/` hold the traceback):", ""]
        lines += [f"- `{n}`: {r.get('error', '?')}" for n, r in failed]
    if missing:
        lines += ["", "Not run (the campaign was stopped; rerun the command to finish): "
                  + ", ".join(f"`{n}`" for n in missing[:20])
                  + (f" and {len(missing) - 20} more" if len(missing) > 20 else "")]
    return lines
