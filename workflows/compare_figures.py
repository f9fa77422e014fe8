"""Figures of ``beadrod compare`` assembled from the fits, the data and ``models/``.

Theory curves come from the same ``models/`` functions the NumPyro models call; fitted
curves and bands come from the InferenceData files through
:func:`inference.numpyro_models.curve_draws` (:mod:`workflows.figure_data`), never
from a second copy of a formula. Colours and labels: :mod:`workflows.styles`.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from . import figure_data, plots, styles
from .plots_data import Curve

__all__ = ["make_figures", "theory_curves", "fitted_specs"]

log = logging.getLogger("beadrod")

_FO, _BB, _EQ25 = (styles.RUNG_LINESTYLES[k] for k in ("first_order", "backbone", "paper_eq25"))


def theory_curves(scene: Any, x: np.ndarray) -> dict[str, Curve]:
    """Delta f/f0 versus x = delta_a/delta0 for each law at the scene's nominal values
    (the paper's Fig. 4, plus the exact backbone): label -> :class:`Curve`."""
    import jax.numpy as jnp

    from models import hertz, jkr, shift, viscoelastic
    from models.backbone_table import backbone_shift_clipped

    xj = jnp.asarray(x)
    curves = {
        "Hertz, first order (nominal)": Curve(np.asarray(shift.first_order_hertz(xj)),
                                              "hertz", _FO, width=1.2),
        # the tabulated exact backbone (<= 1e-6 from the quadrature, which costs ~20 s
        # to compile here); the fits use the same table
        "Hertz, exact backbone (nominal)": Curve(
            np.asarray(backbone_shift_clipped(xj, hertz.EXPONENT)), "hertz", _BB, width=1.2),
    }
    e_star, radius, load, mass = (float(scene.e_star), float(scene.radius), float(scene.load),
                                  float(scene.mass))
    if scene.surface_energy:
        kw = {"e_star": e_star, "radius": radius, "gamma": float(scene.surface_energy)}
        curves["JKR, first order (nominal)"] = Curve(
            np.asarray(jkr.shift_first_order(xj, load=load, **kw)), "jkr", _FO, width=1.2)
    if scene.viscosity:
        young, nu = scene.bead_material.young, scene.bead_material.poisson
        a = viscoelastic.damping_constant(eta1=scene.viscosity, eta2=scene.viscosity,
                                          young=young, poisson=nu)
        omega0 = 2 * np.pi * float(hertz.linear_frequency(load, mass, e_star=e_star,
                                                           radius=radius))
        curves[f"viscoelastic, paper Eq. 25 (eta = {scene.viscosity / 1e6:.3g} MPa s)"] = Curve(
            np.asarray(viscoelastic.shift_paper_eq25(xj, damping_constant=a, omega=omega0)),
            "viscoelastic", _EQ25, width=1.2)
    return curves


def fitted_specs(runs: dict[str, Any], cfg: dict[str, Any]) -> dict[str, Any]:
    """ModelSpec of each fitted law (the run's own where it carries one, else rebuilt as
    the comparison built it); laws whose spec cannot be rebuilt are left out."""
    from .pipeline import comparison_specs

    lik = "student_t" if cfg.get("likelihood", {}).get("robust") else "normal"
    specs = {}
    for name, run in runs.items():
        spec = getattr(run, "spec", None)
        if spec is None:
            # the rung the law was fitted at (its summary says), not today's default
            rung = run.summary.get("rung") or cfg.get("rung", "backbone")
            try:
                spec = comparison_specs([name], rung, lik)[name]
            except (ValueError, KeyError) as exc:
                log.warning("figures: no model spec for %s (%s); its curves are left out",
                            name, exc)
                continue
        specs[name] = spec
    return specs


def _label(run: Any) -> str:
    return styles.label(run.name) if run.name else run.summary.get("label", "")


def _shift_figures(save, runs, specs, inputs, ds, pref: str | None) -> None:
    panels = []
    for name, run in runs.items():
        pp = getattr(run.idata, "posterior_predictive", None)
        if name not in specs or pp is None or "shift_obs" not in pp:
            continue
        panels.append(figure_data.shift_panel(name, _label(run), specs[name], run.idata,
                                              inputs, ds,
                                              status=run.summary.get("status", "ok")))
    if not panels:
        return
    floor = figure_data.noise_floor(panels)
    common = ("Measured Delta f/f0 (black: filled up-pointing triangles are up sweeps, open "
              "down-pointing ones down sweeps) and, per law, the posterior median curve on a "
              "smooth grid (solid: up sweeps; dashed: down sweeps, with the fitted offset), "
              "its 90 % credible band (dark) and the 90 % posterior predictive band with "
              "the fitted noise (light). The x axis is delta_a/delta0,p with delta0,p the "
              "law's own static overlap of protocol p (posterior median). Under each law: "
              "the standardised residuals (y - mean of y_rep)/sd of y_rep, one grey track "
              "per protocol and direction; the grey band is +-2.")
    save(plots.fig_shift_ppc(panels, ds.drive_shift, ds.drive_direction, inputs["proto"],
                             preferred=pref), "shift_ppc_lin",
         common + " Linear axes (paper Fig. 7).", "fit")
    save(plots.fig_shift_ppc(panels, ds.drive_shift, ds.drive_direction, inputs["proto"],
                             log=True, floor=floor, preferred=pref), "shift_ppc_log",
         common + f" Log-log axes of -Delta f/f0 (paper Fig. 9), clipped at {floor:.1g} (a "
         "tenth of the smallest fitted noise sigma_shift, dotted line: each law's "
         "sigma_shift); sweeps at or below it, positive shifts included, sit on the "
         "floor as grey dashes.", "fit")


def _theory_figures(save, runs, specs, inputs, scene) -> None:
    from models import shift
    from models.backbone_table import backbone_shift_fast

    x_grid = np.linspace(1e-3, 1.3, 200)
    curves = theory_curves(scene, x_grid)
    for name, run in runs.items():
        if name not in specs:
            continue
        q05, q50, q95 = figure_data.fitted_curve(specs[name], run.idata, x_grid, inputs)
        # the law-free baseline has no rung (its delta0 is the Hertz overlap from f0)
        rung = "" if "baseline" in (name, getattr(specs[name], "law", "")) else \
            f", {getattr(specs[name], 'rung', '').replace('_', ' ')}"
        curves[f"{_label(run)}: fit{rung} (median, 90 %)"] = Curve(
            q50, name, _BB, band=(q05, q95), width=2.0)
    save(plots.fig_shift_curves(x_grid, curves), "theory_shift",
         "Delta f/f0 versus delta_a/delta0: thin lines, each law at the scene's nominal "
         "parameters (paper Fig. 4; dashed: the paper's first order, solid: the exact "
         "backbone, dotted: the paper's Eq. 25); thick lines, each fitted law's posterior "
         "median with its 90 % band. Curves that coincide are drawn in alternating "
         "dashes.", "theory")
    n = np.linspace(1.01, 3.0, 120)
    fitted = None
    if "powerlaw" in runs:
        fitted = figure_data.posterior_interval(runs["powerlaw"].idata, "n")
    save(plots.fig_max_shift_vs_n(n, np.asarray(shift.first_order_powerlaw(1.0, n)),
                                  np.asarray(backbone_shift_fast(np.ones_like(n), n)),
                                  fitted=fitted),
         "max_shift_vs_n", "Delta f/f0 at delta_a = delta0 versus the power-law exponent n: "
         "the paper's first order (dashed; paper Fig. 5), which hardens for n > 2, and the "
         "exact backbone (solid), which softens for every n > 1"
         + (", with the power-law fit's n (median and 90 % interval)." if fitted else "."),
         "theory")


def _data_figures(save, ds) -> None:
    from models import jkr
    from models.hertz import linear_frequency as hertz_f0
    from models.materials import effective_modulus

    scene = ds.scene
    lo_hi = scene.young_range or (scene.bead_material.young, scene.bead_material.young)
    nu = scene.bead_material.poisson
    ranges = {}
    for label, fn in (("Hertz", lambda es: hertz_f0(scene.load, scene.mass, e_star=es,
                                                    radius=scene.radius)),
                      ("JKR adhesion", lambda es: jkr.linear_frequency(
                          scene.load, scene.mass, e_star=es, radius=scene.radius,
                          gamma=scene.surface_energy or 0.7))):
        vals = [float(fn(effective_modulus(e, nu))) for e in lo_hi]
        ranges[label] = (min(vals), max(vals))
    save(plots.fig_f0_ranges(ds.f0, ranges, protocol_ids=list(ds.protocol_ids)), "f0_ranges",
         "Measured linear resonance of each protocol against the Hertz and JKR ranges for "
         "the scene's Young's modulus range (paper Fig. 6).", "data")
    save(plots.fig_q_vs_f0(ds.f0, ds.q_ref), "q_vs_f0",
         "Reference Q versus linear resonance per protocol (paper Fig. 8).", "data")
    save(plots.fig_inv_q_shift(ds.normalized_amplitude("weight"), ds.drive_inv_q_shift,
                               ds.drive_direction), "inv_q_shift",
         "Delta(1/Q) of paper Eq. 31 versus delta_a/delta0 (delta0: the Hertz overlap under "
         "the weight; paper Fig. 10), with the median and interquartile range per "
         "amplitude bin of each sweep direction.", "data")


def _tension_figures(save, result, out: Path) -> None:
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
             "from the shift alone, from the reference Q alone (filled) and from both with "
             "one shared eta (dashed): the Q-versus-shift tension." + (
                 "" if t.get("eta_in_shift") else " In this (correct) physics eta does not "
                 "enter the shift, so the shift-alone posterior is the prior."), "tension")


