"""The report's warnings: one table, a row per law and a column per check.

The checks are those a statistician would raise on reading the report: the sampling gate,
a posterior against a hard prior bound, the modulus E against the scene's expected range,
the LOO-PIT of the shift, Pareto k > 0.7 of PSIS-LOO, and the agreement of two evidence
estimators. Each cell holds a mark (:data:`OK` passed, :data:`WARN` a warning,
:data:`FAIL` failed, a dash: not checked) and the value behind it; what each check means
is said once, below the table (:func:`warnings_notes`), so nine laws with the same
miscalibrated LOO-PIT read as nine marks, not nine paragraphs.
:func:`statistical_warnings` gives the same findings as one sentence each.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from beadrod.workflows.report.params import BOUND_FRACTION, param_info, parameter_checks
from beadrod.workflows.report.tables import (
    DASH,
    FAILED,
    fmt_num,
    is_failed,
    law_label,
    to_float,
)

__all__ = ["OK", "WARN", "FAIL", "CHECKS", "pit_shape", "warnings_table", "warnings_notes",
           "statistical_warnings", "any_warning"]

OK, WARN, FAIL = "✓", "⚠", "✗"

CHECKS: dict[str, str] = {
    "gate": "sampling gate",
    "prior": "prior bounds",
    "range": "E in the scene's range",
    "pit": "LOO-PIT",
    "pareto": "Pareto k > 0.7",
    "estimators": "log Z estimators",
}
"""Column key -> header of the warnings table, in the table's order."""

Table = tuple[list[str], list[list[str]], list[bool]]


# ------------------------------------------------------------------------------ LOO-PIT
def pit_shape(pit: Mapping) -> tuple[str, str]:
    """What a non-uniform LOO-PIT says, as (a few words for the table, the sentence), from
    its tail share and mean against their sampling sd under uniformity (binomial:
    sqrt(0.1 0.9 / n); mean: sqrt(1/(12 n)))."""
    n = max(to_float(pit.get("n")), 1.0)
    z_tails = (to_float(pit.get("tails")) - 0.1) / math.sqrt(0.09 / n)
    z_mean = (to_float(pit.get("mean")) - 0.5) / math.sqrt(1.0 / (12.0 * n))
    if z_tails > 2:
        return "too narrow", "the predictive is too narrow (too many sweeps in its tails)"
    if z_tails < -2:
        return "too wide", "the predictive is too wide (too few sweeps in its tails)"
    if abs(z_mean) > 2:
        return (("data above", "the data lie above the predictions") if z_mean > 0
                else ("data below", "the data lie below the predictions"))
    return "shape missed", "the law's curve misses the data's shape"


def _pit_numbers(pit: Mapping) -> str:
    return f"D = {fmt_num(pit.get('ks_d'), '.2f')}, p = {fmt_num(pit.get('ks_p'), '.2g')}"


def _pits(result: Mapping) -> Mapping:
    return (result.get("checks") or {}).get("loo_pit") or {}


# ---------------------------------------------------------------------- findings per law
def _findings(result: Mapping, law: Mapping) -> dict[str, tuple[str, str, list[str]]]:
    """Check key -> (mark, cell value, warning sentences) of one law; the mark is "" for a
    check not made."""
    label = law_label(law)
    data = result.get("data") or {}
    out: dict[str, tuple[str, str, list[str]]] = {}

    if is_failed(law):
        why = "; ".join(map(str, law.get("failures") or [])) or "no reason recorded"
        out["gate"] = (FAIL, f"**{FAILED}**: {why}", [])
    else:
        out["gate"] = (OK, "ok", [])

    checks = parameter_checks(law, data.get("young_range_Pa"))
    bound = [c for c in checks if c.check == "prior" and c.warns]
    checked = any(math.isfinite(to_float(p.get("q05"))) for p in law.get("params") or [])
    out["prior"] = ((WARN, "; ".join(f"{c.symbol} {c.interval}: {c.cell}" for c in bound),
                     [f"{label}: {c.sentence}" for c in bound]) if bound
                    else (OK, "none", []) if checked else ("", DASH, []))
    rng = [c for c in checks if c.check == "range"]
    out["range"] = ((WARN if any(c.warns for c in rng) else OK,
                     "; ".join(c.interval for c in rng),
                     [f"{label}: {c.sentence}" for c in rng if c.warns]) if rng
                    else ("", DASH, []))

    pit = _pits(result).get(law.get("name")) or {}
    if pit.get("calibrated") is False:
        short, words = pit_shape(pit)
        tails = f"{100 * to_float(pit.get('tails')):.0f} %"
        out["pit"] = (WARN, f"{short}: {_pit_numbers(pit)}, tails {tails}",
                      [f"{label}: the LOO-PIT of the shift is not uniform (Kolmogorov-Smirnov "
                       f"{_pit_numbers(pit)}; {tails} of the values in the outer 5 % tails "
                       f"against 10 %): {words}."])
    elif pit.get("calibrated") is True:
        out["pit"] = (OK, _pit_numbers(pit), [])
    else:
        out["pit"] = ("", DASH, [])

    bad = to_float(law.get("pareto_k_bad"))
    n = (law.get("loo") or {}).get("n_points")
    of = f" of {n}" if n else ""
    if bad > 0:
        one = bad == 1
        out["pareto"] = (WARN, f"{bad:.0f}{of}",
                         [f"{label}: {bad:.0f}{of} drive sweeps {'has' if one else 'have'} "
                          f"Pareto k > 0.7, so PSIS-LOO is unreliable for "
                          f"{'it' if one else 'them'} and elpd_loo is biased (such sweeps "
                          "dominate the fit; refit without them or use K-fold CV)."])
    elif bad == 0:
        out["pareto"] = (OK, f"0{of}", [])
    else:
        out["pareto"] = ("", DASH, [])

    agree = law.get("evidence_agree")
    out["estimators"] = (
        ("", DASH, []) if agree is None else (OK, "agree", []) if agree else
        (WARN, "disagree", [f"{label}: the two evidence estimators disagree beyond their "
                            "errors (log Z is not settled)."]))
    return out


