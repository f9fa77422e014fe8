"""Synthetic experiments with a recorded ground truth: the embedded datasets.

``paper_like`` is a phenomenological stand-in for the paper's 28 measured
protocols (Merkel et al. 2019, Figs. 1, 6, 7, 8, 10); see data/README.md. Per
protocol p:

* linear resonance f0_p ~ U(2.5, 3.0) kHz, wider than Hertz and JKR allow
  (Fig. 6), carried by the static overlap
  delta0_p = 3 F0 / (2 m (2 pi f0_p)^2)  (models.laws.hertz.overlap_from_frequency);
* linear Q_p log-uniform in [20, 100], independent of f0 (Fig. 8);
* drive steps k = 1..n_p (n_p in 4..12), x_k = delta_a/delta0_p geometric up to
  x_max,p in [0.5, 1]; drive voltage V = x delta0_p / (Q_p d) with d the scene's
  base displacement per volt, so delta_a = Q_p d V (a linear loss: Delta(1/Q) = 0);
* shift s(x) = models.laws.viscoelastic.shift_paper_eq25(x, A, omega0_p), the paper's
  eta = 1.05 MPa s curve as the paper computed it (A from
  models.laws.viscoelastic.damping_constant with E = 210 GPa, the paper's Sec. 6 value);
  up sweeps read s (1 - h x), down sweeps s (1 + h x) (softening hysteresis);
* after drive step k the linear resonance drifts to f0_p (1 + c_p x_k^2) with
  |c_p| <= 1.2 % (slow wear); in four protocols it also drops by 2.5-4 % after one
  step in the second half (and 0.5 % more per later step): they trip the 2 % rule;
* a low-amplitude reference sweep (x = 0.01, up) starts the protocol and follows
  every drive step;
* noise: frequency N(0, 2 Hz), amplitude and Q log-normal (3 %, 5 %); values
  rounded as an analyser would print them.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from beadrod.data.rounding import significant

__all__ = ["WORLDS", "DEFAULT_SEED", "generate", "write_world", "world_names",
           "world_parameters", "check_overrides", "WorldParameterError"]

DEFAULT_SEED = 441
"""Seed of the embedded folders (the paper's volume, J. Sound Vib. 441)."""

WORLDS: dict[str, str] = {
    "paper_like": "phenomenological stand-in for the paper's 28 protocols (default)",
    "hertz_dynamics": "physical: harmonic-balance stepped sweeps of a damped Hertz contact",
    "hysteretic": "physical: Hertz with Masing hysteresis, loss growing with the "
                  "amplitude (data.worlds_loss)",
}

_PAPER_LIKE = {
    "n_protocols": 28,
    "eta_Pa_s": 1.05e6,
    "young_for_A_Pa": 210e9,
    "f0_range_Hz": [2500.0, 3000.0],
    "q_range": [20.0, 100.0],
    "steps_range": [4, 12],
    "x_first_range": [0.02, 0.06],
    "x_max_range": [0.5, 1.0],
    "x_reference": 0.01,
    "hysteresis_h": 0.15,
    "drift_sigma": 0.003,
    "n_tripping": 4,
    "tripping_jump_range": [0.025, 0.04],
    "noise_f_Hz": 2.0,
    "noise_amplitude_rel": 0.03,
    "noise_q_rel": 0.05,
}


_HERTZ_DYNAMICS = {
    "n_protocols": 16,
    "f0_range_Hz": [2500.0, 3000.0],
    "q_range": [20.0, 100.0],
    "steps_range": [3, 6],
    "x_first_range": [0.02, 0.05],
    "x_max_range": [0.2, 0.38],
    "x_reference": 0.01,
    "omega_grid": [0.86, 1.06, 0.0008],
    "harmonics": 3,
    "noise_curve_rel": 0.01,
}


def world_names() -> list[str]:
    return list(WORLDS)


def _rounded(obj: Any, digits: int = 12) -> Any:
    """Floats in a nested structure rounded to ``digits`` significant figures, so that
    truth.json does not change with last-bit differences of the physics code."""
    if isinstance(obj, dict):
        return {k: _rounded(v, digits) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_rounded(v, digits) for v in obj]
    if isinstance(obj, (float, np.floating)):
        return float(f"{float(obj):.{digits - 1}e}") if math.isfinite(obj) else float(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def _paper_scene(world: str = "paper_like") -> tuple[Any, dict]:
    from beadrod.models import scene as scenes

    d = scenes.scene_to_dict(scenes.builtin_scene("paper"))
    d["name"] = world
    d["description"] = (f"The paper's setup (built-in scene 'paper') for the synthetic {world} "
                        "world; drive range widened to 1 mV - 2 V to hold the world's voltages")
    d["drive"]["voltage_min_V"] = 1e-3
    d["drive"]["voltage_max_V"] = 2.0
    return scenes.scene_from_dict(d, "paper_like"), d


def _paper_like(seed: int, **overrides: Any) -> tuple[pd.DataFrame, dict, dict]:
    import jax
    import jax.numpy as jnp

    from beadrod.models.laws import hertz, viscoelastic

    cfg = {**_PAPER_LIKE, **overrides}
    rng = np.random.default_rng(seed)
    scene, scene_dict = _paper_scene()
    mass, load = float(scene.mass), float(scene.load)
    nu = float(scene.bead_material.poisson)
    d_per_v = float(scene.displacement_per_volt)
    P = cfg["n_protocols"]
    ids = [f"P{p + 1:02d}" for p in range(P)]
    f0 = rng.uniform(*cfg["f0_range_Hz"], size=P)
    q = np.exp(rng.uniform(*np.log(cfg["q_range"]), size=P))
    n_steps = rng.integers(cfg["steps_range"][0], cfg["steps_range"][1] + 1, size=P)
    x_first = rng.uniform(*cfg["x_first_range"], size=P)
    x_max = rng.uniform(*cfg["x_max_range"], size=P)
    drift_c = np.clip(rng.normal(0.0, cfg["drift_sigma"], size=P), -0.012, 0.012)
    tripping = np.sort(rng.choice(P, size=cfg["n_tripping"], replace=False))
    trip_after = {int(p): int(rng.integers((n_steps[p] + 1) // 2, n_steps[p] - 1))
                  for p in tripping}
    jump = dict(zip(trip_after, rng.uniform(*cfg["tripping_jump_range"], size=len(tripping))))

    design = []
    for p in range(P):
        delta0 = 1.5 * load / (mass * (2.0 * math.pi * f0[p]) ** 2)
        v_drive = significant(np.geomspace(x_first[p], x_max[p], n_steps[p]) * delta0
                       / (q[p] * d_per_v), 4)
        v_ref = float(significant(cfg["x_reference"] * delta0 / (q[p] * d_per_v), 4)[0])
        design.append((v_drive, v_ref))
    with jax.enable_x64(True):
        a_damp = float(viscoelastic.damping_constant(
            eta1=cfg["eta_Pa_s"], eta2=cfg["eta_Pa_s"], young=cfg["young_for_A_Pa"], poisson=nu))
        # delta0_p that f0_p implies under the weight (the scatter of the paper's Fig. 6)
        delta0 = np.asarray(hertz.overlap_from_frequency(jnp.asarray(f0), load, mass), np.float64)
        x_all = np.concatenate([q[p] * d_per_v * np.append(v, vr) / delta0[p]
                                for p, (v, vr) in enumerate(design)])
        om_all = np.concatenate([np.full(n_steps[p] + 1, 2.0 * math.pi * f0[p])
                                 for p in range(P)])
        s_all = np.asarray(viscoelastic.shift_paper_eq25(
            jnp.asarray(x_all), damping_constant=a_damp, omega=jnp.asarray(om_all)), np.float64)
    bounds = np.concatenate([[0], np.cumsum(n_steps + 1)])

    rows: list[dict] = []
    truth_rows: list[dict] = []
    protocols: dict[str, dict] = {}
    h = cfg["hysteresis_h"]
    for p, pid in enumerate(ids):
        v_drive, v_ref = design[p]
        x_true = x_all[bounds[p]:bounds[p + 1] - 1]
        s_drive, s_ref = s_all[bounds[p]:bounds[p + 1] - 1], float(s_all[bounds[p + 1] - 1])
        # drift of the linear resonance after each drive step: slow wear ~ x^2 for all,
        # plus a jump (> 2 %) after one step of the tripping protocols
        drift = drift_c[p] * np.maximum.accumulate(x_true) ** 2
        if p in trip_after:
            k0 = trip_after[p]
            drift[k0:] -= jump[p] + 0.005 * np.arange(n_steps[p] - k0)
        f_lin = f0[p] * (1.0 + np.concatenate([[0.0], drift]))  # before drive k = 0..n
        ref_f = f_lin * (1.0 + s_ref)
        a_ref_clean = q[p] * d_per_v * v_ref

        def sweep(step, kind, direction, volt, f_clean, a_clean, pid=pid, qp=q[p]):
            f_obs = round(f_clean + rng.normal(0.0, cfg["noise_f_Hz"]), 2)
            noise = math.exp(rng.normal(0.0, cfg["noise_amplitude_rel"]))
            a_obs = float(significant(a_clean * noise, 4)[0])
            q_obs = (round(qp * math.exp(rng.normal(0.0, cfg["noise_q_rel"])), 1)
                     if kind == "reference" else math.nan)
            rows.append({"protocol": pid, "step": step, "kind": kind, "direction": direction,
                         "drive_voltage_V": volt, "f_res_Hz": f_obs, "amplitude_m": a_obs,
                         "q_factor": q_obs})

        sweep(0, "reference", "up", v_ref, ref_f[0], a_ref_clean)
        first_trip = None
        for k in range(n_steps[p]):
            a_clean = q[p] * d_per_v * v_drive[k]
            for direction, sign in (("up", -1.0), ("down", 1.0)):
                f_clean = f_lin[k] * (1.0 + s_drive[k] * (1.0 + sign * h * x_true[k]))
                sweep(2 * k + 1, "drive", direction, float(v_drive[k]), f_clean, a_clean)
                truth_rows.append({
                    "protocol": pid, "step": 2 * k + 1, "direction": direction,
                    "x": float(x_true[k]), "voltage": float(v_drive[k]), "amplitude": a_clean,
                    "f_res": f_clean, "shift": f_clean / ref_f[0] - 1.0,
                    "shift_model": float(s_drive[k]), "inv_q_shift": 0.0,
                    "excluded": first_trip is not None})
            sweep(2 * k + 2, "reference", "up", v_ref, ref_f[k + 1], a_ref_clean)
            if first_trip is None and abs(ref_f[k + 1] / ref_f[0] - 1.0) > 0.02:
                first_trip = 2 * k + 2
        protocols[pid] = {
            "f0_linear_Hz": float(f0[p]), "delta0_m": float(delta0[p]), "q": float(q[p]),
            "n_steps": int(n_steps[p]), "x_max": float(x_true[-1]),
            "drift_coefficient": float(drift_c[p]),
            "jump_after_drive_step": (2 * trip_after[p] + 1) if p in trip_after else None,
            "first_tripping_reference_step": first_trip,
            "f0_reference_Hz": float(ref_f[0]), "ref_voltage_V": v_ref,
            "ref_amplitude_m": float(a_ref_clean)}

    truth = {
        "world": "paper_like", "seed": int(seed), "generator": "data.synth",
        "kind": "phenomenological",
        "shift_law": "models.laws.viscoelastic.shift_paper_eq25(x, damping_constant=A, "
                     "omega=2 pi f0_p), x = delta_a / delta0_p; up sweeps s (1 - h x), "
                     "down sweeps s (1 + h x)",
        "parameters": {**cfg, "damping_constant_A_s": a_damp,
                       "displacement_per_volt_m_V": d_per_v,
                       "tripping_protocols": [ids[i] for i in tripping]},
        "protocols": protocols,
        "observables": {
            "note": "noiseless values of what data.process returns: f0 (f0_reference_Hz) and "
                    "q_ref (q) per protocol; per drive sweep f_res, amplitude, shift against "
                    "the first reference, Delta(1/Q) (Eq. 31), and whether the 2 % rule drops it",
            "drive": {k: [r[k] for r in truth_rows] for k in truth_rows[0]},
        },
    }
    return pd.DataFrame(rows), scene_dict, truth


def _hbm_sweeps(zeta: np.ndarray, drive: np.ndarray, down: np.ndarray, cfg: dict):
    """First-harmonic amplitude x(Omega) of stepped HBM sweeps
    (models.ladder.harmonic_balance.sweep), batched.

    Returns (Omega grid ascending (F,), x on that grid (S, F), converged (S,))."""
    import jax
    import jax.numpy as jnp

    from beadrod.models.ladder import harmonic_balance, oscillator

    lo, hi, step = cfg["omega_grid"]
    om = np.arange(lo, hi + 0.5 * step, step)
    h = cfg["harmonics"]

    def one(z, e, rev):
        o = jnp.where(rev, jnp.asarray(om)[::-1], jnp.asarray(om))
        xs, ok = harmonic_balance.sweep(oscillator.hertz_oscillator(z), e, o, harmonics=h)
        amp = jnp.sqrt(xs[:, 1] ** 2 + xs[:, 2] ** 2)
        return jnp.where(rev, amp[::-1], amp), jnp.all(ok)

    with jax.enable_x64(True):
        x, ok = jax.jit(jax.vmap(one))(jnp.asarray(zeta), jnp.asarray(drive), jnp.asarray(down))
        return om, np.asarray(x, np.float64), np.asarray(ok)


def _hertz_dynamics(seed: int, **overrides: Any) -> tuple[pd.DataFrame, dict, dict]:
    """Physical world: each sweep a stepped harmonic-balance sweep (ladder rung 4) of the
    base-excited Hertz oscillator with a linear contact dashpot (Q_p = 1/(2 zeta_p)),
    read by :func:`data.extract.extract_resonance` from the curve with 1 % vibrometer
    noise per point. Per-protocol delta0_p scatter (local curvature/modulus of the
    contact) sets f0_p = (1/2 pi)(3 g / (2 delta0_p))^(1/2)."""
    from beadrod.data.extract import extract_resonance

    cfg = {**_HERTZ_DYNAMICS, **overrides}
    rng = np.random.default_rng(seed)
    scene, scene_dict = _paper_scene("hertz_dynamics")
    mass, load = float(scene.mass), float(scene.load)
    d_per_v = float(scene.displacement_per_volt)
    P = cfg["n_protocols"]
    ids = [f"H{p + 1:02d}" for p in range(P)]
    f0 = rng.uniform(*cfg["f0_range_Hz"], size=P)
    q = np.exp(rng.uniform(*np.log(cfg["q_range"]), size=P))
    n_steps = rng.integers(cfg["steps_range"][0], cfg["steps_range"][1] + 1, size=P)
    x_first = rng.uniform(*cfg["x_first_range"], size=P)
    x_max = rng.uniform(*cfg["x_max_range"], size=P)
    delta0 = 1.5 * load / (mass * (2.0 * math.pi * f0) ** 2)  # Hertz: K0 = (3/2) F0/delta0

    sweeps = []  # (p, step, kind, direction, voltage)
    for p in range(P):
        v_drive = significant(np.geomspace(x_first[p], x_max[p], n_steps[p]) * delta0[p]
                       / (q[p] * d_per_v), 4)
        v_ref = float(significant(cfg["x_reference"] * delta0[p] / (q[p] * d_per_v), 4)[0])
        sweeps.append((p, 0, "reference", "up", v_ref))
        for k, v in enumerate(v_drive):
            sweeps += [(p, 2 * k + 1, "drive", "up", float(v)),
                       (p, 2 * k + 1, "drive", "down", float(v))]
            sweeps.append((p, 2 * k + 2, "reference", "up", v_ref))
    sp = np.array([s[0] for s in sweeps])
    volt = np.array([s[4] for s in sweeps])
    om, x, ok = _hbm_sweeps(0.5 / q[sp], d_per_v * volt / delta0[sp],
                            np.array([s[3] == "down" for s in sweeps]), cfg)
    if not ok.all():
        raise RuntimeError(f"{int((~ok).sum())} HBM sweeps did not converge")

    rows, truth_rows = [], []
    clean_ref: dict[int, tuple[float, float]] = {}
    for i, (p, step, kind, direction, v) in enumerate(sweeps):
        f = om * f0[p]
        clean = extract_resonance(f, x[i] * delta0[p])
        noisy = extract_resonance(f, x[i] * delta0[p] * np.exp(
            rng.normal(0.0, cfg["noise_curve_rel"], size=om.size)))
        rows.append({"protocol": ids[p], "step": step, "kind": kind, "direction": direction,
                     "drive_voltage_V": v, "f_res_Hz": round(noisy.f_res, 2),
                     "amplitude_m": float(significant(noisy.amplitude, 4)[0]),
                     "q_factor": round(noisy.q, 1) if kind == "reference" else math.nan})
        if kind == "reference" and step == 0:
            clean_ref[p] = (clean.f_res, clean.amplitude, clean.q, v)
        if kind == "drive":
            fr, ar, qr, vr = clean_ref[p]
            truth_rows.append({
                "protocol": ids[p], "step": step, "direction": direction,
                "x": clean.amplitude / delta0[p], "voltage": v, "amplitude": clean.amplitude,
                "f_res": clean.f_res, "shift": clean.f_res / fr - 1.0,
                "inv_q_shift": (v * ar / (vr * clean.amplitude) - 1.0) / qr, "excluded": False})
    protocols = {ids[p]: {
        "f0_linear_Hz": float(f0[p]), "delta0_m": float(delta0[p]), "q": float(q[p]),
        "zeta": float(0.5 / q[p]), "n_steps": int(n_steps[p]),
        "f0_reference_Hz": clean_ref[p][0], "q_reference": clean_ref[p][2],
        "ref_amplitude_m": clean_ref[p][1], "ref_voltage_V": clean_ref[p][3]} for p in range(P)}
    truth = {
        "world": "hertz_dynamics", "seed": int(seed), "generator": "data.synth",
        "kind": "physical",
        "model": "models.ladder.harmonic_balance.sweep of "
                 "models.ladder.oscillator.hertz_oscillator(zeta_p) (base-excited Hertz "
                 "oscillator, unilateral contact, linear dashpot), stepped sweeps up and down",
        "parameters": {**cfg, "displacement_per_volt_m_V": d_per_v},
        "protocols": protocols,
        "observables": {
            "note": "values read from the noiseless curves with data.extract: f0 "
                    "(f0_reference_Hz) and q_ref (q_reference) per protocol; per drive sweep "
                    "f_res, amplitude, shift against the first reference and Delta(1/Q)",
            "drive": {k: [r[k] for r in truth_rows] for k in truth_rows[0]},
        },
    }
    return pd.DataFrame(rows), scene_dict, truth


class WorldParameterError(ValueError):
    """A world parameter override that the world does not have, or of the wrong kind."""


def world_parameters(world: str) -> dict[str, Any]:
    """The parameters of ``world`` that :func:`generate` can override, with their defaults
    (a copy: strengths, exponents, ranges [low, high], counts, noise levels)."""
    if world not in WORLDS:
        raise ValueError(f"unknown world {world!r}; known: {', '.join(WORLDS)}")
    if world == "hysteretic":
        from beadrod.data.worlds_loss import HYSTERETIC

        return dict(HYSTERETIC)
    return dict(_HERTZ_DYNAMICS if world == "hertz_dynamics" else _PAPER_LIKE)


def _number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _checked(world: str, overrides: dict[str, Any]) -> dict[str, Any]:
    """``overrides`` checked against the world's defaults: known names, the same kind of
    value (an integer for a count, a number, or a list of as many numbers, in increasing
    order for a range), never negative. The physics checks the rest when it runs."""
    base = world_parameters(world)
    out: dict[str, Any] = {}
    for key, value in overrides.items():
        if key not in base:
            raise WorldParameterError(
                f"world {world!r} has no parameter {key!r}; it has: {', '.join(base)}")
        default = base[key]
        where = f"world {world!r} parameter {key!r}"
        if isinstance(default, list):
            if not (isinstance(value, list | tuple) and len(value) == len(default)
                    and all(_number(v) for v in value)):
                raise WorldParameterError(
                    f"{where} takes a list of {len(default)} numbers, got {value!r}")
            value = [type(d)(v) if isinstance(d, int) else float(v)
                     for d, v in zip(default, value)]
            if key.endswith("_range") or "_range_" in key:
                if value[0] > value[1]:
                    raise WorldParameterError(f"{where}: a range [low, high] with "
                                              f"low <= high, got {value!r}")
        elif isinstance(default, int):
            if not (_number(value) and float(value).is_integer()):
                raise WorldParameterError(f"{where} takes an integer, got {value!r}")
            value = int(value)
        elif not _number(value):
            raise WorldParameterError(f"{where} takes a finite number, got {value!r}")
        else:
            value = float(value)
        if any(v < 0 for v in (value if isinstance(value, list) else [value])):
            raise WorldParameterError(f"{where} must not be negative, got {value!r}")
        out[key] = value
    merged = {**base, **out}
    if merged.get("n_protocols", 1) < 1:
        raise WorldParameterError(f"world {world!r} needs n_protocols >= 1")
    if merged.get("n_tripping", 0) > merged["n_protocols"]:
        raise WorldParameterError(
            f"world {world!r}: n_tripping ({merged['n_tripping']}) exceeds n_protocols "
            f"({merged['n_protocols']})")
    return out


def check_overrides(world: str, overrides: dict[str, Any]) -> dict[str, Any]:
    """``overrides`` of ``world``'s parameters checked as :func:`generate` checks them,
    without making the world: the values as the world takes them (integers for counts,
    floats otherwise), or :class:`WorldParameterError` naming the world and parameter."""
    if world not in WORLDS:
        raise WorldParameterError(f"unknown world {world!r}; known: {', '.join(WORLDS)}")
    return _checked(world, dict(overrides))


def generate(
    world: str = "paper_like", seed: int = DEFAULT_SEED,
    overrides: dict[str, Any] | None = None,
) -> tuple[pd.DataFrame, dict, dict]:
    """(measurement table, scene dict, truth dict) of a synthetic world; ``overrides``
    replace entries of :func:`world_parameters` (recorded in the truth)."""
    if world not in WORLDS:
        raise ValueError(f"unknown world {world!r}; known: {', '.join(WORLDS)}")
    overrides = check_overrides(world, overrides or {})
    if world == "hysteretic":
        from beadrod.data.worlds_loss import hysteretic

        scene, scene_dict = _paper_scene(world)
        table, scene_dict, truth = hysteretic(int(seed), scene, scene_dict, **overrides)
    else:
        table, scene_dict, truth = (_hertz_dynamics if world == "hertz_dynamics"
                                    else _paper_like)(int(seed), **overrides)
    if overrides:
        truth["overrides"] = overrides
    return table, scene_dict, _rounded(truth)


def write_world(world: str, out_dir: str | Path, seed: int = DEFAULT_SEED,
                overrides: dict[str, Any] | None = None) -> Path:
    """Generate a world and write it as a dataset folder; return the folder."""
    from beadrod.data.load import write_dataset

    table, scene_dict, truth = generate(world, seed, overrides)
    return write_dataset(out_dir, table, scene_dict, truth)
