"""beadrod campaign's engine on a real Dask cluster: a campaign completes and writes its
summary, a rerun runs nothing, a task that raises is FAILED while the rest complete, a
worker killed mid-task gets its task retried; in the slow suite, Ctrl-C keeps the
finished records and closes the cluster, and an external scheduler (`dask scheduler` +
`dask worker` as subprocesses) runs a campaign too.

The tasks here are real SBC tasks (workflows.campaign.tasks.sbc_tasks: their inputs,
keys, records and summary) run by a stand-in body that returns ranks at once instead of
fitting (the fit itself: tests/test_campaign_sbc.py, slow): the engine is what is under
test, and each test costs seconds, mostly the workers' start. The stand-in is a
module-level function of this file, which the workers import (pytest puts tests/ on
sys.path, and spawned workers inherit it; the external worker gets it in PYTHONPATH).
"""

from __future__ import annotations

import functools
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")

from beadrod.workflows.campaign import results  # noqa: E402
from beadrod.workflows.campaign.execute import DONE, FAILED, guarded  # noqa: E402
from beadrod.workflows.campaign.run import run_campaign  # noqa: E402
from beadrod.workflows.campaign.tasks import sbc_tasks  # noqa: E402

SAMPLING = {"chains": 1, "warmup": 20, "samples": 20, "target_accept": 0.9}


def _tasks(n: int = 4, seed: int = 0):
    return sbc_tasks("hertz", n, rung="first_order", sampling=SAMPLING, seed=seed)


def _stand_in(task, *, mode: str, folder: str):
    # what run_sbc_task returns, without the fit; it logs every run in folder/ran.txt
    with open(Path(folder) / "ran.txt", "a") as fh:
        fh.write(f"{task.name} {os.getpid()}\n")
    i = task.inputs["replicate"]
    if mode == "raise" and i == 1:
        raise RuntimeError("a task that raises")
    if mode == "sleep" and i >= 1:
        time.sleep(60)
    marker = Path(folder) / "killed"
    if mode == "kill" and i == 1 and not marker.exists():
        marker.write_text(str(os.getpid()))
        time.sleep(0.2)
        os.kill(os.getpid(), signal.SIGKILL)  # the worker dies mid-task
    rng = np.random.default_rng(i)
    ranks = {"young": int(rng.integers(0, 21)), "log_lik": int(rng.integers(0, 21))}
    return {"ranks": ranks, "n_draws": 20, "truth": {"young": 2e11},
            "gate": {"status": "ok" if i % 2 else "failed",
                     "failures": [] if i % 2 else ["R-hat max nan >= 1.01"],
                     "rhat_max": 1.0, "ess_bulk_min": 10.0, "ess_tail_min": 10.0,
                     "divergences": 0, "ebfmi_min": 1.0},
            "timings": {"fit_s": 0.0, "total_s": 0.0}}


def stand_in_task(task, mode: str = "ok", folder: str = "."):
    """The campaign's task function for these tests (a module-level name: it pickles)."""
    return guarded(task, functools.partial(_stand_in, mode=mode, folder=folder))


def _ran(folder: Path) -> list[str]:
    f = folder / "ran.txt"
    return f.read_text().split("\n")[:-1] if f.exists() else []


def _campaign(tasks, out, folder, mode="ok", **kw):
    fn = functools.partial(stand_in_task, mode=mode, folder=str(folder))
    return run_campaign("sbc", tasks, out, options={"test": mode}, quiet=True, task_fn=fn,
                        **kw)


def test_campaign_completes_writes_summary_and_rerun_runs_nothing(tmp_path):
    out, log = tmp_path / "out", tmp_path / "log"
    log.mkdir()
    tasks = _tasks()
    run = _campaign(tasks, out, log, workers=2)
    assert sorted(run.ran) == sorted(t.name for t in tasks) and not run.failed
    for t in tasks:
        rec = results.read_record(out, t.name)
        assert rec["status"] == DONE and rec["key"] == t.key and rec["seed"] == 0
    md = (out / "summary.md").read_text()
    assert "Replicates that FAILED their sampling gate: 2 of 4" in md  # counted, not dropped
    assert "| young | 4 |" in md and "| log_lik | 4 |" in md
    assert (out / "figures" / "sbc_ecdf.png").stat().st_size > 1000
    assert (out / "figures" / "sbc_ranks.png").stat().st_size > 1000
    assert len((out / "campaign.csv").read_text().splitlines()) == 1 + len(tasks)
    assert not list(out.rglob(".*.part*"))
    mtimes = {p: p.stat().st_mtime_ns for p in (out / "tasks").iterdir()}
    # the same campaign again: nothing runs, no cluster starts
    ran_before = _ran(log)
    again = _campaign(tasks, out, log, workers=2, scheduler="tcp://127.0.0.1:1")
    assert again.ran == [] and sorted(again.reused) == sorted(t.name for t in tasks)
    assert _ran(log) == ran_before
    assert {p: p.stat().st_mtime_ns for p in (out / "tasks").iterdir()} == mtimes


