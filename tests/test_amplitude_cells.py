"""Empty voltage and amplitude cells: reported by file line and column, left out of the
amplitude likelihood only (a drive sweep without amplitude has no x, so it leaves the
shift too, with the reason); zero voltages and negative amplitudes are refused."""

import numpy as np
import pytest

from beadrod.data.load import load_dataset
from beadrod.data.process import process
from beadrod.data.schema import DataError
from tests.test_data_validation import GOOD, replace, write


@pytest.fixture(scope="module")
def scene_text():
    from beadrod.data.load import dump_toml
    from beadrod.models import scene

    return dump_toml(scene.scene_to_dict(scene.builtin_scene("paper")))


def processed(tmp_path, scene_text, rows):
    return process(load_dataset(write(tmp_path, scene_text, rows)))


def test_complete_table_uses_every_sweep(tmp_path, scene_text):
    ds = processed(tmp_path, scene_text, GOOD)
    assert ds.drive_amplitude_usable.all() and ds.n_amplitude_excluded == 0
    assert np.isfinite(ds.drive_inv_q_shift).all()
    assert not any(w.startswith("amplitude") for w in ds.warnings)


@pytest.mark.parametrize("empty", ["", "NaN"])
def test_drive_without_voltage_keeps_its_shift(tmp_path, scene_text, empty):
    ds = processed(tmp_path, scene_text, replace(2, "drive_voltage_V", empty))  # line 4
    assert ds.n_drive == 3  # every drive sweep still in the shift likelihood
    assert ds.drive_amplitude_usable.tolist() == [True, False, True]
    assert np.isnan(ds.drive_inv_q_shift[1]) and np.isfinite(ds.drive_inv_q_shift[[0, 2]]).all()
    row = ds.amplitude_excluded.iloc[0]
    assert (row["file"], row["line"], row["column"]) == ("measurements.csv", 4, "drive_voltage_V")
    assert "amplitude likelihood only" in row["reason"]
    (warning,) = [w for w in ds.warnings if w.startswith("amplitude")]
    assert "1 drive sweeps" in warning and "line 4" in warning


def test_drive_without_amplitude_leaves_the_shift_with_its_reason(tmp_path, scene_text):
    ds = processed(tmp_path, scene_text, replace(1, "amplitude_m", ""))  # line 3
    assert ds.n_drive == 2 and ds.drive_amplitude_usable.all()
    (ex,) = ds.excluded.itertuples()
    assert ex.line == 3 and "amplitude_m is empty" in ex.reason
    assert any("line 3" in w and "amplitude_m" in w for w in ds.warnings)


@pytest.mark.parametrize("column", ["drive_voltage_V", "amplitude_m"])
def test_reference_without_anchor_costs_its_protocol_the_ratios(tmp_path, scene_text, column):
    ds = processed(tmp_path, scene_text, replace(0, column, ""))  # protocol A's first reference
    a = ds.drive_protocol == 0
    assert not ds.drive_amplitude_usable[a].any() and ds.drive_amplitude_usable[~a].all()
    assert set(ds.amplitude_excluded["column"]) == {column}
    assert all("protocol 'A'" in r for r in ds.amplitude_excluded["reason"])
    assert ds.n_drive == 3  # the shifts stay


def test_every_drive_amplitude_empty_is_refused(tmp_path, scene_text):
    rows = replace(1, "amplitude_m", "")
    rows = replace(2, "amplitude_m", "", rows=rows)
    rows = replace(5, "amplitude_m", "", rows=rows)
    with pytest.raises(DataError, match="every drive sweep's amplitude_m is empty"):
        processed(tmp_path, scene_text, rows)


@pytest.mark.parametrize("column,value", [("drive_voltage_V", "0"),
                                          ("amplitude_m", "-1e-9")])
def test_zero_voltage_or_negative_amplitude_refused_with_the_row(tmp_path, scene_text,
                                                                column, value):
    with pytest.raises(DataError) as e:
        load_dataset(write(tmp_path, scene_text, replace(4, column, value)))
    assert "line 6" in str(e.value) and f"column '{column}'" in str(e.value)
