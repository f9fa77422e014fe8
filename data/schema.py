"""The measurement table: its columns, units, and validation.

A dataset is a folder holding ``measurements.csv`` (tidy: one row per sweep)
and ``scene.toml`` (the setup), optionally ``truth.json`` (synthetic data) and
raw sweep curves. Every check here fails loudly with a :class:`DataError`
naming the file, the line as a text editor numbers it (the header is line 1;
blank lines count) and the column: nothing is dropped silently. The plausibility
bounds on values (sweep band, amplitude, drive range, Q, step) are in
:mod:`data.limits`, with the reason for each.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from beadrod.data.limits import AMPLITUDE_LIMIT_FACTOR, Limits, check_value, show

__all__ = [
    "DataError",
    "REQUIRED_COLUMNS",
    "OPTIONAL_COLUMNS",
    "MAY_BE_EMPTY",
    "COLUMN_UNITS",
    "KINDS",
    "DIRECTIONS",
    "AMPLITUDE_LIMIT_FACTOR",
    "Limits",
    "validate_table",
    "canonical_csv",
    "curve_path",
    "where",
]

REQUIRED_COLUMNS: tuple[str, ...] = (
    "protocol", "step", "kind", "direction", "drive_voltage_V", "f_res_Hz", "amplitude_m",
)
OPTIONAL_COLUMNS: tuple[str, ...] = ("q_factor", "curve")
MAY_BE_EMPTY: tuple[str, ...] = ("drive_voltage_V", "amplitude_m", "q_factor")
"""Required columns whose cells may be empty (or NaN): a sweep without them is kept for
what it can still give and reported (:func:`beadrod.data.process.process`)."""
COLUMN_UNITS: dict[str, str] = {
    "protocol": "identifier", "step": "integer order within the protocol",
    "kind": "'reference' or 'drive'", "direction": "'up' or 'down'",
    "drive_voltage_V": "V", "f_res_Hz": "Hz", "amplitude_m": "m (delta_a at resonance)",
    "q_factor": "- (from the -3 dB width)", "curve": "path of a raw sweep CSV",
}
KINDS: tuple[str, ...] = ("reference", "drive")
DIRECTIONS: tuple[str, ...] = ("up", "down")
_CSV_SPECIAL = (",", '"', "\n", "\r")  # what canonical CSV cannot write unquoted


class DataError(ValueError):
    """Bad input data; the message names the file, the line and the column."""


def where(file: str, line: int | str, column: str) -> str:
    """``file, line N, column 'c'``: the place an error message starts with."""
    line_txt = line if isinstance(line, str) else f"line {line}"
    if not column.isprintable() or len(column) > 40:  # a header cell of the user's: one line
        column = _cell(column)[1:-1]
    return f"{file}, {line_txt}, column '{column}'"


def _fail(file: str, line: int | str, column: str, what: str) -> DataError:
    return DataError(f"{where(file, line, column)}: {what}")


def _cell(t: str) -> str:
    # the user's own cell, quoted and cut short: enough to find it, never a page of text
    return repr(t if len(t) <= 40 else t[:37] + "...")


def _check_columns(df: pd.DataFrame, file: str, header: str) -> None:
    allowed = REQUIRED_COLUMNS + OPTIONAL_COLUMNS
    cols = [str(c) for c in df.columns]
    dup = [c for c in cols if cols.count(c) > 1]
    if dup:
        k = [i + 1 for i, c in enumerate(cols) if c == dup[0]]
        raise _fail(file, header, dup[0],
                    f"column appears twice (columns {k[0]} and {k[1]}): keep one")
    for c in cols:
        if c not in allowed:
            near = difflib.get_close_matches(c, allowed, n=1, cutoff=0.5)
            hint = f"; did you mean '{near[0]}'?" if near else ""
            raise _fail(file, header, c, f"unknown column (allowed: {', '.join(allowed)}){hint}")
    for c in REQUIRED_COLUMNS:
        if c not in cols:
            raise _fail(file, header, c, "required column is missing")


def _numeric(raw: pd.Series, file: str, column: str, lines: np.ndarray, *,
             allow_empty: bool) -> np.ndarray:
    text = raw.astype(str).str.strip()
    # a copy: pandas may hand out a read-only view, and NaN-marked cells are written below
    values = pd.to_numeric(text.where(text != "", None), errors="coerce").to_numpy(
        np.float64, copy=True)
    for i, (t, v) in enumerate(zip(text, values, strict=True)):
        if t == "" and allow_empty:
            continue
        if t == "":
            raise _fail(file, int(lines[i]), column, "value is empty")
        if math.isnan(v) and t.lower() in ("nan", "na", "n/a", "none", "null"):
            if allow_empty:
                values[i] = np.nan
                continue
            raise _fail(file, int(lines[i]), column, f"value is NaN ({_cell(t)})")
        if math.isnan(v):
            raise _fail(file, int(lines[i]), column, f"not a number: {_cell(t)}")
        if not math.isfinite(v):
            raise _fail(file, int(lines[i]), column, f"value is not finite: {_cell(t)}")
    return values


def _choice(raw: pd.Series, file: str, column: str, allowed: tuple[str, ...],
            lines: np.ndarray) -> np.ndarray:
    text = raw.astype(str).str.strip()
    for i, t in enumerate(text):
        if t not in allowed:
            near = difflib.get_close_matches(t.lower(), allowed, n=1, cutoff=0.4)
            hint = f"; did you mean '{near[0]}'?" if near else ""
            raise _fail(file, int(lines[i]), column,
                        f"unknown value {_cell(t)} (allowed: {', '.join(allowed)}){hint}")
    return text.to_numpy(dtype=object)


def _text_column(raw: pd.Series, file: str, column: str, lines: np.ndarray) -> np.ndarray:
    text = raw.astype(str).str.strip()
    for i, t in enumerate(text):
        if any(ch in t for ch in _CSV_SPECIAL):
            raise _fail(file, int(lines[i]), column,
                        f"{_cell(t)} contains a comma, quote or line break; use plain text "
                        "(the canonical CSV that is hashed and written cannot hold it)")
    return text.to_numpy(dtype=object)


def validate_table(raw: pd.DataFrame, *, file: str, limits: Limits,
                   lines: Sequence[int] | None = None, header_line: int = 1) -> pd.DataFrame:
    """Validate a measurement table read as strings; return it typed, in canonical order.

    ``raw`` holds text cells (:func:`data.io.read_csv_table`, or ``pd.read_csv(...,
    dtype=str, keep_default_na=False)``) so that empty cells and text stay visible
    to the checks; ``lines`` gives each record's editor line (default: no blank
    lines, the header on ``header_line``). The returned frame has float64 numeric
    columns, int64 ``step``, ``row`` (1-based data row) and ``line`` (editor line)
    columns, and is sorted by (protocol, step, direction), up before down.
    """
    header = f"line {header_line} (header)"
    _check_columns(raw, file, header)
    if len(raw) == 0:
        raise _fail(file, header, "protocol", "the table has no data rows")
    ln = (np.arange(header_line + 1, header_line + 1 + len(raw), dtype=np.int64)
          if lines is None else np.asarray(lines, dtype=np.int64))
    out = pd.DataFrame(index=range(len(raw)))
    out["row"] = np.arange(1, len(raw) + 1, dtype=np.int64)
    out["line"] = ln

    protocol = _text_column(raw["protocol"], file, "protocol", ln)
    for i, p in enumerate(protocol):
        if p == "" or p.lower() == "nan":
            raise _fail(file, int(ln[i]), "protocol", "protocol id is empty")
    out["protocol"] = protocol

    step = _numeric(raw["step"], file, "step", ln, allow_empty=False)
    for i, s in enumerate(step):
        if s != round(s) or s < 0:
            raise _fail(file, int(ln[i]), "step",
                        f"step must be a non-negative integer, got {show(s)}")
        if (problem := check_value("step", s, limits)) is not None:
            raise _fail(file, int(ln[i]), "step", problem)
    out["step"] = step.astype(np.int64)
    out["kind"] = _choice(raw["kind"], file, "kind", KINDS, ln)
    out["direction"] = _choice(raw["direction"], file, "direction", DIRECTIONS, ln)

    has_curve = None
    if "curve" in raw.columns:
        # a row with a raw curve may leave the extracted quantities blank
        has_curve = raw["curve"].astype(str).str.strip() != ""
    for col in ("drive_voltage_V", "f_res_Hz", "amplitude_m"):
        # a missing voltage or amplitude costs its sweep the amplitude likelihood (and a
        # drive sweep without amplitude its x), which data.process reports row by row; a
        # missing resonance frequency leaves nothing to fit, unless a curve gives it
        optional = col in MAY_BE_EMPTY
        may_be_empty = optional or has_curve is not None
        vals = _numeric(raw[col], file, col, ln, allow_empty=may_be_empty)
        for i, v in enumerate(vals):
            if math.isnan(v):
                if not optional and (has_curve is None or not has_curve.iloc[i]):
                    raise _fail(file, int(ln[i]), col,
                                "value is empty (and no curve to extract it)")
                continue
            if v <= 0:
                raise _fail(file, int(ln[i]), col, f"must be positive, got {show(v)}")
            if (problem := check_value(col, v, limits)) is not None:
                raise _fail(file, int(ln[i]), col, problem)
        out[col] = vals

    if "q_factor" in raw.columns:
        q = _numeric(raw["q_factor"], file, "q_factor", ln, allow_empty=True)
        for i, v in enumerate(q):
            if not math.isnan(v) and v <= 0.5:
                raise _fail(file, int(ln[i]), "q_factor",
                            f"a resonance needs Q > 1/2, got {show(v)}")
            if (problem := check_value("q_factor", v, limits)) is not None:
                raise _fail(file, int(ln[i]), "q_factor", problem)
        out["q_factor"] = q
    else:
        out["q_factor"] = np.full(len(raw), np.nan)
    if "curve" in raw.columns:
        out["curve"] = _text_column(raw["curve"], file, "curve", ln)
    else:
        out["curve"] = np.array([""] * len(raw), dtype=object)

    _check_structure(out, file)
    order = out.assign(_d=(out["direction"] == "down").astype(np.int64))  # up before down
    order = order.sort_values(["protocol", "step", "_d"], kind="stable")
    return order.drop(columns="_d").reset_index(drop=True)


def _check_structure(out: pd.DataFrame, file: str) -> None:
    key = out[["protocol", "step", "direction"]]
    later = key.duplicated(keep="first").to_numpy()
    if later.any():
        i = int(np.flatnonzero(later)[0])
        p, s, d = key.iloc[i]
        same = (out["protocol"] == p) & (out["step"] == s) & (out["direction"] == d)
        raise _fail(file, int(out["line"].iloc[i]), "step",
                    f"duplicate (protocol, step, direction) = ({p}, {s}, {d}), "
                    f"first seen on line {int(out.loc[same, 'line'].iloc[0])}")
    kinds = out.groupby(["protocol", "step"], sort=False)["kind"].transform("nunique")
    if (kinds > 1).any():
        i = int(np.flatnonzero((kinds > 1).to_numpy())[-1])
        raise _fail(file, int(out["line"].iloc[i]), "kind",
                    f"protocol {out['protocol'].iloc[i]!r}, step {out['step'].iloc[i]} "
                    "mixes reference and drive sweeps")
    is_ref = out["kind"] == "reference"
    if is_ref.all():
        ln = out["line"]
        raise _fail(file, f"lines {int(ln.min())}-{int(ln.max())}", "kind",
                    "every row is a reference sweep: the table has no drive sweep "
                    "(kind = 'drive'), so there is no shift with amplitude to fit")
    has_ref = is_ref.groupby(out["protocol"], sort=False).transform("any")
    if not has_ref.all():
        i = int(np.flatnonzero(~has_ref.to_numpy())[0])
        raise _fail(file, int(out["line"].iloc[i]), "kind",
                    f"protocol {out['protocol'].iloc[i]!r} has no reference sweep")
    first_ref = out["step"].where(is_ref).groupby(out["protocol"], sort=False).transform("min")
    early = (~is_ref & (out["step"] < first_ref)).to_numpy()
    if early.any():
        i = int(np.flatnonzero(early)[0])
        raise _fail(file, int(out["line"].iloc[i]), "step",
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
    """The file a ``curve`` cell names: a relative path that resolves (symlinks
    followed) to a regular file inside the dataset folder.

    Raises ValueError saying why otherwise (absolute, escaping the folder by
    ``..`` or a symlink, missing, not a regular file): a dataset must not read
    files it does not hold, and a folder must stay valid when moved.
    """
    p = Path(value)
    if p.is_absolute():
        raise ValueError(f"{value!r} is an absolute path; a curve file must lie inside the "
                         "dataset folder, named relative to it")
    root = Path(dataset_dir).resolve()
    target = (root / p).resolve()
    if not target.is_relative_to(root):
        raise ValueError(f"{value!r} leads outside the dataset folder (by '..' or a "
                         "symlink); a curve file must lie inside the dataset folder")
    if not target.exists():
        raise ValueError(f"curve file {value!r} not found in the dataset folder "
                         f"(looked for {root / p})")
    if not target.is_file():
        raise ValueError(f"curve {value!r} is not a file")
    return target
