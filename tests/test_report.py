"""Report rendering: self-contained HTML, failed runs marked, tables that parse back, and a
report that explains itself (headline, priors, warnings, truth, units, tension, data)."""

from __future__ import annotations

import base64
import io
import json
import math
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from beadrod.workflows.report.document import comparison_table, render_report, statistical_warnings
from beadrod.workflows.report.params import param_table, prior_text, priors_table
from beadrod.workflows.report.tables import fmt_pm, headline, timings_table
from beadrod.workflows.report.tension import tension_sentences, tension_table
from beadrod.workflows.report.truth import world_truth

ROOT = Path(__file__).resolve().parents[1]


def _law(name, label, log_z, err, elpd, *, status="ok", failures=(), params=None, z2=None,
         model=None, k_bad=0):
    return {
        "name": name, "label": label, "rung": "first_order", "status": status,
        "model": model or f"{name}/first_order", "failures": list(failures),
        "diagnostics": {"rhat_max": 1.002, "ess_bulk_min": 850.0, "ess_tail_min": 700.0,
                        "divergences": 0, "ebfmi_min": 0.9},
        "params": params or [],
        "log_z": log_z, "log_z_err": err, "log_z_method": "nested",
        "log_z2": z2, "log_z2_err": None if z2 is None else 0.5,
        "log_z2_method": None if z2 is None else "harmonic",
        "evidence_agree": None if z2 is None else True,
        "elpd_loo": elpd, "elpd_loo_se": 3.0, "pareto_k_bad": k_bad,
        "loo": {"n_points": 300},
    }


def _param(name, mean, sd, q05, q95, unit=""):
    return {"name": name, "unit": unit, "mean": mean, "sd": sd, "q05": q05, "q95": q95,
            "truth": None}


def _result(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figs = []
    (tmp_path / "figures").mkdir(parents=True, exist_ok=True)
    for name in ("eta_tension", "evidence"):
        fig, ax = plt.subplots(figsize=(4, 3))
        ax.plot([2600.0, 2700.0], [30.0, 60.0], "o")
        fig.savefig(tmp_path / "figures" / f"{name}.png", dpi=60)
        plt.close(fig)
        figs.append({"path": f"figures/{name}.png", "caption": f"Caption {name}",
                     "section": "tension" if name == "eta_tension" else "comparison"})
    visco_params = [_param("eta", 1.0e6, 0.1e6, 0.85e6, 1.2e6, "Pa s"),
                    _param("young", 2.0e11, 5e9, 1.92e11, 2.08e11, "Pa")]
    truth = {"world": "paper_like", "kind": "phenomenological", "seed": 441,
             "values": {"eta": {"value": 1.05e6, "note": "sets the shift"}},
             "none": {"young": "no truth: f0_p is drawn, not computed from a modulus"}}
    return {
        "title": "Test comparison", "beadrod_version": "0.1.0",
        "created": "2026-11-23T08:00:00+00:00",
        "data": {"source": "/data/paper_like", "hash": "abc123", "n_protocols": 28,
                 "n_drive": 300, "n_excluded": 12, "synthetic": True, "truth": truth,
                 "two_percent_rule": True, "shift_reference": "first",
                 "young_range_Pa": [190e9, 210e9],
                 "excluded": [{"protocol": "P03", "n": 4, "lines": [45, 46, 47, 48],
                               "steps": [11, 13], "reason": "2 % rule: reference step 10"},
                              {"protocol": "P09", "n": 8, "lines": list(range(200, 208)),
                               "steps": [15], "reason": "2 % rule: reference step 14"}]},
        "laws": [
            _law("hertz", "Hertz", -512.3, 0.3, -520.0, z2=-512.9,
                 params=[_param("young", 2e11, 1e10, 1.8e11, 2.2e11, "Pa")]),
            _law("viscoelastic", "Viscoelastic", -480.1, 0.4, -490.0, z2=-480.5,
                 params=visco_params),
            _law("jkr", "JKR", float("nan"), float("nan"), float("nan"), status="failed",
                 failures=["R-hat 1.31 > 1.01", "1203 divergences"]),
        ],
        "preferred": "viscoelastic",
        "tension": {
            "rung": "paper_eq25", "eta_in_shift": True,
            "eta_shift_q05_q50_q95": [0.85e6, 1.0e6, 1.2e6],
            "eta_q_q05_q50_q95": [4.0e4, 6.0e4, 9.0e4],
            "eta_joint_q05_q50_q95": [1.0e5, 1.2e5, 1.4e5],
            "log10_gap_q05_q50_q95": [1.0, 1.22, 1.45], "p_shift_gt_q": 1.0,
            "log_bf_split_vs_shared": 12.4, "log_bf_err": 0.6,
            "ppc": {"shift_p": 0.0004, "q_p": 0.4, "missed": "shift"},
        },
        "figures": figs,
        "timings": {"fit_hertz_s": 12.0, "fit_viscoelastic_s": 30.5, "fits_wall_s": 31.0,
                    "workers": 2, "figures_s": 4.0, "total_s": 40.0},
        "config": {"chains": 2, "draws": 500, "data": None, "laws": None},
    }


class _Refs(HTMLParser):
    def __init__(self):
        super().__init__()
        self.refs: list[tuple[str, str, str]] = []
        self.tables: list[list[list[str]]] = []
        self.stack: list[str] = []
        self.figures: list[list[str]] = []
        self._row: list[str] | None = None
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        for k, v in attrs:
            if k in ("src", "href", "data", "poster", "srcset", "action"):
                self.refs.append((tag, k, v or ""))
        if tag == "figure":
            self.figures.append([])
        elif self.figures and "figure" in self.stack:
            self.figures[-1].append(tag)
        if tag not in ("img", "meta", "br"):
            self.stack.append(tag)
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if self.stack and self.stack[-1] == tag:
            self.stack.pop()
        if tag in ("td", "th") and self._cell is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.tables[-1].append(self._row)
            self._row = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _md_table_after(md: str, heading: str) -> pd.DataFrame:
    lines = md[md.index(heading):].splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith("|"))
    block = []
    for ln in lines[start:]:
        if not ln.startswith("|"):
            break
        if not set(ln.replace("|", "")) <= set("-"):
            block.append(ln.strip().strip("|"))
    return pd.read_csv(io.StringIO("\n".join(block)), sep="|", skipinitialspace=True).rename(
        columns=str.strip).map(lambda v: v.strip() if isinstance(v, str) else v)


