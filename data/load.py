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
from .io import read_csv_table, write_bytes, write_json, write_text
from .limits import AMPLITUDE_LIMIT_FACTOR, Limits, check_value, show
from .schema import DataError, canonical_csv, curve_path, validate_table, where

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
    with ``row`` = 1-based data row, ``line`` = its line in the file as an editor
    numbers it, and curve-extracted values filled in),
    the scene, its dict, the optional truth, and a content hash."""

    path: Path
    table: pd.DataFrame
    scene: Any
    scene_dict: dict
    truth: dict | None
    data_hash: str
    curve_notes: tuple[str, ...] = field(default=())


def scene_limits(scene: Any) -> Limits:
    """Plausibility limits from the scene (:mod:`data.limits`): the sweep band, the
    amplitude ceiling AMPLITUDE_LIMIT_FACTOR x (Hertz delta0 under the scene's load),
    the drive range and the scene's bound on Q."""
    from models import hertz, scenes

    delta0 = float(hertz.static_overlap(float(scene.load), e_star=float(scene.e_star),
                                        radius=float(scene.radius)))
    return Limits(float(scene.f_min), float(scene.f_max), AMPLITUDE_LIMIT_FACTOR * delta0,
                  float(scene.voltage_min), float(scene.voltage_max),
                  float(scenes.QUALITY_FACTOR_MAX))


def load_scene_file(path: Path) -> tuple[Any, dict]:
    """(Scene, scene dict) from a scene TOML; any failure becomes a one-line
    :class:`DataError` that names the file once."""
    from models import scenes

    if not path.exists():
        raise DataError(f"{path}: scene file is missing (a dataset folder needs {SCENE})")
    if not path.is_file():
        raise DataError(f"{path}: not a file (a dataset folder needs a {SCENE} file)")
    try:
        scene = scenes.load_scene(path)
        return scene, scenes.scene_to_dict(scene)
    except scenes.SceneError as exc:  # its message already starts with the path
        raise DataError(str(exc)) from None
    except OSError as exc:
        raise DataError(f"{path}: cannot read the scene ({exc.strerror})") from None


def dataset_hash(csv_bytes: bytes, scene_dict: dict) -> str:
    """sha256 over the canonical CSV bytes and the canonical JSON of the scene dict."""
    h = hashlib.sha256(csv_bytes)
    h.update(b"\0")
    h.update(json.dumps(scene_dict, sort_keys=True, default=str).encode("utf-8"))
    return h.hexdigest()


_AGREE = {"f_res_Hz": 1e-4, "amplitude_m": 1e-2, "q_factor": 5e-2}
"""Relative differences [-] within which a table cell and its curve's extraction count
as the same reading (a 0.27 Hz rounding at 2.7 kHz, 1 % and 5 % for amplitude and Q:
about what an analyser's printout rounds away); beyond, the replaced cell is noted."""


def _apply_curves(table: pd.DataFrame, folder: Path, file: str, limits: Limits) -> list[str]:
    """Fill each row that names a curve with the values extracted from it, checked
    against the same limits as table cells; return notes (fit caveats, replaced cells)."""
    notes: list[str] = []
    table["curve_asymmetric"] = False
    for i in np.flatnonzero((table["curve"].astype(str) != "").to_numpy()):
        rel = str(table.at[i, "curve"])
        line = int(table.at[i, "line"])
        place = where(file, line, "curve")
        try:
            p = curve_path(folder, rel)
        except ValueError as exc:
            raise DataError(f"{place}: {exc}") from None
        curve = read_curve(p, label=f"{rel} (the curve of {file}, line {line})")
        fit = extract_resonance(curve["frequency_Hz"].to_numpy(), curve["amplitude_m"].to_numpy())
        for col, v in (("f_res_Hz", fit.f_res), ("amplitude_m", fit.amplitude),
                       ("q_factor", fit.q)):
            if math.isnan(v):  # no -3 dB Q: the table's Q (if any) stays, fit.note says why
                continue
            if (problem := check_value(col, v, limits)) is not None:
                raise DataError(f"{place}: {col} extracted from {rel}: {problem}")
            old = float(table.at[i, col])
            if not math.isnan(old) and abs(v - old) > _AGREE[col] * abs(old):
                notes.append(f"{file} line {line}: {col} = {show(old)} in the table replaced "
                             f"by {v:.6g} extracted from {rel}")
            table.at[i, col] = v
        table.at[i, "curve_asymmetric"] = bool(fit.asymmetric)
        if fit.note:
            notes.append(f"{file} line {line} ({rel}): {fit.note}")
    return notes


def load_dataset(path: str | Path) -> Dataset:
    """Load and validate a dataset folder (or its ``measurements.csv``)."""
    path = Path(path)
    if path.is_file() and path.suffix != ".csv":
        raise DataError(f"{path}: expected a dataset folder or its {MEASUREMENTS}")
    folder = path.parent if path.suffix == ".csv" else path
    csv = path if path.suffix == ".csv" else folder / MEASUREMENTS
    if not csv.exists():
        raise DataError(f"{csv}: measurements file is missing")
    if not csv.is_file():
        raise DataError(f"{csv}: not a file (a dataset folder needs a {MEASUREMENTS} file)")
    scene, scene_dict = load_scene_file(folder / SCENE)
    limits = scene_limits(scene)
    raw = read_csv_table(csv, label=csv.name)
    table = validate_table(raw.frame(), file=csv.name, limits=limits, lines=raw.lines,
                           header_line=raw.header_line)
    notes = _apply_curves(table, folder, csv.name, limits)
    truth = None
    if (folder / TRUTH).exists():
        try:
            truth = json.loads((folder / TRUTH).read_text(encoding="utf-8"))
        except json.JSONDecodeError as exc:
            raise DataError(f"{folder / TRUTH}, line {exc.lineno}, column {exc.colno}: "
                            f"invalid JSON ({exc.msg})") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise DataError(f"{folder / TRUTH}: cannot read as UTF-8 JSON "
                            f"({type(exc).__name__})") from None
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
    out = Path(out_dir)
    write_bytes(out / MEASUREMENTS, canonical_csv(table))
    write_text(out / SCENE, dump_toml(scene_dict).lstrip("\n"))
    if truth is not None:
        write_json(out / TRUTH, truth)
    return out
