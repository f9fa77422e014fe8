"""Reading and writing dataset folders.

A dataset folder holds ``measurements.csv`` (see :mod:`data.schema`),
``scene.toml`` (the simulator's scene format, :mod:`models.scene`), optionally
``truth.json`` (synthetic worlds) and the raw sweep curves that the ``curve``
column points to (paths relative to the folder).

Loading checks the folder as a whole: each curve's amplitudes against the plausibility
bounds before its peak is fitted; a curve whose largest amplitude is at the sweep's edge
(no resonance inside the sweep) is refused; a curve whose -3 dB Q is not trustworthy
(an asymmetric peak) gives its row no Q (flagged in the table's ``q_untrusted`` column,
counted by :mod:`data.process`); the measured linear resonance is compared with what
the scene implies (:mod:`data.scene_check`: a unit slip in ``scene.toml``); and
``truth.json`` must have the shape the summary and the report read.
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

from beadrod.data.extract import extract_resonance, read_curve
from beadrod.data.io import read_csv_table, write_bytes, write_json, write_text
from beadrod.data.limits import AMPLITUDE_LIMIT_FACTOR, Limits, check_value, show
from beadrod.data.scene_check import check_scene_units
from beadrod.data.schema import DataError, canonical_csv, curve_path, validate_table, where
from beadrod.models.tomlfile import describe_value

__all__ = [
    "Dataset",
    "load_dataset",
    "load_scene_file",
    "load_truth",
    "check_truth",
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
    the scene, its dict, the optional truth, and a content hash. ``curve_notes``: every
    remark on the curves (``beadrod validate`` prints them); ``csv_name``: the name of
    the measurement file, for messages."""

    path: Path
    table: pd.DataFrame
    scene: Any
    scene_dict: dict
    truth: dict | None
    data_hash: str
    curve_notes: tuple[str, ...] = field(default=())
    csv_name: str = MEASUREMENTS


def scene_limits(scene: Any) -> Limits:
    """Plausibility limits from the scene (:mod:`data.limits`): the sweep band, the
    amplitude ceiling AMPLITUDE_LIMIT_FACTOR x (Hertz delta0 under the scene's load),
    the drive range and the scene's bound on Q."""
    from beadrod.models import scene as scenes
    from beadrod.models.laws import hertz

    delta0 = float(hertz.static_overlap(float(scene.load), e_star=float(scene.e_star),
                                        radius=float(scene.radius)))
    return Limits(float(scene.f_min), float(scene.f_max), AMPLITUDE_LIMIT_FACTOR * delta0,
                  float(scene.voltage_min), float(scene.voltage_max),
                  float(scenes.QUALITY_FACTOR_MAX))


def load_scene_file(path: Path) -> tuple[Any, dict]:
    """(Scene, scene dict) from a scene TOML; any failure becomes a one-line
    :class:`DataError` that names the file once."""
    from beadrod.models import scene as scenes

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
    table["q_untrusted"] = False  # a curve's -3 dB Q not trustworthy: the row has no Q
    table["curve_grid_maximum"] = False  # the peak fit failed: f_res is the grid maximum
    for i in np.flatnonzero((table["curve"].astype(str) != "").to_numpy()):
        rel = str(table.at[i, "curve"])
        line = int(table.at[i, "line"])
        place = where(file, line, "curve")
        try:
            p = curve_path(folder, rel)
        except ValueError as exc:
            raise DataError(f"{place}: {exc}") from None
        curve = read_curve(p, label=f"{rel} (the curve of {file}, line {line})")
        freq, amp = curve["frequency_Hz"].to_numpy(), curve["amplitude_m"].to_numpy()
        # the peak's plausibility before the fit: 1/A^2 of an absurd amplitude (1e-300 m)
        # overflows and the fit would fail with a numerical error instead of this message
        if (problem := check_value("amplitude_m", float(amp.max()), limits)) is not None:
            raise DataError(f"{place}: largest amplitude_m in {rel}: {problem}")
        try:
            fit = extract_resonance(freq, amp)
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            raise DataError(f"{place}: no resonance could be read from {rel} "
                            f"({type(exc).__name__})") from None
        if fit.peak_at_edge:
            raise DataError(f"{place}: {rel} has its largest amplitude at the sweep's edge "
                            f"({fit.f_res:.6g} Hz): no resonance peak inside the sweep, so "
                            "no f_res to read (sweep a wider band, or remove the row)")
        # the curve is the sweep's raw record: a Q it shows to be unreliable is not used,
        # nor the table's cell, which (by the format) was read from it
        q_untrusted = bool(fit.asymmetric and not math.isnan(fit.q))
        if q_untrusted:
            table.at[i, "q_factor"] = math.nan
        for col, v in (("f_res_Hz", fit.f_res), ("amplitude_m", fit.amplitude),
                       ("q_factor", math.nan if q_untrusted else fit.q)):
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
        table.at[i, "q_untrusted"] = q_untrusted
        table.at[i, "curve_grid_maximum"] = bool(fit.grid_maximum)
        if fit.note:
            used = "; its Q is not used" if q_untrusted else ""
            notes.append(f"{file} line {line} ({rel}): {fit.note}{used}")
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
    check_scene_units(scene, table, scene_file=folder / SCENE, csv_name=csv.name)
    truth = load_truth(folder / TRUTH) if (folder / TRUTH).exists() else None
    return Dataset(folder, table, scene, scene_dict, truth,
                   dataset_hash(canonical_csv(table), scene_dict), tuple(notes), csv.name)


