"""What a synthetic world's ``truth.json`` says about each fitted parameter.

A synthetic world (``data.synth``) records its generating values, but not every model
parameter has a counterpart there: ``paper_like`` is phenomenological (its f0 is drawn,
not computed from a modulus), ``hertz_dynamics`` has a linear dashpot, not a viscosity.
:func:`world_truth` gives, per parameter, either a value with a note on what it means,
or one line saying why the world defines none. :func:`protocol_truth` compares the
per-protocol truths (static overlap delta0_p [m], linear resonance f0_p [Hz], linear
Q_p) with the data and with each fit. A world whose parameters are a law's (the
``hysteretic`` world's strength and exponent are Hertz with hysteresis's) says so in its
truth.json (``law_parameters``, written by the world's own module), and those truths are
taken as they stand, with any override the world was made with.

Sample values over the world's protocols stand in for hyper-parameters that the world
does not draw from the model's distribution (it draws f0 uniform, the models
assume log-normal delta0): they are what a perfect fit of that hyper-parameter would
find on these protocols.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["world_truth", "protocol_truth"]

_NO_SCATTER_MODEL = ("the world's shift noise is N(0, 2 Hz) on each peak plus drift and "
                     "a multiplicative up/down hysteresis: no single Gaussian scale of Δf/f0")
_BASELINE = "the law-free curve has no counterpart in the world"

# Per world: parameter -> (truth key or None, why there is none / what the value means).
_NOTES: dict[str, dict[str, str]] = {
    "paper_like": {
        "young": "no truth: f0_p is drawn (2.5-3.0 kHz), not computed from a modulus; "
                 "E = 210 GPa enters only the world's damping constant A",
        "eta_q": "no truth: Q_p is drawn log-uniform in [20, 100], not from a viscosity",
        "sigma_logq": "no truth: the world's Q_p does not follow 1/(ω0 A), so no scatter "
                      "about it is defined",
        "n": "no truth: the world's shift is the paper's Eq. 25 curve, not a power-law "
             "contact",
        "gamma": "no truth: the world has no adhesion",
        "sigma_shift": "no truth: " + _NO_SCATTER_MODEL,
        "kappa_shift": "no truth: " + _NO_SCATTER_MODEL,
        "tau_shift": "no truth: the first reference's 2 Hz noise and drift are shared by "
                     "the protocol's shifts, but not as one Gaussian offset",
        "loss_exponent": "no truth: the world draws delta = Q d V, a force proportional to "
                         "the voltage: under base excitation that is beta = 2",
        "sigma_amp": "no truth: amplitudes carry 3 % log-normal noise (sigma_amp ~ 0.03)",
        "tau_amp": "no truth: the reference amplitude carries the same 3 % noise",
        "offset_down": "no truth: down sweeps read s (1 + h x) with h = 0.15, a "
                       "multiplicative split, not a constant offset",
        "amp": "no truth: " + _BASELINE, "power": "no truth: " + _BASELINE,
    },
    "hertz_dynamics": {
        "young": "no truth: f0_p is drawn (2.5-3.0 kHz) and delta0_p set from it, not from "
                 "a modulus",
        "eta": "no truth: the world's loss is a linear dashpot ζ_p = 1/(2 Q_p), not a "
               "viscosity",
        "eta_shift": "no truth: the world's loss is a linear dashpot, not a viscosity",
        "eta_q": "no truth: the world's loss is a linear dashpot, not a viscosity",
        "sigma_logq": "no truth: Q_p is drawn, not computed from a viscosity",
        "gamma": "no truth: the world has no adhesion",
        "sigma_shift": "no truth: the shift noise is 1 % vibrometer noise on each curve, "
                       "read through a peak fit: no single Gaussian scale",
        "kappa_shift": "no truth: the shift noise is vibrometer noise read through a peak "
                       "fit, not a set fraction of the shift",
        "tau_shift": "no truth: the first reference's error is shared by the protocol's "
                     "shifts, but it comes from a peak fit, not one Gaussian offset",
        "loss_exponent": "no truth: the world's dashpot is stiffness-proportional (beta = 3 "
                         "in one harmonic, less with its harmonics)",
        "sigma_amp": "no truth: amplitudes are read by a peak fit from curves with 1 % noise",
        "tau_amp": "no truth: the reference amplitude is read by the same peak fit",
        "offset_down": "no truth: up and down sweeps differ by the harmonic-balance "
                       "hysteresis, not by a set offset",
        "amp": "no truth: " + _BASELINE, "power": "no truth: " + _BASELINE,
    },
}


def _protocol_values(truth: Mapping, key: str) -> np.ndarray | None:
    prot = truth.get("protocols") or {}
    vals = [p.get(key) for p in prot.values()]
    if not vals or any(v is None for v in vals):
        return None
    return np.asarray(vals, float)


def _law_parameters(truth: Mapping) -> dict[str, dict[str, Any]]:
    """The truths a world states for a law's parameters (truth.json ``law_parameters``:
    ``law`` and ``values``, parameter -> {value, world_parameter, note}; written by the
    world's own module, e.g. data.worlds_loss.LAW_PARAMETERS). Entries without a finite
    number are skipped."""
    lp = truth.get("law_parameters")
    if not isinstance(lp, Mapping) or not isinstance(lp.get("values"), Mapping):
        return {}
    out = {}
    for name, v in lp["values"].items():
        value = v.get("value") if isinstance(v, Mapping) else None
        if isinstance(value, int | float) and not isinstance(value, bool) \
                and np.isfinite(value):
            src = v.get("world_parameter", name)
            note = str(v.get("note") or f"the world's {src}")
            out[str(name)] = {"value": float(value), "law": lp.get("law"),
                              "note": f"{note} ({lp.get('law', 'the law')}'s {name})"}
    return out


def world_truth(truth: Mapping | None) -> dict[str, Any] | None:
    """Per-parameter truths of a synthetic world (None for measured data).

    Returns ``world``, ``kind``, ``seed``, ``values`` (parameter -> {"value" [SI; natural
    log of metres for delta0_ref_log], "note"}) and ``none`` (parameter -> one line why
    the world defines no value).
    """
    if not truth:
        return None
    world = str(truth.get("world", "?"))
    params = truth.get("parameters") or {}
    values: dict[str, dict[str, Any]] = {}
    eta = params.get("eta_Pa_s")
    if eta is not None:
        note = ("sets the world's shift through the paper's Eq. 25 (A at E = 210 GPa); Q_p "
                "is drawn independently, so only the shift-alone fit under Eq. 25 should "
                "recover it")
        values["eta"] = {"value": float(eta), "note": note}
        values["eta_shift"] = {"value": float(eta), "note": note}
    if truth.get("kind") == "physical" and "hertz" in str(truth.get("model", "")).lower():
        values["n"] = {"value": 1.5, "note": "the world is a Hertz contact, F ~ delta^(3/2)"}
    d0 = _protocol_values(truth, "delta0_m")
    if d0 is not None and d0.size >= 2:  # a sample sd needs two protocols
        ln = np.log(d0)
        values["delta0_scatter"] = {
            "value": float(np.std(ln, ddof=1)),
            "note": "sample sd of ln δ0_p over the world's protocols (its f0_p is drawn "
                    "uniform, not log-normal)"}
        values["delta0_ref_log"] = {"value": float(np.mean(ln)),
                                    "note": "geometric mean of the world's δ0_p (Hertz "
                                            "overlaps; stored as the mean of ln δ0_p)"}
    f0 = _protocol_values(truth, "f0_reference_Hz")
    if f0 is not None and f0.size >= 2:
        values["mu_f0"] = {"value": float(np.mean(f0)), "note": "sample mean of f0_p"}
        values["tau_f0"] = {"value": float(np.std(f0, ddof=1)), "note": "sample sd of f0_p"}
    q = _protocol_values(truth, "q_reference")
    if q is None:
        q = _protocol_values(truth, "q")
    if q is not None and q.size >= 2:
        values["mu_logq"] = {"value": float(np.mean(np.log(q))),
                             "note": "sample mean of ln Q_p (Q_p drawn log-uniform)"}
        values["tau_logq"] = {"value": float(np.std(np.log(q), ddof=1)),
                              "note": "sample sd of ln Q_p"}
    values.update(_law_parameters(truth))
    none = {k: v for k, v in _NOTES.get(world, {}).items() if k not in values}
    return {"world": world, "kind": truth.get("kind"), "seed": truth.get("seed"),
            "values": values, "none": none}


def _draws(idata: Any, name: str) -> np.ndarray | None:
    post = getattr(idata, "posterior", None)
    if post is None or name not in post:
        return None
    arr = np.asarray(post[name], float)
    return arr.reshape(-1, arr.shape[-1]) if arr.ndim == 3 else None


def _cover(draws: np.ndarray, truth: np.ndarray) -> dict[str, Any]:
    lo, med, hi = np.percentile(draws, [5, 50, 95], axis=0)
    return {"covered": int(np.sum((lo <= truth) & (truth <= hi))), "n": int(truth.size),
            "median_rel_error_max": float(np.max(np.abs(med / truth - 1.0))),
            "rel_width_median": float(np.median((hi - lo) / np.abs(med)))}


def protocol_truth(truth: Mapping | None, protocol_ids: tuple[str, ...] | list[str],
                   f0_measured: np.ndarray, q_measured: np.ndarray,
                   idatas: Mapping[str, Any]) -> dict[str, Any] | None:
    """Per-protocol truths against the data and each fit (None without truth).

    Returns, per quantity (``delta0`` [m], ``f0`` [Hz], ``q``), the truth's range over
    protocols, the largest relative error of the measured value (f0 and Q are data), and
    per law whose posterior has that per-protocol site (``delta0``, ``q_pred``) how many
    protocols' 90 % intervals hold the truth, the largest relative error of the posterior
    median and the median relative width of the 90 % intervals (a law whose delta0_p
    follows from the measured f0_p alone has a near-point interval: its error is the
    measured f0's, and coverage means little there).
    """
    prot = (truth or {}).get("protocols") or {}
    if not prot or not all(p in prot for p in protocol_ids):
        return None
    ids = list(protocol_ids)

    def col(key: str) -> np.ndarray | None:
        vals = [prot[p].get(key) for p in ids]
        return None if any(v is None for v in vals) else np.asarray(vals, float)

    out: dict[str, Any] = {}
    specs = (("delta0", col("delta0_m"), None, "delta0"),
             ("f0", col("f0_reference_Hz"), f0_measured, None),
             ("q", col("q_reference") if col("q_reference") is not None else col("q"),
              q_measured, "q_pred"))
    for key, t, measured, site in specs:
        if t is None:
            continue
        entry: dict[str, Any] = {"range": [float(t.min()), float(t.max())], "n": int(t.size),
                                 "laws": {}}
        if measured is not None:
            m = np.asarray(measured, float)
            ok = np.isfinite(m)
            entry["measured_rel_error_max"] = (float(np.max(np.abs(m[ok] / t[ok] - 1.0)))
                                               if ok.any() else None)
        for law, idata in (idatas.items() if site else ()):
            d = _draws(idata, site)
            if d is not None and d.shape[1] == t.size:
                entry["laws"][law] = _cover(d, t)
        out[key] = entry
    return out
