"""Figures of ``beadrod compare`` assembled from the fits, the data and ``models/``.

Theory curves come from the same ``models/`` functions the NumPyro models call;
posterior predictive bands come from the InferenceData files, never re-simulated
with a second copy of a formula.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from . import plots

__all__ = ["make_figures", "theory_curves"]

log = logging.getLogger("beadrod")


def theory_curves(scene: Any, x: np.ndarray) -> dict[str, np.ndarray]:
    """Delta f/f0 versus x = delta_a/delta0 for each law at the scene's nominal values
    (the paper's Fig. 4, plus the exact backbone)."""
    import jax.numpy as jnp

    from models import backbone, hertz, jkr, shift, viscoelastic

    xj = jnp.asarray(x)
    curves = {
        "Hertz, first order": np.asarray(shift.first_order_hertz(xj)),
        "Hertz, exact backbone": np.asarray(backbone.backbone_shift(xj, 1.5)),
    }
    e_star, radius, load, mass = (float(scene.e_star), float(scene.radius), float(scene.load),
                                  float(scene.mass))
    if scene.surface_energy:
        kw = {"e_star": e_star, "radius": radius, "gamma": float(scene.surface_energy)}
        curves["JKR, first order"] = np.asarray(jkr.shift_first_order(xj, load=load, **kw))
    if scene.viscosity:
        young, nu = scene.bead_material.young, scene.bead_material.poisson
        a = viscoelastic.damping_constant(eta1=scene.viscosity, eta2=scene.viscosity,
                                          young=young, poisson=nu)
        omega0 = 2 * np.pi * float(hertz.linear_frequency(load, mass, e_star=e_star,
                                                           radius=radius))
        curves[f"viscoelastic, paper Eq. 25 (eta = {scene.viscosity:.3g} Pa s)"] = np.asarray(
            viscoelastic.shift_paper_eq25(xj, damping_constant=a, omega=omega0))
    return curves


def _bands_from_ppc(idata: Any, x: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    rep = np.asarray(idata.posterior_predictive["shift_obs"])
    rep = rep.reshape(-1, rep.shape[-1])
    order = np.argsort(x)
    q = np.percentile(rep[:, order], [5, 50, 95], axis=0)
    return x[order], (q[0], q[1], q[2])


def make_figures(runs: dict[str, Any], inputs: dict[str, Any], ds: Any, result: dict[str, Any],
                 out: Path) -> list[dict[str, Any]]:
    """Write every figure into ``out/figures`` and return their report entries."""
    from models import jkr, shift
    from models.backbone import backbone_shift
    from models.hertz import linear_frequency as hertz_f0
    from models.materials import effective_modulus

    fig_dir = out / "figures"
    entries: list[dict[str, Any]] = []

    def save(fig, name: str, caption: str, section: str) -> None:
        plots.save_figure(fig, fig_dir / name)
        entries.append({"path": f"figures/{name}.png", "caption": caption, "section": section})

    scene = ds.scene
    x_grid = np.linspace(1e-3, 1.3, 200)
    save(plots.fig_shift_curves(x_grid, theory_curves(scene, x_grid)), "theory_shift",
         "Predicted Delta f/f0 versus delta_a/delta0 for each law at the scene's nominal "
         "parameters (paper Fig. 4), with the exact backbone for comparison.", "theory")
    n = np.linspace(1.01, 3.0, 120)
    save(plots.fig_max_shift_vs_n(n, np.asarray(shift.first_order_powerlaw(1.0, n))),
         "max_shift_vs_n", "First-order shift at delta_a = delta0 versus the power-law "
         "exponent n (paper Fig. 5).", "theory")
    del backbone_shift  # imported to fail early if the backbone is missing

    # Measured f0 against each law's range over the scene's E range (paper Fig. 6).
    lo_hi = scene.young_range or (scene.bead_material.young, scene.bead_material.young)
    nu = scene.bead_material.poisson
    ranges = {}
    for label, fn in (("Hertz", lambda es: hertz_f0(scene.load, scene.mass, e_star=es,
                                                    radius=scene.radius)),
                      ("JKR", lambda es: jkr.linear_frequency(
                          scene.load, scene.mass, e_star=es, radius=scene.radius,
                          gamma=scene.surface_energy or 0.7))):
        vals = [float(fn(effective_modulus(e, nu))) for e in lo_hi]
        ranges[label] = (min(vals), max(vals))
    save(plots.fig_f0_ranges(ds.f0, ranges), "f0_ranges",
         "Measured linear resonance of each protocol against the Hertz and JKR ranges for "
         "the scene's Young's modulus range (paper Fig. 6).", "data")
    save(plots.fig_q_vs_f0(ds.f0, ds.q_ref), "q_vs_f0",
         "Reference Q versus linear resonance per protocol (paper Fig. 8).", "data")
    x_data = ds.normalized_amplitude("weight")
    save(plots.fig_inv_q_shift(x_data, ds.drive_inv_q_shift, ds.drive_direction), "inv_q_shift",
         "Delta(1/Q) of paper Eq. 31 versus delta_a/delta0 (paper Fig. 10).", "data")

    # Posterior predictive shift for every law that has it (paper Figs. 7 and 9).
    bands = {}
    for run in runs.values():
        if "posterior_predictive" in run.idata and "shift_obs" in run.idata.posterior_predictive:
            xs, b = _bands_from_ppc(run.idata, x_data)
            bands[run.summary["label"]] = b
    if bands:
        for log_axes, suffix in ((False, "lin"), (True, "log")):
            save(plots.fig_shift_ppc(x_data, ds.drive_shift, ds.drive_direction, xs, bands,
                                     log=log_axes), f"shift_ppc_{suffix}",
                 "Measured Delta f/f0 (grey: up sweeps, orange: down sweeps) with the "
                 "posterior predictive 90 % band of each law, versus delta_a/delta0 with delta0 "
                 f"the Hertz overlap under the weight ({'log' if log_axes else 'linear'} axes; "
                 "paper Figs. 7 and 9).", "fit")

    tension = result.get("tension")
    for t in (tension, (tension or {}).get("paper")):
        npz = out / "idata" / f"tension_eta_samples_{(t or {}).get('rung')}.npz"
        if t is None or not npz.exists():
            continue
        z = np.load(npz)
        shift_label = "shift alone" if t.get("eta_in_shift") else "shift alone (= prior)"
        save(plots.fig_eta_tension({shift_label: np.log10(z["shift"]),
                                    "Q alone": np.log10(z["q"]),
                                    "joint (shared eta)": np.log10(z["joint"])}),
             f"eta_tension_{t['rung']}", f"Forward model '{t['rung']}': posterior of log10 eta "
             "from the shift alone, from the reference Q alone and from both with one shared "
             "eta: the Q-versus-shift tension." + ("" if t.get("eta_in_shift") else
             " In this (correct) physics eta does not enter the shift, so the shift-alone "
             "posterior is the prior."), "tension")

    laws = [r for r in result["laws"] if r.get("log_z") is not None]
    if laws:
        two = all(r.get("log_z2") is not None for r in laws)
        save(plots.fig_evidence(
            [r["label"] for r in laws], [r["log_z"] for r in laws],
            [r["log_z_err"] for r in laws],
            [r["log_z2"] for r in laws] if two else None,
            [r["log_z2_err"] for r in laws] if two else None,
            estimators=(laws[0]["log_z_method"], laws[0].get("log_z2_method") or ""),
            failed=[r["status"] != "ok" for r in laws]),
            "evidence", "log evidence per law relative to the best, with 1-sigma errors "
            f"({'both estimators' if two else 'one estimator'}); failed runs hatched.",
            "comparison")

    pref = result.get("preferred")
    if pref in runs:
        idata = runs[pref].idata
        names = [p["name"] for p in runs[pref].summary["params"]][:6]
        cfg = result["config"]["report"]
        if cfg.get("pair_plots", True) and len(names) >= 2:
            save(plots.fig_pair(idata, names, units={p["name"]: p["unit"]
                                                     for p in runs[pref].summary["params"]}),
                 "pair_preferred", f"Pair plot of the {pref} posterior (divergences in red).",
                 "diagnostics")
        if cfg.get("rank_plots", True) and names:
            save(plots.fig_rank(idata, names), "rank_preferred",
                 f"Rank plots per chain of the {pref} posterior (uniform if chains agree).",
                 "diagnostics")
        try:
            save(plots.fig_loo_pit(idata, "shift_obs"), "loo_pit_preferred",
                 f"LOO-PIT of the {pref} fit to the shift (uniform if calibrated).",
                 "diagnostics")
        except Exception as exc:  # LOO-PIT can fail on degenerate tiny runs; say so
            log.warning("LOO-PIT figure skipped: %s", exc)
    return entries
