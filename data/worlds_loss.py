"""Synthetic worlds whose loss changes with the amplitude as a law says it does.

``hysteretic``: a Hertz contact with Masing hysteresis (models.laws.hertz_hysteretic),
driven through the rod (base excitation), with a background loss L0 Omega^beta. Per
protocol p:

* f0_p ~ U(2.5, 3.0) kHz and delta0_p = 3 F0/(2 m (2 pi f0_p)^2) (Hertz under the weight);
* linear Q_p log-uniform in [20, 100], L0,p = 1/Q_p;
* drive steps x_k = delta_a/delta0_p geometric from x_first,p to x_max,p in [0.5, 1], up and
  down sweeps, each followed by a reference sweep at x = 0.01;
* the resonance at amplitude x: Omega^2 = (1 + s_H(x))^2 - 2 h x^(m-1) (s_H Hertz's exact
  backbone, models.tables.powerlaw_backbone), its loss L(x) = L0,p Omega^beta + h rho(m) x^(m-1);
* the drive that puts the peak at x: the rod end moves by Y = d V and drives the bead with
  m omega^2 Y, and at the peak x = E Omega^2 / L(x) with E = Y/delta0_p (one harmonic;
  docs/damping.md bounds what harmonics add), so V = x L(x) delta0_p / (Omega^2 d);
* the reference Q read as 1/L(0.01), the −3 dB width at the reference's amplitude;
* noise: frequency N(0, 2 Hz) on every peak, amplitude log-normal 1 %, Q log-normal 5 %.

The strength h is the hysteretic frequency drop at x = 1 (so h 0.5^(m-1) at x = 0.5).
Its defaults (h = 0.03, m = 2, beta = 1: a constant dashpot) put the hysteretic share of
the shift at x = 0.5 at 0.015.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

from beadrod.data.rounding import significant

__all__ = ["HYSTERETIC", "LAW_PARAMETERS", "hysteretic"]

HYSTERETIC = {
    "n_protocols": 20,
    "strength": 0.03,
    "exponent": 2.0,
    "background_exponent": 1.0,
    "f0_range_Hz": [2500.0, 3000.0],
    "q_range": [20.0, 100.0],
    "steps_range": [5, 9],
    "x_first_range": [0.03, 0.08],
    "x_max_range": [0.5, 1.0],
    "x_reference": 0.01,
    "noise_f_Hz": 2.0,
    "noise_amplitude_rel": 0.01,
    "noise_q_rel": 0.05,
}

LAW_PARAMETERS = {
    "strength": ("strength", "the hysteretic frequency drop h at x = 1, the world's "
                             "strength"),
    "exponent": ("exponent", "the Masing loop's exponent m, the world's exponent"),
}
"""Which parameters of the generating law (models.laws.hertz_hysteretic) the world's
parameters are: law parameter -> (world parameter, what it is). Written into truth.json
as ``law_parameters`` (the law's name and, per parameter, the value the world was made
with, its overrides included), which workflows.report.truth.world_truth reads as the
world's truths. The background exponent beta is no law parameter's truth: Hertz with
hysteresis fixes its own background loss, and a law without a loss of its own would fit
beta to the hysteretic loss as well."""


def _law_parameters(cfg: dict) -> dict:
    from beadrod.models.laws import hertz_hysteretic

    return {"law": hertz_hysteretic.LAW.name,
            "values": {name: {"value": float(cfg[key]), "world_parameter": key, "note": note}
                       for name, (key, note) in LAW_PARAMETERS.items()}}


def hysteretic(seed: int, scene: Any, scene_dict: dict,
                     **overrides: Any) -> tuple[pd.DataFrame, dict, dict]:
    """(measurement table, scene dict, truth) of the hysteretic world (module docstring);
    ``overrides`` replace entries of :data:`HYSTERETIC` (strength, exponent, ...)."""
    import jax
    import jax.numpy as jnp

    from beadrod.models.laws import hertz, masing
    from beadrod.models.laws import hertz_hysteretic as law
    from beadrod.models.tables.powerlaw_backbone import backbone_shift_clipped

    cfg = {**HYSTERETIC, **overrides}
    rng = np.random.default_rng(seed)
    mass, load = float(scene.mass), float(scene.load)
    d_per_v = float(scene.displacement_per_volt)
    h, m, beta = float(cfg["strength"]), float(cfg["exponent"]), float(cfg["background_exponent"])
    P = int(cfg["n_protocols"])
    ids = [f"M{p + 1:02d}" for p in range(P)]
    f0 = rng.uniform(*cfg["f0_range_Hz"], size=P)
    q = np.exp(rng.uniform(*np.log(cfg["q_range"]), size=P))
    n_steps = rng.integers(cfg["steps_range"][0], cfg["steps_range"][1] + 1, size=P)
    x_first = rng.uniform(*cfg["x_first_range"], size=P)
    x_max = rng.uniform(*cfg["x_max_range"], size=P)

    with jax.enable_x64(True):
        delta0 = np.asarray(hertz.overlap_from_frequency(jnp.asarray(f0), load, mass))

        def state(x: np.ndarray, lin: float) -> tuple[np.ndarray, np.ndarray]:
            xj = jnp.asarray(x, float)
            s = law.shift(xj, elastic=backbone_shift_clipped(xj, hertz.EXPONENT),
                          strength=h, exponent=m)
            om = 1.0 + np.asarray(s)
            loss = lin * om**beta + np.asarray(masing.loss_change(xj, strength=h,
                                                                  exponent=m))
            return om, loss

        rows: list[dict] = []
        truth_rows: list[dict] = []
        protocols: dict[str, dict] = {}
        for p, pid in enumerate(ids):
            lin = 1.0 / q[p]
            x_drive = np.geomspace(x_first[p], x_max[p], n_steps[p])
            om_d, loss_d = state(x_drive, lin)
            om_r, loss_r = state(np.array([cfg["x_reference"]]), lin)
            v_drive = significant(x_drive * loss_d * delta0[p] / (om_d**2 * d_per_v), 4)
            v_ref = float(significant(cfg["x_reference"] * loss_r * delta0[p]
                               / (om_r**2 * d_per_v), 4)[0])
            # the clean amplitude at the rounded voltage: the peak's x moves with V
            # (x L(x)/Omega^2 is monotone here), so solve it back by a few Newton steps
            x_d = _amplitude_at(v_drive * d_per_v / delta0[p], x_drive, state, lin)
            x_r = _amplitude_at(np.array([v_ref * d_per_v / delta0[p]]),
                                np.array([cfg["x_reference"]]), state, lin)
            om_d, _ = state(x_d, lin)
            om_r, loss_r = state(x_r, lin)
            f_ref = f0[p] * float(om_r[0])
            q_ref = 1.0 / float(loss_r[0])

            def sweep(step, kind, direction, volt, f_clean, a_clean, q_clean=math.nan,
                      pid=pid):
                f_obs = round(f_clean + rng.normal(0.0, cfg["noise_f_Hz"]), 2)
                a_obs = float(significant(a_clean * math.exp(
                    rng.normal(0.0, cfg["noise_amplitude_rel"])), 4)[0])
                q_obs = (round(q_clean * math.exp(rng.normal(0.0, cfg["noise_q_rel"])), 1)
                         if kind == "reference" else math.nan)
                rows.append({"protocol": pid, "step": step, "kind": kind,
                             "direction": direction, "drive_voltage_V": volt,
                             "f_res_Hz": f_obs, "amplitude_m": a_obs, "q_factor": q_obs})

            a_ref = float(x_r[0] * delta0[p])
            sweep(0, "reference", "up", v_ref, f_ref, a_ref, q_ref)
            for k in range(n_steps[p]):
                f_clean = f0[p] * float(om_d[k])
                a_clean = float(x_d[k] * delta0[p])
                for direction in ("up", "down"):
                    sweep(2 * k + 1, "drive", direction, float(v_drive[k]), f_clean, a_clean)
                    truth_rows.append({
                        "protocol": pid, "step": 2 * k + 1, "direction": direction,
                        "x": float(x_d[k]), "voltage": float(v_drive[k]),
                        "amplitude": a_clean, "f_res": f_clean, "shift": f_clean / f_ref - 1,
                        "inv_q_shift": (float(v_drive[k]) * a_ref / (v_ref * a_clean) - 1)
                        / q_ref, "excluded": False})
                sweep(2 * k + 2, "reference", "up", v_ref, f_ref, a_ref, q_ref)
            protocols[pid] = {"f0_linear_Hz": float(f0[p]), "delta0_m": float(delta0[p]),
                              "q": float(q[p]), "n_steps": int(n_steps[p]),
                              "f0_reference_Hz": f_ref, "q_reference": q_ref,
                              "ref_amplitude_m": a_ref, "ref_voltage_V": v_ref}

    truth = {
        "world": "hysteretic", "seed": int(seed), "generator": "data.worlds_loss",
        "kind": "physical",
        "model": "models.laws.hertz_hysteretic (Hertz backbone + Masing element) with a "
                 "background loss L0 Omega^beta, peaks at x = E Omega^2 / L(x)",
        "parameters": {**cfg, "displacement_per_volt_m_V": d_per_v},
        "law_parameters": _law_parameters(cfg),
        "protocols": protocols,
        "observables": {
            "note": "noiseless values: f0 (f0_reference_Hz) and q_ref (q_reference) per "
                    "protocol; per drive sweep f_res, amplitude, shift against the first "
                    "reference and Delta(1/Q) (Eq. 31)",
            "drive": {k: [r[k] for r in truth_rows] for k in truth_rows[0]},
        },
    }
    return pd.DataFrame(rows), scene_dict, truth


def _amplitude_at(drive: np.ndarray, guess: np.ndarray, state: Any, lin: float) -> np.ndarray:
    """x with x L(x)/Omega(x)^2 = drive (E), by secant steps from ``guess``."""
    x = np.asarray(guess, float).copy()

    def g(v: np.ndarray) -> np.ndarray:
        om, loss = state(v, lin)
        return v * loss / om**2 - drive

    x_prev, g_prev = x * 1.01, g(x * 1.01)
    for _ in range(30):
        gx = g(x)
        step = gx * (x - x_prev) / np.where(gx != g_prev, gx - g_prev, 1.0)
        x_prev, g_prev = x, gx
        x = np.maximum(x - step, 1e-6)
        if np.max(np.abs(step) / x) < 1e-12:
            break
    return x
