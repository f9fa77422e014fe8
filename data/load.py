"""Reading and writing dataset folders.

A dataset folder holds ``measurements.csv`` (see :mod:`data.schema`),
``scene.toml`` (the simulator's scene format, :mod:`models.scenes`), optionally
``truth.json`` (synthetic worlds) and the raw sweep curves that the ``curve``
column points to (paths relative to the folder).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .extract import extract_resonance, read_curve
from .schema import (
    AMPLITUDE_LIMIT_FACTOR,
    DataError,
    Limits,
    canonical_csv,
    curve_path,
    validate_table,
)

__all__ = [
    "Dataset",
    "load_dataset",
    "load_scene_file",
    "scene_limits",
    "dataset_hash",
    "dump_toml",
    "write_dataset",
    "MEASUREMENTS",
    "SCENE",
    "TRUTH",
]

MEASUREMENTS = "measurements.csv"
SCENE = "scene.toml"
TRUTH = "truth.json"


@dataclass(frozen=True)
class Dataset:
    """A validated dataset: the typed table (sorted by protocol, step, direction,
    with ``row`` = 1-based row in the file and curve-extracted values filled in),
    the scene, its dict, the optional truth, and a content hash."""

    path: Path
    table: pd.DataFrame
    scene: Any
    scene_dict: dict
    truth: dict | None
    data_hash: str
    curve_notes: tuple[str, ...] = field(default=())


def scene_limits(scene: Any) -> Limits:
    """Plausibility limits from the scene: sweep band and the amplitude ceiling
    AMPLITUDE_LIMIT_FACTOR x (Hertz delta0 under the scene's load)."""
    from models import hertz

    delta0 = float(hertz.static_overlap(float(scene.load), e_star=float(scene.e_star),
                                        radius=float(scene.radius)))
    return Limits(float(scene.f_min), float(scene.f_max), AMPLITUDE_LIMIT_FACTOR * delta0)


def load_scene_file(path: Path) -> tuple[Any, dict]:
    """(Scene, scene dict) from a scene TOML; any failure becomes a :class:`DataError`."""
    from models import scenes

    if not path.is_file():
        raise DataError(f"{path}: scene file is missing (a dataset folder needs {SCENE})")
    try:
        scene = scenes.load_scene(path)
        return scene, scenes.scene_to_dict(scene)
    except DataError:
        raise
    except Exception as exc:  # the scene loader's own errors, re-labelled with the file
        raise DataError(f"{path}: invalid scene ({type(exc).__name__}: {exc})") from exc


def dataset_hash(csv_bytes: bytes, scene_dict: dict) -> str:
    """sha256 over the canonical CSV bytes and the canonical JSON of the scene dict."""
    h = hashlib.sha256(csv_bytes)
    h.update(b"\0")
    h.update(json.dumps(scene_dict, sort_keys=True, default=str).encode("utf-8"))
    return h.hexdigest()


def _apply_curves(table: pd.DataFrame, folder: Path, file: str) -> list[str]:
    notes: list[str] = []
    table["curve_asymmetric"] = False
    for i in np.flatnonzero((table["curve"].astype(str) != "").to_numpy()):
        rel = str(table.at[i, "curve"])
        row = int(table.at[i, "row"])
        p = curve_path(folder, rel)
        if not p.is_file():
            raise DataError(f"{file}, row {row}, column 'curve': curve file {rel!r} not found "
                            f"(looked for {p})")
        curve = read_curve(p, label=f"{rel} (curve of {file} row {row})")
        fit = extract_resonance(curve["frequency_Hz"].to_numpy(), curve["amplitude_m"].to_numpy())
        table.at[i, "f_res_Hz"] = fit.f_res
        table.at[i, "amplitude_m"] = fit.amplitude
        if not math.isnan(fit.q):
            table.at[i, "q_factor"] = fit.q
        table.at[i, "curve_asymmetric"] = bool(fit.asymmetric)
        if fit.note:
            notes.append(f"{file} row {row} ({rel}): {fit.note}")
    return notes


def load_dataset(path: str | Path) -> Dataset:
    """Load and validate a dataset folder (or its ``measurements.csv``)."""
    path = Path(path)
    folder = path.parent if path.suffix == ".csv" else path
    csv = path if path.suffix == ".csv" else folder / MEASUREMENTS
    if not csv.is_file():
        raise DataError(f"{csv}: measurements file is missing")
    scene, scene_dict = load_scene_file(folder / SCENE)
    try:
        raw = pd.read_csv(csv, dtype=str, keep_default_na=False, skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise DataError(f"{csv}, row ?, column '?': cannot parse as CSV ({exc})") from exc
    raw.columns = [str(c).strip() for c in raw.columns]
    table = validate_table(raw, file=csv.name, limits=scene_limits(scene))
    notes = _apply_curves(table, folder, csv.name)
    truth = None
    if (folder / TRUTH).is_file():
        try:
            truth = json.loads((folder / TRUTH).read_text())
        except json.JSONDecodeError as exc:
            raise DataError(f"{folder / TRUTH}, row {exc.lineno}, column {exc.colno}: "
                            f"invalid JSON ({exc.msg})") from exc
    return Dataset(folder, table, scene, scene_dict, truth,
                   dataset_hash(canonical_csv(table), scene_dict), tuple(notes))


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        x = float(v)
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return repr(x)
    if isinstance(v, str):
        return json.dumps(v)  # a JSON string is a valid TOML basic string
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def dump_toml(d: dict, _prefix: str = "") -> str:
    """A nested dict of scalars, lists and tables as TOML (None values are left out)."""
    lines = [f"{k} = {_toml_value(v)}" for k, v in d.items()
             if v is not None and not isinstance(v, dict)]
    out = "\n".join(lines) + ("\n" if lines else "")
    for k, v in d.items():
        if isinstance(v, dict):
            name = f"{_prefix}.{k}" if _prefix else str(k)
            body = dump_toml(v, name)
            has_scalars = any(not isinstance(x, dict) and x is not None for x in v.values())
            header = f"\n[{name}]\n" if has_scalars or not v else ""
            out += header + body
    return out


def write_dataset(out_dir: str | Path, table: pd.DataFrame, scene_dict: dict,
                  truth: dict | None = None) -> Path:
    """Write a dataset folder (atomically, file by file); return the folder."""
    from workflows._io import write_bytes, write_json, write_text

    out = Path(out_dir)
    write_bytes(out / MEASUREMENTS, canonical_csv(table))
    write_text(out / SCENE, dump_toml(scene_dict).lstrip("\n"))
    if truth is not None:
        write_json(out / TRUTH, truth)
    return out
