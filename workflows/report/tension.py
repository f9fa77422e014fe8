"""The tension section of the report: per rung, one short table of η and two sentences.

The numbers are :func:`inference.evidence.tension.analyse_tension`'s (stored under ``tension`` in
result.json, the paper's Eq. 25 block under ``tension.paper``). The table gives η [one
unit for the whole column] from each source, with the world's truth on synthetic data;
the first sentence says whether the shift and Q need different viscosities (the gap
log10 η_shift − log10 η_Q and P(η_shift > η_Q)), the second what the Bayes factor of two
viscosities over one and the one-η fit's predictive checks say, each statistic with its
reading.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from beadrod.workflows.report.tables import DASH, evidence_words, fmt_num, fmt_pm, to_float

__all__ = ["eta_unit", "tension_table", "tension_sentences"]

_ROWS = (("shift", "η from the shift alone"), ("q", "η from Q alone"),
         ("joint", "η joint (one η for both)"), ("split_shift", "η_shift (split model)"),
         ("split_q", "η_Q (split model)"))


def _triple(t: Mapping, key: str) -> list[float] | None:
    v = t.get(f"eta_{key}_q05_q50_q95")
    if v is None or len(v) != 3:
        return None
    return [to_float(x) for x in v]


def eta_unit(values: list[float]) -> tuple[str, float]:
    """(unit, scale) for η [Pa s] values: the largest unit in which the largest is >= 0.1."""
    top = max((abs(v) for v in values if math.isfinite(v)), default=1.0)
    for scale, unit in ((1e6, "MPa s"), (1e3, "kPa s")):
        if top >= 0.1 * scale:
            return unit, scale
    return "Pa s", 1.0


def tension_table(t: Mapping, truth_eta: float | None = None
                  ) -> tuple[list[str], list[list[str]], list[bool]]:
    """η per source: median and 90 % interval in one unit; truth [Pa s] where given."""
    if not t.get("eta_in_shift"):
        truth_eta = None  # the world's η sets its shift through Eq. 25 only
    rows = [(name, _triple(t, key), key) for key, name in _ROWS]
    vals = [v for _, tr, _ in rows if tr for v in tr] + ([truth_eta] if truth_eta else [])
    unit, scale = eta_unit(vals)
    headers = ["estimate", f"median [{unit}]", f"90 % interval [{unit}]"]
    if truth_eta is not None:
        headers.append(f"truth [{unit}]")
    body = []
    for name, tr, key in rows:
        if tr is None and key == "shift" and not t.get("eta_in_shift", True):
            cells = [name, DASH, "η does not enter the shift on this rung"]
        elif tr is None:
            continue
        else:
            if key == "split_shift" and not t.get("eta_in_shift", True):
                name += ": its prior, unused on this rung"
            cells = [name, f"{tr[1] / scale:.3g}", f"[{tr[0] / scale:.3g}, {tr[2] / scale:.3g}]"]
        if truth_eta is not None:
            # the world's η sets its shift (Eq. 25): the shift-side rows have a truth
            cells.append(f"{truth_eta / scale:.3g}" if key in ("shift", "split_shift")
                         else DASH)
        body.append(cells)
    return headers, body, [False] * len(body)


def _p(v: Any) -> str:
    f = to_float(v)
    return DASH if not math.isfinite(f) else ("< 0.001" if f < 0.001 else f"{f:.3f}")


def tension_sentences(t: Mapping) -> str:
    """Two sentences: the gap between the sources, then Bayes factor and predictive check."""
    gap = t.get("log10_gap_q05_q50_q95")
    if t.get("eta_in_shift") and gap:
        g = [to_float(v) for v in gap]
        differ = g[0] > 0 or g[2] < 0
        first = (f"The shift alone puts η {fmt_num(g[1], '+.2f')} decades from Q alone "
                 f"(gap log10 η_shift − log10 η_Q, 90 % interval [{g[0]:+.2f}, {g[2]:+.2f}]"
                 + (f"; P(η_shift > η_Q) = {_p(t.get('p_shift_gt_q'))} in the split model"
                    if t.get("p_shift_gt_q") is not None else "")
                 + "): " + ("the two observables need different viscosities, which is the "
                            "tension." if differ else "an interval holding 0, so no tension."))
    else:
        first = ("On this rung η does not enter the shift (damping moves the damping, not the "
                 "stiffness), so only Q measures η and there is no tension to test; the "
                 "paper's Eq. 25 block shows where the paper's tension comes from.")
    bf = to_float(t.get("log_bf_split_vs_shared"))
    parts = []
    if math.isfinite(bf):
        side = "two viscosities" if bf > 0 else "one viscosity"
        words = evidence_words(abs(bf))
        parts.append(f"The log Bayes factor of two viscosities over one is "
                     f"{fmt_pm(bf, t.get('log_bf_err'), signed=True)} nats "
                     f"({words}{'' if abs(bf) < 1 else ' for ' + side}"
                     + ("; 0 is expected here, as η_shift is then unused" if not
                        t.get("eta_in_shift") else "") + ")")
    ppc = t.get("ppc") or {}
    if ppc:
        bad = [name for key, name in (("shift_p", "the shift"), ("q_p", "Q"))
               if to_float(ppc.get(key)) < 0.05]
        verdict = (f"it cannot reproduce {' or '.join(bad)}" if bad else
                   "it reproduces both; p < 0.05 would flag a misfit")
        parts.append(f"the one-η fit's posterior predictive p-values are {_p(ppc.get('shift_p'))}"
                     f" for the shift and {_p(ppc.get('q_p'))} for Q ({verdict})")
    second = ("; ".join(parts) + ".") if parts else ""
    return (first + " " + second[:1].upper() + second[1:]).strip()
