"""The measurement table: its columns, units, and validation.

A dataset is a folder holding ``measurements.csv`` (tidy: one row per sweep)
and ``scene.toml`` (the setup), optionally ``truth.json`` (synthetic data) and
raw sweep curves. Every check here fails loudly with a :class:`DataError`
naming the file, the 1-based data row (the header is row 0) and the column:
nothing is dropped silently.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

__all__ = [
    "DataError",
    "REQUIRED_COLUMNS",
    "OPTIONAL_COLUMNS",
    "COLUMN_UNITS",
    "KINDS",
    "DIRECTIONS",
    "AMPLITUDE_LIMIT_FACTOR",
    "Limits",
    "validate_table",
    "canonical_csv",
    "curve_path",
]

REQUIRED_COLUMNS: tuple[str, ...] = (
    "protocol", "step", "kind", "direction", "drive_voltage_V", "f_res_Hz", "amplitude_m",
)
OPTIONAL_COLUMNS: tuple[str, ...] = ("q_factor", "curve")
COLUMN_UNITS: dict[str, str] = {
    "protocol": "identifier", "step": "integer order within the protocol",
    "kind": "'reference' or 'drive'", "direction": "'up' or 'down'",
    "drive_voltage_V": "V", "f_res_Hz": "Hz", "amplitude_m": "m (delta_a at resonance)",
    "q_factor": "- (from the -3 dB width)", "curve": "path of a raw sweep CSV",
}
KINDS: tuple[str, ...] = ("reference", "drive")
DIRECTIONS: tuple[str, ...] = ("up", "down")

AMPLITUDE_LIMIT_FACTOR = 1000.0
"""An amplitude above this many static overlaps delta0 (Hertz, under the scene's
load; ~50 um for the paper's bead) is taken as a unit slip (nm or um written as m):
at 2.7 kHz it would mean an acceleration above 1000 g on a bead held by its weight."""


class DataError(ValueError):
    """Bad input data; the message names the file, the row and the column."""


@dataclass(frozen=True)
class Limits:
    """Plausibility limits drawn from the scene: resonance band [Hz], amplitude ceiling [m]."""

    f_min: float
    f_max: float
    amplitude_max: float


def _where(file: str, row: int | str, column: str) -> str:
    row_txt = row if isinstance(row, str) else f"row {row}"
    return f"{file}, {row_txt}, column '{column}'"


def _fail(file: str, row: int | str, column: str, what: str) -> DataError:
    return DataError(f"{_where(file, row, column)}: {what}")


def _check_columns(df: pd.DataFrame, file: str) -> None:
    allowed = REQUIRED_COLUMNS + OPTIONAL_COLUMNS
    cols = [str(c) for c in df.columns]
    for c in cols:
        if c not in allowed:
            near = difflib.get_close_matches(c, allowed, n=1, cutoff=0.5)
            hint = f"; did you mean '{near[0]}'?" if near else ""
            raise _fail(file, "header", c, f"unknown column (allowed: {', '.join(allowed)}){hint}")
    for c in REQUIRED_COLUMNS:
        if c not in cols:
            raise _fail(file, "header", c, "required column is missing")
    dup = [c for c in cols if cols.count(c) > 1]
    if dup:
        raise _fail(file, "header", dup[0], "column appears twice")


def _numeric(raw: pd.Series, file: str, column: str, *, allow_empty: bool) -> np.ndarray:
    text = raw.astype(str).str.strip()
    values = pd.to_numeric(text.where(text != "", None), errors="coerce").to_numpy(np.float64)
    for i, (t, v) in enumerate(zip(text, values, strict=True)):
        if t == "" and allow_empty:
            continue
        if t == "":
            raise _fail(file, i + 1, column, "value is empty")
        if math.isnan(v) and t.lower() in ("nan", "na", "n/a", "none", "null"):
            if allow_empty:
                values[i] = np.nan
                continue
            raise _fail(file, i + 1, column, f"value is NaN ({t!r})")
        if math.isnan(v):
            raise _fail(file, i + 1, column, f"not a number: {t!r}")
        if not math.isfinite(v):
            raise _fail(file, i + 1, column, f"value is not finite: {t!r}")
    return values


def _choice(raw: pd.Series, file: str, column: str, allowed: tuple[str, ...]) -> np.ndarray:
    text = raw.astype(str).str.strip()
    for i, t in enumerate(text):
        if t not in allowed:
            near = difflib.get_close_matches(t.lower(), allowed, n=1, cutoff=0.4)
            hint = f"; did you mean '{near[0]}'?" if near else ""
            raise _fail(file, i + 1, column,
                        f"unknown value {t!r} (allowed: {', '.join(allowed)}){hint}")
    return text.to_numpy(dtype=object)


def validate_table(raw: pd.DataFrame, *, file: str, limits: Limits) -> pd.DataFrame:
    """Validate a measurement table read as strings; return it typed, in canonical order.

    ``raw`` must come from ``pd.read_csv(..., dtype=str, keep_default_na=False)``
    so that empty cells and text stay visible to the checks. The returned frame
    has float64 numeric columns, int64 ``step``, an ``row`` column with the
    1-based data row in the file, and is sorted by (protocol, step, direction), up before down.
    """
    _check_columns(raw, file)
    if len(raw) == 0:
        raise _fail(file, "row 1", "protocol", "the table has no data rows")
    out = pd.DataFrame(index=range(len(raw)))
    out["row"] = np.arange(1, len(raw) + 1, dtype=np.int64)

    protocol = raw["protocol"].astype(str).str.strip()
    for i, p in enumerate(protocol):
        if p == "" or p.lower() == "nan":
            raise _fail(file, i + 1, "protocol", "protocol id is empty")
    out["protocol"] = protocol.to_numpy(dtype=object)

    step = _numeric(raw["step"], file, "step", allow_empty=False)
    for i, s in enumerate(step):
        if s != round(s) or s < 0:
            raise _fail(file, i + 1, "step", f"step must be a non-negative integer, got {s!r}")
    out["step"] = step.astype(np.int64)
    out["kind"] = _choice(raw["kind"], file, "kind", KINDS)
    out["direction"] = _choice(raw["direction"], file, "direction", DIRECTIONS)

    for col in ("drive_voltage_V", "f_res_Hz", "amplitude_m"):
        has_curve = None
        if "curve" in raw.columns and col != "drive_voltage_V":
            # a row with a raw curve may leave the extracted quantities blank
            has_curve = raw["curve"].astype(str).str.strip() != ""
        vals = _numeric(raw[col], file, col, allow_empty=has_curve is not None)
        for i, v in enumerate(vals):
            if math.isnan(v):
                if has_curve is None or not has_curve.iloc[i]:
                    raise _fail(file, i + 1, col, "value is empty (and no curve to extract it)")
                continue
            if v <= 0:
                raise _fail(file, i + 1, col, f"must be positive, got {v!r}")
        out[col] = vals
    _check_scales(out, file, limits)

    if "q_factor" in raw.columns:
        q = _numeric(raw["q_factor"], file, "q_factor", allow_empty=True)
        for i, v in enumerate(q):
            if not math.isnan(v) and v <= 0.5:
                raise _fail(file, i + 1, "q_factor",
                            f"a resonance needs Q > 1/2, got {v!r}")
        out["q_factor"] = q
    else:
        out["q_factor"] = np.full(len(raw), np.nan)
    if "curve" in raw.columns:
        out["curve"] = raw["curve"].astype(str).str.strip().to_numpy(dtype=object)
    else:
        out["curve"] = np.array([""] * len(raw), dtype=object)

    _check_structure(out, file)
    order = out.assign(_d=(out["direction"] == "down").astype(np.int64))  # up before down
    order = order.sort_values(["protocol", "step", "_d"], kind="stable")
    return order.drop(columns="_d").reset_index(drop=True)


def _check_scales(out: pd.DataFrame, file: str, limits: Limits) -> None:
    for i, f in enumerate(out["f_res_Hz"]):
        if not math.isnan(f) and not limits.f_min <= f <= limits.f_max:
            raise _fail(file, i + 1, "f_res_Hz",
                        f"{f!r} Hz lies outside the scene's sweep band "
                        f"[{limits.f_min:g}, {limits.f_max:g}] Hz (kHz written as Hz?)")
    for i, a in enumerate(out["amplitude_m"]):
        if not math.isnan(a) and a > limits.amplitude_max:
            raise _fail(file, i + 1, "amplitude_m",
                        f"{a!r} m exceeds {limits.amplitude_max:.3g} m "
                        f"({AMPLITUDE_LIMIT_FACTOR:g} static overlaps): nm or um written as m?")


def _check_structure(out: pd.DataFrame, file: str) -> None:
    key = out[["protocol", "step", "direction"]]
    later = key.duplicated(keep="first").to_numpy()
    if later.any():
        i = int(np.flatnonzero(later)[0])
        p, s, d = key.iloc[i]
        same = (out["protocol"] == p) & (out["step"] == s) & (out["direction"] == d)
        raise _fail(file, int(out["row"].iloc[i]), "step",
                    f"duplicate (protocol, step, direction) = ({p}, {s}, {d}), "
                    f"first seen in row {int(out.loc[same, 'row'].iloc[0])}")
    kinds = out.groupby(["protocol", "step"], sort=False)["kind"].transform("nunique")
    if (kinds > 1).any():
        i = int(np.flatnonzero((kinds > 1).to_numpy())[-1])
        raise _fail(file, int(out["row"].iloc[i]), "kind",
                    f"protocol {out['protocol'].iloc[i]!r}, step {out['step'].iloc[i]} "
                    "mixes reference and drive sweeps")
    is_ref = out["kind"] == "reference"
    has_ref = is_ref.groupby(out["protocol"], sort=False).transform("any")
    if not has_ref.all():
        i = int(np.flatnonzero(~has_ref.to_numpy())[0])
        raise _fail(file, int(out["row"].iloc[i]), "kind",
                    f"protocol {out['protocol'].iloc[i]!r} has no reference sweep")
    first_ref = out["step"].where(is_ref).groupby(out["protocol"], sort=False).transform("min")
    early = (~is_ref & (out["step"] < first_ref)).to_numpy()
    if early.any():
        i = int(np.flatnonzero(early)[0])
        raise _fail(file, int(out["row"].iloc[i]), "step",
                    f"protocol {out['protocol'].iloc[i]!r}: drive step {out['step'].iloc[i]} "
                    f"comes before the first reference sweep (step {int(first_ref.iloc[i])})")


def _fmt(v: object) -> str:
    if isinstance(v, (float, np.floating)):
        return "" if math.isnan(v) else repr(float(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return str(v)


def canonical_csv(table: pd.DataFrame) -> bytes:
    """The table as canonical CSV bytes: schema column order, shortest round-trip floats.

    Optional columns are written only when used (any non-empty value). Used both
    to write datasets and to hash them, so a file written here hashes like its
    re-read copy.
    """
    cols = list(REQUIRED_COLUMNS)
    if "q_factor" in table and table["q_factor"].notna().any():
        cols.append("q_factor")
    if "curve" in table and (table["curve"].astype(str) != "").any():
        cols.append("curve")
    for c in cols:
        for v in table[c]:
            if "," in str(v) or '"' in str(v) or "\n" in str(v):
                raise DataError(f"column '{c}': value {v!r} contains a CSV delimiter or quote")
    lines = [",".join(cols)]
    lines += [",".join(_fmt(v) for v in rec) for rec in table[cols].itertuples(index=False)]
    return ("\n".join(lines) + "\n").encode("utf-8")


def curve_path(dataset_dir: Path, value: str) -> Path:
    """Resolve a ``curve`` cell relative to the dataset folder."""
    p = Path(value)
    return p if p.is_absolute() else dataset_dir / p
