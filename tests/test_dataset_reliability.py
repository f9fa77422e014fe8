"""Datasets that loaded and then crashed a later step, or that passed with a silent loss
(issue 47, items 15-18, 20, 21): a missing Q, no drive sweep, a curve whose peak is at
the sweep's edge or whose Q is not trustworthy, a unit slip in scene.toml, a truth.json
of the wrong shape, a curve of absurd amplitudes.

Each case either loads, with what it leaves out counted and said (the summary that
``beadrod validate`` prints, the warnings a fit logs, the report's data section), or is
refused before any fitting with one line naming the file (and line, column or key).
"""

import json
import math
import types

import numpy as np
import pytest

from beadrod.data.load import dump_toml, load_dataset
from beadrod.data.process import process
from beadrod.data.schema import DataError
from beadrod.workflows.cli import main

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


def folder(tmp_path, scene_text, lines, name="ds"):
    d = tmp_path / name
    d.mkdir(exist_ok=True)
    (d / "scene.toml").write_text(scene_text)
    (d / "measurements.csv").write_text("\n".join(lines) + "\n")
    return d


def set_cell(line, column, value, header=HEADER):
    cells = line.split(",")
    cells[header.split(",").index(column)] = value
    return ",".join(cells)


def refuse(d, *needles, step=load_dataset):
    with pytest.raises(DataError) as e:
        step(d)
    msg = str(e.value)
    for n in needles:
        assert n in msg, msg
    assert "\n" not in msg, msg
    return msg


def validate(d, capsys):
    rc = main(["validate", str(d)])
    out = capsys.readouterr()
    return rc, out.out, out.err


# --- 15: a missing Q is a missing value ---------------------------------------------------


@pytest.mark.parametrize("cell", ["nan", "NA", "N/A", ""])
def test_nan_or_na_in_a_reference_q_is_a_missing_q(tmp_path, scene_text, capsys, cell):
    d = folder(tmp_path, scene_text, [HEADER, set_cell(GOOD[0], "q_factor", cell), *GOOD[1:]])
    p = process(load_dataset(d))
    assert math.isnan(p.q_ref[0]) and p.q_ref[1] == 30.0
    assert p.n_q_missing == 1
    assert any("1 of 2 protocols have no reference Q" in w and "protocol A" in w
               for w in p.warnings), p.warnings
    rc, out, err = validate(d, capsys)
    assert rc == 0, err
    assert "warning: Q: 1 of 2 protocols have no reference Q" in out


def test_dataset_without_a_q_column_loads_and_says_so(tmp_path, scene_text, capsys):
    lines = [",".join(x.split(",")[:-1]) for x in [HEADER, *GOOD]]
    p = process(load_dataset(folder(tmp_path, scene_text, lines)))
    assert p.n_q_missing == 2 and np.isnan(p.q_ref).all()
    assert any("2 of 2 protocols have no reference Q" in w for w in p.warnings)


def _tiny(q_ref):
    from beadrod.models.scene import builtin_scene

    return types.SimpleNamespace(
        f0=np.array([2650.0, 2700.0, 2680.0]), q_ref=np.asarray(q_ref, float),
        drive_protocol=np.array([0, 0, 1, 2]), drive_direction=np.array([0, 1, 0, 1]),
        drive_amplitude=np.array([1e-8, 1e-8, 2e-8, 3e-8]),
        drive_shift=np.array([-0.001, -0.0012, -0.002, -0.003]),
        scene=builtin_scene("paper"))


