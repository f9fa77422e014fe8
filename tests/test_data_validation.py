"""One test per kind of bad input: the DataError names the file, the line (as a text editor
numbers it: the header is line 1) and the column."""

import argparse

import pytest

from beadrod.data.load import dump_toml, load_dataset
from beadrod.data.schema import DataError

HEADER = "protocol,step,kind,direction,drive_voltage_V,f_res_Hz,amplitude_m,q_factor"
GOOD = [
    "A,0,reference,up,0.01,2700.0,5.0e-10,40.0",
    "A,1,drive,up,0.5,2690.0,2.5e-8,",
    "A,1,drive,down,0.5,2688.0,2.6e-8,",
    "A,2,reference,up,0.01,2701.0,5.1e-10,41.0",
    "B,0,reference,up,0.01,2650.0,4.0e-10,30.0",
    "B,1,drive,up,0.8,2630.0,3.0e-8,",
]


@pytest.fixture(scope="module")
def scene_text():
    from beadrod.models import scene

    return dump_toml(scene.scene_to_dict(scene.builtin_scene("paper")))


def write(tmp_path, scene_text, rows, header=HEADER):
    (tmp_path / "scene.toml").write_text(scene_text)
    (tmp_path / "measurements.csv").write_text("\n".join([header, *rows]) + "\n")
    return tmp_path


def replace(row_index, column, value, rows=GOOD, header=HEADER):
    cols = header.split(",")
    out = list(rows)
    cells = out[row_index].split(",")
    cells[cols.index(column)] = value
    out[row_index] = ",".join(cells)
    return out


def check(tmp_path, scene_text, rows, line, column, *extra, header=HEADER):
    with pytest.raises(DataError) as e:
        load_dataset(write(tmp_path, scene_text, rows, header))
    msg = str(e.value)
    assert "measurements.csv" in msg, msg
    assert (line if isinstance(line, str) else f"line {line}") in msg, msg
    assert f"column '{column}'" in msg, msg
    for word in extra:
        assert word in msg, msg
    return msg


def test_good_table_loads(tmp_path, scene_text):
    ds = load_dataset(write(tmp_path, scene_text, GOOD))
    assert len(ds.table) == len(GOOD) and ds.table["row"].min() == 1
    assert sorted(ds.table["line"]) == list(range(2, len(GOOD) + 2))  # header on line 1


def test_missing_column(tmp_path, scene_text):
    header = HEADER.replace(",f_res_Hz", "")
    rows = [",".join(r.split(",")[:5] + r.split(",")[6:]) for r in GOOD]
    check(tmp_path, scene_text, rows, "line 1 (header)", "f_res_Hz", "missing", header=header)


def test_unknown_column_suggests_closest(tmp_path, scene_text):
    header = HEADER.replace("amplitude_m", "amplitude_nm")
    check(tmp_path, scene_text, GOOD, "line 1 (header)", "amplitude_nm",
          "did you mean 'amplitude_m'", header=header)


def test_non_numeric(tmp_path, scene_text):
    check(tmp_path, scene_text, replace(2, "f_res_Hz", "2.7k"), 4, "f_res_Hz", "not a number")


def test_nan_value(tmp_path, scene_text):
    check(tmp_path, scene_text, replace(1, "f_res_Hz", "NaN"), 3, "f_res_Hz", "NaN")


def test_empty_required_value(tmp_path, scene_text):
    # voltage and amplitude may be empty (tests/test_amplitude_cells.py): f_res may not
    check(tmp_path, scene_text, replace(3, "f_res_Hz", ""), 5, "f_res_Hz", "empty")


@pytest.mark.parametrize("column,value", [("f_res_Hz", "0"), ("amplitude_m", "-2e-8"),
                                          ("drive_voltage_V", "0.0")])
def test_zero_or_negative(tmp_path, scene_text, column, value):
    check(tmp_path, scene_text, replace(5, column, value), 7, column, "positive")


@pytest.mark.parametrize("value", ["25.0", "0.025"])  # 25 nm, 0.025 um written as m
def test_amplitude_in_nm_or_um(tmp_path, scene_text, value):
    check(tmp_path, scene_text, replace(2, "amplitude_m", value), 4, "amplitude_m",
          "nm or um written as m")


def test_frequency_in_khz(tmp_path, scene_text):
    check(tmp_path, scene_text, replace(0, "f_res_Hz", "2.7"), 2, "f_res_Hz", "sweep band")