def test_a_changed_input_gives_a_new_key():
    a, b = _tasks(2, seed=0), _tasks(2, seed=1)
    assert a[0].key == _tasks(2, seed=0)[0].key  # the same inputs, the same key
    assert a[0].key != a[1].key and a[0].key != b[0].key
    c = sbc_tasks("hertz", 1, rung="first_order", sampling={**SAMPLING, "warmup": 21}, seed=0)
    assert c[0].key != a[0].key
    from beadrod.workflows.campaign.tasks import SBC_DESIGN, sbc_design_inputs

    ratios = dict(SBC_DESIGN, amplitude_ratios=True)  # --amplitude-ratios
    assert "amp_idx" in sbc_design_inputs(ratios) and "amp_idx" not in sbc_design_inputs(
        SBC_DESIGN)
    d = sbc_tasks("hertz", 1, rung="first_order", sampling=SAMPLING, seed=0, design=ratios)
    assert d[0].key != a[0].key
    rec = {"key": a[0].key, "status": DONE}
    assert results.reusable(rec, a[0]) and not results.reusable(rec, b[0])
    assert not results.reusable({"key": a[0].key, "status": FAILED}, a[0])


def test_a_task_that_raises_is_failed_and_the_rest_complete(tmp_path):
    out, log = tmp_path / "out", tmp_path / "log"
    log.mkdir()
    tasks = _tasks(3)
    run = _campaign(tasks, out, log, mode="raise", workers=2)
    assert run.failed == [tasks[1].name]
    rec = results.read_record(out, tasks[1].name)
    assert rec["status"] == FAILED and "RuntimeError: a task that raises" in rec["error"]
    assert "Traceback" in rec["traceback"]
    assert all(results.read_record(out, t.name)["status"] == DONE for t in (tasks[0], tasks[2]))
    md = (out / "summary.md").read_text()
    assert "FAILED 1" in md and "a task that raises" in md


def test_a_killed_worker_gets_its_task_retried(tmp_path):
    out, log = tmp_path / "out", tmp_path / "log"
    log.mkdir()
    tasks = _tasks(3)
    run = _campaign(tasks, out, log, mode="kill", workers=2, retries=2)
    killed = int((log / "killed").read_text())
    assert not run.failed and len(run.records) == 3
    rec = results.read_record(out, tasks[1].name)
    assert rec["status"] == DONE and not rec["worker"].endswith(f":{killed}")
    assert [r.split()[0] for r in _ran(log)].count(tasks[1].name) == 2  # run twice


@pytest.mark.slow  # ~15-25 s on 2 cores: the default suite keeps the three above
def test_ctrl_c_keeps_finished_records_and_closes_the_cluster(tmp_path):
    import _thread
    import threading

    import psutil

    out, log = tmp_path / "out", tmp_path / "log"
    log.mkdir()
    tasks = _tasks(3)
    first = results.record_path(out, tasks[0].name)

    def press_ctrl_c() -> None:
        t0 = time.monotonic()
        while not first.exists() and time.monotonic() - t0 < 120:
            time.sleep(0.1)
        _thread.interrupt_main()

    threading.Thread(target=press_ctrl_c, daemon=True).start()
    with pytest.raises(KeyboardInterrupt):
        _campaign(tasks, out, log, mode="sleep", workers=2)
    assert results.read_record(out, tasks[0].name)["status"] == DONE
    assert not results.record_path(out, tasks[1].name).exists()
    assert not list(out.rglob(".*.part*"))
    time.sleep(1.0)
    # the workers and nannies are gone (multiprocessing's resource tracker stays: it
    # belongs to this process's lifetime, whatever spawned a process)
    alive = [p for p in psutil.Process().children(recursive=True) if p.is_running()
             and p.status() != psutil.STATUS_ZOMBIE
             and "resource_tracker" not in " ".join(p.cmdline())]
    assert not alive, [p.cmdline() for p in alive]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for(check, timeout: float = 60.0) -> None:
    t0 = time.monotonic()
    while not check():
        if time.monotonic() - t0 > timeout:
            raise TimeoutError("the external cluster did not come up")
        time.sleep(0.5)


