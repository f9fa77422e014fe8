"""Fuzzing the two files a user writes: scene.toml and measurements.csv (issue 47).

Every case is the embedded ``paper_like`` world with random damage: keys deleted, values
replaced by TOML values of any type (nested arrays and tables, strings, huge and tiny
numbers, NaN, integers beyond the float range, nesting deeper than the parser goes),
unknown keys added; table cells replaced by NaN text, empty cells, odd numbers and text,
columns deleted or added, rows deleted or repeated, a byte-order mark, raw curve files
of absurd amplitudes, a ``truth.json`` of any shape. Each case must either load (and
then process into the arrays the fits take, and print as ``beadrod validate`` prints it)
or raise the project's one-line error (:class:`data.DataError`,
:class:`models.scene.SceneError`): never another exception, never a message of several
lines.
"""

from __future__ import annotations

import csv
import io
import json
import math
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from beadrod.data.load import load_dataset
from beadrod.data.process import process
from beadrod.data.schema import DataError
from beadrod.models.scene import SceneError, load_scene

ROOT = Path(__file__).resolve().parents[1]
WORLD = ROOT / "data" / "paper_like"
SCENE = tomllib.loads((WORLD / "scene.toml").read_text())
_ROWS = list(csv.reader(io.StringIO((WORLD / "measurements.csv").read_text())))
HEADER, ROWS = _ROWS[0], [r for r in _ROWS[1:] if r[0] in ("P01", "P02")]  # 50 rows
FUZZ = settings(max_examples=300, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])

# --- TOML values of every type, and a writer for them -------------------------------------

_SPECIAL_FLOATS = [0.0, -0.0, 0.5, 1.0, 5e-324, 1e-300, 1e-15, 7.7, 7.938, 1e300, 1.7e308,
                   math.inf, -math.inf, math.nan]
_SCALARS = st.one_of(
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.sampled_from([10**400, -(10**400), 0, 1, -1]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from(_SPECIAL_FLOATS),
    st.booleans(),
    st.text(max_size=12),
    st.sampled_from(["steel", "bead", "rod", "paper", "", "nan", "1e9"]),
)
_FACTORS = st.sampled_from([1e-6, 1e-3, 1e-2, 0.1, 0.5, 2.0, 10.0, 1e3, 1e6])
_KEYS = st.one_of(st.sampled_from(["name", "material", "radius_m", "young_Pa", "steel", "x"]),
                  st.text(min_size=1, max_size=8))


class Deep:
    """An array nested ``n`` levels deep, written as raw text (too deep for a dict)."""

    def __init__(self, n: int) -> None:
        self.n = n


_NESTED = st.recursive(
    _SCALARS,
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(_KEYS, inner, max_size=3)),
    max_leaves=8,
)
_VALUES = st.one_of(_NESTED, _NESTED, _NESTED, _NESTED,  # one value in five nested deeply
                    st.integers(min_value=2, max_value=3000).map(Deep))


def _toml_value(v: Any) -> str:
    if isinstance(v, Deep):
        return "[" * v.n + "]" * v.n
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return "{" + ", ".join(f"{_toml_value(k)} = {_toml_value(x)}" for k, x in v.items()) + "}"


def _toml(d: dict) -> str:
    # every value inline (tables as inline tables): any nesting, one line per top-level key
    return "".join(f"{_toml_value(k)} = {_toml_value(v)}\n" for k, v in d.items())


def _paths(d: Any, prefix: tuple = ()) -> list[tuple]:
    out = []
    if isinstance(d, dict):
        for k, v in d.items():
            out.append(prefix + (k,))
            out += _paths(v, prefix + (k,))
    return out


