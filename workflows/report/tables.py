"""The comparison report's headline and tables, and the number formatting they share.

Each ``*_table`` builder turns part of the pipeline's result dictionary into
(headers, rows, failed-row flags), the ``table`` block that :mod:`workflows.report.document`
renders to both Markdown and HTML; :func:`comparison_table` also gives the comparison as
Markdown and CSV (columns: docs/outputs.md). Missing or non-finite numbers print as a
dash; failed runs are marked in bold capitals (``**FAILED**``), which the HTML renderer
colours.

Numbers with an error carry as many digits as the error needs (:func:`fmt_pm`, the
Particle Data Group's rule: the error to two significant digits if its three leading
digits are 100-354, else to one, and the value to the same decimal place). The ranking of
laws is :func:`inference.evidence.ranking.rank_evidence`'s: Delta log Z against the preferred law,
the law-free baseline's lead stated separately. log Z and elpd in nats.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from typing import Any

from beadrod.inference.evidence.ranking import rank_evidence
from beadrod.workflows.report.markdown import md_escape

__all__ = ["DASH", "FAILED", "to_float", "fmt_num", "fmt_pm", "pm_decimals", "is_failed",
           "is_baseline", "status_cell", "law_label", "markdown_table", "ranking",
           "evidence_words", "headline", "comparison_table", "comparison_block",
           "diagnostics_table", "timings_table", "exclusions_table", "resolved_config"]

DASH = "—"
FAILED = "FAILED"
Table = tuple[list[str], list[list[str]], list[bool]]


# ----------------------------------------------------------------------------- numbers
def to_float(v: Any) -> float:
    """``v`` as a float, NaN when it is missing or not a number."""
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def fmt_num(v: Any, fmt: str = ".3g") -> str:
    """``v`` formatted, or a dash when missing or not finite."""
    f = to_float(v)
    return DASH if not math.isfinite(f) else format(f, fmt)


def pm_decimals(err: float) -> int:
    """Decimal places that an error ``err`` > 0 needs (PDG rounding; negative: round to
    tens, hundreds, ...)."""
    exp = math.floor(math.log10(err))
    lead = int(round(err / 10.0 ** (exp - 2)))  # the three leading digits, 100..1000
    if lead >= 1000:
        lead, exp = 100, exp + 1
    if lead <= 354:
        digits = 2
    elif lead <= 949:
        digits = 1
    else:  # 950-999 rounds up to 1000: two digits of the next decade (1.0)
        digits, exp = 2, exp + 1
    return digits - 1 - exp


def _fixed(v: float, decimals: int) -> str:
    if decimals >= 0:
        return f"{v:.{decimals}f}"
    return f"{round(v, decimals):.0f}"


def fmt_pm(v: Any, err: Any, *, signed: bool = False) -> str:
    """``v ± err`` with the digits ``err`` needs; ``v`` alone (3 significant digits) when
    the error is missing; a dash when ``v`` is."""
    f, e = to_float(v), to_float(err)
    if not math.isfinite(f):
        return DASH
    if not math.isfinite(e) or e <= 0:
        return format(f, "+.3g" if signed else ".3g")
    d = pm_decimals(e)
    val = _fixed(f, d)
    if signed and f >= 0 and not val.startswith("-"):
        val = "+" + val
    return f"{val} ± {_fixed(e, d)}"


# -------------------------------------------------------------------------- law status
def is_failed(law: Mapping) -> bool:
    return str(law.get("status", "ok")).lower() != "ok"


def is_baseline(law: Mapping) -> bool:
    """The law-free baseline (its model name starts with 'baseline')."""
    return str(law.get("model") or law.get("name") or "").split("/")[0] == "baseline"


def status_cell(law: Mapping) -> str:
    return f"**{FAILED}**" if is_failed(law) else "ok"


def law_label(law: Mapping | None) -> str:
    if not law:
        return "?"
    return str(law.get("label") or law.get("name") or "?")


# --------------------------------------------------------------------------- markdown
def _md_cell(s: str) -> str:
    return md_escape(s).replace("|", r"\|").replace("\n", " ")


def markdown_table(headers: Sequence[str], body: Sequence[Sequence[str]]) -> str:
    """A GitHub-flavoured Markdown table (cells escaped by workflows.report.markdown.md_escape,
    pipes too)."""
    lines = ["| " + " | ".join(_md_cell(h) for h in headers) + " |",
             "|" + "|".join("---" for _ in headers) + "|"]
    lines += ["| " + " | ".join(_md_cell(c) for c in row) + " |" for row in body]
    return "\n".join(lines)


# ---------------------------------------------------------------------------- ranking
def ranking(laws: Sequence[Mapping]) -> dict[str, Any]:
    """inference.evidence.ranking.rank_evidence over the result's law summaries."""
    return rank_evidence([{"name": lw.get("name"), "log_z": lw.get("log_z"),
                           "log_z_err": lw.get("log_z_err"), "ok": not is_failed(lw),
                           "baseline": is_baseline(lw)} for lw in laws])


