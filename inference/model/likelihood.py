"""Observation models shared by the contact-law models, and the data they consume.

``model_inputs(ds)`` turns a ProcessedDataset (or any object with the same fields)
into the dict of arrays every model takes; observations live under ``f0``, ``shift``,
``q_obs`` and (where the dataset has amplitude ratios, :mod:`inference.model.amplitude`)
``amp_obs``, and are set to None by :func:`without_observations` for prior predictive
simulation. Q is observed only where the protocol has one (NaN rows are dropped
here, once, so shapes stay static under jit); with no Q at all there is no Q site.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np
import numpyro
import numpyro.distributions as dist

from beadrod.inference.model.amplitude import amplitude_inputs
from beadrod.models.registry import get_law, law_names

__all__ = ["model_inputs", "without_observations", "observe_shift", "observe_logq",
           "design_inputs", "simulate", "scene_quantities", "sweep_layout", "SWEEP_LAYOUT_KEYS",
           "OBSERVED_SITES", "OBSERVED_DATA_KEYS"]

OBSERVED_SITES = ("f0_obs", "shift_obs", "q_obs", "amp_obs")
OBSERVED_DATA_KEYS = {"f0_obs": "f0", "shift_obs": "shift", "q_obs": "q_obs",
                      "amp_obs": "amp_obs"}
"""The model input that holds each observation site's values."""


def model_inputs(ds: Any) -> dict[str, Any]:
    """Arrays (float64) a model needs from a processed dataset.

    Needs ``f0``, ``q_ref``, ``drive_protocol``, ``drive_direction``, ``drive_amplitude``,
    ``drive_shift`` and a ``scene`` with ``mass``, ``load``, ``radius``, ``bead_material``,
    ``rod_material`` (Poisson ratios; E is inferred and taken equal for bead and rod).
    """
    f0 = np.asarray(ds.f0, float)
    q_ref = np.asarray(ds.q_ref, float)
    q_idx = np.flatnonzero(np.isfinite(q_ref))
    amp = np.asarray(ds.drive_amplitude, float)
    shift = np.asarray(ds.drive_shift, float)
    if not (np.all(np.isfinite(amp)) and np.all(amp > 0)):
        raise ValueError("drive_amplitude must be finite and > 0 for every included sweep")
    if not np.all(np.isfinite(shift)):
        raise ValueError("drive_shift must be finite for every included sweep")
    if not np.all(np.isfinite(f0)):
        raise ValueError("f0 must be finite for every protocol")
    sc = ds.scene
    return {
        "f0": jnp.asarray(f0),
        "q_idx": jnp.asarray(q_idx, dtype=jnp.int32),
        "q_obs": jnp.asarray(q_ref[q_idx]),
        "proto": jnp.asarray(np.asarray(ds.drive_protocol), dtype=jnp.int32),
        "direction": jnp.asarray(np.asarray(ds.drive_direction), dtype=jnp.float64),
        "amplitude": jnp.asarray(amp),
        "shift": jnp.asarray(shift),
        "mass": float(sc.mass),
        "load": float(sc.load),
        "radius": float(sc.radius),
        "nu_bead": float(sc.bead_material.poisson),
        "nu_rod": float(sc.rod_material.poisson),
        "scene": scene_quantities(sc),
        **_jnp_layout(ds.drive_protocol, f0.size),
        **(amplitude_inputs(ds) if _has_amplitude_data(ds) else {}),
    }


def _has_amplitude_data(ds: Any) -> bool:
    # a dataset object without the reference amplitudes (built by hand) has no ratios
    return all(getattr(ds, k, None) is not None
               for k in ("drive_voltage", "ref_amplitude", "ref_voltage"))


SWEEP_LAYOUT_KEYS = ("sweep_grid", "sweep_valid", "sweep_position")
"""The model inputs that lay the sweeps out by protocol (:func:`sweep_layout`)."""


