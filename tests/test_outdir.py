"""The one writer of output folders (workflows.outdir): what --force may delete, the lock,
the manifest, and each writing command's use of them. Each test failed on the code
before the manifest and the lock (issue: the second round of bad-input probes)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from beadrod.data.io import write_text
from beadrod.workflows import outdir
from beadrod.workflows.cli import main
from beadrod.workflows.runtime import UserError

ROOT = Path(__file__).parents[1]


@pytest.fixture(autouse=True)
def _release():
    yield
    outdir.release_all()


def _earlier_run(out: Path) -> None:
    """A folder as a finished run leaves it: files written through the atomic writer."""
    outdir.check_out(out, force=False)
    write_text(out / "result.json", "{}\n")
    write_text(out / "laws" / "hertz.json", "{}\n")
    write_text(out / "figures" / "fig4.png", "png")
    outdir.release(out)


def test_force_never_deletes_through_a_symlink(tmp_path):
    victim = tmp_path / "v"
    victim.mkdir()
    (victim / "a.json").write_text("{}")
    out = tmp_path / "o"
    out.mkdir()
    (out / "laws").symlink_to(victim)
    (out / "result.json").write_text("x")
    with pytest.raises(UserError, match="symbolic link"):
        outdir.check_out(out, force=True)
    assert (victim / "a.json").read_text() == "{}"
    # a link made after beadrod's run, where its manifest names a file below it
    out2 = tmp_path / "o2"
    _earlier_run(out2)
    (out2 / "laws" / "hertz.json").unlink()
    (out2 / "laws").rmdir()
    (out2 / "laws").symlink_to(victim)
    (victim / "hertz.json").write_text("{}\n")  # the very bytes beadrod wrote
    with pytest.raises(UserError, match="symbolic link"):
        outdir.check_out(out2, force=True)
    assert (victim / "hertz.json").exists() and (out2 / "result.json").exists()


def test_force_deletes_only_what_beadrod_wrote(tmp_path):
    out = tmp_path / "o"
    _earlier_run(out)
    (out / "figures" / "thesis.png").write_bytes(b"mine")
    (out / "notes.md").write_text("mine")
    outdir.check_out(out, force=True)
    assert (out / "figures" / "thesis.png").read_bytes() == b"mine"
    assert (out / "notes.md").exists()
    assert not (out / "result.json").exists() and not (out / "laws").exists()


def test_force_refuses_a_changed_or_foreign_file_and_deletes_nothing(tmp_path):
    out = tmp_path / "o"
    _earlier_run(out)
    (out / "result.json").write_text("edited by hand")
    with pytest.raises(UserError, match=r"result\.json was changed"):
        outdir.check_out(out, force=True)
    assert (out / "laws" / "hertz.json").exists()  # nothing deleted
    out2 = tmp_path / "o2"
    _earlier_run(out2)
    (out2 / "report.md").write_text("the user's own report")  # where the run will write
    with pytest.raises(UserError, match=r"report\.md was not written by beadrod"):
        outdir.check_out(out2, force=True)


def test_folder_without_manifest_is_refused_even_with_force(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / "report.md").write_text("mine")
    for kw in ({"force": True}, {"force": False}, {"force": False, "resume": True}):
        with pytest.raises(UserError, match="no manifest"):
            outdir.check_out(out, **kw)
    assert (out / "report.md").read_text() == "mine"


def test_manifest_lists_files_written_by_worker_processes(tmp_path):
    out = tmp_path / "o"
    outdir.check_out(out, force=False)
    code = ("import sys; from beadrod.data.io import write_text; "
            "write_text(sys.argv[1], 'from a child')")
    subprocess.run([sys.executable, "-c", code, str(out / "figures" / "w.png")], check=True,
                   env=os.environ.copy(), timeout=60)
    outdir.release(out)
    assert "figures/w.png" in outdir.manifest_entries(out)
    outdir.check_out(out, force=True)
    assert not (out / "figures").exists()


def test_second_run_into_a_locked_folder_is_refused(tmp_path):
    out = tmp_path / "o"
    code = ("import sys, time; from beadrod.workflows.outdir import check_out; "
            "check_out(__import__('pathlib').Path(sys.argv[1]), force=False, command='fit'); "
            "print('locked', flush=True); time.sleep(60)")
    p = subprocess.Popen([sys.executable, "-c", code, str(out)], stdout=subprocess.PIPE,
                         text=True)
    try:
        assert p.stdout.readline().strip() == "locked"
        with pytest.raises(UserError, match=rf"in use by beadrod fit \(pid {p.pid}"):
            outdir.check_out(out, force=True)
        p.kill()  # the OS releases the lock of a killed process
        p.wait(timeout=30)
        outdir.check_out(out, force=False)
    finally:
        p.kill()


def test_force_and_resume_together_are_refused(tmp_path):
    with pytest.raises(UserError, match="--force and --resume"):
        outdir.check_out(tmp_path / "o", force=True, resume=True)


def test_read_only_folder_is_one_line(tmp_path, capsys):
    if os.geteuid() == 0:  # root writes through permissions: a read-only mount stands in
        pytest.skip("needs a non-root user for a read-only folder")
    out = tmp_path / "ro"
    out.mkdir()
    out.chmod(0o500)
    try:
        assert main(["sweep", "--out", str(out), "--drive", "1"]) == 2
        err = capsys.readouterr().err
        assert "Traceback" not in err and str(out) in err
    finally:
        out.chmod(0o700)


def test_read_only_folder_as_root(tmp_path, monkeypatch):
    """Root ignores permission bits; an EROFS from the OS is what a read-only mount gives."""
    real = os.open

    def ro(path, flags, *a):
        if str(path).endswith(outdir.LOCK_FILE):
            raise OSError(30, "Read-only file system", str(path))
        return real(path, flags, *a)

    monkeypatch.setattr(outdir.os, "open", ro)
    with pytest.raises(UserError, match=r"cannot write to the output folder .*Read-only"):
        outdir.check_out(tmp_path / "o", force=False)


def test_full_disk_while_logging_gives_one_line(tmp_path, capsys):
    import logging

    from beadrod.workflows import runtime

    runtime.setup_logging(tmp_path, quiet=False)
    try:
        fh = next(h for h in logging.getLogger("beadrod").handlers
                  if isinstance(h, logging.FileHandler))
        fh.stream.close()
        fh.stream = open("/dev/full", "w")  # every write: ENOSPC
        logging.getLogger("beadrod").warning("one")
        logging.getLogger("beadrod").warning("two")
        err = capsys.readouterr().err
        assert "Logging error" not in err and "Traceback" not in err
        assert err.count("can no longer be written") == 1 and "two" in err
    finally:
        runtime.setup_logging(None, quiet=False)


def test_figure_worker_ends_with_its_killed_parent(tmp_path):
    code = """