def _sentences(text: str) -> list[str]:
    # a sentence ends at . ! ? before a capital letter or the end ("Eq. 25" does not end one)
    return [s for s in re.split(r"(?<=[.!?])\s+(?=[A-Z])", text.strip()) if s]


def _section(md: str, heading: str) -> str:
    start = md.index(heading)
    nxt = md.find("\n## ", start + len(heading))
    return md[start:nxt if nxt > 0 else None]


# ------------------------------------------------------------------ self-contained HTML
def test_html_is_self_contained_and_embeds_every_figure(tmp_path):
    md_path, html_path = render_report(_result(tmp_path), tmp_path)
    assert md_path == tmp_path / "report.md" and html_path == tmp_path / "report.html"
    text = html_path.read_text()
    parser = _Refs()
    parser.feed(text)
    assert parser.refs, "expected embedded images"
    for tag, attr, value in parser.refs:
        assert value.startswith("data:"), (tag, attr, value[:60])
    imgs = [v for t, a, v in parser.refs if t == "img"]
    assert len(imgs) == 2 and all(v.startswith("data:image/png;base64,") for v in imgs)
    assert "url(" not in text and "@import" not in text
    png = base64.b64decode(imgs[0].split(",", 1)[1])
    assert png == (tmp_path / "figures" / "eta_tension.png").read_bytes()
    assert "](figures/eta_tension.png)" in md_path.read_text()


def test_failed_law_is_marked_in_every_table(tmp_path):
    md_path, html_path = render_report(_result(tmp_path), tmp_path)
    md = md_path.read_text()
    assert "⚠ FAILED: 1 of 3 fits failed their sampling gate (JKR)" in md
    gate = _md_table_after(md, "## Warnings").set_index("law")["sampling gate"]
    assert gate["JKR"] == "✗ **FAILED**: R-hat 1.31 > 1.01; 1203 divergences"
    assert gate["Hertz"] == "✓ ok"
    for heading in ("## Evidence and LOO", "## Sampler diagnostics"):
        df = _md_table_after(md, heading)
        assert list(df.loc[df["law"] == "JKR", "status"]) == ["**FAILED**"]
        assert not df.loc[df["law"] != "JKR", "status"].str.contains("FAILED").any()
    assert "### JKR — FAILED" in md
    parser = _Refs()
    parser.feed(html_path.read_text())
    comp = next(t for t in parser.tables if any("Δ log Z vs preferred" in c for c in t[0]))
    assert [r[1] for r in comp[1:]] == ["ok", "ok", "FAILED"]


# --------------------------------------------------------------------- digits, headline
@pytest.mark.parametrize("v, err, text", [
    (1147.1712, 0.0123, "1147.171 ± 0.012"), (1147.1712, 0.01, "1147.171 ± 0.010"),
    (1147.1712, 0.04, "1147.17 ± 0.04"), (1147.1712, 0.006, "1147.171 ± 0.006"),
    (1147.2, 0.04, "1147.20 ± 0.04"), (12.44, 0.6, "12.4 ± 0.6"), (512.3, 35.0, "512 ± 35"),
    (1234.0, 500.0, "1200 ± 500"), (3.14159, 0.0987, "3.14 ± 0.10"), (0.5, 0.96, "0.5 ± 1.0"),
    (-480.1, 0.4, "-480.1 ± 0.4")])
def test_numbers_carry_the_digits_their_error_needs(v, err, text):
    # Particle Data Group rounding (Review of Particle Physics, "Rounding" in the
    # introduction): 100-354 -> two significant digits, 355-949 -> one, 950-999 -> 1000
    assert fmt_pm(v, err) == text