def sweep_layout(proto: Any, n_protocols: int) -> dict[str, np.ndarray]:
    """The sweeps laid out as a (protocol, slot) grid, K = most sweeps of one protocol.

    ``sweep_grid`` (P, K): the sweep in each slot (a padding slot repeats index 0);
    ``sweep_valid`` (P, K): True in the slots that hold a sweep; ``sweep_position``
    (n_sweeps,): each sweep's slot in the flattened grid. Why: a law whose backbone shape
    depends on the protocol (its delta0) then evaluates the shape's per-protocol part once
    per protocol, not once per sweep, and no per-sweep gather of delta0 enters the
    gradient (the rough sphere's likelihood gradient: measured in docs/bench)."""
    proto = np.asarray(proto, int).reshape(-1)
    n_p = int(n_protocols)
    if proto.size and (proto.min() < 0 or proto.max() >= n_p):
        raise ValueError(f"sweep protocol indices must lie in [0, {n_p}), got "
                         f"[{proto.min()}, {proto.max()}]")
    counts = np.bincount(proto, minlength=n_p)
    k = max(int(counts.max(initial=0)), 1)
    grid = np.zeros((n_p, k), np.int32)
    valid = np.zeros((n_p, k), bool)
    position = np.zeros(proto.size, np.int32)
    fill = np.zeros(n_p, int)
    for i, p in enumerate(proto):
        grid[p, fill[p]] = i
        valid[p, fill[p]] = True
        position[i] = p * k + fill[p]
        fill[p] += 1
    return {"sweep_grid": grid, "sweep_valid": valid, "sweep_position": position}


def _jnp_layout(proto: Any, n_protocols: int) -> dict[str, Any]:
    return {k: jnp.asarray(v) for k, v in sweep_layout(proto, n_protocols).items()}


def scene_quantities(sc: Any) -> dict[str, float]:
    """The scene quantities a contact law may ask for by name (models.law.SCENE_KEYS):
    radius [m], young [Pa] and poisson [-] of the bead (bead and rod are taken to be the
    same material), load [N], mass [kg], gravity [m/s^2], roughness_rms [m],
    surface_energy [J/m^2]."""
    return {"radius": float(sc.radius), "young": float(sc.bead_material.young),
            "poisson": float(sc.bead_material.poisson), "load": float(sc.load),
            "mass": float(sc.mass), "gravity": float(sc.gravity),
            "roughness_rms": float(sc.roughness_rms),
            "surface_energy": float(sc.surface_energy)}


def without_observations(inputs: dict[str, Any]) -> dict[str, Any]:
    """Copy of ``inputs`` with the observed values removed (prior predictive)."""
    out = dict(inputs)
    if inputs.get("f0") is not None:
        out["n_protocols"] = int(inputs["f0"].shape[0])
    for k in ("f0", "shift", "q_obs", "amp_obs"):
        if k in inputs or k != "amp_obs":
            out[k] = None
    return out


def observe_shift(pred: jnp.ndarray, sigma: jnp.ndarray, obs: jnp.ndarray | None, *,
                  likelihood: str, df: float) -> jnp.ndarray:
    """Delta f/f0 ~ Normal(pred, sigma) or StudentT(df, pred, sigma) (robust option)."""
    if likelihood == "normal":
        d = dist.Normal(pred, sigma)
    elif likelihood == "student_t":
        d = dist.StudentT(df, pred, sigma)
    else:
        raise ValueError(f"likelihood must be 'normal' or 'student_t', got {likelihood!r}")
    with numpyro.plate("sweeps", pred.shape[0]):
        return numpyro.sample("shift_obs", d, obs=obs)


def observe_logq(log_q_pred: jnp.ndarray, sigma: jnp.ndarray, obs: jnp.ndarray | None, *,
                 likelihood: str, df: float) -> jnp.ndarray:
    """Q ~ LogNormal(log Q_pred, sigma) (Q is positive and scatters multiplicatively).

    The Student-t option puts the t on log Q (a log-t), exp-transformed. With no
    protocol to observe (a dataset without Q) there is no site: an empty plate cannot be
    built, and an empty observation adds nothing to the likelihood.
    """
    if log_q_pred.shape[0] == 0:
        return log_q_pred
    if likelihood == "normal":
        d = dist.LogNormal(log_q_pred, sigma)
    else:
        d = dist.TransformedDistribution(dist.StudentT(df, log_q_pred, sigma),
                                         dist.transforms.ExpTransform())
    with numpyro.plate("q_protocols", log_q_pred.shape[0]):
        return numpyro.sample("q_obs", d, obs=obs)


