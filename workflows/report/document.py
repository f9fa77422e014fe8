"""The comparison report: ``report.md`` and a self-contained ``report.html``.

Both are rendered from one list of blocks (headings, paragraphs, lists, tables, figures)
built from the pipeline's result dictionary, so the two files always say the same thing.
The HTML embeds every figure as a base64 ``data:`` URI and references no other file: it
can be mailed or archived on its own, and printed to PDF without a heading or caption
torn from its figure. Failed runs are marked in every table and in a banner at the top.
Optional keys of the result may be missing; the report then says less.

Order: the headline (the preferred law, or the baseline first when it beats every law),
the evidence table, one warnings table (a row per law, a column per check a statistician
would raise, each explained once below it), the preferred law's parameters, the truth of
a synthetic world, the η tension, the loss against the shift and the law each observable
prefers, every law's parameters and priors, the data, the
sampler diagnostics, the figures, a glossary, timings and the configuration. Tables:
:mod:`workflows.report.tables`, :mod:`workflows.report.checks`,
:mod:`workflows.report.params`, :mod:`workflows.report.tension`; renderers:
:mod:`workflows.report.render`. log Z and elpd in nats.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

from beadrod.data.io import write_text
from beadrod.workflows.report.checks import (
    statistical_warnings,
    warnings_notes,
    warnings_table,
)
from beadrod.workflows.report.loss_shift import loss_shift_blocks
from beadrod.workflows.report.params import (
    GLOSSARY,
    glossary_table,
    param_table,
    priors_table,
    truth_tables,
)
from beadrod.workflows.report.render import Block, blocks_to_html, blocks_to_markdown
from beadrod.workflows.report.tables import (
    DASH,
    FAILED,
    comparison_block,
    comparison_table,
    diagnostics_table,
    exclusions_table,
    fmt_num,
    headline,
    is_failed,
    law_label,
    markdown_table,
    ranking,
    resolved_config,
    timings_table,
    to_float,
)
from beadrod.workflows.report.tension import tension_sentences, tension_table

__all__ = ["render_report", "comparison_table", "markdown_table", "report_blocks",
           "statistical_warnings", "blocks_to_markdown", "blocks_to_html"]


def _no_warnings(result: Mapping) -> str:
    """What was checked and found fine (only what was checked)."""
    done = ["no posterior against a prior bound or outside the scene's range",
            "every Pareto k ≤ 0.7"]
    pits = (result.get("checks") or {}).get("loo_pit")
    done.append("LOO-PIT uniform for every law" if pits else "LOO-PIT not computed")
    return "None: " + "; ".join(done) + "."


# ----------------------------------------------------------------------------- blocks
def _data_blocks(data: Mapping) -> list[Block]:
    b: list[Block] = [("h", 2, "Data")]
    rule = data.get("two_percent_rule")
    rows = [
        ["source", str(data.get("source", DASH))], ["scene", str(data.get("scene") or DASH)],
        ["hash", str(data.get("hash", DASH))],
        ["protocols", fmt_num(data.get("n_protocols"), ".0f")],
        ["protocols without a reference Q (not in the likelihood)",
         fmt_num(data.get("n_q_missing"), ".0f")],
        ["drive sweeps used", fmt_num(data.get("n_drive"), ".0f")],
        ["drive sweeps excluded", fmt_num(data.get("n_excluded"), ".0f")],
        ["2 % rule", DASH if rule is None else ("on" if rule else "off")],
        ["shift relative to", f"the {data['shift_reference']} reference"
         if data.get("shift_reference") else DASH],
        ["synthetic (ground truth known)", "yes" if data.get("synthetic") else "no"]]
    b.append(("table", ["item", "value"], rows, [False] * len(rows)))
    excluded = data.get("excluded") or []
    if excluded:
        b.append(("p", "Excluded drive sweeps, per protocol. The 2 % rule: once a reference "
                       "sweep's linear resonance has drifted by more than 2 % from the "
                       "protocol's first, the contact has changed and the later drive sweeps "
                       "of that protocol are dropped."))
        b.append(("table", *exclusions_table(excluded)))
    elif data.get("n_excluded"):
        b.append(("p", f"{data['n_excluded']} drive sweeps were excluded (no detail recorded)."))
    else:
        b.append(("p", "No drive sweep was excluded."))
    return b


def _truth_blocks(result: Mapping, laws: Sequence[Mapping]) -> list[Block]:
    data = result.get("data") or {}
    truth = data.get("truth")
    if not data.get("synthetic") or not isinstance(truth, Mapping):
        return []
    b: list[Block] = [("h", 2, "Truth of the synthetic world"),
                      ("p", f"World `{truth.get('world', '?')}` ({truth.get('kind') or '?'}, "
                            f"seed {truth.get('seed', '?')}): the values it was generated "
                            "with, where it defines one for a fitted parameter.")]
    table, none = truth_tables(truth, laws)
    if table[1]:
        b.append(("table", *table))
    if none:
        b.append(("p", "No truth in this world for:"))
        b.append(("ul", none))
    per = result.get("truth_protocols") or {}
    by_name = {lw.get("name"): lw for lw in laws}
    rows = []
    for key, label, unit, scale in (("delta0", "δ0_p", "nm", 1e9), ("f0", "f0_p", "Hz", 1.0),
                                    ("q", "Q_p", "–", 1.0)):
        e = per.get(key)
        if not e:
            continue
        lo, hi = (to_float(v) * scale for v in e.get("range", (math.nan, math.nan)))
        meas = e.get("measured_rel_error_max")
        fits = "; ".join(_coverage(law_label(by_name.get(n, {"name": n})), c)
                         for n, c in (e.get("laws") or {}).items())
        rows.append([label, unit, f"{lo:.4g}-{hi:.4g}",
                     DASH if meas is None else f"≤ {_pct(meas)} off", fits or DASH])
    if rows:
        b.append(("p", "Per protocol: the truth's range over the protocols, how far the "
                       "measured values lie from it (the models condition on the measured "
                       "f0), and how many protocols' 90 % posterior intervals hold it."))
        b.append(("table", ["quantity", "unit", "truth (range)", "measured", "fits"], rows,
                  [False] * len(rows)))
    return b


def _pct(frac: object) -> str:
    """A relative error as a percentage with two significant digits (no exponent)."""
    v = 100 * to_float(frac)
    return DASH if not math.isfinite(v) else (f"{v:.0f} %" if v >= 10 else f"{v:.2g} %")


def _coverage(label: str, c: Mapping) -> str:
    text = f"{label}: median ≤ {_pct(c.get('median_rel_error_max'))} off"
    width = to_float(c.get("rel_width_median"))
    if math.isfinite(width) and width < 1e-3:
        # a deterministic function of the data: nothing to cover
        return text + " (fixed by the measured f0_p: its posterior has no width)"
    return text + f", {c.get('covered')}/{c.get('n')} inside the 90 % intervals"


def _tension_blocks(result: Mapping) -> list[Block]:
    main = result.get("tension")
    if not main:
        return []
    truth = (result.get("data") or {}).get("truth") or {}
    eta_truth = ((truth.get("values") or {}).get("eta_shift") or {}).get("value") \
        if isinstance(truth, Mapping) else None
    b: list[Block] = [("h", 2, "Viscosity tension: shift versus Q"),
                      ("p", "Does one viscosity η explain both the amplitude-dependent shift "
                            "and the linear Q? η from each observable alone, from both with "
                            "one η, and from both with a separate η for each (the split model).")]
    for t in (main, main.get("paper")):
        if not t:
            continue
        b.append(("h", 3, f"Forward model (rung) `{t.get('rung', '?')}`"))
        bad = [k for k, ok in (t.get("fits_ok") or {}).items() if not ok]
        if bad:
            b.append(("warn", f"{FAILED}: the {', '.join(bad)} fit(s) of this block failed "
                              "their diagnostics; read its numbers with care."))
        b.append(("table", *tension_table(t, eta_truth)))
        b.append(("p", tension_sentences(t)))
    return b


def _warning_blocks(result: Mapping) -> list[Block]:
    """One table, a row per law and a column per check, what each check means once below
    it, then the warnings that belong to no law (the data's)."""
    b: list[Block] = [("h", 2, "Warnings")]
    if result.get("laws"):
        b.append(("table", *warnings_table(result)))
        b.append(("notes", warnings_notes(result)))
    if not statistical_warnings(result):
        b.append(("p", _no_warnings(result)))
    for warning in (result.get("data") or {}).get("warnings") or []:
        b.append(("p", f"Data warning: {warning}."))  # data.process: what a fit must say
    return b


def report_blocks(result: Mapping) -> list[Block]:
    """The report as a list of blocks, shared by the Markdown and HTML renderers."""
    b: list[Block] = [("h", 1, result.get("title") or "beadrod model comparison")]
    b.append(("p", f"beadrod {result.get('beadrod_version', '?')} · "
                   f"created {result.get('created', '?')}"))
    b += list(headline(result))
    laws = list(result.get("laws") or [])
    failed = [lw for lw in laws if is_failed(lw)]
    if failed:
        b.append(("warn", f"{FAILED}: {len(failed)} of {len(laws)} fits failed their sampling "
                          f"gate ({', '.join(law_label(lw) for lw in failed)}), and their "
                          "numbers below are not trustworthy (the Warnings table says why)."))

    b.append(("h", 2, "Evidence and LOO"))
    b.append(("table", *comparison_block(result, checks=False)))
    b.append(("note", "log Z: log evidence in nats ± the estimator's own error. Δ log Z: "
                      "against the preferred law (errors in quadrature); the baseline's row "
                      "is positive where it beats it. elpd_loo: expected log predictive "
                      "density of the drive sweeps by Pareto-smoothed leave-one-out ± its "
                      "standard error (its reliability, Pareto k, and the agreement of the "
                      "evidence estimators: the Warnings table)."))
    b += _warning_blocks(result)

    truth = (result.get("data") or {}).get("truth")
    truth = truth if isinstance(truth, Mapping) else None
    pref = next((lw for lw in laws if lw.get("name") == ranking(laws)["best"]), None)
    if pref is not None and pref.get("params"):
        b.append(("h", 2, f"Parameters of the preferred law: {law_label(pref)}"))
        b.append(("table", *param_table(pref, truth)))
    b += _truth_blocks(result, laws)
    b += _tension_blocks(result)
    b += loss_shift_blocks(result)

    b.append(("h", 2, "Parameters of every law"))
    gl = glossary_table(laws)
    if gl[1]:
        b.append(("p", "What each parameter is, and the unit the tables print it in:"))
        b.append(("table", *gl))
    for lw in laws:
        title = law_label(lw) + (f" — {FAILED}" if is_failed(lw) else "")
        b.append(("h", 3, title))
        if is_failed(lw):
            b.append(("warn", f"{FAILED} run: " + ("; ".join(map(str, lw.get("failures")
                                                                    or [])) or "no reason")))
        b.append(("table", *param_table(lw, truth)) if lw.get("params")
                 else ("p", "No parameter summary."))
    pr = priors_table(laws)
    if pr[1]:
        b.append(("h", 2, "Priors"))
        b.append(("p", "The evidence integrates the likelihood over these priors, so they are "
                       "part of every log Z above."))
        b.append(("table", *pr))

    b += _data_blocks(result.get("data") or {})
    b.append(("h", 2, "Sampler diagnostics"))
    b.append(("table", *diagnostics_table(laws)))

    figures = list(result.get("figures") or [])
    if figures:
        b.append(("h", 2, "Figures"))
        sections: dict[str, list[Mapping]] = {}
        for f in figures:
            sections.setdefault(str(f.get("section") or "Other"), []).append(f)
        for name, figs in sections.items():
            b.append(("h", 3, name[:1].upper() + name[1:]))
            b += [("fig", str(f["path"]), str(f.get("caption", ""))) for f in figs]

    b.append(("h", 2, "Glossary"))
    b.append(("ul", [f"**{k}**: {v}" for k, v in GLOSSARY.items()]))
    timings = result.get("timings") or {}
    if timings:
        table, note = timings_table(timings)
        b += [("h", 2, "Timings"), ("table", *table), ("p", note)]
    if result.get("config") is not None:
        b.append(("h", 2, "Configuration"))
        b.append(("p", "As resolved for this run (defaults filled in); config.resolved.toml "
                       "holds the same."))
        b.append(("code", json.dumps(resolved_config(result), indent=2, sort_keys=True,
                                     default=str)))
    return b


def render_report(result: Mapping, out_dir: str | Path) -> tuple[Path, Path]:
    """Write ``report.md`` and self-contained ``report.html`` into ``out_dir`` (atomically).

    Figure paths in ``result["figures"]`` are relative to ``out_dir``.
    """
    out_dir = Path(out_dir)
    blocks = report_blocks(result)
    md = write_text(out_dir / "report.md", blocks_to_markdown(blocks))
    page = write_text(out_dir / "report.html", blocks_to_html(blocks, out_dir))
    return md, page