def test_headline_names_law_evidence_and_gap(tmp_path):
    res = _result(tmp_path)
    res["laws"][0].update(log_z=1130.35, log_z_err=0.0213)
    res["laws"][1].update(log_z=1147.1712, log_z_err=0.0123)
    blocks = headline(res)
    assert [k for k, _ in blocks] == ["p"]
    text = blocks[0][1]
    assert "**Viscoelastic**" in text and "1147.171 ± 0.012 nats" in text
    # gap 16.8212 +- hypot(0.0123, 0.0213) = 0.0246
    assert "16.821 ± 0.025 nats above the next law, Hertz" in text
    assert "very strong" in text and "0.0 " not in text
    md = render_report(res, tmp_path)[0].read_text()
    first = md.split("\n## ")[0]
    assert text in first  # the headline is on the first screen, before any section


def test_baseline_beating_every_law_is_said_first(tmp_path):
    res = _result(tmp_path)
    res["laws"].append(_law("baseline", "law-free baseline", -470.0, 0.5, -480.0,
                            model="baseline"))
    blocks = headline(res)
    assert blocks[0][0] == "warn" and "law-free baseline beats every contact law" in blocks[0][1]
    assert "10.1 ± 0.6 nats above the best law's (Viscoelastic)" in blocks[0][1]
    assert "**Viscoelastic**" in blocks[1][1]
    md, csv_text = comparison_table(res)
    d = pd.read_csv(io.StringIO(csv_text)).set_index("law")
    # Delta log Z against the best law, not the baseline; the baseline's lead separately
    assert d.loc["viscoelastic", "delta_log_z"] == 0.0
    assert d.loc["baseline", "delta_log_z"] == pytest.approx(10.1)
    assert d.loc["hertz", "delta_log_z"] == pytest.approx(-32.2)
    assert bool(d.loc["viscoelastic", "preferred"]) and not d.loc["baseline", "preferred"]
    page = render_report(res, tmp_path)[0].read_text()
    assert page.index("baseline beats every contact law") < page.index("Preferred law:")


def test_comparison_table_parses_and_is_right(tmp_path):
    md, csv_text = comparison_table(_result(tmp_path))
    df = pd.read_csv(io.StringIO(csv_text))
    assert list(df["law"]) == ["hertz", "viscoelastic", "jkr"]
    assert list(df["status"]) == ["ok", "ok", "failed"]
    d = df.set_index("law")
    assert d.loc["viscoelastic", "delta_log_z"] == 0.0
    assert d.loc["hertz", "delta_log_z"] == pytest.approx(-512.3 + 480.1)
    assert d.loc["hertz", "delta_log_z_err"] == pytest.approx(math.hypot(0.3, 0.4))
    assert d.loc["hertz", "delta_elpd_loo"] == pytest.approx(-30.0)
    assert math.isnan(d.loc["jkr", "log_z"])
    assert "divergences" in d.loc["jkr", "failures"]
    mdf = pd.read_csv(io.StringIO("\n".join(
        ln.strip().strip("|") for ln in md.splitlines() if not ln.startswith("|---"))),
        sep="|", skipinitialspace=True).rename(columns=str.strip)
    assert "log Z ± err (nested)" in mdf.columns and "log Z ± err (harmonic)" in mdf.columns
    assert mdf["log Z ± err (nested)"].str.strip().iloc[0] == "-512.30 ± 0.30"
    assert mdf["Δ log Z vs preferred"].str.strip().iloc[1] == "0 (reference)"
    assert mdf["Δ log Z vs preferred"].str.strip().iloc[0] == "-32.2 ± 0.5"


def test_best_law_ignores_failed_runs():
    res = {"laws": [_law("a", "A", -10.0, 0.1, -5.0),
                    _law("b", "B", -1.0, 0.1, -1.0, status="failed")]}
    df = pd.read_csv(io.StringIO(comparison_table(res)[1])).set_index("law")
    assert df.loc["a", "delta_log_z"] == 0.0
    assert df.loc["b", "delta_log_z"] == pytest.approx(9.0)


# ------------------------------------------------------------------- priors, parameters
def test_priors_table_lists_every_law_prior_readably(tmp_path):
    import numpyro.distributions as dist

    assert prior_text("young", dist.Uniform(150e9, 250e9)) == "Uniform(150, 250) GPa"
    assert prior_text("delta0_ref_log", dist.Normal(math.log(55e-9), 1.0)) == \
        "ln δ0,ref ~ Normal(ln 55 nm, 1)"
    res = _result(tmp_path)
    res["laws"].append(_law("powerlaw", "power law", -500.0, 0.3, -500.0, params=[
        _param("n", 1.6, 0.05, 1.5, 1.7), _param("delta0_ref_log", math.log(55e-9), 0.1,
                                                  math.log(48e-9), math.log(62e-9))]))
    headers, body, _ = priors_table(res["laws"])
    rows = {r[0]: r for r in body}
    assert set(rows) == {"E (young)", "η (eta)", "n (n)", "δ0,ref (delta0_ref_log)"}
    assert rows["E (young)"][1] == "Uniform(150, 250) GPa"
    assert rows["E (young)"][2] == "Hertz, Viscoelastic"
    assert rows["η (eta)"][1] == "LogUniform(0.0001, 100) MPa s"
    assert rows["n (n)"][1] == "Uniform(1, 3)"
    for r in body:  # a justification from inference.model.priors, as plain text
        assert len(r[3]) > 30 and "`" not in r[3], r
    assert "Hurst" in rows["n (n)"][3]
    md = render_report(res, tmp_path)[0].read_text()
    assert "## Priors" in md and "Uniform(150, 250) GPa" in _section(md, "## Priors")


