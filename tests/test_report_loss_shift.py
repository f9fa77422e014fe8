"""The report's loss-against-shift tables and the law each observable prefers: rendered in
Markdown and HTML from a result.json built by hand (no fit), with a law that did not read
an observable, and documented in docs/outputs.md."""

from __future__ import annotations

import re

import pandas as pd

from beadrod.workflows.report.document import render_report
from beadrod.workflows.report.loss_shift import loss_shift_sentence, observable_sentence
from tests.test_report import ROOT, _md_table_after, _Refs, _result, _section


def _table_after(md: str, heading: str) -> pd.DataFrame:
    """The first Markdown table after ``heading``, cells split at unescaped pipes (the
    headers hold |Δf/f0|) and unescaped."""
    lines = md[md.index(heading):].splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith("|"))
    rows = []
    for ln in lines[start:]:
        if not ln.startswith("|"):
            break
        cells = [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", ln)[1:-1]]
        if not all(set(c) <= {"-"} for c in cells):
            rows.append(cells)
    return pd.DataFrame(rows[1:], columns=rows[0])


def _row(ratio, *, sign="narrows", q=52.9, src="data", beta=(2.0, 2.2, 2.4), p=(2, 2, 2),
         r=(2, 2, 2), rung="backbone"):
    return {"rung": rung, "q_ref_source": src, "beta_source": "fitted", "q_ref": q,
            "shift": [-7e-5] * 3, "shift_exponent": list(p), "loss_change": [-3e-6] * 3,
            "loss_exponent": list(r), "ratio": list(ratio), "ratio_eq31": [-0.007, -0.003, 0.0],
            "beta": list(beta), "p_widens": 0.0 if sign == "narrows" else 1.0, "sign": sign,
            "note": None}


def _contest(site, what, pref, runner, d, se, absent=(), k_bad=0):
    return {"site": site, "observable": what, "absent": list(absent),
            "elpd": {pref: {"elpd_loo": 10.0, "se": 2.0, "k_bad": k_bad, "n": 28},
                     runner: {"elpd_loo": 10.0 - d, "se": 2.0, "k_bad": 0, "n": 28}},
            "preferred": pref, "runner_up": runner, "delta_elpd": d, "delta_se": se,
            "resolved": d > 2 * se, "baseline": None, "baseline_delta": None,
            "baseline_delta_se": None}


def _with_tables(tmp_path):
    res = _result(tmp_path)
    exact = {"hertz": _row((-0.045, -0.041, -0.038)),
             "viscoelastic": {**_row((-0.13, -0.12, -0.10), src="law", q=50.5),
                              "beta": [3.0, 3.0, 3.0], "beta_source": "own"},
             "jkr": {"error": "ValueError: no draws"}}
    paper = {**exact, "viscoelastic": {**exact["viscoelastic"], "rung": "paper_eq25",
                                       "shift_exponent": [1.18, 1.2, 1.22],
                                       "source": "the tension's Eq. 25 fit"}}
    res["loss_shift"] = {
        "x_small": 0.04, "exact": exact, "paper": paper,
        "data": {"ratio": [-0.046, 0.017], "ratio_eq31": [-0.005, 0.017], "ratio_x_max": 0.158,
                 "ratio_n": 227, "shift_exponent": [1.526, 0.022], "loss_exponent": None,
                 "shift": -7e-4, "loss_change": None, "sign": "either", "q_ref": 52.9,
                 "n": 454}}
    res["observables"] = {
        "observables": [
            _contest("shift_obs", "shift", "viscoelastic", "hertz", 33.0, 5.0),
            _contest("q_obs", "reference Q", "viscoelastic", "hertz", 0.04, 0.13, k_bad=2),
            _contest("amp_obs", "amplitude per volt", "hertz", "viscoelastic", 17.0, 4.0,
                     absent=["jkr"])],
        "all": {"preferred": "viscoelastic", "runner_up": "hertz", "delta_log_z": 32.2,
                "delta_log_z_err": 0.5, "baseline": None, "baseline_lead": None,
                "baseline_lead_err": None},
        "unread": ["f0"], "gate_ignored": False}
    return res


def test_loss_against_shift_tables_render_in_markdown_and_html(tmp_path):
    res = _with_tables(tmp_path)
    md_path, html_path = render_report(res, tmp_path)
    md = md_path.read_text()
    sec = _section(md, "## Loss against shift")
    assert "x = δa/δ0 = 0.04" in sec
    assert "### Exact physics" in sec and "### The paper's Eq. 25 reading" in sec
    df = _table_after(md, "### Exact physics")
    assert list(df["model"]) == ["Hertz", "Viscoelastic", "JKR", "**data**"]
    row = df.set_index("model")
    assert row.loc["Hertz", "the resonance"] == "narrows"
    assert row.loc["Hertz", "Δ(1/Q)/|Δf/f0|"] == "−0.041 [−0.045, −0.038]"
    assert row.loc["Viscoelastic", "β (loss ∝ Ω^β)"] == "3 (its own)"
    assert row.loc["Viscoelastic", "Q0"] == "50.5 (the law)"
    assert row.loc["JKR", "Q0"].startswith("not computed: ValueError")
    assert row.loc["**data**", "Δf/f0 ∝ x^p: p"] == "1.526 ± 0.022"
    assert row.loc["**data**", "Δ(1/Q) ∝ x^r: r"] == "not resolved"
    assert row.loc["**data**", "the resonance"] == "sign not resolved"
    paper = _table_after(md, "### The paper's Eq. 25 reading")
    assert "Viscoelastic (the tension's Eq. 25 fit), `paper_eq25`" in list(paper["model"])
    text = loss_shift_sentence(res["loss_shift"], "exact",
                               {"hertz": "Hertz", "viscoelastic": "Viscoelastic"})
    assert "−0.046 ± 0.017" in text and "of Hertz" in text
    assert "outside that of Viscoelastic" in text and text in sec
    html = html_path.read_text()
    assert "Loss against shift" in html and "Δ(1/Q)/|Δf/f0|" in html
    parser = _Refs()
    parser.feed(html)
    heads = [t[0] for t in parser.tables]
    assert any(h[:2] == ["model", "Q0"] for h in heads)
    assert any(h[0] == "observable" for h in heads)


def test_preferred_law_per_observable_renders_with_absent_laws(tmp_path):
    res = _with_tables(tmp_path)
    md = render_report(res, tmp_path)[0].read_text()
    df = _md_table_after(md, "## The law each observable prefers").set_index("observable")
    assert df.loc["shift", "preferred law"] == "Viscoelastic"
    assert df.loc["shift", "lead over the runner-up"] == "33 ± 5 nats elpd"
    assert "not resolved" in df.loc["reference Q", "lead over the runner-up"]
    assert df.loc["amplitude per volt", "not in the contest (not read)"] == "JKR"
    assert df.loc["**all together** (evidence)", "preferred law"] == "Viscoelastic"
    assert df.loc["**all together** (evidence)", "lead over the runner-up"] == \
        "32.2 ± 0.5 nats log Z"
    labels = {"hertz": "Hertz", "viscoelastic": "Viscoelastic"}
    text = observable_sentence(res["observables"], labels)
    assert "amplitude per volt prefers Hertz" in text
    assert "all together the evidence prefers Viscoelastic, as shift and reference Q do" in text
    assert "unreliable" in text and "Viscoelastic on reference Q" in text
    assert "No model read f0" in text
    assert text in _section(md, "## The law each observable prefers")


def test_report_without_the_new_keys_says_nothing_of_them(tmp_path):
    md = render_report(_result(tmp_path), tmp_path)[0].read_text()
    assert "Loss against shift" not in md and "each observable prefers" not in md
    res = _result(tmp_path)
    res["observables"] = {"error": "DataHashMismatch: models were fitted to different data"}
    md = render_report(res, tmp_path)[0].read_text()
    assert "Not computed: DataHashMismatch" in md


def test_outputs_doc_covers_the_new_keys():
    doc = (ROOT / "docs" / "outputs.md").read_text()
    documented = set(re.findall(r"^\| `([\w.\[\]]+)` \|", doc, flags=re.M))
    keys = ["loss_shift", "observables"]
    keys += [f"loss_shift.{k}" for k in ("x_small", "exact", "paper", "data")]
    keys += [f"observables.{k}" for k in ("observables", "unread", "all", "gate_ignored")]
    for k in keys:
        assert k in documented, f"result.json key {k!r} not in docs/outputs.md"


# ----------------------------------------------------------- what the pipeline assembles
def test_the_paper_reading_takes_the_tension_fit_where_there_is_one():
    from beadrod import data as bd
    from beadrod.workflows.pipeline.fits import LawRun
    from beadrod.workflows.pipeline.outputs import loss_shift

    ds = bd.load_default()
    own, paper, tension = _row((-1, -1, -1)), _row((-2, -2, -2)), _row((-3, -3, -3))
    runs = {"viscoelastic": LawRun("viscoelastic", {}, None,
                                   loss_shift={"exact": own, "paper": paper}),
            "hertz": LawRun("hertz", {}, None, loss_shift={"exact": own, "paper": paper})}
    done = {"tension:viscoelastic": LawRun("viscoelastic_paper_eq25", {}, None,
                                           loss_shift={"exact": tension, "paper": tension})}
    block = loss_shift(runs, ds, done)
    assert block["x_small"] == 0.04 and block["data"]["n"] == 454
    assert block["exact"]["viscoelastic"] is own
    assert block["paper"]["viscoelastic"]["ratio"] == [-3, -3, -3]
    assert block["paper"]["viscoelastic"]["source"] == "the tension's Eq. 25 fit"
    assert block["paper"]["hertz"] is paper


def test_observable_preference_ignores_the_gate_only_where_no_law_passed():
    from beadrod.workflows.pipeline.fits import LawRun
    from beadrod.workflows.pipeline.outputs import observable_preference
    from tests.test_loss_shift import _toy

    def run(name, mean, status):
        return LawRun(name, {"name": name, "label": name, "status": status, "log_z": -mean,
                             "log_z_err": 0.1, "model": f"{name}/backbone",
                             "data_hash": "h"}, _toy({"shift_obs": mean, "amp_obs": mean}))

    ds = type("DS", (), {"data_hash": "h"})()
    out = observable_preference({"a": run("a", 0.0, "failed"), "b": run("b", 1.0, "ok")}, ds)
    assert not out["gate_ignored"] and out["observables"][0]["preferred"] == "b"
    out = observable_preference({"a": run("a", 0.0, "failed"),
                                 "b": run("b", 1.0, "failed")}, ds)
    assert out["gate_ignored"] and out["observables"][0]["preferred"] == "a"
    assert out["all"]["preferred"] == "a"