def _mutate_scene(data: st.DataObject) -> dict:
    d = json.loads(json.dumps(SCENE))  # a deep copy
    for _ in range(data.draw(st.integers(1, 3), label="n_ops")):
        paths = _paths(d)
        op = data.draw(st.sampled_from(["delete", "replace", "replace", "add", "scale",
                                        "scale"]), label="op")
        if not paths:
            break
        path = data.draw(st.sampled_from(paths), label="path")
        parent = d
        for k in path[:-1]:
            parent = parent[k]
        if op == "delete":
            del parent[path[-1]]
        elif op == "replace":
            parent[path[-1]] = data.draw(_VALUES, label="value")
        elif op == "scale":  # a unit slip: the value loads, its meaning is off
            v = parent[path[-1]]
            if isinstance(v, float | int) and not isinstance(v, bool):
                parent[path[-1]] = v * data.draw(_FACTORS, label="factor")
        elif isinstance(parent, dict):
            parent[data.draw(_KEYS, label="new key")] = data.draw(_VALUES, label="value")
    return d


# --- what every case must do --------------------------------------------------------------


def _one_line(exc: Exception) -> None:
    msg = str(exc)
    assert msg and "\n" not in msg and "\r" not in msg, repr(msg)
    assert len(msg) < 1000, msg
    assert "Traceback" not in msg and "np.float64" not in msg, msg


def _load_all(folder: Path) -> None:
    """Load, process, summarise and build the model inputs, or refuse in one line."""
    from beadrod.inference.model.likelihood import model_inputs
    from beadrod.workflows.commands.validate import summary

    try:
        ds = load_dataset(folder)
        p = process(ds)
    except DataError as exc:
        _one_line(exc)
        return
    assert "\n" not in "".join(p.warnings)
    summary(p, ds)
    inputs = model_inputs(p)  # a ValueError here is a fit that would crash
    assert np.all(np.isfinite(np.asarray(inputs["q_obs"])))
    assert np.asarray(inputs["q_obs"]).shape == np.asarray(inputs["q_idx"]).shape


def _write_csv(folder: Path, header: list[str], rows: list[list[str]], *, bom: bool,
               trailing: bool) -> None:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    for r in [header, *rows]:
        w.writerow(r + ([""] if trailing else []))
    data = buf.getvalue().encode("utf-8", "surrogatepass")
    (folder / "measurements.csv").write_bytes((b"\xef\xbb\xbf" if bom else b"") + data)


# --- scene.toml ---------------------------------------------------------------------------


@FUZZ
@given(data=st.data(), bom=st.booleans())
def test_fuzzed_scene_loads_or_is_refused_in_one_line(data, bom):
    d = _mutate_scene(data)
    text = _toml(d)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "scene.toml").write_bytes((b"\xef\xbb\xbf" if bom else b"")
                                            + text.encode("utf-8", "surrogatepass"))
        _write_csv(folder, HEADER, ROWS, bom=False, trailing=False)
        try:
            load_scene(folder / "scene.toml")
        except SceneError as exc:
            _one_line(exc)
        _load_all(folder)


def test_the_scene_writer_round_trips_the_embedded_scene():
    # the fuzz cases are written by _toml: it must write the unmutated scene faithfully
    assert tomllib.loads(_toml(SCENE)) == SCENE


# --- measurements.csv (and its curves and truth.json) -------------------------------------

_CELLS = st.one_of(
    st.sampled_from(["", " ", "nan", "NaN", "NA", "N/A", "null", "inf", "-inf", "1e-300",
                     "1e300", "1e309", "-1", "0", "-0.0", "abc", "1,5", '"', "\n", "2700",
                     "2700.5", "2.5e-8", "0.5", "40", "0.4", "1e20", "9" * 30, "−1", "0x10",
                     "reference", "drive", "up", "down", "P01", "curve.csv", "../x.csv"]),
    st.text(max_size=10),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)
_COLUMNS = st.sampled_from(["q_factor", "curve", "protocol", "step", "kind", "direction",
                            "drive_voltage_V", "f_res_Hz", "amplitude_m", "extra",
                            "frequency_Hz", ""])
_CURVE_SCALES = st.sampled_from([1e-300, 1e-200, 1e-20, 1e-9, 1.0, 1e10, 1e300])


