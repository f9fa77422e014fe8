"""Report rendering: self-contained HTML, failed runs marked, tables that parse back."""

from __future__ import annotations

import io
import math
from html.parser import HTMLParser

import numpy as np
import pandas as pd
import pytest

from workflows import plots
from workflows.report import comparison_table, render_report, tension_paragraph


def _law(name, label, log_z, err, elpd, *, status="ok", failures=(), params=None, z2=None):
    return {
        "name": name, "label": label, "rung": "first_order", "status": status,
        "failures": list(failures),
        "diagnostics": {"rhat_max": 1.002, "ess_bulk_min": 850.0, "ess_tail_min": 700.0,
                        "divergences": 0, "ebfmi_min": 0.9},
        "params": params or [],
        "log_z": log_z, "log_z_err": err, "log_z_method": "nested",
        "log_z2": z2, "log_z2_err": None if z2 is None else 0.5,
        "log_z2_method": None if z2 is None else "harmonic", "evidence_agree": None if z2 is None else True,
        "elpd_loo": elpd, "elpd_loo_se": 3.0, "pareto_k_bad": 0,
    }


def _result(tmp_path, *, paragraph=None):
    figs = []
    for name in ("eta_tension", "evidence"):
        fig = plots.fig_q_vs_f0(np.array([2600.0, 2700.0]), np.array([30.0, 60.0]))
        plots.save_figure(fig, tmp_path / "figures" / name)
        figs.append({"path": f"figures/{name}.png", "caption": f"Caption {name}",
                     "section": "Tension" if name == "eta_tension" else "Comparison"})
    visco_params = [
        {"name": "eta", "unit": "Pa s", "mean": 1.0e6, "sd": 0.1e6, "q05": 0.85e6,
         "q95": 1.2e6, "truth": 1.05e6},
        {"name": "young", "unit": "Pa", "mean": 2.0e11, "sd": 5e9, "q05": 1.92e11,
         "q95": 2.08e11, "truth": 2.5e11},  # truth outside: must say "no"
    ]
    return {
        "title": "Test comparison", "beadrod_version": "0.1.0",
        "created": "2026-11-23T08:00:00+00:00",
        "data": {"source": "embedded paper_like", "hash": "abc123", "n_protocols": 28,
                 "n_drive": 300, "n_excluded": 12, "synthetic": True,
                 "truth": {"eta": 1.05e6}},
        "laws": [
            _law("hertz", "Hertz", -512.3, 0.3, -520.0, z2=-512.9,
                 params=[{"name": "young", "unit": "Pa", "mean": 2e11, "sd": 1e10,
                          "q05": 1.8e11, "q95": 2.2e11, "truth": None}]),
            _law("viscoelastic", "Viscoelastic", -480.1, 0.4, -490.0, z2=-480.5,
                 params=visco_params),
            _law("jkr", "JKR", float("nan"), float("nan"), float("nan"), status="failed",
                 failures=["R-hat 1.31 > 1.01", "1203 divergences"]),
        ],
        "preferred": "viscoelastic",
        "preferred_reason": "highest evidence by 32 nats, well beyond the errors",
        "tension": {
            "eta_shift_q05_q50_q95": [0.85e6, 1.0e6, 1.2e6],
            "eta_q_q05_q50_q95": [4.0e4, 6.0e4, 9.0e4],
            "eta_joint_q05_q50_q95": [1.0e5, 1.2e5, 1.4e5],
            "overlap": 0.0, "p_shift_gt_q": 1.0, "log_bf_split_vs_shared": 12.4,
            "log_bf_err": 0.6,
            "ppc": {"shift_p": 0.001, "q_p": 0.4, "missed": "the shift at δa/δ0 > 0.5",
                    "by_how_much": "a factor of 3"},
            "paragraph": paragraph,
        },
        "figures": figs,
        "timings": {"compile": 12.0, "sample": 30.5},
        "config": {"chains": 2, "draws": 500},
    }


