"""The report's loss-against-shift tables and the law each observable prefers.

The numbers are :func:`inference.evidence.loss_shift.loss_shift_block`'s rows (stored under
``loss_shift`` in result.json: ``exact``, each fit at its rung; ``paper``, the paper's
Eq. 25 reading; ``data``) and :func:`inference.evidence.observables.preference_by_observable`'s
(under ``observables``). One table per reading: per model the linear Q0, the loss
exponent beta, the local exponents of Delta f/f0 and Delta(1/Q) at the small amplitude
x_s, the ratio Delta(1/Q)/|Delta f/f0| there (signed: < 0 the resonance narrows), the
sign, and the ratio as the paper's Eq. 31 reads it; a "data" row last. Then one table of
the preferred law per observable (elpd_loo) and all together (log Z), and a sentence.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from beadrod.inference.evidence.observables import RESOLVED_SE
from beadrod.workflows.report.tables import DASH, fmt_pm, law_label, to_float

__all__ = ["loss_shift_table", "loss_shift_sentence", "observable_table",
           "observable_sentence", "loss_shift_blocks"]

_HEADERS = ["model", "Q0", "β (loss ∝ Ω^β)", "Δf/f0 ∝ x^p: p", "Δ(1/Q) ∝ x^r: r",
            "Δ(1/Q)/|Δf/f0|", "the resonance", "Eq. 31 reads"]
_SIGN = {"narrows": "narrows", "widens": "widens", "either": "sign not resolved",
         "none": "no change"}


def _g(v: float) -> str:
    """A number in three significant digits, with a proper minus sign."""
    return f"{v:.3g}".replace("-", "−")


def _interval(t: Any, *, exact_width: float = 1e-3) -> str:
    """``median [q05, q95]``, or the median alone where the interval is narrower than
    ``exact_width`` (a fixed value)."""
    if not t or len(t) != 3:
        return DASH
    lo, mid, hi = (to_float(v) for v in t)
    if not all(math.isfinite(v) for v in (lo, mid, hi)):
        return DASH
    if hi - lo <= exact_width * max(abs(mid), 1e-300):
        return _g(mid)
    return f"{_g(mid)} [{_g(lo)}, {_g(hi)}]"


def _pm(pair: Any) -> str:
    if not pair:
        return DASH
    return fmt_pm(pair[0], pair[1]).replace("-", "−")


def _model_cells(row: Mapping) -> list[str]:
    if row.get("error"):
        return [f"not computed: {row['error']}"] + [DASH] * (len(_HEADERS) - 2)
    q = to_float(row.get("q_ref"))
    q_cell = DASH if not math.isfinite(q) else (
        f"{q:.3g} ({'the law' if row.get('q_ref_source') == 'law' else 'the data'})")
    beta = row.get("beta")
    beta_cell = (_interval(beta) + (" (its own)" if row.get("beta_source") == "own"
                                    else " (fitted)")) if beta else DASH
    if row.get("note"):
        return [q_cell, DASH, _interval(row.get("shift_exponent")), DASH, DASH,
                row["note"], DASH]
    r_cell = (_interval(row.get("loss_exponent")) if row.get("loss_exponent")
              else "no change" if row.get("sign") == "none" else DASH)
    return [q_cell, beta_cell, _interval(row.get("shift_exponent")), r_cell,
            _interval(row.get("ratio")), _SIGN.get(row.get("sign"), DASH),
            _interval(row.get("ratio_eq31"))]


def _data_cells(d: Mapping) -> list[str]:
    q = to_float(d.get("q_ref"))
    return [DASH if not math.isfinite(q) else f"{q:.3g} (measured, median)", DASH,
            _pm(d.get("shift_exponent")),
            _pm(d.get("loss_exponent")) if d.get("loss_exponent") else "not resolved",
            _pm(d.get("ratio")), _SIGN.get(d.get("sign"), DASH), _pm(d.get("ratio_eq31"))]


def loss_shift_table(block: Mapping, reading: str, labels: Mapping[str, str]
                     ) -> tuple[list[str], list[list[str]], list[bool]]:
    """One reading's table (``reading``: 'exact' or 'paper'); ``labels``: model name ->
    its label. Rows in the result's order, the data last."""
    body = []
    for name, row in (block.get(reading) or {}).items():
        label = labels.get(name, name)
        if row.get("source"):
            label += f" ({row['source']})"
        if reading == "paper" and row.get("rung"):
            label += f", `{row['rung']}`"
        body.append([label, *_model_cells(row)])
    if block.get("data"):
        body.append(["**data**", *_data_cells(block["data"])])
    return list(_HEADERS), body, [False] * len(body)