def evidence_words(d: float) -> str:
    """Kass & Raftery (1995) bands for a log Bayes factor ``d`` [nats] >= 0, in nats:
    < 1 not worth more than a bare mention, 1-3 positive, 3-5 strong, > 5 very strong."""
    return ("no evidence either way" if d < 1 else "positive evidence" if d < 3
            else "strong evidence" if d < 5 else "very strong evidence")


def _cap(text: str) -> str:
    return text[:1].upper() + text[1:]


def headline(result: Mapping) -> list[tuple[str, str]]:
    """The report's first statement as blocks ("p" or "warn", text): the law-free baseline
    first when it beats every law, then the preferred law, its evidence and its lead over
    the next law. When no law passed its gate, it says so and then what the ranking would
    be without the gate."""
    laws = list(result.get("laws") or [])
    by_name = {lw.get("name"): lw for lw in laws}
    r = ranking(laws)
    out: list[tuple[str, str]] = []
    prefix, kind, which = "", "p", "preferred"
    if r["best"] is None:
        out.append(("warn", "No preferred law: no contact law passed its sampling gate with "
                            "an evidence estimate."))
        r = ranking([{**lw, "status": "ok"} for lw in laws])  # said as such below
        if r["best"] is None:
            return out
        prefix, kind, which = "ignoring the gate (numbers not trustworthy), ", "warn", "best"
    best = by_name[r["best"]]
    lead = to_float(r["baseline_lead"])
    if math.isfinite(lead) and lead > 0:
        within = lead < 2 * to_float(r["baseline_lead_err"])
        out.append(("warn", _cap(f"{prefix}the {law_label(by_name[r['baseline']])} beats "
                                 f"every contact law: its log Z is "
                                 f"{fmt_pm(lead, r['baseline_lead_err'])} nats above the best "
                                 f"law's ({law_label(best)})"
                                 + (", within twice its error. " if within else ". ")
                                 + "No contact law captures the shape of the data.")))
    method = best.get("log_z_method")
    text = (f"{prefix}{which} law: **{law_label(best)}**, log Z = "
            f"{fmt_pm(best.get('log_z'), best.get('log_z_err'))} nats"
            + (f" ({method})" if method else ""))
    runner = by_name.get(r["runner_up"])
    if runner is not None:
        gap, gap_err = to_float(r["gap"]), to_float(r["gap_err"])
        text += (f", {fmt_pm(gap, gap_err)} nats above the next law, {law_label(runner)}: "
                 f"{evidence_words(gap)}")
        if math.isfinite(gap_err) and gap < 2 * gap_err:
            text += ", but within twice its error"
    out.append((kind, _cap(text) + "."))
    return out


# ------------------------------------------------------------------------ comparison
def _comparison_rows(result: Mapping) -> list[dict[str, Any]]:
    laws = list(result.get("laws", []))
    r = ranking(laws)
    ref = next((lw for lw in laws if lw.get("name") == r["reference"]), None)
    elpd_ref = to_float(ref.get("elpd_loo")) if ref else math.nan
    rows = []
    for lw in laws:
        dz, dz_err = r["delta"].get(lw.get("name"), (math.nan, math.nan))
        agree = lw.get("evidence_agree")
        rows.append({
            "law": lw.get("name", "?"), "label": law_label(lw),
            "status": "failed" if is_failed(lw) else "ok", "rung": lw.get("rung", ""),
            "baseline": is_baseline(lw), "preferred": lw.get("name") == r["best"],
            "log_z": to_float(lw.get("log_z")), "log_z_err": to_float(lw.get("log_z_err")),
            "log_z_method": lw.get("log_z_method") or "",
            "log_z2": to_float(lw.get("log_z2")), "log_z2_err": to_float(lw.get("log_z2_err")),
            "log_z2_method": lw.get("log_z2_method") or "",
            "delta_log_z": dz, "delta_log_z_err": dz_err,
            "elpd_loo": to_float(lw.get("elpd_loo")),
            "elpd_loo_se": to_float(lw.get("elpd_loo_se")),
            "delta_elpd_loo": to_float(lw.get("elpd_loo")) - elpd_ref,
            "pareto_k_bad": lw.get("pareto_k_bad", ""),
            "evidence_agree": "" if agree is None else bool(agree),
            "failures": "; ".join(map(str, lw.get("failures") or [])),
            "observables": ", ".join(map(str, lw.get("observables") or [])),
        })
    return rows


