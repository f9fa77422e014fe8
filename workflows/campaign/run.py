"""A campaign from start to end: open the folder, skip what is finished, run the rest on
the Dask engine with a progress display, write each record as it comes, rebuild the
summary from the records.

The output folder follows workflows.outdir's rule for a run folder, with one difference:
a campaign always resumes (rerunning the same command is how a campaign is continued),
and ``--force`` deletes the earlier records first.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from beadrod.workflows.campaign import results
from beadrod.workflows.campaign.execute import DONE, FAILED, run_task, task_record
from beadrod.workflows.campaign.tasks import Task
from beadrod.workflows.progress import RunProgress, done, format_seconds

__all__ = ["CampaignRun", "CampaignProgress", "run_campaign"]

log = logging.getLogger("beadrod")


@dataclass
class CampaignRun:
    """What a campaign did: the tasks, their records (name -> record), the names it ran
    this time and those it reused, and the summary files it wrote."""

    tasks: list[Task]
    records: dict[str, dict[str, Any]]
    ran: list[str] = field(default_factory=list)
    reused: list[str] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)

    @property
    def failed(self) -> list[str]:
        """Names of the tasks whose record is FAILED."""
        return [n for n, r in self.records.items() if r.get("status") == FAILED]


class CampaignProgress(RunProgress):
    """workflows.progress.RunProgress with a campaign's counts: done, running, failed and
    left, and the ETA from the mean wall time of the tasks done so far."""

    def __init__(self, total: int, **kw: Any) -> None:
        super().__init__(total, total, what="tasks", **kw)
        self.counts = {"done": 0, "running": 0, "failed": 0, "left": total}

    def line(self) -> str:
        """The counts as one line."""
        c = self.counts
        return (f"done {c['done']}, running {c['running']}, failed {c['failed']}, "
                f"left {c['left']}")

    def _refresh(self) -> None:
        if self._bar is None:
            return
        self._bar.set_postfix_str(self.line(), refresh=False)
        self._bar.refresh()


def _lost_record(task: Task, error: str) -> dict[str, Any]:
    rec = task_record(task)
    rec.update({"status": FAILED, "worker": None,
                "error": f"the worker was lost and the retries ran out ({error})",
                "wall_s": None})
    return rec


def run_campaign(kind: str, tasks: list[Task], out: Path, *, options: dict[str, Any],
                 workers: int = 2, scheduler: str | None = None, retries: int = 2,
                 cache: str = "own", quiet: bool = False, force: bool = False,
                 task_fn: Callable[[Task], dict[str, Any]] = run_task) -> CampaignRun:
    """Run the campaign of ``tasks`` (all of one ``kind``) into ``out`` and write its
    summary (workflows.campaign.summary); return what it did.

    ``task_fn`` runs one task in a worker (default workflows.campaign.execute.run_task; a
    module-level function). Tasks with a finished record of the same key are skipped; with
    none left no cluster is started."""
    from beadrod.workflows import runtime
    from beadrod.workflows.campaign import summary
    from beadrod.workflows.outdir import check_out, release

    out = Path(out)
    names = [t.name for t in tasks]
    if len(set(names)) != len(names):
        raise runtime.UserError("two tasks of the campaign have the same name: give the "
                                "dataset folders distinct names")
    check_out(out, force=force, resume=not force, command=f"campaign {kind}")
    try:
        runtime.setup_logging(out, quiet)
        results.write_campaign(out, kind, options, tasks)
        records = results.load_records(out, tasks)
        todo = [t for t in tasks if not results.reusable(records.get(t.name), t)]
        run = CampaignRun(tasks, records, reused=[t.name for t in tasks if t not in todo])
        log.info("campaign %s: %d tasks, %d finished earlier with the same inputs, %d to "
                 "run", kind, len(tasks), len(run.reused), len(todo))
        if todo:
            _dispatch(todo, out, run, workers=workers, scheduler=scheduler,
                      retries=retries, cache=cache, task_fn=task_fn)
        run.files = summary.write_summary(kind, tasks, run.records, out)
        log.info("summary: %s", out / summary.SUMMARY_MD)
        return run
    finally:
        release(out)


def _dispatch(todo: list[Task], out: Path, run: CampaignRun, *, workers: int,
              scheduler: str | None, retries: int, cache: str,
              task_fn: Callable[[Task], dict[str, Any]]) -> None:
    from beadrod.workflows.campaign import engine

    where = scheduler or f"a local cluster of {workers} worker processes"
    log.info("starting %s", "the client of " + where if scheduler else where)
    t0 = time.perf_counter()
    with engine.open_client(workers=workers, scheduler=scheduler, retries=retries,
                            cache=cache) as client:
        link = engine.dashboard_link(client)
        if link:
            log.info("Dask dashboard: %s", link)
        n_workers = len(client.scheduler_info().get("workers", {}))
        log.info("%d workers ready (%.0f s); running %d tasks", n_workers,
                 time.perf_counter() - t0, len(todo))
        with CampaignProgress(len(todo)) as progress:
            progress.counts["running"] = min(n_workers, len(todo))

            def on_result(task: Task, record: dict[str, Any], running: int) -> None:
                results.write_record(out, record)
                run.records[task.name] = record
                run.ran.append(task.name)
                c = progress.counts
                c["done" if record.get("status") == DONE else "failed"] += 1
                c["left"] = len(todo) - c["done"] - c["failed"]
                c["running"] = min(running, n_workers, c["left"])
                wall = record.get("wall_s")
                what = "done" if record.get("status") == DONE else \
                    f"FAILED: {record.get('error', '?')}"
                took = f", {format_seconds(wall)}" if isinstance(wall, (int, float)) else ""
                done(log, task.name, "%s %s%s | %s", task.name, what, took, progress.line(),
                     final=True)

            engine.run_tasks(client, todo, fn=task_fn, retries=retries,
                             on_result=on_result, lost=_lost_record)