def _consistent(row: Mapping, ratio: Any) -> bool | None:
    """Whether a model's 90 % interval of the ratio meets the data's ratio +- 2 se."""
    t, d = row.get("ratio"), ratio
    if not t or not d or row.get("error"):
        return None
    lo, hi = to_float(d[0]) - 2 * to_float(d[1]), to_float(d[0]) + 2 * to_float(d[1])
    return bool(to_float(t[0]) <= hi and to_float(t[2]) >= lo)


def loss_shift_sentence(block: Mapping, reading: str, labels: Mapping[str, str]) -> str:
    """Which models' ratio the data's allows (its value ± 2 se against their 90 %
    intervals)."""
    d = block.get("data") or {}
    ratio = d.get("ratio")
    if not ratio:
        return ""
    rows = block.get(reading) or {}
    fits = [labels.get(k, k) for k, r in rows.items() if _consistent(r, ratio)]
    miss = [labels.get(k, k) for k, r in rows.items() if _consistent(r, ratio) is False]
    text = (f"The data's Δ(1/Q)/|Δf/f0| is {_pm(ratio)} over the {d.get('ratio_n')} sweeps "
            f"with x ≤ {to_float(d.get('ratio_x_max')):.2g}")
    if fits:
        text += f"; within twice its error of the 90 % interval of {', '.join(fits)}"
    if miss:
        text += f"; outside that of {', '.join(miss)}"
    return text + "."


def _elpd_lead(c: Mapping) -> str:
    d, se = to_float(c.get("delta_elpd")), to_float(c.get("delta_se"))
    if not math.isfinite(d):
        return DASH
    return fmt_pm(d, se) + " nats elpd" + ("" if c.get("resolved")
                                           else " (not resolved: < 2 se)")


def observable_table(obs: Mapping, labels: Mapping[str, str]
                     ) -> tuple[list[str], list[list[str]], list[bool]]:
    """observable | preferred law | runner-up | its lead | not in the contest."""
    lab = lambda n: DASH if n is None else labels.get(n, n)  # noqa: E731
    body = []
    for c in obs.get("observables") or []:
        absent = ", ".join(lab(n) for n in c.get("absent") or []) or DASH
        body.append([c.get("observable", c.get("site", "?")), lab(c.get("preferred")),
                     lab(c.get("runner_up")), _elpd_lead(c) if c.get("runner_up") else DASH,
                     absent])
    a = obs.get("all") or {}
    body.append(["**all together** (evidence)", lab(a.get("preferred")),
                 lab(a.get("runner_up")),
                 f"{fmt_pm(a.get('delta_log_z'), a.get('delta_log_z_err'))} nats log Z"
                 if a.get("runner_up") else DASH, DASH])
    return (["observable", "preferred law", "runner-up", "lead over the runner-up",
             "not in the contest (not read)"], body, [False] * len(body))