@pytest.mark.parametrize("law", ["baseline", "viscoelastic"])
def test_missing_q_is_masked_out_of_the_likelihood_term_by_term(law):
    # baseline: the law-free Q model of every law that predicts no Q; viscoelastic: a law
    # that predicts Q. Dropping a protocol's Q removes exactly its term; with no Q at all
    # (a dataset without the column) the log density is the rest, finite, and no Q site
    # is left (an empty plate crashed every fit)
    import numpyro.distributions as dist
    from numpyro import handlers
    from numpyro.infer.util import log_density

    from beadrod.inference.model.likelihood import model_inputs
    from beadrod.inference.model.numpyro_models import ModelSpec, build_model

    model = build_model(ModelSpec(law, fold=False))
    full = model_inputs(_tiny([30.0, 40.0, 50.0]))
    tr = handlers.trace(handlers.seed(model, 0)).get_trace(full)
    params = {k: v["value"] for k, v in tr.items()
              if v["type"] == "sample" and not v["is_observed"]}
    if law == "baseline":
        q_dist = dist.LogNormal(params["mu_logq"], params["tau_logq"])
        terms = [float(q_dist.log_prob(q)) for q in (30.0, 40.0, 50.0)]
    else:
        q_pred = np.asarray(tr["q_pred"]["value"])
        terms = [float(dist.LogNormal(np.log(q_pred[i]), params["sigma_logq"]).log_prob(q))
                 for i, q in enumerate((30.0, 40.0, 50.0))]

    def logp(q_ref):
        return float(log_density(model, (model_inputs(_tiny(q_ref)),), {}, params)[0])

    lf = logp([30.0, 40.0, 50.0])
    assert logp([30.0, np.nan, 50.0]) == pytest.approx(lf - terms[1], abs=1e-9)
    none = logp([np.nan] * 3)
    assert math.isfinite(none) and none == pytest.approx(lf - sum(terms), abs=1e-9)
    no_q = handlers.trace(handlers.seed(model, 0)).get_trace(model_inputs(_tiny([np.nan] * 3)))
    assert "q_obs" not in no_q


def test_report_data_section_counts_protocols_without_q(tmp_path, scene_text):
    from beadrod.workflows.pipeline.outputs import data_block
    from beadrod.workflows.report.document import _data_blocks, _warning_blocks

    d = folder(tmp_path, scene_text, [HEADER, set_cell(GOOD[0], "q_factor", "nan"), *GOOD[1:]])
    block = data_block(process(load_dataset(d)))
    assert block["n_q_missing"] == 1
    blocks = _data_blocks(block)
    rows = dict(next(b for b in blocks if b[0] == "table")[2])
    assert rows["protocols without a reference Q (not in the likelihood)"] == "1"
    # the data's warnings stand under the report's warnings table, once
    warned = [b for b in _warning_blocks({"data": block}) if b[0] == "p"]
    assert sum("no reference Q" in b[1] for b in warned) == 1


# --- 16: no drive sweep --------------------------------------------------------------------


def test_dataset_without_drive_sweeps_is_refused(tmp_path, scene_text, capsys):
    d = folder(tmp_path, scene_text, [HEADER, GOOD[0], GOOD[3], GOOD[4]])
    refuse(d, "measurements.csv", "lines 2-4", "column 'kind'", "no drive sweep")
    rc, _, err = validate(d, capsys)
    assert rc == 2 and err.count("\n") == 1 and "no drive sweep" in err


def test_dataset_whose_drives_the_two_percent_rule_all_drops_is_refused(tmp_path, scene_text,
                                                                        capsys):
    lines = [HEADER, "A,0,reference,up,0.01,2700.0,5.0e-10,40.0",
             "A,1,reference,up,0.01,2600.0,5.0e-10,40.0", "A,2,drive,up,0.5,2590.0,2.5e-8,"]
    d = folder(tmp_path, scene_text, lines)
    ds = load_dataset(d)
    refuse(ds, "measurements.csv", "no drive sweep is left", "2 % rule",
           "--no-two-percent-rule", step=process)
    assert process(ds, two_percent_rule=False).n_drive == 1
    rc, _, err = validate(d, capsys)
    assert rc == 2 and "no drive sweep is left" in err


# --- 17: what validate says about a curve, the fit applies --------------------------------


def lorentz_csv(f0=2683.21, q=25.0, peak=3e-8, lo=2500.0, hi=2900.0, step=1.0, width_hi=None):
    f = np.arange(lo, hi, step)
    g = np.where(f < f0, f0 / (2 * q), (width_hi or f0 / (2 * q)))
    a = peak * g / np.sqrt((f - f0) ** 2 + g**2)
    return "frequency_Hz,amplitude_m\n" + "".join(f"{x:.17g},{y:.17g}\n" for x, y in zip(f, a))