def _curve_text(data: st.DataObject) -> str:
    kind = data.draw(st.sampled_from(["lorentz", "edge", "random", "asymmetric"]), label="c")
    f = np.arange(2400.0, 2900.0, 2.0)
    f0 = {"edge": 2300.0}.get(kind, 2650.0)
    g = np.where(f < f0, 40.0, 8.0 if kind == "asymmetric" else 40.0)
    a = data.draw(_CURVE_SCALES, label="scale") * g / np.sqrt((f - f0) ** 2 + g**2)
    if kind == "random":
        vals = data.draw(st.lists(st.floats(allow_nan=True, allow_infinity=True),
                                  min_size=1, max_size=12), label="amps")
        a = np.resize(np.asarray(vals, float), f.size)
    return "frequency_Hz,amplitude_m\n" + "".join(f"{x!r},{float(y)!r}\n"
                                                    for x, y in zip(f.tolist(), a.tolist()))


@FUZZ
@given(data=st.data(), bom=st.booleans(), trailing=st.booleans())
def test_fuzzed_measurements_load_or_are_refused_in_one_line(data, bom, trailing):
    header, rows = list(HEADER), [list(r) for r in ROWS]
    files: dict[str, str] = {}
    for _ in range(data.draw(st.integers(1, 4), label="n_ops")):
        op = data.draw(st.sampled_from(["cell", "cell", "q", "scale", "del_col", "add_col",
                                        "del_row", "dup_row", "curve", "truth"]), label="op")
        if op == "q" and "q_factor" in header and rows:  # a missing or odd Q
            i = data.draw(st.integers(0, len(rows) - 1), label="row")
            rows[i][header.index("q_factor")] = data.draw(
                st.sampled_from(["", "nan", "NA", "0.5", "0.51", "1e5", "1e6", "40"]), label="q")
        elif op == "scale" and rows:  # a unit slip in one cell
            i = data.draw(st.integers(0, len(rows) - 1), label="row")
            j = data.draw(st.integers(0, len(header) - 1), label="col")
            try:
                rows[i][j] = repr(float(rows[i][j]) * data.draw(_FACTORS, label="factor"))
            except ValueError:
                pass
        elif op == "cell" and rows:
            i = data.draw(st.integers(0, len(rows) - 1), label="row")
            j = data.draw(st.integers(0, len(header) - 1), label="col")
            rows[i][j] = data.draw(_CELLS, label="cell")
        elif op == "del_col" and len(header) > 1:
            j = data.draw(st.integers(0, len(header) - 1), label="col")
            del header[j]
            for r in rows:
                del r[j]
        elif op == "add_col":
            header.append(data.draw(_COLUMNS | st.text(max_size=6), label="name"))
            cell = data.draw(_CELLS, label="fill")
            for r in rows:
                r.append(cell)
        elif op == "del_row" and rows:
            del rows[data.draw(st.integers(0, len(rows) - 1), label="row")]
        elif op == "dup_row" and rows:
            rows.append(list(rows[data.draw(st.integers(0, len(rows) - 1), label="row")]))
        elif op == "curve" and rows:
            if "curve" not in header:
                header.append("curve")
                for r in rows:
                    r.append("")
            i = data.draw(st.integers(0, len(rows) - 1), label="row")
            rows[i][header.index("curve")] = "c.csv"
            files["c.csv"] = _curve_text(data)
        elif op == "truth":
            files["truth.json"] = json.dumps(data.draw(_VALUES.filter(
                lambda v: not isinstance(v, Deep)), label="truth"))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "scene.toml").write_text((WORLD / "scene.toml").read_text())
        _write_csv(folder, header, rows, bom=bom, trailing=trailing)
        for name, text in files.items():
            (folder / name).write_bytes(text.encode("utf-8", "surrogatepass"))
        _load_all(folder)


def test_the_unmutated_fuzz_table_loads():
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "scene.toml").write_text((WORLD / "scene.toml").read_text())
        _write_csv(folder, HEADER, ROWS, bom=False, trailing=False)
        assert process(load_dataset(folder)).n_protocols == 2