def _and(items: list[str]) -> str:
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def observable_sentence(obs: Mapping, labels: Mapping[str, str]) -> str:
    """Which law each observable prefers, which agree with the evidence, and the PSIS
    caveats (points with Pareto k > 0.7)."""
    lab = lambda n: labels.get(n, n)  # noqa: E731
    sites = [c for c in obs.get("observables") or [] if c.get("preferred")]
    best = (obs.get("all") or {}).get("preferred")
    parts = [f"{c['observable']} prefers {lab(c['preferred'])}"
             + (" (not resolved)" if c.get("resolved") is False else "") for c in sites]
    text = ("By its leave-one-out predictive density, " + "; ".join(parts)
            if parts else "No observable has a law to prefer")
    if best:
        agree = [c["observable"] for c in sites if c["preferred"] == best]
        text += (f"; all together the evidence prefers {lab(best)}"
                 + (f", as {_and(agree)} {'does' if len(agree) == 1 else 'do'}"
                    if agree else ", which no observable prefers alone"))
    text += "."
    beaten = [f"{c['observable']} ({fmt_pm(c['baseline_delta'], c.get('baseline_delta_se'))}"
              " nats)" for c in sites if to_float(c.get("baseline_delta"))
              > RESOLVED_SE * to_float(c.get("baseline_delta_se"))]
    if beaten:
        text += (" The law-free baseline predicts " + ", ".join(beaten)
                 + " better than the preferred law, by more than twice the error.")
    shaky = sorted({f"{lab(n)} on {c['observable']}" for c in sites
                    for n, e in (c.get("elpd") or {}).items() if e.get("k_bad")})
    if shaky:
        text += (" PSIS-LOO is unreliable (Pareto k > 0.7 at some points) for "
                 + ", ".join(shaky) + ".")
    if obs.get("unread"):
        text += f" No model read {', '.join(obs['unread'])} (--observables)."
    if obs.get("gate_ignored"):
        text += " No law passed its sampling gate: this ranks them ignoring it."
    return text


def loss_shift_blocks(result: Mapping) -> list[tuple]:
    """The report's blocks: the loss-against-shift tables and the preference per
    observable (empty where the result has neither)."""
    labels = {lw.get("name"): law_label(lw) for lw in result.get("laws") or []}
    b: list[tuple] = []
    block = result.get("loss_shift")
    if block:
        xs = to_float(block.get("x_small"))
        b += [("h", 2, "Loss against shift: what each model predicts, what the data say"),
              ("p", f"At the small amplitude x = δa/δ0 = {xs:.2g} (the data's lowest tenth; "
                    "δ0 the model's overlap), from each fit's posterior draws: the local "
                    "exponents of the shift and of the loss change, their ratio (< 0: the "
                    "resonance narrows as the amplitude grows, > 0: it widens), and the "
                    "ratio as the paper's Eq. 31 reads it, which adds the base "
                    "excitation's 2/Q0. Medians and 90 % intervals.")]
        for reading, title in (("exact", "Exact physics (each fit's rung)"),
                               ("paper", "The paper's Eq. 25 reading")):
            if not block.get(reading):
                continue
            b.append(("h", 3, title))
            b.append(("table", *loss_shift_table(block, reading, labels)))
            sentence = loss_shift_sentence(block, reading, labels)
            if sentence:
                b.append(("p", sentence))
        b.append(("note", "What each mechanism predicts for the ratio (docs/damping.md): an "
                          "elastic law with a background loss L0 Ω^β gives −β/Q0 (a "
                          "constant loss factor, β = 0: no change; a dashpot, β = 1), "
                          "Kuwabara–Kono damping −3/Q0, Masing hysteresis alone +ρ(m) "
                          "(8/(3π) ≈ 0.85 at m = 2). The data: Δ(1/Q) from Eq. 31 with the "
                          "base excitation taken out, the ratio the least-squares slope "
                          "through the origin against |Δf/f0| over the lower half of x "
                          "± its standard error, the exponents those of power laws fitted "
                          "to all sweeps (that of Δ(1/Q) only where its coefficient is "
                          "beyond twice its error). Q0: the law's own linear Q, else the "
                          "median measured reference Q (the amplitude likelihood's)."))
    obs = result.get("observables")
    if obs:
        b.append(("h", 2, "The law each observable prefers"))
        if obs.get("error"):
            b.append(("p", f"Not computed: {obs['error']}."))
            return b
        b.append(("table", *observable_table(obs, labels)))
        b.append(("p", observable_sentence(obs, labels)))
        b.append(("note", "Per observable, elpd_loo of its observations alone (PSIS-LOO, "
                          "nats) among the laws that passed their gate; the lead ± the "
                          "standard error of the point-wise differences, resolved beyond "
                          "twice it. The law-free baseline is ranked but never preferred. "
                          "A law whose likelihood did not read an observable "
                          "(--observables) is not in its contest. All together: the "
                          "evidence ranking, log Z of every observable jointly."))
    return b
