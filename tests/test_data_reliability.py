"""Bad input that used to pass silently or fail with a misleading message (issue 14).

Each test builds a small dataset folder whose defect is known by construction and
checks that loading refuses it with a message naming the file, the line (as a text
editor numbers it) and the column, or, where the input is harmless, that it loads to
exactly the table the clean file gives.
"""

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from beadrod.data.load import dump_toml, load_dataset
from beadrod.data.schema import DataError

ROOT = Path(__file__).resolve().parents[1]
HEADER = "protocol,step,kind,direction,drive_voltage_V,f_res_Hz,amplitude_m,q_factor"
GOOD = [
    "A,0,reference,up,0.01,2700.0,5.0e-10,40.0",
    "A,1,drive,up,0.5,2690.0,2.5e-8,",
    "A,1,drive,down,0.5,2688.0,2.6e-8,",
    "A,2,reference,up,0.01,2701.0,5.1e-10,41.0",
    "B,0,reference,up,0.01,2650.0,4.0e-10,30.0",
    "B,1,drive,up,0.8,2630.0,3.0e-8,",
]
CURVE_HEADER = HEADER + ",curve"


@pytest.fixture(scope="module")
def scene_text():
    from beadrod.models import scene

    return dump_toml(scene.scene_to_dict(scene.builtin_scene("paper")))


def folder(tmp_path, scene_text, lines, name="ds"):
    d = tmp_path / name
    d.mkdir(exist_ok=True)
    (d / "scene.toml").write_text(scene_text)
    (d / "measurements.csv").write_text("\n".join(lines) + "\n")
    return d


def refuse(d, *needles, absent=()):
    with pytest.raises(DataError) as e:
        load_dataset(d)
    msg = str(e.value)
    for n in needles:
        assert n in msg, msg
    for n in absent:
        assert n not in msg, msg
    assert "\n" not in msg, msg  # one line
    return msg


def set_cell(line, column, value, header=HEADER):
    cells = line.split(",")
    cells[header.split(",").index(column)] = value
    return ",".join(cells)


# --- layering: atomic writes live in data/ ------------------------------------------------


def test_data_does_not_import_workflows():
    for path in sorted((ROOT / "data").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) and
                     node.level == 0 else [])
            assert not any(n.split(".")[0] in ("workflows", "inference") for n in names), \
                f"{path.name} imports {names}"


