"""``beadrod campaign`` end to end with real fits on a 2-worker LocalCluster (slow: each
worker compiles its sampler once, about a minute and a half on the 2-core machine, then
fits a replicate in seconds).

- ``campaign sbc``: Hertz at first order, 4 replicates, writes every record, the summary
  and its figures; the same command again runs nothing;
- a worker killed (``os.kill``) while it fits: its replicate runs again elsewhere and the
  campaign completes with nothing lost;
- ``campaign datasets``: two embedded dataset folders, a log Z per dataset and law.
"""

from __future__ import annotations

import functools
import json
import os
import signal
from pathlib import Path

import pytest

pytest.importorskip("distributed")

from beadrod.workflows.campaign import results  # noqa: E402
from beadrod.workflows.campaign.execute import DONE  # noqa: E402
from beadrod.workflows.cli import main  # noqa: E402

ROOT = Path(__file__).parents[1]
TINY = ["--chains", "1", "--warmup", "30", "--samples", "30", "--rung", "first_order",
        "--workers", "2", "--quiet"]


@pytest.mark.slow
def test_sbc_campaign_fits_ranks_summarises_and_reruns_nothing(tmp_path):
    out = tmp_path / "sbc"
    argv = ["campaign", "sbc", "--law", "hertz", "--n", "4", *TINY, "--out", str(out)]
    assert main(argv) == 0
    recs = [json.loads(p.read_text()) for p in sorted((out / "tasks").glob("*.json"))]
    assert len(recs) == 4 and all(r["status"] == DONE for r in recs)
    for r in recs:
        assert r["n_draws"] == 30 and set(r["ranks"]) >= {"young", "sigma_shift", "log_lik"}
        assert all(0 <= v <= 30 for v in r["ranks"].values())
        assert r["gate"]["status"] in ("ok", "failed") and r["timings"]["fit_s"] > 0
    assert len({r["worker"] for r in recs}) == 2  # both workers ran replicates
    md = (out / "summary.md").read_text()
    assert "| young | 4 |" in md and "| log_lik | 4 |" in md
    assert (out / "figures" / "sbc_ecdf.png").exists()
    mtimes = {p.name: p.stat().st_mtime_ns for p in (out / "tasks").iterdir()}
    assert main(argv) == 0  # the same command: every task reused
    assert {p.name: p.stat().st_mtime_ns for p in (out / "tasks").iterdir()} == mtimes
    assert "4 finished earlier with the same inputs, 0 to run" in (out / "beadrod.log").read_text()


def kill_once(task, folder: str):
    """The real SBC task, but the first attempt at replicate 1 kills its worker mid-fit."""
    from beadrod.workflows.campaign.execute import run_task

    marker = Path(folder) / "killed"
    if task.inputs["replicate"] == 1 and not marker.exists():
        marker.write_text(str(os.getpid()))
        os.kill(os.getpid(), signal.SIGKILL)
    return run_task(task)


@pytest.mark.slow
def test_sbc_campaign_survives_a_killed_worker(tmp_path):
    from beadrod.workflows.campaign.run import run_campaign
    from beadrod.workflows.campaign.tasks import sbc_tasks

    sampling = {"chains": 1, "warmup": 30, "samples": 30, "target_accept": 0.9}
    tasks = sbc_tasks("hertz", 3, rung="first_order", sampling=sampling, seed=0)
    fn = functools.partial(kill_once, folder=str(tmp_path))
    run = run_campaign("sbc", tasks, tmp_path / "out", options={}, workers=2, retries=2,
                       quiet=True, task_fn=fn)
    killed = int((tmp_path / "killed").read_text())
    assert not run.failed and len(run.records) == 3
    rec = results.read_record(tmp_path / "out", tasks[1].name)
    assert rec["status"] == DONE and not rec["worker"].endswith(f":{killed}")


@pytest.mark.slow
def test_datasets_campaign_compares_each_folder(tmp_path):
    out = tmp_path / "ds"
    dirs = [str(ROOT / "data" / "hertz_dynamics"), str(ROOT / "data" / "paper_like")]
    assert main(["campaign", "datasets", *dirs, "--laws", "hertz,baseline", *TINY,
                 "--out", str(out)]) == 0
    md = (out / "summary.md").read_text()
    assert "| hertz_dynamics |" in md and "| paper_like |" in md
    rows = (out / "campaign.csv").read_text().splitlines()
    assert len(rows) == 1 + 2 * 2  # (dataset, law)