def design_inputs(scene: Any, *, n_protocols: int, amplitudes: Any,
                  directions: tuple[int, ...] = (0, 1), q_every: int = 1,
                  amplitude_ratios: bool = False, ref_amplitude: float = 0.3e-9,
                  q_plugin: float = 45.0) -> dict[str, Any]:
    """An experiment design without observations: every protocol is swept at the
    drive amplitudes ``amplitudes`` [m] in each of ``directions``; Q is observed on
    every ``q_every``-th protocol. Fill the observations with :func:`simulate`.

    ``amplitude_ratios``: every sweep also reads its amplitude per volt against the
    protocol's reference sweep at ``ref_amplitude`` [m] (inference.model.amplitude), with
    the linear Q ``q_plugin`` [-] standing for the measured reference Q of laws that
    predict none.
    """
    amps = np.asarray(amplitudes, float)
    proto, direc, amp = [], [], []
    for p in range(n_protocols):
        for d in directions:
            proto += [p] * len(amps)
            direc += [d] * len(amps)
            amp += list(amps)
    q_idx = np.arange(0, n_protocols, q_every)
    ratios = {} if not amplitude_ratios else {
        "amp_obs": None, "amp_idx": jnp.arange(len(proto), dtype=jnp.int32),
        "amp_proto": jnp.asarray(proto, dtype=jnp.int32),
        "ref_amplitude": jnp.full(n_protocols, float(ref_amplitude)),
        "q_plugin": jnp.full(n_protocols, float(q_plugin))}
    return {
        **ratios,
        "f0": None, "q_obs": None, "shift": None, "n_protocols": int(n_protocols),
        "q_idx": jnp.asarray(q_idx, dtype=jnp.int32),
        "proto": jnp.asarray(proto, dtype=jnp.int32),
        "direction": jnp.asarray(direc, dtype=jnp.float64),
        "amplitude": jnp.asarray(amp),
        "mass": float(scene.mass), "load": float(scene.load), "radius": float(scene.radius),
        "nu_bead": float(scene.bead_material.poisson),
        "nu_rod": float(scene.rod_material.poisson),
        "scene": scene_quantities(scene),
        **_jnp_layout(proto, n_protocols),
    }


def simulate(model: Any, design: dict[str, Any], truth: dict[str, Any],
             seed: int = 0) -> tuple[dict[str, Any], dict[str, Any]]:
    """Observations drawn from ``model`` with its latent sites fixed at ``truth``
    (sites not in ``truth`` are drawn from their priors); returns the model inputs
    with ``f0``, ``shift``, ``q_obs`` and ``amp_obs`` filled, and the values of every sample and
    deterministic site of the simulating trace (the truth, delta0 included).
    """
    import jax
    from numpyro import handlers

    spec = getattr(model, "spec", None)
    if spec is not None and spec.law in law_names():
        # a parameter sampled scaled (models.law.SamplerHints.scales) is conditioned
        # at its sample site
        truth = get_law(spec.law).sampler_values(truth)
    cond = handlers.condition(model, data={k: jnp.asarray(v) for k, v in truth.items()})
    tr = handlers.trace(handlers.seed(cond, jax.random.PRNGKey(seed))).get_trace(design)
    # a value for a site that is not sampled (a deterministic, a misspelling) would be
    # silently ignored: refuse it
    ignored = sorted(k for k in truth if tr.get(k, {}).get("type") != "sample")
    if ignored:
        raise ValueError(f"simulate: {ignored} are not sample sites of the model; its "
                         "sample sites are "
                         f"{sorted(k for k, s in tr.items() if s['type'] == 'sample')}")
    out = dict(design)
    out.pop("n_protocols", None)
    out["f0"] = tr["f0_obs"]["value"]
    if "shift_obs" in tr:
        out["shift"] = tr["shift_obs"]["value"]
    if "q_obs" in tr:
        out["q_obs"] = tr["q_obs"]["value"]
    if "amp_obs" in tr:
        out["amp_obs"] = tr["amp_obs"]["value"]
    values = {k: s["value"] for k, s in tr.items() if s["type"] in ("sample", "deterministic")}
    return out, values