def test_log_overlap_printed_in_nm_and_one_unit_per_row(tmp_path):
    law = _law("powerlaw", "power law", -500.0, 0.3, -500.0, params=[
        _param("delta0_ref_log", math.log(55e-9), 0.02, math.log(53.3e-9), math.log(56.8e-9))])
    headers, body, _ = param_table(law, None)
    row = dict(zip(headers, body[0]))
    assert row["parameter"] == "δ0,ref (delta0_ref_log)" and row["unit"] == "nm"
    assert row["mean ± sd"] == "55.0 ± 1.1"  # e^mean, sd by the delta method: 55 * 0.02
    assert row["90 % interval"] == "[53.3, 56.8]"
    assert "log m" not in json.dumps(body)


def test_every_parameter_is_explained(tmp_path):
    names = ["delta0_scatter", "mu_logq", "tau_logq", "offset_down", "sigma_shift", "amp",
             "power", "mu_f0", "tau_f0"]
    res = _result(tmp_path)
    res["laws"].append(_law("baseline", "law-free baseline", -600.0, 0.5, -600.0,
                            model="baseline", params=[_param(n, 0.1, 0.01, 0.08, 0.12)
                                                      for n in names]))
    md = render_report(res, tmp_path)[0].read_text()
    gloss = _md_table_after(md, "## Parameters of every law")
    meaning = dict(zip(gloss["name"], gloss["meaning"]))
    for n in names + ["eta", "young"]:
        assert n in meaning and len(meaning[n]) > 15 and meaning[n] != "(no description)", n
    glossary = _section(md, "## Glossary")
    for term in ("**rung**", "**backbone**", "**scene**"):
        assert term in glossary


# ------------------------------------------------------------------------------ warnings
def test_warnings_a_statistician_would_raise(tmp_path):
    res = _result(tmp_path)
    res["laws"] = [
        _law("hertz", "Hertz", -10.0, 0.1, -5.0, k_bad=3,
             params=[_param("young", 224e9, 3.5e9, 218e9, 230e9)]),
        _law("powerlaw", "power law", -11.0, 0.1, -5.0,
             params=[_param("n", 2.98, 0.02, 2.94, 3.00)]),
        _law("powerlaw2", "well-posed power law", -12.0, 0.1, -5.0,
             params=[_param("n", 1.6, 0.05, 1.52, 1.68), _param("young", 200e9, 3e9, 195e9,
                                                                 205e9)]),
    ]
    res["checks"] = {"loo_pit": {
        "hertz": {"ks_d": 0.21, "ks_p": 2e-6, "tails": 0.31, "mean": 0.5, "calibrated": False,
                  "n": 300},
        "powerlaw2": {"ks_d": 0.03, "ks_p": 0.8, "tails": 0.1, "mean": 0.5, "calibrated": True}}}
    w = statistical_warnings(res)
    text = "\n".join(w)
    assert any("power law: n = 2.980 ± 0.020, 90 % interval [2.940, 3.000]" in x and "piled against its prior bound 3" in x
               for x in w), text
    assert any("Hertz: E = 224.0 ± 3.5 GPa" in x and "outside the scene's expected range 190-210"
               in x for x in w), text
    assert any("Hertz: the LOO-PIT" in x and "31 % of the values" in x and "too narrow" in x
               for x in w), text
    assert any("Hertz: 3 of 300 drive sweeps have Pareto k > 0.7" in x for x in w), text
    assert "well-posed" not in text  # inside its bounds and range, calibrated: no warning
    assert len(w) == 4


def _flagged(tmp_path):
    """Three laws, two of them with the same miscalibrated LOO-PIT and the same modulus
    outside the scene's range, and a data warning."""
    res = _result(tmp_path)
    young = _param("young", 224e9, 7e9, 218e9, 230e9)
    res["laws"] = [
        _law("hertz", "Hertz", -10.0, 0.1, -5.0, k_bad=3, params=[young], z2=-10.3),
        _law("visco", "visco", -11.0, 0.1, -5.0, z2=-11.2,
             params=[young, _param("n", 2.98, 0.02, 2.94, 3.00)]),
        _law("fine", "fine", -12.0, 0.1, -5.0, status="failed", failures=["R-hat 1.2 > 1.01"],
             params=[_param("young", 200e9, 5e9, 195e9, 205e9)], z2=-12.1),
    ]
    res["laws"][1]["evidence_agree"] = False
    bad = {"ks_d": 0.21, "ks_p": 2e-6, "tails": 0.31, "mean": 0.5, "calibrated": False,
           "n": 300}
    res["checks"] = {"loo_pit": {"hertz": bad, "visco": bad,
                                 "fine": {"ks_d": 0.03, "ks_p": 0.8, "tails": 0.1,
                                          "mean": 0.5, "calibrated": True, "n": 300}}}
    res["data"]["warnings"] = ["2 protocols without a reference Q (not in the likelihood)"]
    return res


