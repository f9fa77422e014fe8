"""One comparison, as a Dask worker runs it: a dataset folder's (``campaign datasets``) or
a synthetic world's (``campaign recovery``).

The worker writes the dataset (the files that travelled in the task, or the world made by
data.synth.write_world, the code of ``beadrod simulate``) into a private temporary folder,
runs the comparison there (workflows.commands.compare.run, the code of ``beadrod
compare``, in this one process, without figures, report or tension fits) and returns what
the campaign's summary reads: each law's evidence, gate and parameters, the preferred law,
the world's truths, and the warnings it logged. Nothing is left on the worker's disk: a
campaign on a cluster assumes no shared file system.
"""

from __future__ import annotations

import contextlib
import io
import tempfile
import time
from pathlib import Path
from typing import Any

__all__ = ["run_compare_task"]


def _write_files(folder: Path, files: dict[str, str]) -> None:
    for rel, text in files.items():
        f = folder / rel
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(text, encoding="utf-8")


def _law_row(r: dict[str, Any]) -> dict[str, Any]:
    return {"name": r["name"], "status": r["status"], "failures": list(r.get("failures", [])),
            "log_z": r.get("log_z"), "log_z_err": r.get("log_z_err"),
            "log_z_method": r.get("log_z_method"), "diagnostics": r.get("diagnostics"),
            "params": [{k: p.get(k) for k in ("name", "unit", "mean", "sd", "q05", "q95")}
                       for p in r.get("params", [])]}


def run_compare_task(kind: str, inputs: dict[str, Any]) -> dict[str, Any]:
    """The comparison of one dataset (``kind`` "datasets": inputs dataset, files, cfg) or
    one world (``kind`` "recovery": inputs world, law, world_seed, overrides, cfg)."""
    from beadrod.workflows import runtime
    from beadrod.workflows.commands.compare import run

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="beadrod-campaign-") as tmp:
        data = Path(tmp) / "data"
        data.mkdir()
        if kind == "datasets":
            _write_files(data, inputs["files"])
        else:
            from beadrod.data.synth import write_world

            write_world(inputs["world"], data, seed=int(inputs["world_seed"]),
                        overrides=inputs.get("overrides") or None)
        cfg = dict(inputs["cfg"])
        cfg["data"] = str(data)
        out = Path(tmp) / "out"
        said = io.StringIO()  # the comparison's warnings: into the record, not the console
        try:
            with contextlib.redirect_stderr(said):
                result = run(cfg, out, report=False).result
        finally:
            runtime.setup_logging(None, quiet=True)  # the log file was in the folder
    truth = (result.get("data") or {}).get("truth") or {}
    return {"preferred": result["preferred"], "preferred_reason": result["preferred_reason"],
            "data_hash": (result.get("data") or {}).get("hash"),
            "laws": [_law_row(r) for r in result["laws"]],
            "truth": {k: v.get("value") for k, v in (truth.get("values") or {}).items()},
            "warnings": [ln for ln in said.getvalue().splitlines() if ln.strip()],
            "timings": {"total_s": time.perf_counter() - t0}}