def test_duplicate_key(tmp_path, scene_text):
    rows = GOOD + ["A,1,drive,down,0.6,2686.0,3.0e-8,"]
    check(tmp_path, scene_text, rows, 8, "step", "duplicate", "line 4")


def test_protocol_without_reference(tmp_path, scene_text):
    rows = GOOD + ["C,1,drive,up,0.5,2600.0,2.0e-8,", "C,2,drive,up,0.7,2590.0,3.0e-8,"]
    check(tmp_path, scene_text, rows, 8, "kind", "'C' has no reference")


def test_drive_before_first_reference(tmp_path, scene_text):
    rows = GOOD + ["B,2,reference,up,0.01,2650.0,4.0e-10,30.0"]
    rows = replace(4, "step", "3", rows)
    rows = replace(6, "step", "4", rows)
    check(tmp_path, scene_text, rows, 7, "step", "before the first reference")


@pytest.mark.parametrize("column,value,hint", [("kind", "calibration", "allowed"),
                                               ("kind", "Drive", "did you mean 'drive'"),
                                               ("direction", "upward", "did you mean 'up'")])
def test_unknown_kind_or_direction(tmp_path, scene_text, column, value, hint):
    check(tmp_path, scene_text, replace(1, column, value), 3, column, hint)


def test_step_not_integer(tmp_path, scene_text):
    check(tmp_path, scene_text, replace(1, "step", "1.5"), 3, "step", "integer")


def test_q_not_a_resonance(tmp_path, scene_text):
    check(tmp_path, scene_text, replace(0, "q_factor", "0.2"), 2, "q_factor", "Q > 1/2")


CURVE_HEADER = HEADER + ",curve"


def curve_rows(curve):
    return [r + ("," + curve if i == 1 else ",") for i, r in enumerate(GOOD)]


def test_missing_curve_file(tmp_path, scene_text):
    check(tmp_path, scene_text, curve_rows("curves/none.csv"), 3, "curve", "not found",
          header=CURVE_HEADER)


def test_malformed_curve_file(tmp_path, scene_text):
    (tmp_path / "curves").mkdir()
    (tmp_path / "curves" / "bad.csv").write_text(
        "frequency_Hz,amplitude_m\n" + "".join(f"{2600 + i},1e-9\n" for i in range(5))
        + "2606,oops\n2607,1e-9\n")
    msg = check(tmp_path, scene_text, curve_rows("curves/bad.csv"), 7, "amplitude_m",
                header=CURVE_HEADER)
    assert "bad.csv" in msg and "line 3" in msg  # the curve file and the measurement line
    assert "oops" not in msg  # the curve's content is not echoed


def test_curve_values_replace_table(tmp_path, scene_text):
    import numpy as np

    (tmp_path / "curves").mkdir()
    f = np.arange(2500.0, 2900.0, 1.0)
    g = 2683.21 / (2 * 25.0)
    a = 3e-8 * g / np.sqrt((f - 2683.21) ** 2 + g**2)
    (tmp_path / "curves" / "s1.csv").write_text(
        "frequency_Hz,amplitude_m\n" + "".join(f"{float(x)!r},{float(y)!r}\n" for x, y in zip(f, a)))
    rows = curve_rows("curves/s1.csv")
    rows = replace(1, "f_res_Hz", "", rows, CURVE_HEADER)
    rows = replace(1, "amplitude_m", "", rows, CURVE_HEADER)
    ds = load_dataset(write(tmp_path, scene_text, rows, CURVE_HEADER))
    r = ds.table[ds.table["line"] == 3].iloc[0]
    assert r["f_res_Hz"] == pytest.approx(2683.21, abs=0.01)
    assert r["amplitude_m"] == pytest.approx(3e-8, rel=1e-4)
    assert r["q_factor"] == pytest.approx(25.0, rel=5e-3)


def test_missing_scene(tmp_path):
    (tmp_path / "measurements.csv").write_text("\n".join([HEADER, *GOOD]) + "\n")
    with pytest.raises(DataError, match="scene.toml"):
        load_dataset(tmp_path)


def test_validate_command_reports_bad_data(tmp_path, scene_text):
    from beadrod.workflows.commands import validate

    parser = argparse.ArgumentParser()
    validate.register(parser.add_subparsers())
    folder = write(tmp_path, scene_text, replace(2, "f_res_Hz", "2.7k"))
    args = parser.parse_args(["validate", str(folder)])
    with pytest.raises(DataError, match=r"measurements.csv, line 4, column 'f_res_Hz'"):
        args.func(args)