import os, sys, time
from beadrod.workflows.figures.pool import FigureWriter
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
w = FigureWriter(2).__enter__()
w.save(plt.figure(), sys.argv[1])
w._pending[0][1].result(timeout=120)
print(" ".join(str(p.pid) for p in w._pool._processes.values()), flush=True)
time.sleep(120)
"""
    p = subprocess.Popen([sys.executable, "-c", code, str(tmp_path / "f")],
                         stdout=subprocess.PIPE, text=True)
    pids = [int(x) for x in p.stdout.readline().split()]
    assert pids
    os.kill(p.pid, signal.SIGKILL)
    p.wait(timeout=30)
    deadline = time.time() + 20
    alive = pids
    while alive and time.time() < deadline:
        time.sleep(0.2)
        alive = [q for q in pids if _alive(q)]
    assert not alive, f"orphaned figure workers: {alive}"


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split()[2] != "Z"
    except FileNotFoundError:
        return False


# ---------------------------------------------------------------- each command uses it


def test_simulate_refuses_every_existing_output(tmp_path, capsys):
    out = tmp_path / "w"
    out.mkdir()
    (out / "scene.toml").write_text("# mine\n")
    assert main(["simulate", "--out", str(out)]) == 2
    assert "scene.toml exists" in capsys.readouterr().err
    assert main(["simulate", "--out", str(out), "--force"]) == 2  # not beadrod's
    assert "not written by beadrod" in capsys.readouterr().err
    assert (out / "scene.toml").read_text() == "# mine\n"
    (out / "truth.json").write_text("{}")
    (out / "scene.toml").unlink()
    assert main(["simulate", "--out", str(out)]) == 2
    assert "truth.json exists" in capsys.readouterr().err


def test_simulate_force_replaces_its_own_dataset(tmp_path):
    out = tmp_path / "w"
    assert main(["simulate", "--out", str(out), "--seed", "3"]) == 0
    first = (out / "measurements.csv").read_bytes()
    (out / "notes.txt").write_text("mine")
    assert main(["simulate", "--out", str(out), "--seed", "4", "--force"]) == 0
    assert (out / "measurements.csv").read_bytes() != first
    assert (out / "notes.txt").exists()
    assert {"measurements.csv", "scene.toml", "truth.json"} <= set(outdir.manifest_entries(out))


@pytest.mark.parametrize("name", ["sweep.json", "frc.csv", "frc.png"])
def test_sweep_refuses_existing_outputs(tmp_path, capsys, name):
    out = tmp_path / "s"
    out.mkdir()
    (out / name).write_text("mine")
    assert main(["sweep", "--out", str(out), "--drive", "1"]) == 2
    assert f"{name} exists" in capsys.readouterr().err
    assert (out / name).read_text() == "mine"


@pytest.mark.parametrize("argv, option", [
    (["--drive", "0"], "--drive"), (["--drive=-1"], "--drive"), (["--drive", "nan"], "--drive"),
    (["--n-freq", "0"], "--n-freq"), (["--n-freq=-5"], "--n-freq"),
])
def test_sweep_checks_its_ranges_up_front(capsys, argv, option):
    assert main(["sweep", *argv]) == 2
    err = capsys.readouterr().err
    assert f"error: {option}" in err and "Traceback" not in err


@pytest.mark.parametrize("command", [["compare"], ["fit", "--law", "hertz"], ["rungs"]])
def test_run_commands_use_the_writer(tmp_path, capsys, command):
    out = tmp_path / "o"
    out.mkdir()
    (out / "thesis.png").write_bytes(b"mine")
    assert main([*command, "--out", str(out), "--force"]) == 2
    assert "no manifest" in capsys.readouterr().err
    assert (out / "thesis.png").exists()
    if command[0] != "rungs":
        assert main([*command, "--out", str(out), "--force", "--resume"]) == 2
        assert "--force and --resume" in capsys.readouterr().err


def test_bench_refuses_existing_outputs(tmp_path, capsys):
    (tmp_path / "bench_physics.md").write_text("mine")
    assert main(["bench", "physics", "--quick", "--quiet", "--out", str(tmp_path)]) == 2
    assert "bench_physics.md exists" in capsys.readouterr().err


def test_resume_with_a_folder_where_a_summary_belongs(tmp_path):
    from beadrod.workflows.pipeline.fits import _cached

    (tmp_path / "hertz.json").mkdir()
    with pytest.raises(UserError, match="is not a file"):
        _cached("hertz", "k", tmp_path / "hertz.json", tmp_path / "hertz.nc")


def test_report_failure_keeps_the_fits_and_says_so(tmp_path):
    from beadrod.workflows.pipeline.run import _report_failed

    exc = _report_failed(tmp_path, {"hertz": None}, KeyError("protocols"))
    assert isinstance(exc, UserError)
    assert "fits of hertz are written" in str(exc) and "--resume" in str(exc)
    assert "\n" not in str(exc)


def test_manifest_survives_a_torn_line(tmp_path):
    out = tmp_path / "o"
    _earlier_run(out)
    with open(out / outdir.MANIFEST_FILE, "a") as fh:
        fh.write('{"path": "report.ht')  # a run killed mid-write
    entries = outdir.manifest_entries(out)
    assert "result.json" in entries and len(entries) == 4  # and the log
    assert json.loads((out / outdir.MANIFEST_FILE).read_text().splitlines()[0])


def test_manifest_variable_is_one_name():
    from beadrod.data.io import MANIFEST_ENV

    assert outdir._MANIFEST_ENV == MANIFEST_ENV


def test_a_disk_that_fills_during_a_command_is_one_line(tmp_path, capsys, monkeypatch):
    import errno

    from beadrod.data import load

    def full(target, *a, **k):
        raise OSError(errno.ENOSPC, "No space left on device", str(target))

    monkeypatch.setattr(load, "write_bytes", full)
    assert main(["simulate", "--out", str(tmp_path / "w")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "No space left on device" in err
    assert "measurements.csv" in err
    assert not [p for p in (tmp_path / "w").iterdir() if p.name.endswith(".part.csv")]