def test_first_screen_is_the_evidence_then_one_warnings_table(tmp_path):
    res = _flagged(tmp_path)
    md_path, html_path = render_report(res, tmp_path)
    md = md_path.read_text()
    # the evidence table comes before every warning; above it only the headline and the
    # gate's one-line banner
    evidence, warnings = md.index("## Evidence and LOO"), md.index("## Warnings")
    assert evidence < warnings < md.index("## Parameters of the preferred law")
    head = [ln for ln in md[:evidence].splitlines() if "⚠" in ln]
    assert len(head) == 1 and head[0].startswith("> ⚠ FAILED: 1 of 3 fits"), head
    for word in ("LOO-PIT", "Pareto", "prior", "scene", "Data warning"):
        assert word not in md[:evidence], word
    # one warnings table, a row per law, a column per check, each cell a mark and a value
    sec = _section(md, "## Warnings")
    assert "> ⚠" not in sec  # no box per warning
    df = _md_table_after(md, "## Warnings").set_index("law")
    assert list(df.index) == ["Hertz", "visco", "fine"]
    assert list(df.columns) == ["sampling gate", "prior bounds", "E in 190-210 GPa",
                                "LOO-PIT", "Pareto k > 0.7", "log Z estimators"]
    assert df.loc["Hertz", "LOO-PIT"] == "⚠ too narrow: D = 0.21, p = 2e-06, tails 31 %"
    assert df.loc["visco", "LOO-PIT"] == df.loc["Hertz", "LOO-PIT"]
    assert df.loc["fine", "LOO-PIT"] == "✓ D = 0.03, p = 0.8"
    assert df.loc["Hertz", "E in 190-210 GPa"] == "⚠ [218, 230] GPa"
    assert df.loc["fine", "E in 190-210 GPa"] == "✓ [195, 205] GPa"
    assert df.loc["visco", "prior bounds"].startswith("⚠ n [2.940, 3.000\\]: piled against "
                                                      "its bound 3")
    assert df.loc["Hertz", "prior bounds"] == "✓ none"
    assert df.loc["Hertz", "Pareto k > 0.7"] == "⚠ 3 of 300"
    assert df.loc["visco", "Pareto k > 0.7"] == "✓ 0 of 300"
    assert df.loc["fine", "sampling gate"] == "✗ **FAILED**: R-hat 1.2 > 1.01"
    assert list(df["log Z estimators"]) == ["✓ agree", "⚠ disagree", "✓ agree"]
    # what each check means: once, however many laws it flags
    for words in ("too many sweeps in its tails", "needs an unphysical modulus",
                  "the bound, not the data, cuts the posterior off", "K-fold CV",
                  "log Z is not settled"):
        assert md.count(words) == 1, words
    assert "the LOO-PIT of the shift is not uniform" not in md  # the old per-law sentence
    # the data's own warning: a short line under the table, and only there
    line = "Data warning: 2 protocols without a reference Q (not in the likelihood)."
    assert md.count(line) == 1 and line in sec
    html = html_path.read_text()
    assert 'class="caution"' not in html
    parser = _Refs()
    parser.feed(html)
    heads = [t[0][:2] for t in parser.tables]
    assert heads.index(["law", "status"]) < heads.index(["law", "sampling gate"])
    assert len([h for h in heads if h == ["law", "sampling gate"]]) == 1
    # a cell is tinted by its mark
    assert '<td class="failing">✗ <strong class="failed">FAILED</strong>' in html
    assert '<td class="warning">⚠ 3 of 300</td>' in html and '<td class="ok">✓ none</td>' in html
    # one evidence estimator: said once, where its column shows a dash
    assert "cross-check" not in md
    for lw in res["laws"]:
        lw.update(log_z2=None, log_z2_method=None, evidence_agree=None)
    one = render_report(res, tmp_path)[0].read_text()
    assert one.count("no cross-check") == 1 and "no cross-check" in _section(one, "## Warnings")


def test_posterior_filling_its_prior_is_flagged():
    law = _law("p", "P", -1.0, 0.1, -1.0, params=[_param("n", 2.0, 0.55, 1.1, 2.9)])
    (w,) = statistical_warnings({"laws": [law]})
    assert "fills its prior [1, 3]" in w


def test_a_broad_posterior_leaning_on_a_bound_is_not_piled_against_it():
    """Maugis-Dugdale's lam on the embedded data: 90 % interval [0.525, 80.2] under a
    LogUniform(0.1, 100) prior (whose own 90 % interval is [0.141, 70.8]) spans 73 % of
    the prior's log range; near the upper bound only because it barely moved."""
    law = _law("md", "MD", -1.0, 0.1, -1.0, params=[_param("lam", 20.0, 25.0, 0.525, 80.2)])
    (w,) = statistical_warnings({"laws": [law]})
    assert "spans 73% of its prior [0.1, 100] on a log scale" in w, w
    assert "lean towards its bound 100" in w and "piled against" not in w, w
    # narrow and at the bound: piled against it, as before
    law = _law("md", "MD", -1.0, 0.1, -1.0, params=[_param("lam", 90.0, 5.0, 80.0, 99.9)])
    (w,) = statistical_warnings({"laws": [law]})
    assert "piled against its prior bound 100" in w, w