@pytest.mark.slow  # ~15 s on 2 cores: two more processes start and import JAX
def test_an_external_scheduler_runs_the_campaign(tmp_path):
    from distributed import Client

    dask_cli = [sys.executable, "-m", "dask"]
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(Path(__file__).parent),
                                         env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    procs = [subprocess.Popen([*dask_cli, "scheduler", "--host", "127.0.0.1", "--port",
                               str(port), "--no-dashboard"], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        procs.append(subprocess.Popen(
            [*dask_cli, "worker", address, "--nworkers", "1", "--nthreads", "1",
             "--no-dashboard", "--local-directory", str(tmp_path / "worker")], env=env,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        with Client(address, timeout="60s") as c:
            _wait_for(lambda: len(c.scheduler_info()["workers"]) == 1)
        out, log = tmp_path / "out", tmp_path / "log"
        log.mkdir()
        tasks = _tasks(2)
        run = _campaign(tasks, out, log, scheduler=address)
        assert not run.failed and sorted(run.ran) == sorted(t.name for t in tasks)
        assert (out / "summary.md").exists()
        # the plugin set the worker up: its own compilation cache, in its scratch folder
        with Client(address, timeout="30s") as c:
            env_of = c.run(lambda: (os.environ.get("JAX_COMPILATION_CACHE_DIR"),
                                    os.environ.get("TQDM_DISABLE")))
        (cache, tqdm), = env_of.values()
        assert cache and str(tmp_path / "worker") in cache and tqdm == "1"
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in reversed(procs):
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
    assert all(p.returncode is not None for p in procs)


def test_the_command_names_the_extra_when_dask_is_missing(monkeypatch):
    from beadrod.workflows.commands.campaign import INSTALL_HINT, _need_dask
    from beadrod.workflows.runtime import UserError

    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed fails
    with pytest.raises(UserError, match=r'pip install "beadrod\[campaign\]"'):
        _need_dask()
    assert INSTALL_HINT == 'pip install "beadrod[campaign]"'


def test_records_are_whole_json(tmp_path):
    rec = {"name": "sbc-hertz-0000", "key": "k", "status": DONE, "x": float("nan")}
    path = results.write_record(tmp_path, rec)
    assert json.loads(path.read_text())["x"] is None  # strict JSON
    assert results.read_record(tmp_path, "sbc-hertz-0000")["key"] == "k"
    path.write_text("{torn")
    assert results.read_record(tmp_path, "sbc-hertz-0000") is None


def _law(name, log_z, status="ok", young=(1.9e11, 2.1e11)):
    return {"name": name, "status": status, "log_z": log_z, "log_z_err": 0.1,
            "params": [{"name": "young", "unit": "Pa", "mean": sum(young) / 2, "sd": 1e9,
                        "q05": young[0], "q95": young[1]}]}


def test_comparison_summaries_from_records(tmp_path):
    from beadrod.workflows.campaign.summary import write_summary
    from beadrod.workflows.campaign.tasks import Task

    rec = lambda pref, laws, truth=None: {"status": DONE, "preferred": pref, "laws": laws,
                                          "truth": truth or {}}
    tasks = [Task("recovery", f"r{i}", {"world": "hertz_dynamics", "world_seed": i,
                                        "law": "hertz"}, "k") for i in range(3)]
    records = {"r0": rec("hertz", [_law("hertz", 10.0), _law("jkr", 8.0)], {"young": 2e11}),
               "r1": rec("jkr", [_law("hertz", 7.0), _law("jkr", 8.0)], {"young": 2.5e11}),
               "r2": {"status": FAILED, "error": "ValueError: boom"}}
    write_summary("recovery", tasks, records, tmp_path)
    md = (tmp_path / "summary.md").read_text()
    assert "| hertz | 1 | 1 |" in md  # generating hertz: preferred hertz once, jkr once
    assert "| hertz.young | 2 | 1 (50%) |" in md
    assert "median 0.50, min -1.00, max 2.00" in md and "FAILED 1" in md
    assert (tmp_path / "figures" / "recovery_delta_log_z.png").exists()

    out = tmp_path / "ds"
    tasks = [Task("datasets", f"d{i}", {"dataset": f"bead{i}"}, "k") for i in range(3)]
    records = {f"d{i}": rec(p, [_law("hertz", 1.0), _law("jkr", 2.0, "failed")])
               for i, p in enumerate(["hertz", "hertz", "jkr"])}
    write_summary("datasets", tasks, records, out)
    md = (out / "summary.md").read_text()
    assert "Majority preferred law: **hertz** (2 of 3)" in md
    assert "| bead2 | 1.00 | 2.00 (gate) | jkr | **yes** |" in md
    assert (out / "figures" / "forest_hertz.png").exists()
    assert len((out / "campaign.csv").read_text().splitlines()) == 1 + 3 * 2


def test_a_recovery_grid_is_checked(tmp_path):
    from beadrod.workflows.campaign.recovery import read_grid
    from beadrod.workflows.runtime import UserError

    good = tmp_path / "g.toml"
    good.write_text('laws = ["hertz", "baseline"]\n[[world]]\nworld = "hertz_dynamics"\n'
                    'law = "hertz"\nseeds = [3, 1, 3]\n')
    assert read_grid(good) == {"laws": ["hertz", "baseline"], "worlds": [
        {"world": "hertz_dynamics", "law": "hertz", "seeds": [1, 3], "overrides": {}}]}
    bad = tmp_path / "b.toml"
    bad.write_text('[[world]]\nworld = "mars"\nlaw = "hertz"\nseeds = [1]\n')
    with pytest.raises(UserError, match="entry 1: world = 'mars'"):
        read_grid(bad)