def curve_lines(cell, row):
    out = [HEADER + ",curve"]
    for i, r in enumerate(GOOD):
        if i == row:
            r = set_cell(set_cell(r, "f_res_Hz", ""), "amplitude_m", "")
            out.append(r + "," + cell)
        else:
            out.append(r + ",")
    return out


def test_reference_curve_peaking_at_the_sweeps_edge_is_refused(tmp_path, scene_text):
    # the case: the extraction took the edge (2550 Hz) as f0, the 2 % rule then
    # dropped the protocol's drives without a word
    d = folder(tmp_path, scene_text, curve_lines("c.csv", row=3))
    (d / "c.csv").write_text(lorentz_csv(f0=2500.0, lo=2550.0, hi=2900.0))
    refuse(d, "measurements.csv, line 5, column 'curve'", "c.csv", "sweep's edge",
           "2550 Hz")


def test_untrustworthy_reference_q_is_not_used_and_is_counted(tmp_path, scene_text, capsys):
    d = folder(tmp_path, scene_text, curve_lines("c.csv", row=0))
    (d / "c.csv").write_text(lorentz_csv(f0=2700.0, q=40.0, width_hi=10.0, lo=2550.0,
                                         hi=2850.0, step=0.5))
    ds = load_dataset(d)
    assert any("not trustworthy" in n and "its Q is not used" in n for n in ds.curve_notes)
    p = process(ds)
    assert math.isnan(p.q_ref[0]) and p.n_q_missing == 1 and p.n_q_untrusted == 1
    assert any("1 because the curve's -3 dB Q is not trustworthy" in w for w in p.warnings)
    rc, out, _ = validate(d, capsys)
    assert rc == 0 and "warning: Q: 1 of 2 protocols have no reference Q (1 because" in out


def test_curve_whose_peak_fit_fails_is_said_in_the_warnings(tmp_path, scene_text):
    d = folder(tmp_path, scene_text, curve_lines("c.csv", row=1))
    f = np.arange(2600.0, 2760.0, 1.0)
    # a ramp that drops off a cliff: the cubic through 1/A^2 has no minimum in its window
    a = np.where(f <= 2683.0, 2.5e-8 * (0.5 + 0.5 * (f - 2600.0) / 83.0),
                 7.5e-9 * np.exp(-(f - 2683.0) / 30.0))
    (d / "c.csv").write_text("frequency_Hz,amplitude_m\n"
                             + "".join(f"{x:.17g},{y:.17g}\n" for x, y in zip(f, a)))
    ds = load_dataset(d)
    assert ds.table["curve_grid_maximum"].sum() == 1
    p = process(ds)
    assert any("peak fit failed on 1 sweeps" in w and "line 3" in w for w in p.warnings)


# --- 18: a unit slip in scene.toml ---------------------------------------------------------


@pytest.mark.parametrize("old,new,needles", [
    ("radius_m = 0.007938", "radius_m = 7.938",
     ("[bead] radius_m = 7.938 looks like millimetres", "0.007938 m")),
    ("density_kg_m3 = 7700.0", "density_kg_m3 = 7.7",
     ("[materials.bead] density_kg_m3 = 7.7 looks like g/cm^3", "7700 kg/m^3")),
])
def test_unit_slip_in_the_scene_is_named(tmp_path, scene_text, capsys, old, new, needles):
    assert old in scene_text
    d = folder(tmp_path, scene_text.replace(old, new), [HEADER, *GOOD])
    msg = refuse(d, str(d / "scene.toml"), "2700 Hz", *needles)
    assert msg.count(str(d / "scene.toml")) == 1
    rc, _, err = validate(d, capsys)
    assert rc == 2 and needles[0] in err


def test_scene_that_fits_no_slip_is_refused_in_general_terms(tmp_path, scene_text):
    text = scene_text.replace("f_min_Hz = 1500.0", "f_min_Hz = 10.0")
    lines = [HEADER] + [set_cell(x, "f_res_Hz", str(float(x.split(",")[5]) / 100)) for x in GOOD]
    refuse(folder(tmp_path, text, lines), "does not describe these measurements", "27 Hz")