# --------------------------------------------------------------------------------- truth
def test_truth_from_the_embedded_world():
    t = world_truth(json.loads((ROOT / "data/paper_like/truth.json").read_text()))
    assert t["world"] == "paper_like"
    assert t["values"]["eta"]["value"] == pytest.approx(1.05e6)  # the paper's shift eta
    assert t["values"]["eta_shift"]["value"] == pytest.approx(1.05e6)
    for name in ("young", "eta_q", "gamma", "sigma_shift", "offset_down"):
        assert name in t["none"] and len(t["none"][name]) > 20
    # sample sd of ln delta0 over 28 protocols, f0 uniform in 2.5-3 kHz: delta0 ~ f0^-2,
    # so sd(ln delta0) = 2 sd(ln f0) ~ 2 * 0.18 / (2 sqrt 3) / 2.75 ~ 0.1
    assert 0.05 < t["values"]["delta0_scatter"]["value"] < 0.15
    hd = world_truth(json.loads((ROOT / "data/hertz_dynamics/truth.json").read_text()))
    assert hd["values"]["n"]["value"] == 1.5 and "eta" in hd["none"] and "eta" not in hd["values"]


def test_truth_shown_or_explained_never_an_empty_column(tmp_path):
    md = render_report(_result(tmp_path), tmp_path)[0].read_text()
    df = _md_table_after(md, "## Parameters of the preferred law")
    row = df.set_index("parameter")
    assert row.loc["η (eta)", "truth"] == "1.05" and row.loc["η (eta)", "truth in 90 %"] == "yes"
    assert row.loc["η (eta)", "unit"] == "MPa s"
    assert row.loc["E (young)", "truth"] == "none"
    truth = _section(md, "## Truth of the synthetic world")
    assert "- E (young): f0_p is drawn, not computed from a modulus" in truth
    # a law none of whose parameters has a truth gets no truth column at all
    hertz = _md_table_after(md, "### Hertz")
    assert "truth" not in hertz.columns


def test_protocol_truth_coverage():
    import arviz as az

    from beadrod.workflows.report.truth import protocol_truth

    rng = np.random.default_rng(0)
    d0 = np.array([50e-9, 55e-9, 45e-9])
    truth = {"protocols": {p: {"delta0_m": d, "f0_reference_Hz": 2700.0, "q": 30.0}
                           for p, d in zip(("A", "B", "C"), d0)}}
    good = az.from_dict(posterior={"delta0": d0 * (1 + 0.01 * rng.normal(size=(2, 400, 3)))})
    off = az.from_dict(posterior={"delta0": 1.2 * d0 * (1 + 0.01 * rng.normal(size=(2, 400, 3)))})
    out = protocol_truth(truth, ("A", "B", "C"), np.full(3, 2701.0), np.array([33.0, np.nan, 30]),
                         {"good": good, "off": off})
    assert out["delta0"]["laws"]["good"]["covered"] == 3
    assert out["delta0"]["laws"]["off"]["covered"] == 0
    assert out["delta0"]["laws"]["off"]["median_rel_error_max"] == pytest.approx(0.2, abs=0.01)
    assert out["f0"]["measured_rel_error_max"] == pytest.approx(1 / 2700)
    assert out["q"]["measured_rel_error_max"] == pytest.approx(0.1)


# ------------------------------------------------------------------------------- tension
def test_tension_is_a_table_and_two_sentences(tmp_path):
    res = _result(tmp_path)
    t = res["tension"]
    headers, body, _ = tension_table(t, 1.05e6)
    assert headers == ["estimate", "median [MPa s]", "90 % interval [MPa s]", "truth [MPa s]"]
    rows = {r[0]: r for r in body}
    assert rows["η from Q alone"][1:3] == ["0.06", "[0.04, 0.09]"]  # one unit: no kPa s
    assert rows["η from the shift alone"][3] == "1.05" and rows["η from Q alone"][3] == "—"
    text = tension_sentences(t)
    assert len(_sentences(text)) == 2, text
    assert "+1.22 decades" in text and "+12.4 ± 0.6 nats" in text and "very strong" in text
    assert "< 0.001 for the shift" in text and "it cannot reproduce the shift)" in text
    assert "Bhattacharyya" not in text
    md = render_report(res, tmp_path)[0].read_text()
    sec = _section(md, "## Viscosity tension")
    assert "kPa" not in sec and "Bhattacharyya" not in sec and text in sec


def test_tension_on_a_rung_without_eta_in_the_shift():
    t = {"rung": "backbone", "eta_in_shift": False, "eta_shift_q05_q50_q95": None,
         "eta_q_q05_q50_q95": [4e4, 6e4, 9e4], "eta_joint_q05_q50_q95": [4e4, 6e4, 9e4],
         "eta_split_shift_q05_q50_q95": [2e2, 1e5, 4e7],
         "log10_gap_q05_q50_q95": None, "p_shift_gt_q": None,
         "log_bf_split_vs_shared": 0.1, "log_bf_err": 0.3,
         "ppc": {"shift_p": 0.3, "q_p": 0.4, "missed": "shift"}}
    headers, body, _ = tension_table(t, 1.05e6)
    assert "truth [kPa s]" not in headers  # the world's η is a truth of Eq. 25's shift only
    assert body[0] == ["η from the shift alone", "—", "η does not enter the shift on this rung"]
    assert headers[1] == "median [MPa s]" and body[1][1] == "0.06"  # one unit per column
    assert body[-1][0] == "η_shift (split model): its prior, unused on this rung"
    text = tension_sentences(t)
    assert "does not enter the shift" in text and "0 is expected here" in text
    assert "it reproduces both" in text
    assert len(_sentences(text)) == 2, text