def statistical_warnings(result: Mapping) -> list[str]:
    """The findings of the warnings table as one sentence each, law by law: posteriors
    against a prior bound or outside the scene's range, miscalibrated LOO-PIT, Pareto
    k > 0.7, disagreeing evidence estimators (not the sampling gate, which the report
    states on its own)."""
    out: list[str] = []
    for lw in result.get("laws") or []:
        for _, _, sentences in _findings(result, lw).values():
            out += sentences
    return out


def any_warning(result: Mapping) -> bool:
    """Whether any law fails a check of the warnings table (the gate included)."""
    return any(mark in (WARN, FAIL) for lw in result.get("laws") or []
               for mark, _, _ in _findings(result, lw).values())


# ------------------------------------------------------------------------------- table
def _young_range(result: Mapping) -> str | None:
    r = (result.get("data") or {}).get("young_range_Pa")
    if r is None or len(r) != 2:
        return None
    info = param_info("young")
    return f"{float(r[0]) * info.scale:.4g}-{float(r[1]) * info.scale:.4g} {info.unit}"


def _header(key: str, result: Mapping) -> str:
    rng = _young_range(result)
    return f"E in {rng}" if key == "range" and rng else CHECKS[key]


def warnings_table(result: Mapping) -> Table:
    """(headers, rows, failed-row flags): a row per law, a column per check (:data:`CHECKS`),
    each cell its mark and value."""
    laws: Sequence[Mapping] = list(result.get("laws") or [])
    headers = ["law"] + [_header(k, result) for k in CHECKS]
    body = []
    for lw in laws:
        f = _findings(result, lw)
        body.append([law_label(lw)] + [f"{mark} {value}" if mark else value
                                       for mark, value, _ in (f[k] for k in CHECKS)])
    # no failed-row flags: the gate's column marks a failed fit, and a row in red would
    # hide the other cells' marks
    return headers, body, [False] * len(laws)


def warnings_notes(result: Mapping) -> list[str]:
    """What each check of the warnings table means, once for all laws."""
    rng = _young_range(result)
    laws = list(result.get("laws") or [])
    one = bool(laws) and not any(lw.get("log_z2_method") for lw in laws)
    return [
        f"{OK} passed, {WARN} a warning, {FAIL} failed, {DASH} not checked. Intervals: the "
        "posterior's 90 % interval.",
        f"**{CHECKS['gate']}**: R-hat, ESS, divergences and E-BFMI against the gate's "
        f"thresholds (Sampler diagnostics below); a {FAILED} fit's numbers are not "
        "trustworthy.",
        f"**{CHECKS['prior']}**: an interval that ends within {BOUND_FRACTION:.0%} of its "
        "own width of a hard prior bound. Piled against its bound: the bound, not the "
        "data, cuts the posterior off (the law wants to go beyond its physical range). "
        "Fills its prior: the data do not constrain it, and the evidence depends on the "
        "prior's width. Spans most of its prior, leaning towards a bound: the data barely "
        "constrain it and lean towards that bound, which cuts the posterior off; the "
        "evidence depends on the prior's width.",
        f"**{_header('range', result)}**: E's interval outside the scene's expected range"
        + (f" {rng}" if rng else "") + " means the law needs an unphysical modulus to fit.",
        f"**{CHECKS['pit']}**: "
        + ("not computed." if not _pits(result) else
           "where each drive sweep's shift falls in its leave-one-out predictive, uniform "
           "for a calibrated law (Kolmogorov-Smirnov D and p; tails: the share of values "
           "in the outer 5 % tails, 10 % when uniform). Too narrow: the predictive has too "
           "many sweeps in its tails; too wide: too few; data above or below: the data lie "
           "above or below the predictions; shape missed: the law's curve misses the "
           "data's shape."),
        f"**{CHECKS['pareto']}**: drive sweeps whose Pareto k exceeds 0.7, of all; PSIS-LOO "
        "is unreliable for them and elpd_loo is biased (such sweeps dominate the fit; refit "
        "without them or use K-fold CV).",
        f"**{CHECKS['estimators']}**: "
        + ("one evidence estimator only, no cross-check: run again with `--evidence "
           "bridge,ns` to add nested sampling (jaxns) beside bridge sampling; this column "
           "then says whether the two agree." if one else
           "whether the two evidence estimators agree within their errors; where they "
           "disagree, log Z is not settled."),
    ]