class _Refs(HTMLParser):
    def __init__(self):
        super().__init__()
        self.refs: list[tuple[str, str, str]] = []
        self.tables: list[list[list[str]]] = []
        self._row: list[str] | None = None
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        for k, v in attrs:
            if k in ("src", "href", "data", "poster", "srcset", "action"):
                self.refs.append((tag, k, v or ""))
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
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
        columns=str.strip)


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
    # The embedded bytes are the PNG written to disk.
    import base64

    png = base64.b64decode(imgs[0].split(",", 1)[1])
    assert png == (tmp_path / "figures" / "eta_tension.png").read_bytes()
    # The Markdown links the figures by relative path instead.
    assert "](figures/eta_tension.png)" in md_path.read_text()


def test_failed_law_is_marked_in_every_table(tmp_path):
    md_path, html_path = render_report(_result(tmp_path), tmp_path)
    md = md_path.read_text()
    assert "⚠ FAILED: JKR" in md and "R-hat 1.31 > 1.01" in md
    for heading in ("## Evidence and LOO", "## Sampler diagnostics"):
        df = _md_table_after(md, heading)
        jkr = df[df["law"].str.strip() == "JKR"]
        assert len(jkr) == 1
        assert "FAILED" in jkr["status"].iloc[0]
        ok = df[df["law"].str.strip() != "JKR"]
        assert not ok["status"].str.contains("FAILED").any()
    assert "### JKR — FAILED" in md
    parser = _Refs()
    parser.feed(html_path.read_text())
    assert html_path.read_text().count('<tr class="failed">') == 2
    comp = next(t for t in parser.tables if any("Δ log Z vs best" in c for c in t[0]))
    assert [r[1] for r in comp[1:]] == ["ok", "ok", "FAILED"]


def test_preferred_law_parameters_and_truth(tmp_path):
    md, _ = render_report(_result(tmp_path), tmp_path)
    text = md.read_text()
    pref = text[text.index("## Preferred law"):text.index("## Evidence")]
    assert "**Viscoelastic**: highest evidence by 32 nats" in pref
    df = _md_table_after(text, "## Preferred law")
    assert list(df["parameter"].str.strip()) == ["eta", "young"]
    assert df["90 % interval"].str.strip().iloc[0] == "[8.5e+05, 1.2e+06]"
    assert list(df["truth in 90 %"].str.strip()) == ["yes", "**no**"]


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
    assert mdf["Δ log Z vs best"].str.strip().iloc[1] == "0.00 ± 0.00"


def test_best_law_ignores_failed_runs():
    res = {"laws": [_law("a", "A", -10.0, 0.1, -5.0),
                    _law("b", "B", -1.0, 0.1, -1.0, status="failed")]}
    df = pd.read_csv(io.StringIO(comparison_table(res)[1])).set_index("law")
    assert df.loc["a", "delta_log_z"] == 0.0
    assert df.loc["b", "delta_log_z"] == pytest.approx(9.0)


def test_tension_paragraph_composed_from_numbers(tmp_path):
    res = _result(tmp_path)
    text = tension_paragraph(res["tension"])
    assert "η = 1 MPa s (90 % interval 0.85 MPa s to 1.2 MPa s)" in text
    assert "η = 60 kPa s" in text
    assert "disjoint" in text
    assert "12.40 ± 0.60 nats: very strong evidence for separate viscosities" in text
    assert "misses the shift at δa/δ0 > 0.5 by a factor of 3" in text
    md, _ = render_report(res, tmp_path)
    assert text in md.read_text()
    # A given paragraph is used verbatim.
    md, _ = render_report(_result(tmp_path, paragraph="Given paragraph."), tmp_path)
    assert "Given paragraph." in md.read_text() and text not in md.read_text()


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
    from pathlib import Path as P

    res = {"laws": [{"name": "hertz"}, {"name": "dmt", "status": "failed", "params": [
        {"name": "gamma", "mean": None}]}], "preferred": "hertz",
        "config": {"out": P("/x")}, "data": {"synthetic": True}}
    md, _ = render_report(res, tmp_path)
    text = md.read_text()
    assert "**hertz**" in text and "### dmt — FAILED" in text and '"out": "/x"' in text
    df = pd.read_csv(io.StringIO(comparison_table(res)[1]))
    assert list(df["status"]) == ["ok", "failed"] and df["log_z"].isna().all()