# ---------------------------------------------------------------------- data, timings
def test_data_section_lists_exclusions_per_protocol(tmp_path):
    md = render_report(_result(tmp_path), tmp_path)[0].read_text()
    df = _md_table_after(md, "Excluded drive sweeps, per protocol")
    assert list(df["protocol"]) == ["P03", "P09"]
    assert list(df["lines in measurements.csv"]) == ["45-48", "200-207"]
    assert df["reason"].iloc[0].startswith("2 % rule")


def test_exclusions_of_the_embedded_data_match_its_truth():
    from beadrod.data import load_default
    from beadrod.workflows.pipeline.outputs import exclusions

    ex = exclusions(load_default().excluded)
    truth = json.loads((ROOT / "data/paper_like/truth.json").read_text())
    drive = truth["observables"]["drive"]
    expect: dict[str, int] = {}
    for p, e in zip(drive["protocol"], drive["excluded"]):
        if e:
            expect[p] = expect.get(p, 0) + 1
    assert {e["protocol"]: e["n"] for e in ex} == expect
    assert set(expect) <= set(truth["parameters"]["tripping_protocols"])
    assert all(len(e["lines"]) == e["n"] and "2 % rule" in e["reason"] for e in ex)


def test_timings_keep_workers_out_and_total_as_measured():
    (headers, rows, _), note = timings_table({"fit_a_s": 10.0, "fit_b_s": 20.0,
                                              "fits_wall_s": 21.0, "workers": 2,
                                              "figures_s": 3.0, "total_s": 25.0})
    stages = [r[0] for r in rows]
    assert headers == ["stage", "seconds"] and not any("workers" in s for s in stages)
    assert rows[-1] == ["**total (wall clock)**", "**25.0**"]  # total_s, not a sum (79)
    assert "2 worker process(es) side by side" in note


def test_configuration_shows_resolved_values(tmp_path):
    md = render_report(_result(tmp_path), tmp_path)[0].read_text()
    cfg = json.loads(_section(md, "## Configuration").split("```json\n")[1].split("```")[0])
    assert cfg["data"] == "/data/paper_like"
    assert cfg["laws"] == ["hertz", "viscoelastic", "jkr"]


# ----------------------------------------------------------------------- housekeeping
def test_no_literal_backticks_and_captions_once(tmp_path):
    res = _result(tmp_path)
    res["figures"][0]["caption"] = "Posterior of `eta` per source."
    md_path, html_path = render_report(res, tmp_path)
    page = re.sub(r"<pre>.*?</pre>", "", html_path.read_text(), flags=re.S)
    assert "`" not in page and "<code>eta</code>" in page
    md = md_path.read_text()
    for f in res["figures"]:
        assert md.count(f["caption"]) == 1, f["caption"]


def test_print_keeps_headings_and_captions_with_their_figures(tmp_path):
    text = render_report(_result(tmp_path), tmp_path)[1].read_text()
    assert "break-inside:avoid" in text and "break-after:avoid" in text
    parser = _Refs()
    parser.feed(text)
    assert parser.figures and all(f == ["img", "figcaption"] for f in parser.figures)
    # every heading right before a figure sits in one unbreakable block with it
    for m in re.finditer(r"<h3>[^<]*</h3>\s*<figure>", text):
        before = text[:m.start()]
        assert before.rstrip().endswith('<div class="keep">'), text[m.start() - 40:m.end()]


def test_minimal_result_and_missing_figure(tmp_path):
    md, page = render_report({"laws": [], "figures": [{"path": "figures/none.png",
                                                       "caption": "gone"}]}, tmp_path)
    assert "No preferred law" in md.read_text()
    html = page.read_text()
    assert "Figure missing: figures/none.png" in html
    parser = _Refs()
    parser.feed(html)
    assert parser.refs == []


def test_html_escapes_user_text(tmp_path):
    res = _result(tmp_path)
    res["laws"][2]["failures"] = ["<script>alert(1)</script> | pipe"]
    _, page = render_report(res, tmp_path)
    text = page.read_text()
    assert "<script>" not in text and "&lt;script&gt;" in text


def test_sparse_law_entries_render(tmp_path):
    res = {"laws": [{"name": "hertz", "log_z": -3.0, "log_z_err": 0.1},
                    {"name": "dmt", "status": "failed", "params": [{"name": "gamma",
                                                                    "mean": None}]}],
           "config": {"out": Path("/x")}, "data": {"synthetic": True}}
    md, _ = render_report(res, tmp_path)
    text = md.read_text()
    assert "**hertz**" in text and "### dmt — FAILED" in text and '"out": "/x"' in text
    df = pd.read_csv(io.StringIO(comparison_table(res)[1]))
    assert list(df["status"]) == ["ok", "failed"] and df["log_z"].isna().tolist() == [False,
                                                                                     True]


