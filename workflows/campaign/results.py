"""A campaign's files: one JSON record per task, written atomically as the task finishes,
and the campaign's description; the records a rerun finds.

``OUT/tasks/NAME.json`` holds a task's record (workflows.campaign.execute: name, kind,
key, inputs, seed, worker, status, timings, and what the task found; ``error`` and
``traceback`` for a FAILED one). It is written by the driver, through data.io's atomic
writer (a temporary renamed onto the name), so an interrupted campaign leaves whole
records or none, and the output folder's manifest lists it (workflows.outdir).

A rerun reuses a record whose key is the task's (workflows.campaign.tasks.task_key) and
whose status is done; a FAILED task, or one whose inputs changed, runs again.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from beadrod.workflows.campaign.execute import DONE
from beadrod.workflows.campaign.tasks import Task

__all__ = ["TASKS_DIR", "CAMPAIGN_FILE", "record_path", "write_record", "read_record",
           "reusable", "write_campaign", "load_records"]

TASKS_DIR = "tasks"
CAMPAIGN_FILE = "campaign.json"


def record_path(out: Path, name: str) -> Path:
    """Where the record of task ``name`` lives."""
    return Path(out) / TASKS_DIR / f"{name}.json"


def write_record(out: Path, record: dict[str, Any]) -> Path:
    """Write one task's record atomically (data.io.write_json)."""
    from beadrod.data.io import write_json

    return write_json(record_path(out, record["name"]), record)


def read_record(out: Path, name: str) -> dict[str, Any] | None:
    """The record of task ``name``, None when there is none or it does not read back."""
    f = record_path(out, name)
    try:
        rec = json.loads(f.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None
    return rec if isinstance(rec, dict) else None


def reusable(record: dict[str, Any] | None, task: Task) -> bool:
    """Whether ``record`` is a finished run of ``task`` with its inputs unchanged."""
    return bool(record) and record.get("key") == task.key and record.get("status") == DONE


def load_records(out: Path, tasks: list[Task]) -> dict[str, dict[str, Any]]:
    """The records of ``tasks`` in ``out`` whose key is the task's (done or FAILED)."""
    found = {}
    for t in tasks:
        rec = read_record(out, t.name)
        if rec is not None and rec.get("key") == t.key:
            found[t.name] = rec
    return found


def write_campaign(out: Path, kind: str, options: dict[str, Any], tasks: list[Task]) -> Path:
    """``OUT/campaign.json``: the kind, the options and every task's name and key."""
    from beadrod.data.io import write_json
    from beadrod.workflows.pipeline.fits import beadrod_version

    return write_json(Path(out) / CAMPAIGN_FILE, {
        "kind": kind, "options": options, "beadrod_version": beadrod_version(),
        "tasks": [{"name": t.name, "key": t.key} for t in tasks]})