def _reference_law(laws: list[dict[str, Any]], result: dict[str, Any]) -> str | None:
    """The preferred law, else the law (not the baseline) of highest log Z."""
    if result.get("preferred") in {r["name"] for r in laws}:
        return result["preferred"]
    cand = [r for r in laws if r["name"] != "baseline"]
    return max(cand, key=lambda r: r["log_z"])["name"] if cand else None


def _evidence_figure(save, result) -> None:
    laws = [r for r in result["laws"] if r.get("log_z") is not None]
    if not laws:
        return
    two = all(r.get("log_z2") is not None for r in laws)
    save(plots.fig_evidence(
        [styles.label(r["name"]) for r in laws], [r["log_z"] for r in laws],
        [r["log_z_err"] for r in laws],
        [r["log_z2"] for r in laws] if two else None,
        [r["log_z2_err"] for r in laws] if two else None,
        estimators=(laws[0]["log_z_method"], laws[0].get("log_z2_method") or ""),
        failed=[r["status"] != "ok" for r in laws], names=[r["name"] for r in laws],
        preferred=result.get("preferred"), reference=_reference_law(laws, result)),
        "evidence", "log evidence of each model minus that of the preferred law (where no "
        "law passed its gate: of the best law; the law-free baseline is never the "
        "reference, so its lead over the laws is read off directly), with 1-sigma "
        f"errors ({'both estimators' if two else 'one estimator'}; each value is printed "
        "beside its point, since most error bars are smaller than the marker); the preferred "
        "law is starred, failed runs shaded.", "comparison")