def test_writing_a_dataset_imports_no_workflows(tmp_path):
    code = ("import sys\n"
            "from beadrod.data.load import load_dataset, write_dataset\n"
            f"ds = load_dataset({str(ROOT / 'data' / 'paper_like')!r})\n"
            f"write_dataset({str(tmp_path / 'copy')!r}, ds.table, ds.scene_dict, ds.truth)\n"
            "print(sorted(m for m in sys.modules if 'workflows' in m.split('.')[:2]))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, timeout=300, check=True).stdout
    assert out.strip() == "[]"
    assert load_dataset(tmp_path / "copy").data_hash == load_dataset(
        ROOT / "data" / "paper_like").data_hash


def test_workflows_io_reexports_data_io():
    from beadrod.data import io
    from beadrod.data import io as _io

    for name in ("atomic_path", "write_text", "write_bytes", "write_json"):
        assert getattr(_io, name) is getattr(io, name)


def test_write_json_is_strict_and_atomic(tmp_path):
    from beadrod.data.io import atomic_path, write_json

    p = write_json(tmp_path / "a.json", {"x": float("nan"), "y": [1.0, float("inf")], "z": 2})
    assert json.loads(p.read_text()) == {"x": None, "y": [1.0, None], "z": 2}
    umask = os.umask(0)
    os.umask(umask)
    assert p.stat().st_mode & 0o777 == 0o666 & ~umask
    target = tmp_path / "b.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("interrupted")
    assert target.read_text() == "old"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.json", "b.txt"]  # no .part left


# --- curve files: only inside the dataset folder, never echoed ----------------------------


def lorentz_csv(f0=2683.21, q=25.0, peak=3e-8, lo=2500.0, hi=2900.0, step=1.0):
    f = np.arange(lo, hi, step)
    g = f0 / (2 * q)
    a = peak * g / np.sqrt((f - f0) ** 2 + g**2)
    return "frequency_Hz,amplitude_m\n" + "".join(f"{x:.17g},{y:.17g}\n" for x, y in zip(f, a))


def curve_lines(cell, row=1, blank_values=True):
    out = [CURVE_HEADER]
    for i, r in enumerate(GOOD):
        if i == row:
            if blank_values:
                r = set_cell(set_cell(r, "f_res_Hz", ""), "amplitude_m", "")
            out.append(r + "," + cell)
        else:
            out.append(r + ",")
    return out


def test_absolute_curve_path_refused(tmp_path, scene_text):
    d = folder(tmp_path, scene_text, curve_lines("/etc/passwd"))
    refuse(d, "measurements.csv, line 3, column 'curve'", "inside the dataset folder",
           absent=("root:",))


def test_curve_escaping_the_folder_refused(tmp_path, scene_text):
    (tmp_path / "outside.csv").write_text(lorentz_csv())  # a valid curve, but outside
    d = folder(tmp_path, scene_text, curve_lines("../outside.csv"))
    refuse(d, "line 3, column 'curve'", "inside the dataset folder")


def test_symlink_out_of_the_folder_refused_and_inside_accepted(tmp_path, scene_text):
    (tmp_path / "outside.csv").write_text(lorentz_csv())
    d = folder(tmp_path, scene_text, curve_lines("curves/s1.csv"))
    (d / "curves").mkdir()
    (d / "curves" / "s1.csv").symlink_to(tmp_path / "outside.csv")
    refuse(d, "line 3, column 'curve'", "inside the dataset folder")
    (d / "curves" / "s1.csv").unlink()
    (d / "curves" / "real.csv").write_text(lorentz_csv())
    (d / "curves" / "s1.csv").symlink_to(d / "curves" / "real.csv")
    r = load_dataset(d).table.set_index("line").loc[3]
    assert r["f_res_Hz"] == pytest.approx(2683.21, abs=0.01)


def test_curve_path_that_is_a_folder_refused(tmp_path, scene_text):
    d = folder(tmp_path, scene_text, curve_lines("curves"))
    (d / "curves").mkdir()
    refuse(d, "line 3, column 'curve'", "not a file")


def test_malformed_curve_content_is_not_echoed(tmp_path, scene_text):
    d = folder(tmp_path, scene_text, curve_lines("c.csv"))
    (d / "c.csv").write_text("root:x:0:0:root,amplitude_m\n" + "2600,1e-9\n" * 8)
    refuse(d, "c.csv", "line 1 (header)", "line 3", absent=("root:x",))
    rows = "".join(f"{2600 + i},1e-9\n" for i in range(5))
    (d / "c.csv").write_text("frequency_Hz,amplitude_m\n" + rows + "2606,hunter2secret\n"
                             + "2607,1e-9\n")
    refuse(d, "c.csv", "line 7", "column 'amplitude_m'", "not a finite number",
           absent=("hunter2secret",))


# --- values extracted from curves get the table's checks ----------------------------------


def test_extracted_resonance_outside_band_refused(tmp_path, scene_text):
    d = folder(tmp_path, scene_text, curve_lines("c.csv"))
    (d / "c.csv").write_text(lorentz_csv(f0=10_000.0, q=40.0, lo=9000.0, hi=11000.0, step=2.0))
    refuse(d, "measurements.csv, line 3, column 'curve'", "c.csv", "f_res_Hz",
           "[1500, 3500] Hz")


def test_extracted_amplitude_absurd_refused(tmp_path, scene_text):
    d = folder(tmp_path, scene_text, curve_lines("c.csv"))
    (d / "c.csv").write_text(lorentz_csv(peak=0.5e-3))  # 0.5 mm
    refuse(d, "line 3, column 'curve'", "c.csv", "amplitude_m", "nm or um written as m")


def test_curve_replacing_a_different_table_value_is_noted(tmp_path, scene_text):
    d = folder(tmp_path, scene_text, curve_lines("c.csv", blank_values=False))
    (d / "c.csv").write_text(lorentz_csv())
    ds = load_dataset(d)
    assert ds.table.set_index("line").loc[3, "f_res_Hz"] == pytest.approx(2683.21, abs=0.01)
    note = " ".join(ds.curve_notes)
    assert "line 3" in note and "f_res_Hz" in note and "2690" in note  # the replaced value


# --- range checks: the scene's drive range, Q, amplitude, step ----------------------------


@pytest.mark.parametrize("value,needle", [("50", "50"), ("1e308", "1e+308"), ("1e-300", "")])
def test_drive_voltage_far_outside_the_scene_range(tmp_path, scene_text, value, needle):
    lines = [HEADER, GOOD[0], set_cell(GOOD[1], "drive_voltage_V", value), *GOOD[2:]]
    refuse(folder(tmp_path, scene_text, lines), "line 3, column 'drive_voltage_V'", needle,
           "drive range")


def test_drive_voltage_a_little_beyond_the_range_is_kept(tmp_path, scene_text):
    lines = [HEADER, GOOD[0], set_cell(GOOD[1], "drive_voltage_V", "1.5"), *GOOD[2:]]
    assert load_dataset(folder(tmp_path, scene_text, lines)).table["drive_voltage_V"].max() == 1.5


def test_absurd_q_refused(tmp_path, scene_text):
    lines = [HEADER, set_cell(GOOD[0], "q_factor", "1e308"), *GOOD[1:]]
    refuse(folder(tmp_path, scene_text, lines), "line 2, column 'q_factor'", "1e+308")


def test_vanishing_amplitude_refused(tmp_path, scene_text):
    lines = [HEADER, GOOD[0], set_cell(GOOD[1], "amplitude_m", "1e-300"), *GOOD[2:]]
    refuse(folder(tmp_path, scene_text, lines), "line 3, column 'amplitude_m'", "1e-300")


def test_step_overflow_refused(tmp_path, scene_text):
    lines = [HEADER, GOOD[0], set_cell(GOOD[1], "step", "1e20"), *GOOD[2:]]
    refuse(folder(tmp_path, scene_text, lines), "line 3, column 'step'", "1e+20",
           absent=("-9223372036854775808",))


def test_bead_radius_inf_overlap_refused(tmp_path, scene_text):
    text = scene_text.replace("radius_m = 0.007938", "radius_m = 1e300")
    assert text != scene_text
    d = folder(tmp_path, text, [HEADER, *GOOD])
    msg = refuse(d, "scene.toml", "[bead]", "'radius_m'", "1e+300")
    assert msg.count(str(d / "scene.toml")) == 1


# --- CSV shape: trailing commas, ragged rows, quotes, duplicates, blank lines -------------


def test_trailing_comma_on_every_line_loads_the_same_table(tmp_path, scene_text):
    clean = load_dataset(folder(tmp_path, scene_text, [HEADER, *GOOD], "clean"))
    both = load_dataset(folder(tmp_path, scene_text, [x + "," for x in [HEADER, *GOOD]], "b"))
    rows = load_dataset(folder(tmp_path, scene_text, [HEADER, *(x + "," for x in GOOD)], "r"))
    for ds in (both, rows):
        assert ds.data_hash == clean.data_hash
        assert list(ds.table["protocol"]) == list(clean.table["protocol"])


def test_value_under_an_unnamed_column_refused(tmp_path, scene_text):
    lines = [HEADER + ",", *(x + "," for x in GOOD[:2]), GOOD[2] + ",7", *GOOD[3:]]
    refuse(folder(tmp_path, scene_text, lines), "measurements.csv, line 4", "column 9",
           "no header")


def test_ragged_rows_name_line_and_column(tmp_path, scene_text):
    long = [HEADER, *GOOD[:2], GOOD[2] + ",extra", *GOOD[3:]]
    refuse(folder(tmp_path, scene_text, long, "long"), "measurements.csv, line 4", "column 9",
           "9 fields", absent=("row ?", "column '?'"))
    short = [HEADER, *GOOD[:2], "A,1,drive,down,0.5", *GOOD[3:]]
    refuse(folder(tmp_path, scene_text, short, "short"), "measurements.csv, line 4",
           "column 'f_res_Hz'", "5 fields", absent=("row ?", "column '?'"))


def test_comma_inside_a_quoted_protocol_id(tmp_path, scene_text):
    lines = [HEADER, '"A,x",0,reference,up,0.01,2700.0,5.0e-10,40.0', *GOOD[1:]]
    refuse(folder(tmp_path, scene_text, lines), "measurements.csv, line 2, column 'protocol'",
           "comma")


def test_unclosed_quote_names_the_line(tmp_path, scene_text):
    lines = [HEADER, GOOD[0], '"A,1,drive,up,0.5,2690.0,2.5e-8,', *GOOD[2:]]
    refuse(folder(tmp_path, scene_text, lines), "measurements.csv, line 3", "quot")


def test_duplicated_column_reported_as_duplicated(tmp_path, scene_text):
    lines = [HEADER + ",q_factor", *(x + ",1" for x in GOOD)]
    refuse(folder(tmp_path, scene_text, lines), "line 1 (header), column 'q_factor'",
           "appears twice", absent=("q_factor.1", "unknown"))


def test_line_numbers_after_blank_lines_match_the_editor(tmp_path, scene_text):
    lines = [HEADER, GOOD[0], "", GOOD[1], "", "", set_cell(GOOD[2], "f_res_Hz", "2.7k"),
             *GOOD[3:]]
    refuse(folder(tmp_path, scene_text, lines), "measurements.csv, line 7, column 'f_res_Hz'")
    lines[6] = GOOD[2]
    ds = load_dataset(folder(tmp_path, scene_text, lines, "ok"))
    text = (tmp_path / "ok" / "measurements.csv").read_text().split("\n")
    for _, r in ds.table.iterrows():  # the line column points at the row's own text
        assert text[r["line"] - 1].startswith(f"{r['protocol']},{r['step']},{r['kind']}")


def test_byte_order_mark_and_bad_encoding(tmp_path, scene_text):
    d = folder(tmp_path, scene_text, [HEADER, *GOOD])
    csv = d / "measurements.csv"
    clean = load_dataset(d).data_hash
    csv.write_bytes(b"\xef\xbb\xbf" + csv.read_bytes())  # Excel's UTF-8 BOM
    assert load_dataset(d).data_hash == clean
    csv.write_bytes(csv.read_bytes().replace(b"B,1,drive", b"\xff,1,drive"))
    refuse(d, "measurements.csv, line 7", "UTF-8")


# --- messages: no numpy reprs, the path once, directories ---------------------------------


def test_no_numpy_repr_in_messages(tmp_path, scene_text):
    lines = [HEADER, GOOD[0], set_cell(GOOD[1], "drive_voltage_V", "-0.0"), *GOOD[2:]]
    refuse(folder(tmp_path, scene_text, lines), "got -0.0", absent=("np.", "float64"))


def test_scene_error_names_the_path_once(tmp_path, scene_text):
    d = folder(tmp_path, scene_text.replace("radius_m =", "radius ="), [HEADER, *GOOD])
    msg = refuse(d, "did you mean 'radius_m'")
    assert msg.count(str(d / "scene.toml")) == 1, msg


def test_scene_or_table_that_is_a_folder(tmp_path, scene_text):
    d = tmp_path / "ds"
    (d / "scene.toml").mkdir(parents=True)
    (d / "measurements.csv").write_text("\n".join([HEADER, *GOOD]) + "\n")
    refuse(d, "scene.toml", "not a file")
    (d / "scene.toml").rmdir()
    (d / "scene.toml").write_text(scene_text)
    (d / "measurements.csv").unlink()
    (d / "measurements.csv").mkdir()
    refuse(d, "measurements.csv", "not a file")


# --- nothing silently dropped --------------------------------------------------------------


def test_unused_drive_q_is_noted(tmp_path, scene_text):
    from beadrod.data.process import process

    lines = [HEADER, GOOD[0], set_cell(GOOD[1], "q_factor", "33.0"), *GOOD[2:]]
    p = process(load_dataset(folder(tmp_path, scene_text, lines)))
    assert any("q_factor" in n and "line 3" in n for n in p.notes), p.notes


def test_validate_lists_notes_and_excluded_lines(tmp_path, scene_text, capsys):
    import argparse

    from beadrod.workflows.commands import validate

    lines = [HEADER, GOOD[0], set_cell(GOOD[1], "q_factor", "33.0"), *GOOD[2:]]
    lines += ["B,2,reference,up,0.01,2580.0,4.0e-10,30.0", "B,3,drive,up,0.8,2570.0,3.0e-8,"]
    parser = argparse.ArgumentParser()
    validate.register(parser.add_subparsers())
    args = parser.parse_args(["validate", str(folder(tmp_path, scene_text, lines))])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "line 3" in out and "q_factor" in out
    assert "B: 1 drive sweeps dropped (line 9)" in out, out
