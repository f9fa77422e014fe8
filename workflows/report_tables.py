"""The tables of the comparison report, and the number formatting they share.

Each ``_*_block``/``_*_table`` builder turns part of the pipeline's result dictionary into
(headers, rows, failed-row flags), the ``table`` block that :mod:`workflows.report`
renders to both Markdown and HTML; :func:`comparison_table` also gives the comparison as
Markdown and CSV, and :func:`tension_paragraph` states in words what the tension table
shows. Missing or non-finite numbers print as a dash; failed runs are marked in bold
capitals (``**FAILED**``), which the HTML renderer colours.

A module of its own so that :mod:`workflows.report` holds only the report's layout and
renderers. Units: η values in ``tension.eta_*_q05_q50_q95`` are in Pa s; log Z and elpd
in nats.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from typing import Any

__all__ = ["comparison_table", "markdown_table", "tension_paragraph"]

_DASH = "—"
_FAILED = "FAILED"


# ----------------------------------------------------------------------------- numbers
def _float(v: Any) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def _num(v: Any, fmt: str = ".4g") -> str:
    f = _float(v)
    return _DASH if not math.isfinite(f) else format(f, fmt)


def _pm(v: Any, err: Any, fmt: str = ".2f") -> str:
    if not math.isfinite(_float(v)):
        return _DASH
    return f"{_num(v, fmt)} ± {_num(err, fmt)}" if math.isfinite(_float(err)) else _num(v, fmt)


def _eta(v: Any) -> str:
    """η [Pa s] in the unit that keeps three significant figures readable."""
    f = _float(v)
    if not math.isfinite(f):
        return _DASH
    for scale, unit in ((1e6, "MPa s"), (1e3, "kPa s")):
        if abs(f) >= 0.1 * scale:
            return f"{f / scale:.3g} {unit}"
    return f"{f:.3g} Pa s"


def _is_failed(law: Mapping) -> bool:
    return str(law.get("status", "ok")).lower() != "ok"


def _status(law: Mapping) -> str:
    return f"**{_FAILED}**" if _is_failed(law) else "ok"


# --------------------------------------------------------------------------- markdown
def _md_cell(s: str) -> str:
    return str(s).replace("|", r"\|").replace("\n", " ")


def _md_table(headers: Sequence[str], body: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(_md_cell(h) for h in headers) + " |",
             "|" + "|".join("---" for _ in headers) + "|"]
    lines += ["| " + " | ".join(_md_cell(c) for c in row) + " |" for row in body]
    return "\n".join(lines)


markdown_table = _md_table  # public: benchmarks format their tables the same way


# ------------------------------------------------------------------------ comparison
def _best_log_z(laws: Sequence[Mapping]) -> Mapping | None:
    """The law with the highest log Z among successful runs (all runs if none succeeded)."""
    for pool in ([lw for lw in laws if not _is_failed(lw)], list(laws)):
        finite = [lw for lw in pool if math.isfinite(_float(lw.get("log_z")))]
        if finite:
            return max(finite, key=lambda lw: _float(lw.get("log_z")))
    return None


def _comparison_rows(result: Mapping) -> list[dict[str, Any]]:
    laws = list(result.get("laws", []))
    best = _best_log_z(laws)
    z_best = _float(best.get("log_z")) if best else math.nan
    e_best = _float(best.get("log_z_err")) if best else math.nan
    elpd_best = max((_float(lw.get("elpd_loo")) for lw in laws if not _is_failed(lw)
                     and math.isfinite(_float(lw.get("elpd_loo")))), default=math.nan)
    rows = []
    for lw in laws:
        z = _float(lw.get("log_z"))
        e = _float(lw.get("log_z_err"))
        is_best = best is not None and lw is best
        dz = z - z_best
        # The two runs are independent, so their errors add in quadrature.
        dz_err = 0.0 if is_best else math.hypot(e, e_best) if math.isfinite(e_best) else e
        agree = lw.get("evidence_agree")
        rows.append({
            "law": lw.get("name", "?"), "label": lw.get("label", lw.get("name", "?")),
            "status": "failed" if _is_failed(lw) else "ok", "rung": lw.get("rung", ""),
            "log_z": z, "log_z_err": e, "log_z_method": lw.get("log_z_method") or "",
            "log_z2": _float(lw.get("log_z2")), "log_z2_err": _float(lw.get("log_z2_err")),
            "log_z2_method": lw.get("log_z2_method") or "",
            "delta_log_z": dz, "delta_log_z_err": dz_err,
            "elpd_loo": _float(lw.get("elpd_loo")), "elpd_loo_se": _float(lw.get("elpd_loo_se")),
            "delta_elpd_loo": _float(lw.get("elpd_loo")) - elpd_best,
            "pareto_k_bad": lw.get("pareto_k_bad", ""),
            "evidence_agree": "" if agree is None else bool(agree),
            "failures": "; ".join(map(str, lw.get("failures") or [])),
        })
    return rows


def _common(values: Sequence[str]) -> str | None:
    vals = {v for v in values if v}
    return vals.pop() if len(vals) == 1 else None


def _comparison_block(result: Mapping) -> tuple[list[str], list[list[str]], list[bool]]:
    rows = _comparison_rows(result)
    m1 = _common([r["log_z_method"] for r in rows])
    m2 = _common([r["log_z2_method"] for r in rows])
    has2 = any(math.isfinite(r["log_z2"]) for r in rows)
    headers = ["law", "status", "rung", f"log Z ± err ({m1 or 'method'})"]
    if has2:
        headers.append(f"log Z ± err ({m2 or 'second method'})")
    headers += ["Δ log Z vs best", "elpd_loo ± se", "Δ elpd_loo", "Pareto k > 0.7",
                "estimators agree"]
    body, failed = [], []
    for r in rows:
        z1 = _pm(r["log_z"], r["log_z_err"])
        if not m1 and r["log_z_method"]:
            z1 += f" ({r['log_z_method']})"
        cells = [r["label"], f"**{_FAILED}**" if r["status"] == "failed" else "ok",
                 r["rung"] or _DASH, z1]
        if has2:
            z2 = _pm(r["log_z2"], r["log_z2_err"])
            if not m2 and r["log_z2_method"] and z2 != _DASH:
                z2 += f" ({r['log_z2_method']})"
            cells.append(z2)
        agree = r["evidence_agree"]
        cells += [_pm(r["delta_log_z"], r["delta_log_z_err"]),
                  _pm(r["elpd_loo"], r["elpd_loo_se"]), _num(r["delta_elpd_loo"], ".2f"),
                  str(r["pareto_k_bad"]) if r["pareto_k_bad"] != "" else _DASH,
                  _DASH if agree == "" else ("yes" if agree else "**NO**")]
        body.append(cells)
        failed.append(r["status"] == "failed")
    return headers, body, failed


def comparison_table(result: Mapping) -> tuple[str, str]:
    """The model-comparison table as (Markdown, CSV), one row per law.

    Δ log Z is against the best successful law (errors in quadrature); Δ elpd_loo against
    the best successful elpd. The CSV carries raw numbers (empty where missing) and the
    failure reasons; the Markdown marks failed runs in bold capitals.
    """
    headers, body, _ = _comparison_block(result)
    md = _md_table(headers, body)
    rows = _comparison_rows(result)
    buf = io.StringIO()
    fields = list(rows[0]) if rows else ["law", "status"]
    writer = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    for r in rows:
        writer.writerow({k: ("" if isinstance(v, float) and not math.isfinite(v) else v)
                         for k, v in r.items()})
    return md, buf.getvalue()


# ---------------------------------------------------------------------------- tension
def _triple(t: Mapping, key: str) -> list[float] | None:
    v = t.get(key)
    if v is None or len(v) != 3:
        return None
    return [_float(x) for x in v]


def _bf_words(bf: float) -> str:
    # Kass & Raftery (1995) bands, converted to natural-log units.
    a = abs(bf)
    strength = ("not worth more than a bare mention" if a < 1 else "positive" if a < 3
                else "strong" if a < 5 else "very strong")
    side = "separate viscosities (tension)" if bf > 0 else "one shared viscosity"
    return f"{strength} evidence for {side}"


def tension_paragraph(tension: Mapping) -> str:
    """One paragraph stating the η tension from the numbers (used when none is given)."""
    s: list[str] = []
    sh, q, jt = (_triple(tension, f"eta_{k}_q05_q50_q95") for k in ("shift", "q", "joint"))
    if sh:
        s.append(f"The frequency shift alone needs η = {_eta(sh[1])} "
                 f"(90 % interval {_eta(sh[0])} to {_eta(sh[2])}).")
    if q:
        s.append(f"The linear Q factors alone give η = {_eta(q[1])} "
                 f"({_eta(q[0])} to {_eta(q[2])}).")
    if jt:
        s.append(f"One η shared by both gives {_eta(jt[1])} ({_eta(jt[0])} to {_eta(jt[2])}).")
    if sh and q:
        disjoint = sh[0] > q[2] or q[0] > sh[2]
        s.append("The two 90 % intervals are disjoint, which is the tension (compare the "
                 "shaded ranges in the η figure)." if disjoint else
                 "The two 90 % intervals overlap (compare the shaded ranges in the η figure).")
    if math.isfinite(_float(tension.get("overlap"))):
        s.append(f"The overlap coefficient of the two posteriors is "
                 f"{_num(tension['overlap'], '.3g')} (1 = identical, 0 = disjoint).")
    if math.isfinite(_float(tension.get("p_shift_gt_q"))):
        s.append(f"P(η_shift > η_Q) = {_num(tension['p_shift_gt_q'], '.3g')}.")
    bf = _float(tension.get("log_bf_split_vs_shared"))
    if math.isfinite(bf):
        s.append(f"The log Bayes factor of separate over shared η is "
                 f"{_pm(bf, tension.get('log_bf_err'), '.2f')} nats: {_bf_words(bf)}.")
    ppc = tension.get("ppc") or {}
    ps = [f"{name} p = {_num(ppc.get(k), '.3g')}" for k, name in
          (("shift_p", "shift"), ("q_p", "Q")) if math.isfinite(_float(ppc.get(k)))]
    if ps:
        s.append("Posterior predictive checks of the shared-η model: " + ", ".join(ps) + ".")
    if ppc.get("missed"):
        miss = f"It misses {ppc['missed']}"
        s.append(miss + (f" by {ppc['by_how_much']}." if ppc.get("by_how_much") else "."))
    return " ".join(s) if s else "No tension analysis was run."


# ----------------------------------------------------------------------------- tables
def _param_block(law: Mapping, truth: Mapping | None, synthetic: bool
                 ) -> tuple[list[str], list[list[str]], list[bool]]:
    show_truth = synthetic or any(p.get("truth") is not None for p in law.get("params", []))
    headers = ["parameter", "unit", "mean ± sd", "90 % interval"]
    if show_truth:
        headers += ["truth", "truth in 90 %"]
    body = []
    for p in law.get("params", []):
        name = str(p.get("name", "?"))
        cells = [name, p.get("unit") or "-", f"{_num(p.get('mean'))} ± {_num(p.get('sd'))}",
                 f"[{_num(p.get('q05'))}, {_num(p.get('q95'))}]"]
        if show_truth:
            t = p.get("truth")
            if t is None and truth:
                t = truth.get(name)
            tf = _float(t)
            inside = (_float(p.get("q05")) <= tf <= _float(p.get("q95"))
                      if math.isfinite(tf) else None)
            cells += [_num(tf), _DASH if inside is None else ("yes" if inside else "**no**")]
        body.append(cells)
    return headers, body, [_is_failed(law)] * len(body)


def _diag_block(laws: Sequence[Mapping]) -> tuple[list[str], list[list[str]], list[bool]]:
    headers = ["law", "status", "R-hat max", "ESS bulk min", "ESS tail min", "divergences",
               "E-BFMI min", "warnings"]
    body = []
    for lw in laws:
        d = lw.get("diagnostics") or {}
        warn = []
        if _float(d.get("rhat_max")) > 1.01:
            warn.append("R-hat > 1.01")
        if min(_float(d.get("ess_bulk_min")), _float(d.get("ess_tail_min"))) < 400:
            warn.append("ESS < 400")
        if _float(d.get("divergences")) > 0:
            warn.append("divergences")
        if _float(d.get("ebfmi_min")) < 0.3:
            warn.append("E-BFMI < 0.3")
        warn += [str(f) for f in lw.get("failures") or []]
        body.append([lw.get("label", lw.get("name", "?")), _status(lw),
                     _num(d.get("rhat_max"), ".3f"), _num(d.get("ess_bulk_min"), ".0f"),
                     _num(d.get("ess_tail_min"), ".0f"), _num(d.get("divergences"), ".0f"),
                     _num(d.get("ebfmi_min"), ".2f"), "; ".join(warn) or "none"])
    return headers, body, [_is_failed(lw) for lw in laws]


def _tension_table(t: Mapping) -> tuple[list[str], list[list[str]], list[bool]]:
    body = []
    for key, name in (("shift", "η from shift"), ("q", "η from Q"), ("joint", "η joint")):
        tr = _triple(t, f"eta_{key}_q05_q50_q95")
        if tr:
            body.append([name, _eta(tr[0]), _eta(tr[1]), _eta(tr[2])])
    return ["estimate", "5 %", "median", "95 %"], body, [False] * len(body)