def test_embedded_worlds_and_builtin_scenes_pass_the_unit_check():
    from pathlib import Path

    import pandas as pd

    from beadrod.data.scene_check import F0_TOLERANCE, check_scene_units, implied_f0_range
    from beadrod.models import scene

    root = Path(__file__).resolve().parents[1] / "data"
    for world in ("paper_like", "hertz_dynamics"):
        ds = load_dataset(root / world)  # loading runs the check
        ref = ds.table.loc[ds.table["kind"] == "reference", "f_res_Hz"]
        lo, hi = implied_f0_range(ds.scene)
        assert lo <= ref.median() <= hi  # inside the range itself, not just the band
    for name in scene.builtin_scene_names():
        # a resonance in the middle of the scene's own sweep band: what it was drawn for
        sc = scene.builtin_scene(name)
        mid = math.sqrt(sc.f_min * sc.f_max)
        table = pd.DataFrame({"kind": ["reference"], "f_res_Hz": [mid]})
        check_scene_units(sc, table, scene_file=Path(f"{name}.toml"), csv_name="m.csv")
        lo, hi = implied_f0_range(sc)
        assert lo / F0_TOLERANCE < mid < hi * F0_TOLERANCE


# --- 20: truth.json of the wrong shape -----------------------------------------------------


@pytest.mark.parametrize("truth,needles", [
    ([1], ("must hold a JSON object", "an array")),
    ({"protocols": 5}, ("key 'protocols' must be an object", "a number")),
    ({"world": ["x"]}, ("key 'world' must be a string",)),
    ({"seed": "441"}, ("key 'seed' must be an integer",)),
    ({"protocols": {"A": [1]}}, ("key 'protocols' -> 'A' must be an object",)),
    ({"protocols": {"A": {"f0_reference_Hz": "2700"}}},
     ("'protocols' -> 'A' -> 'f0_reference_Hz' must be a positive number",)),
    ({"protocols": {"A": {"q": -3}}}, ("-> 'q' must be a positive number",)),
    ({"parameters": {"eta_Pa_s": [1]}}, ("'parameters' -> 'eta_Pa_s'",)),
])
def test_truth_of_the_wrong_shape_is_refused_with_the_dataset(tmp_path, scene_text, capsys,
                                                             truth, needles):
    d = folder(tmp_path, scene_text, [HEADER, *GOOD])
    (d / "truth.json").write_text(json.dumps(truth))
    refuse(d, str(d / "truth.json"), *needles)
    rc, _, err = validate(d, capsys)
    assert rc == 2 and err.count("\n") == 1


def test_truth_nested_too_deeply_is_one_line(tmp_path, scene_text):
    d = folder(tmp_path, scene_text, [HEADER, *GOOD])
    (d / "truth.json").write_text("[" * 100_000 + "]" * 100_000)
    refuse(d, "truth.json", "nested too deeply")


def test_truth_of_the_embedded_worlds_passes():
    from pathlib import Path

    from beadrod.data.load import TRUTH, load_truth

    root = Path(__file__).resolve().parents[1] / "data"
    for world in ("paper_like", "hertz_dynamics"):
        assert load_truth(root / world / TRUTH)["world"] == world


# --- 21: a curve of absurd amplitudes ------------------------------------------------------


@pytest.mark.parametrize("peak,needle", [(1e-300, "below 1e-15 m"),
                                         (1e-200, "below 1e-15 m"),
                                         (5e-3, "nm or um written as m")])
def test_curve_of_absurd_amplitudes_refused_before_the_peak_fit(tmp_path, scene_text, peak,
                                                                needle):
    d = folder(tmp_path, scene_text, curve_lines("c.csv", row=1))
    (d / "c.csv").write_text(lorentz_csv(peak=peak))
    refuse(d, "measurements.csv, line 3, column 'curve'", "c.csv", "amplitude_m", needle)
