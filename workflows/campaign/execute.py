"""What a Dask worker runs for a task: :func:`run_task`, which never raises for an error of
the task itself.

An ordinary exception (bad numbers, a fit that cannot start, a bug) comes back as a FAILED
record with its error and traceback, and the campaign goes on; only the loss of the
worker process (killed, out of memory) escapes, and Dask retries the task on another
worker (workflows.campaign.engine). A task function is a module-level function, so that
it pickles by reference into the workers.
"""

from __future__ import annotations

import os
import socket
import time
import traceback
from collections.abc import Callable
from typing import Any

from beadrod.workflows.campaign.tasks import Task

__all__ = ["run_task", "guarded", "task_record", "DONE", "FAILED"]

DONE = "done"
FAILED = "FAILED"


def task_record(task: Task) -> dict[str, Any]:
    """The fields every result file has: name, kind, key, inputs (a dataset's file
    contents left out), seed, and where it ran."""
    inputs = {k: v for k, v in task.inputs.items() if k != "files"}
    seed = task.inputs.get("seed", (task.inputs.get("cfg") or {}).get("seed"))
    return {"name": task.name, "kind": task.kind, "key": task.key, "inputs": inputs,
            "seed": seed, "worker": f"{socket.gethostname()}:{os.getpid()}"}


def guarded(task: Task, body: Callable[[Task], dict[str, Any]]) -> dict[str, Any]:
    """``task``'s record with what ``body(task)`` returns, status DONE; or, where it raises
    an ordinary exception, status FAILED with ``error`` and ``traceback``."""
    rec = task_record(task)
    t0 = time.perf_counter()
    rec["started"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    try:
        rec.update(body(task))
        rec["status"] = DONE
    except Exception as exc:  # noqa: BLE001 - recorded, and the campaign goes on
        rec["status"] = FAILED
        rec["error"] = f"{type(exc).__name__}: {exc}"
        rec["traceback"] = traceback.format_exc()
    rec["wall_s"] = time.perf_counter() - t0
    return rec


def _body(task: Task) -> dict[str, Any]:
    if task.kind == "sbc":
        from beadrod.workflows.campaign.sbc_task import run_sbc_task

        return run_sbc_task(task.inputs)
    if task.kind in ("datasets", "recovery"):
        from beadrod.workflows.campaign.compare_task import run_compare_task

        return run_compare_task(task.kind, task.inputs)
    raise ValueError(f"unknown task kind {task.kind!r}")


def run_task(task: Task) -> dict[str, Any]:
    """Run ``task`` in this process; its record, status DONE or FAILED (:func:`guarded`)."""
    return guarded(task, _body)
