"""The tasks of a campaign and their keys.

A task is one unit of work a Dask worker runs alone: one SBC replicate (draw a truth from
the prior, simulate a dataset from the model on a fixed design, fit it, rank the truth
among the draws) or one comparison (a recovery world, or a dataset folder). A task holds
only JSON-ready inputs, fully resolved, so that it pickles small, runs on a machine that
shares no file system with the driver (a dataset's files travel in the task), and hashes
to its **key**.

The key is what ``compare --resume`` matches a finished fit against, built from the same
helpers (workflows.pipeline.fits: the package version, the digest of the ``models`` and
``inference`` code, the digest of the model inputs), with the campaign package's own
files added to the code digest: a changed input, option or code gives a new key, and a
rerun recomputes that task only.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["Task", "task_key", "campaign_code", "sbc_tasks", "dataset_tasks",
           "recovery_tasks", "point_label", "SBC_DESIGN", "KINDS"]

KINDS = ("sbc", "recovery", "datasets")

SBC_DESIGN: dict[str, Any] = {
    "scene": "paper", "n_protocols": 4, "amplitudes_m": [8e-9, 40e-9, 4],
    "amplitude_ratios": False,
}
"""The fixed design of an SBC campaign: the built-in scene, the protocols, and the drive
amplitudes (first, last, count: evenly spaced) each protocol is swept at, up and down,
with a reference Q on every protocol (inference.model.likelihood.design_inputs); with
``amplitude_ratios`` every sweep also reads its amplitude per volt against its
protocol's reference sweep, the amplitude likelihood ``compare`` fits where the data
have amplitudes."""


@dataclass(frozen=True)
class Task:
    """One unit of work: ``kind`` (sbc | recovery | datasets), a ``name`` unique in its
    campaign (the name of its result file), its resolved ``inputs`` (JSON-ready; what the
    worker reads) and its ``key`` (:func:`task_key`)."""

    kind: str
    name: str
    inputs: dict[str, Any] = field(hash=False)
    key: str = ""


def campaign_code() -> tuple[str, ...]:
    """The campaign package's source files, for the code digest of a task's key."""
    here = Path(__file__).parent
    return tuple(str(f) for f in sorted(here.glob("*.py")))


def task_key(kind: str, inputs: dict[str, Any], content: str) -> str:
    """sha256 of a task's kind, resolved inputs, the digest ``content`` of what it reads
    (the SBC design's model inputs, a dataset's hash), the package version and the code
    digest (workflows.pipeline.fits.code_digest with the campaign's files)."""
    from beadrod.workflows.pipeline.fits import beadrod_version, code_digest

    blob = json.dumps({"kind": kind, "inputs": inputs, "content": content,
                       "version": beadrod_version(), "code": code_digest(campaign_code())},
                      sort_keys=True, default=repr)
    return hashlib.sha256(blob.encode()).hexdigest()


def _design_digest(design: dict[str, Any]) -> str:
    from beadrod.workflows.pipeline.fits import inputs_digest

    return inputs_digest(sbc_design_inputs(design))


def sbc_design_inputs(design: dict[str, Any]) -> dict[str, Any]:
    """The model inputs of an SBC design (:data:`SBC_DESIGN`'s keys), no observations."""
    import numpy as np

    from beadrod.inference.model.likelihood import design_inputs
    from beadrod.models.scene import builtin_scene

    first, last, count = design["amplitudes_m"]
    return design_inputs(builtin_scene(design["scene"]), n_protocols=int(design["n_protocols"]),
                         amplitudes=np.linspace(float(first), float(last), int(count)),
                         amplitude_ratios=bool(design.get("amplitude_ratios", False)))


def sbc_tasks(law: str, n: int, *, rung: str, sampling: dict[str, Any], seed: int,
              thin: int = 1, design: dict[str, Any] | None = None,
              spec: dict[str, Any] | None = None) -> list[Task]:
    """``n`` SBC replicates of ``law`` at ``rung``: replicate i draws its truth and its
    data with seed (``seed``, i) and fits with ``sampling`` (chains, warmup, samples,
    target_accept), keeping every ``thin``-th draw. ``spec``: further ModelSpec fields
    (likelihood, use_q, shift_noise, ...)."""
    design = dict(SBC_DESIGN if design is None else design)
    digest = _design_digest(design)
    spec = {"law": law, "rung": rung, **(spec or {})}
    tasks = []
    for i in range(int(n)):
        inputs = {"spec": spec, "design": design, "sampling": dict(sampling), "seed": int(seed),
                  "replicate": i, "thin": int(thin)}
        tasks.append(Task("sbc", f"sbc-{law}-{i:04d}", inputs, task_key("sbc", inputs, digest)))
    return tasks


def _dataset_files(folder: Path) -> dict[str, str]:
    # the files of a dataset folder that data.load reads, as text: they travel in the task
    from beadrod.data.load import MEASUREMENTS, SCENE, TRUTH

    files = {}
    for name in (MEASUREMENTS, SCENE, TRUTH):
        f = folder / name
        if f.is_file():
            files[name] = f.read_text(encoding="utf-8")
    curves = folder / "curves"
    if curves.is_dir():
        for f in sorted(curves.glob("*.csv")):
            files[f"curves/{f.name}"] = f.read_text(encoding="utf-8")
    return files


def _unique_names(folders: list[Path]) -> list[str]:
    names = [f.name or "dataset" for f in folders]
    seen: dict[str, int] = {}
    out = []
    for n in names:
        k = seen.get(n, 0)
        seen[n] = k + 1
        out.append(n if names.count(n) == 1 else f"{n}-{k + 1}")
    return out


def dataset_tasks(folders: list[str | Path], cfg: dict[str, Any]) -> list[Task]:
    """One comparison per dataset folder, under the resolved comparison options ``cfg``
    (workflows.config.resolve: laws, rung, sampling, evidence, likelihood, seed). Each
    folder is validated here (a bad one is refused before anything runs) and its files
    travel in the task."""
    from beadrod.data.load import load_dataset

    paths = [Path(f) for f in folders]
    tasks = []
    for path, name in zip(paths, _unique_names([p.resolve() for p in paths])):
        ds = load_dataset(path)
        inputs = {"dataset": name, "source": str(path.resolve()), "cfg": _fit_cfg(cfg),
                  "files": _dataset_files(path)}
        keyed = {k: v for k, v in inputs.items() if k not in ("files", "source")}
        tasks.append(Task("datasets", f"dataset-{name}", inputs,
                          task_key("datasets", keyed, ds.data_hash)))
    return tasks


def _fit_cfg(cfg: dict[str, Any]) -> dict[str, Any]:
    # the options a comparison in a worker runs with: one process, no figures, no report,
    # no tension fits (a campaign compares the laws' evidence and parameters)
    out = json.loads(json.dumps(cfg, default=str))
    out.update({"workers": 1, "quiet": True, "out": None, "data": None})
    out.setdefault("report", {})["figures"] = False
    out.setdefault("tension", {})["enabled"] = False
    return out


def point_label(overrides: dict[str, Any]) -> str:
    """An override point as text, for a task's name and the CSV: ``key=value`` joined by
    '-' in key order, a range as ``low_high``; '' for none."""
    def fmt(v: Any) -> str:
        return "_".join(fmt(x) for x in v) if isinstance(v, list | tuple) else f"{v:g}"

    return "-".join(f"{k}={fmt(v)}" for k, v in sorted(overrides.items()))


def recovery_tasks(worlds: list[dict[str, Any]], cfg: dict[str, Any]) -> list[Task]:
    """One comparison per (world, override point, seed) of a recovery grid: ``worlds``
    are the grid's items (world, law, seeds, overrides;
    workflows.campaign.recovery.read_grid), each world made by data.synth.write_world as
    ``beadrod simulate --set`` makes it, in the worker. The overrides are part of the
    task's inputs, so of its key and its name."""
    from beadrod import data

    h = hashlib.sha256()  # the worlds are made by the data package's code
    for f in sorted(Path(data.__file__).parent.glob("*.py")):
        h.update(f.name.encode() + f.read_bytes())
    tasks = []
    for w in worlds:
        overrides = dict(w.get("overrides") or {})
        label = point_label(overrides)
        for s in w["seeds"]:
            inputs = {"world": w["world"], "law": w["law"], "world_seed": int(s),
                      "overrides": overrides, "cfg": _fit_cfg(cfg)}
            name = "-".join(["recovery", w["world"], *([label] if label else []), str(int(s))])
            tasks.append(Task("recovery", name, inputs,
                              task_key("recovery", inputs, h.hexdigest())))
    return tasks