def _common(values: Sequence[str]) -> str | None:
    vals = {v for v in values if v}
    return vals.pop() if len(vals) == 1 else None


def comparison_block(result: Mapping, *, checks: bool = True) -> Table:
    """The evidence and LOO table, one row per law; without ``checks``, without the
    columns of Pareto k > 0.7 and of the estimators' agreement (the report gives them in
    its warnings table)."""
    rows = _comparison_rows(result)
    m1 = _common([r["log_z_method"] for r in rows])
    m2 = _common([r["log_z2_method"] for r in rows])
    has2 = any(math.isfinite(r["log_z2"]) for r in rows)
    headers = ["law", "status", "rung", f"log Z ± err ({m1 or 'method'})"]
    if has2:
        headers.append(f"log Z ± err ({m2 or 'second method'})")
    headers += ["Δ log Z vs preferred", "elpd_loo ± se", "Δ elpd_loo vs preferred"]
    if checks:
        headers += ["Pareto k > 0.7", "estimators agree"]
    body, failed = [], []
    for r in rows:
        z1 = fmt_pm(r["log_z"], r["log_z_err"])
        if not m1 and r["log_z_method"]:
            z1 += f" ({r['log_z_method']})"
        cells = [r["label"], f"**{FAILED}**" if r["status"] == "failed" else "ok",
                 r["rung"] if r["rung"] and not r["baseline"] else DASH, z1]
        if has2:
            z2 = fmt_pm(r["log_z2"], r["log_z2_err"])
            if not m2 and r["log_z2_method"] and z2 != DASH:
                z2 += f" ({r['log_z2_method']})"
            cells.append(z2)
        agree = r["evidence_agree"]
        is_ref = r["delta_log_z"] == 0.0 and r["delta_log_z_err"] == 0.0
        cells += ["0 (reference)" if is_ref else fmt_pm(r["delta_log_z"], r["delta_log_z_err"],
                                                        signed=True),
                  fmt_pm(r["elpd_loo"], r["elpd_loo_se"]),
                  "0 (reference)" if is_ref and math.isfinite(r["delta_elpd_loo"])
                  else fmt_num(r["delta_elpd_loo"], "+.1f")]
        if checks:
            cells += [str(r["pareto_k_bad"]) if r["pareto_k_bad"] != "" else DASH,
                      DASH if agree == "" else ("yes" if agree else "**NO**")]
        body.append(cells)
        failed.append(r["status"] == "failed")
    return headers, body, failed


def comparison_table(result: Mapping) -> tuple[str, str]:
    """The model-comparison table as (Markdown, CSV), one row per law.

    Delta log Z and Delta elpd_loo are against the preferred law (the best contact law
    that passed its gate), errors of Delta log Z in quadrature; the baseline's row is
    positive where it leads. The CSV carries raw numbers (empty where missing) and the
    failure reasons (columns: docs/outputs.md); the Markdown marks failed runs in bold.
    """
    headers, body, _ = comparison_block(result)
    md = markdown_table(headers, body)
    rows = _comparison_rows(result)
    buf = io.StringIO()
    fields = list(rows[0]) if rows else ["law", "status"]
    writer = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    for r in rows:
        writer.writerow({k: ("" if isinstance(v, float) and not math.isfinite(v) else v)
                         for k, v in r.items()})
    return md, buf.getvalue()