def _diagnostic_figures(save, runs, result) -> None:
    pref = result.get("preferred")
    if pref not in runs:
        return
    idata = runs[pref].idata
    params = runs[pref].summary["params"]
    names = [p["name"] for p in params][:6]
    cfg = result["config"]["report"]
    if cfg.get("pair_plots", True) and len(names) >= 2:
        save(plots.fig_pair(idata, names, units={p["name"]: p["unit"] for p in params}),
             "pair_preferred", f"Pair plot of the {pref} posterior (divergences in red).",
             "diagnostics")
    if cfg.get("rank_plots", True) and names:
        save(plots.fig_rank(idata, names), "rank_preferred",
             f"Rank plots per chain of the {pref} posterior (uniform if chains agree).",
             "diagnostics")
    try:
        save(plots.fig_loo_pit(idata, "shift_obs"), "loo_pit_preferred",
             f"LOO-PIT of the {pref} fit to the shift (uniform if calibrated).", "diagnostics")
    except Exception as exc:  # LOO-PIT can fail on degenerate tiny runs; say so
        log.warning("LOO-PIT figure skipped: %s", exc)


def make_figures(runs: dict[str, Any], inputs: dict[str, Any], ds: Any, result: dict[str, Any],
                 out: Path) -> list[dict[str, Any]]:
    """Write every figure into ``out/figures`` and return their report entries."""
    fig_dir = out / "figures"
    entries: list[dict[str, Any]] = []

    def save(fig, name: str, caption: str, section: str) -> None:
        plots.save_figure(fig, fig_dir / name)
        entries.append({"path": f"figures/{name}.png", "caption": caption, "section": section})

    specs = fitted_specs(runs, result.get("config", {}))
    _theory_figures(save, runs, specs, inputs, ds.scene)
    _data_figures(save, ds)
    _shift_figures(save, runs, specs, inputs, ds, result.get("preferred"))
    _tension_figures(save, result, out)
    _evidence_figure(save, result)
    _diagnostic_figures(save, runs, result)
    return entries