# ----------------------------------------------------------------------- docs/outputs.md
def test_outputs_doc_covers_every_column_and_key(tmp_path):
    doc = (ROOT / "docs" / "outputs.md").read_text()
    res = _result(tmp_path)
    res["laws"].append(_law("baseline", "law-free baseline", -470.0, 0.5, -480.0,
                            model="baseline"))
    _, csv_text = comparison_table(res)
    documented = set(re.findall(r"^\| `([\w.\[\]]+)` \|", doc, flags=re.M))
    for col in pd.read_csv(io.StringIO(csv_text)).columns:
        assert col in documented, f"comparison.csv column {col!r} not in docs/outputs.md"
    keys = ["title", "beadrod_version", "created", "data", "laws", "preferred",
            "preferred_reason", "tension", "checks", "truth_protocols", "figures", "timings",
            "config"]
    keys += [f"data.{k}" for k in ("source", "hash", "scene", "n_protocols", "protocol_ids",
                                   "n_drive", "n_excluded", "excluded", "two_percent_rule",
                                   "shift_reference", "young_range_Pa", "synthetic", "truth")]
    keys += [f"tension.{k}" for k in ("rung", "eta_in_shift", "eta_shift_q05_q50_q95",
                                      "eta_q_q05_q50_q95", "eta_joint_q05_q50_q95",
                                      "log10_gap_q05_q50_q95", "p_shift_gt_q",
                                      "log_bf_split_vs_shared", "log_bf_err", "ppc",
                                      "fits_ok", "q_scale", "log_bf_method", "paper")]
    for k in keys:
        assert k in documented, f"result.json key {k!r} not in docs/outputs.md"


def test_headline_when_no_law_passed_its_gate(tmp_path):
    res = {"laws": [_law("a", "A", -10.0, 0.1, -5.0, status="failed"),
                    _law("b", "B", -12.0, 0.1, -5.0, status="failed"),
                    _law("baseline", "law-free baseline", -1.0, 0.1, -1.0, status="failed",
                         model="baseline")]}
    blocks = headline(res)
    assert [k for k, _ in blocks] == ["warn", "warn", "warn"]
    assert blocks[0][1].startswith("No preferred law")
    assert blocks[1][1].startswith("Ignoring the gate (numbers not trustworthy), the "
                                   "law-free baseline beats every contact law")
    assert "9.00 ± 0.14 nats above the best law's (A)" in blocks[1][1]
    assert "best law: **A**" in blocks[2][1] and "Preferred" not in blocks[2][1]


def test_diagnostics_warnings_say_each_reason_once():
    from beadrod.workflows.report.tables import diagnostics_table

    law = _law("a", "A", -1.0, 0.1, -1.0, status="failed", failures=["R-hat max 1.03 >= 1.01"])
    law["diagnostics"]["rhat_max"] = 1.03
    _, body, _ = diagnostics_table([law, _law("b", "B", -1.0, 0.1, -1.0)])
    assert body[0][-1] == "R-hat max 1.03 >= 1.01" and body[1][-1] == "none"


def test_wide_log_uniform_interval_keeps_its_lower_end():
    law = _law("v", "V", -1.0, 0.1, -1.0, params=[_param("eta_shift", 4e6, 13e6, 225.0, 41.6e6)])
    _, body, _ = param_table(law, None)
    assert body[0][2:] == ["4 ± 13", "[0.000225, 41.6]"]  # not [0, 42]


def test_point_like_overlap_is_said_to_be_a_point(tmp_path):
    res = _result(tmp_path)
    res["truth_protocols"] = {"delta0": {"range": [41.7e-9, 59.6e-9], "n": 28, "laws": {
        "hertz": {"covered": 0, "n": 28, "median_rel_error_max": 0.0059,
                  "rel_width_median": 0.0},
        "viscoelastic": {"covered": 27, "n": 28, "median_rel_error_max": 0.02,
                         "rel_width_median": 0.05}}}}
    md = render_report(res, tmp_path)[0].read_text()
    df = _md_table_after(md, "Per protocol:")
    fits = df.set_index("quantity").loc["δ0_p", "fits"]
    assert "Hertz: median ≤ 0.59 % off (fixed by the measured f0_p: its posterior has no" in fits
    assert "Viscoelastic: median ≤ 2 % off, 27/28 inside the 90 % intervals" in fits


@pytest.mark.parametrize("tails, mean, words", [
    (0.31, 0.5, "too narrow"), (0.06, 0.5, "too wide"), (0.1, 0.56, "lie above"),
    (0.1, 0.5, "misses the data's shape")])
def test_loo_pit_shape_is_read_against_its_sampling_error(tails, mean, words):
    # n = 454: the tail share's sd under uniformity is sqrt(0.09 / 454) = 0.014, the
    # mean's sqrt(1 / (12 * 454)) = 0.0135
    pit = {"ks_d": 0.1, "ks_p": 1e-5, "tails": tails, "mean": mean, "calibrated": False,
           "n": 454}
    (w,) = statistical_warnings({"laws": [_law("h", "H", -1.0, 0.1, -1.0)],
                                 "checks": {"loo_pit": {"h": pit}}})
    assert words in w