# ---------------------------------------------------------------------- diagnostics
def diagnostics_table(laws: Sequence[Mapping]) -> Table:
    """Sampler diagnostics per law against the gate's thresholds."""
    headers = ["law", "status", "R-hat max", "ESS bulk min", "ESS tail min", "divergences",
               "E-BFMI min", "warnings"]
    body = []
    for lw in laws:
        d = lw.get("diagnostics") or {}
        warn = [str(f) for f in lw.get("failures") or []]  # the gate's own reasons
        if not warn:  # advice below the gate's thresholds
            if to_float(d.get("rhat_max")) > 1.01:
                warn.append("R-hat > 1.01")
            if min(to_float(d.get("ess_bulk_min")), to_float(d.get("ess_tail_min"))) < 400:
                warn.append("ESS < 400")
            if to_float(d.get("divergences")) > 0:
                warn.append("divergences")
            if to_float(d.get("ebfmi_min")) < 0.3:
                warn.append("E-BFMI < 0.3")
        body.append([law_label(lw), status_cell(lw),
                     fmt_num(d.get("rhat_max"), ".3f"), fmt_num(d.get("ess_bulk_min"), ".0f"),
                     fmt_num(d.get("ess_tail_min"), ".0f"), fmt_num(d.get("divergences"), ".0f"),
                     fmt_num(d.get("ebfmi_min"), ".2f"), "; ".join(warn) or "none"])
    return headers, body, [is_failed(lw) for lw in laws]


# -------------------------------------------------------------------- housekeeping
def resolved_config(result: Mapping[str, Any]) -> dict[str, Any]:
    """The run's configuration with the defaults it resolved filled in: ``data`` (None:
    the embedded world) becomes the folder read, ``laws`` (None: all) the laws fitted."""
    cfg = dict(result.get("config") or {})
    if cfg.get("data") is None and (result.get("data") or {}).get("source"):
        cfg["data"] = result["data"]["source"]
    if cfg.get("laws") is None and result.get("laws"):
        cfg["laws"] = [lw.get("name") for lw in result["laws"]]
    return cfg


_STAGES = {"fits_wall_s": "all fits (wall clock)", "tension_s": "tension analysis",
           "figures_s": "figures", "total_s": "total (wall clock)"}


def timings_table(timings: Mapping[str, Any]) -> tuple[Table, str]:
    """(table of seconds, sentence): each fit's own time, then the wall-clock stages and
    the run's total as measured (fits run side by side overlap, so they are not summed).
    Entries that are not durations (``workers``) go into the sentence."""
    fits = [(k, v) for k, v in timings.items() if k.startswith("fit_") and k.endswith("_s")]
    stages = [(k, v) for k, v in timings.items() if k in _STAGES and k != "total_s"]
    other = [(k, v) for k, v in timings.items() if k.endswith("_s") and k not in _STAGES
             and (k, v) not in fits]
    rows = [[f"fit: {k.removeprefix('fit_').removesuffix('_s')}", fmt_num(v, ".1f")]
            for k, v in fits]
    rows += [[_STAGES[k], fmt_num(v, ".1f")] for k, v in stages]
    rows += [[k.removesuffix("_s"), fmt_num(v, ".1f")] for k, v in other]
    if "total_s" in timings:
        rows.append([f"**{_STAGES['total_s']}**", f"**{fmt_num(timings['total_s'], '.1f')}**"])
    workers = timings.get("workers")
    note = "Seconds of wall-clock time."
    if workers is not None:
        note += (f" The fits ran in {fmt_num(workers, '.0f')} worker process(es)"
                 + (" side by side, so their times overlap and do not add up to the total."
                    if to_float(workers) > 1 else ", one after another."))
    return (["stage", "seconds"], rows, [False] * len(rows)), note


def exclusions_table(excluded: Sequence[Mapping]) -> Table:
    """Excluded drive sweeps per protocol (compare_outputs.exclusions; as ``beadrod
    validate`` prints them)."""
    body = []
    for e in excluded:
        lines = e.get("lines") or []
        body.append([str(e.get("protocol", "?")), fmt_num(e.get("n"), ".0f"),
                     _ranges(lines) if lines else DASH, str(e.get("reason", ""))])
    return (["protocol", "drive sweeps dropped", "lines in measurements.csv", "reason"], body,
            [False] * len(body))


def _ranges(values: Sequence[int]) -> str:
    """1, 2, 3, 7, 8 -> '1-3, 7-8'."""
    vals = sorted(int(v) for v in values)
    parts, start, prev = [], vals[0], vals[0]
    for v in vals[1:] + [None]:
        if v is not None and v == prev + 1:
            prev = v
            continue
        parts.append(f"{start}" if start == prev else f"{start}-{prev}")
        if v is not None:
            start = prev = v
    return ", ".join(parts)