_TRUTH_TEXT = ("world", "kind", "model", "generator", "shift_law")
"""truth.json keys that, where present, are text."""
_TRUTH_TABLES = ("parameters", "protocols", "observables")
"""truth.json keys that, where present, are objects."""
_TRUTH_PROTOCOL_NUMBERS = ("delta0_m", "f0_reference_Hz", "f0_linear_Hz", "q", "q_reference")
"""Per-protocol truth.json values the report reads (positive numbers or null)."""


def _json_kind(v: Any) -> str:
    return {dict: "an object", list: "an array", str: "a string", bool: "a boolean",
            type(None): "null", int: "a number", float: "a number"}.get(type(v), "a value")


def _positive_number(v: Any) -> bool:
    try:
        return (isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                and v > 0)
    except OverflowError:  # a JSON integer beyond the float range
        return False


def check_truth(truth: Any, file: str | Path) -> None:
    """Refuse a ``truth.json`` whose shape the validation summary or the report cannot
    read: a :class:`DataError` naming the file and the key."""
    if not isinstance(truth, dict):
        raise DataError(f"{file}: must hold a JSON object (key -> value), got "
                        f"{_json_kind(truth)}")
    for key in _TRUTH_TEXT:
        if key in truth and not isinstance(truth[key], str):
            raise DataError(f"{file}: key '{key}' must be a string, got {_json_kind(truth[key])}")
    seed = truth.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
        raise DataError(f"{file}: key 'seed' must be an integer, got {_json_kind(seed)}")
    for key in _TRUTH_TABLES:
        if key in truth and not isinstance(truth[key], dict):
            raise DataError(f"{file}: key '{key}' must be an object, got "
                            f"{_json_kind(truth[key])}")
    eta = (truth.get("parameters") or {}).get("eta_Pa_s")
    if eta is not None and not _positive_number(eta):
        raise DataError(f"{file}: key 'parameters' -> 'eta_Pa_s' must be a positive number, "
                        f"got {_json_kind(eta)}")
    for pid, values in (truth.get("protocols") or {}).items():
        if not isinstance(values, dict):
            raise DataError(f"{file}: key 'protocols' -> {describe_value(pid)} must be an "
                            f"object, got {_json_kind(values)}")
        for key in _TRUTH_PROTOCOL_NUMBERS:
            v = values.get(key)
            if v is not None and not _positive_number(v):
                raise DataError(f"{file}: key 'protocols' -> {describe_value(pid)} -> '{key}' "
                                f"must be a positive number or null, got {_json_kind(v)}")


def load_truth(path: Path) -> dict:
    """``truth.json`` read and checked (:func:`check_truth`); DataError naming the file."""
    try:
        truth = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise DataError(f"{path}, line {exc.lineno}, column {exc.colno}: "
                        f"invalid JSON ({exc.msg})") from None
    except RecursionError:
        raise DataError(f"{path}: its arrays or objects are nested too deeply to read") \
            from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise DataError(f"{path}: cannot read as UTF-8 JSON ({type(exc).__name__})") from None
    check_truth(truth, path)
    return truth


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
