"""Figures of ``beadrod compare`` assembled from the fits, the data and ``models/``.

Theory curves come from the same ``models/`` functions the NumPyro models call; fitted
curves and bands come from the InferenceData files through
:func:`inference.model.numpyro_models.curve_draws` (:mod:`workflows.figures.numbers`), never
from a second copy of a formula. Colours and labels: :mod:`workflows.figures.styles`.
"""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from beadrod.inference.model.amplitude import loss_points
from beadrod.workflows.figures import damping, gallery, numbers, styles
from beadrod.workflows.figures.physics import Curve
from beadrod.workflows.figures.pool import FigureWriter

__all__ = ["make_figures", "draw_figures", "theory_curves", "figure_laws", "fitted_specs",
           "exponent_law", "f0_ranges"]

log = logging.getLogger("beadrod")

_BB = styles.RUNG_LINESTYLES["backbone"]


_RUNG_WORDS = {"first_order": "first order", "backbone": "exact backbone",
               "paper_eq25": "paper Eq. 25"}


def figure_laws(names: Any = ()) -> list[Any]:
    """The laws a figure draws at their nominal parameters: every law of the default
    comparison plus the registered laws among ``names`` (the fitted ones), in registry
    order."""
    from beadrod.models.registry import laws

    names = set(names)
    return [law for law in laws() if law.presentation.in_default_comparison or law.name in names]


def _nominal_state(law: Any, sc: dict[str, float]) -> dict[str, Any] | None:
    """The law's linear state at its nominal parameters (models.nominal), None (and a
    warning) where it cannot be computed, so that one law does not cost every figure."""
    from beadrod.models.nominal import checked_parameters, linear_state

    try:
        # a scene value outside the law's domain (a surface energy of 0) is a ValueError,
        # and no state to draw
        return linear_state(law, sc, checked_parameters(law, sc)[0])
    except Exception as exc:  # noqa: BLE001 (a law file's law may fail anywhere)
        log.warning("figures: no nominal state of %s (%s: %s); its curves are left out",
                    law.name, type(exc).__name__, exc)
        return None


def _merge(curves: list[tuple[str, str, Curve]]) -> dict[str, Curve]:
    """One entry per distinct curve: laws whose nominal curves of one rung coincide
    (Hertz and the viscoelastic laws share their conservative backbone) share one label,
    'A, rung (nominal)' over '= B, C', coloured as the first."""
    groups: list[tuple[list[str], str, Curve]] = []
    for law_label, rung_words, c in curves:
        for labels, words, first in groups:
            if words == rung_words and np.allclose(c.y, first.y, rtol=1e-9, atol=1e-12):
                labels.append(law_label)
                break
        else:
            groups.append(([law_label], rung_words, c))
    return {f"{labels[0]}, {words} (nominal)"
            + (f"\n= {', '.join(labels[1:])}" if len(labels) > 1 else ""): c
            for labels, words, c in groups}


def theory_curves(scene: Any, x: np.ndarray, laws: Any = None) -> dict[str, Curve]:
    """Delta f/f0 versus x = delta_a/delta0 of each law of ``laws`` (default:
    :func:`figure_laws`) at its nominal parameters (models.nominal: the scene's value,
    else the prior median), at first order and on the exact backbone, and on the paper's
    Eq. 25 where that differs from first order (the paper's Fig. 4, plus the exact
    backbone): label -> :class:`Curve`. Only rungs with a fast path (the law's
    ``shifts``) are drawn: the generic quadrature is too slow for a figure."""
    from beadrod.workflows.commands.shift import scene_keywords

    sc = scene_keywords(scene)
    xs = np.asarray(x, float)
    rows: list[tuple[str, str, Curve]] = []
    for law in figure_laws() if laws is None else laws:
        state = _nominal_state(law, sc)
        if state is None:
            continue
        ys: dict[str, np.ndarray] = {}
        for rung in ("first_order", "backbone", "paper_eq25"):
            if rung not in law.physics.rungs:
                continue
            if rung not in law.physics.shifts:  # the generic quadrature is too slow for a figure
                log.info("figures: %s has no fast path at rung %s; its nominal curve there "
                         "is left out", law.name, rung)
                continue
            y = np.asarray(law.shift(xs, rung=rung, **state["kw"]), float)
            inside = law.in_domain(xs, rung=rung, **state["kw"])
            if inside is not None and not np.all(inside):
                # the fast path holds a value that is not the law's there (a table's end)
                log.info("figures: %s's fast path at rung %s does not cover this scene's "
                         "nominal curve; it is left out", law.name, rung)
                continue
            if rung == "paper_eq25" and "first_order" in ys and np.allclose(
                    y, ys["first_order"], rtol=1e-9, atol=1e-12):
                continue  # the paper's formula is this law's first order: drawn already
            ys[rung] = y
            rows.append((law.presentation.label, _RUNG_WORDS[rung],
                         Curve(y, law.name, styles.RUNG_LINESTYLES[rung], width=1.2)))
    return _merge(rows)


def fitted_specs(runs: dict[str, Any], cfg: dict[str, Any]) -> dict[str, Any]:
    """ModelSpec of each fitted law (the run's own where it carries one, else rebuilt as
    the comparison built it); laws whose spec cannot be rebuilt are left out."""
    from beadrod.workflows.config import shift_noise
    from beadrod.workflows.pipeline.fits import comparison_specs

    lik = "student_t" if cfg.get("likelihood", {}).get("robust") else "normal"
    specs = {}
    for name, run in runs.items():
        spec = getattr(run, "spec", None)
        if spec is None:
            # the rung the law was fitted at (its summary says), not the default
            rung = run.summary.get("rung") or cfg.get("rung", "backbone")
            try:
                spec = comparison_specs([name], rung, lik,
                                        shift_noise=shift_noise(cfg))[name]
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
        status = run.summary.get("status", "ok")
        pre = (run.figure_data or {}).get("shift_panel")  # computed with the fit
        panels.append(replace(pre, label=_label(run), status=status) if pre is not None
                      else numbers.shift_panel(name, _label(run), specs[name], run.idata,
                                                   inputs, ds, status=status))
    if not panels:
        return
    floor = numbers.noise_floor(panels)
    common = ("Measured Delta f/f0 (black: filled up-pointing triangles are up sweeps, open "
              "down-pointing ones down sweeps) and, per law, the posterior median curve on a "
              "smooth grid (solid: up sweeps; dashed: down sweeps, with the fitted offset), "
              "its 90 % credible band (dark) and the 90 % posterior predictive band with "
              "the fitted noise (light). The x axis is delta_a/delta0,p with delta0,p the "
              "law's own static overlap of protocol p (posterior median). Under each law: "
              "the standardised residuals (y - mean of y_rep)/sd of y_rep, one grey track "
              "per protocol and direction; the grey band is +-2.")
    save(gallery.fig_shift_ppc(panels, ds.drive_shift, ds.drive_direction, inputs["proto"],
                             preferred=pref), "shift_ppc_lin",
         common + " Linear axes (paper Fig. 7).", "fit")
    save(gallery.fig_shift_ppc(panels, ds.drive_shift, ds.drive_direction, inputs["proto"],
                             log=True, floor=floor, preferred=pref), "shift_ppc_log",
         common + f" Log-log axes of -Delta f/f0 (paper Fig. 9), clipped at {floor:.1g} (a "
         "tenth of the smallest fitted noise sigma_shift, dotted line: each law's "
         "sigma_shift); sweeps at or below it, positive shifts included, sit on the "
         "floor as grey dashes.", "fit")


def _damping_figures(save, runs, inputs, ds) -> None:
    """Paper Fig. 10 with each law's posterior predictive band, and the loss change
    against the frequency drop with what each mechanism predicts (docs/damping.md)."""
    panels = []
    for name, run in runs.items():
        pre = (run.figure_data or {}).get("inv_q_panel")  # computed with the fit
        panel = (replace(pre, label=_label(run)) if pre is not None
                 else damping.inv_q_panel(name, _label(run), run.idata, inputs, ds))
        if panel is not None:
            panels.append(panel)
    if panels:
        save(damping.fig_inv_q_ppc(panels), "inv_q_ppc",
             "Delta(1/Q) of paper Eq. 31 per drive sweep (triangles: up and down sweeps; "
             "grey crosses: protocols without a measured Q, scaled by the median Q) and, "
             "per law, the posterior predictive: each sweep's 90 % interval (thin lines), "
             "the 90 % band of the sweeps of each amplitude bin pooled, and the noise-free "
             "median. The x axis is delta_a/delta0,p with the law's own overlap (paper "
             "Fig. 10).", "fit")
    points = loss_points(ds)  # the loss-against-shift table's data row reads the same
    if points.x.size:
        save(damping.fig_loss_vs_shift(points.shift, points.eq31, np.asarray(ds.q_ref, float),
                                       direction=points.direction),
             "loss_vs_shift",
             "Delta(1/Q) of paper Eq. 31 against -Delta f/f0 for each drive sweep, with "
             "what each mechanism predicts at the median reference Q: an elastic law with "
             "a background loss L0 Omega^beta (beta = 0, 1; 2 is the zero line), viscous "
             "Kuwabara-Kono damping or radiation into the rod (beta = 3), and Masing "
             "hysteresis alone (its share of shift and loss, slope rho(m)); under base "
             "excitation (docs/damping.md).", "data")


def exponent_law(names: Any = ()) -> Any:
    """The law whose force exponent the max_shift_vs_n figure (paper Fig. 5) is drawn
    against: the law with a parameter named ``n``, a fitted one (among ``names``) first;
    None if no registered law has one."""
    from beadrod.models.registry import laws

    names = set(names)
    with_n = [law for law in laws() if "n" in law.param_names]
    fitted = [law for law in with_n if law.name in names]
    return (fitted or with_n or [None])[0]


def _theory_figures(save, runs, specs, inputs, scene) -> None:
    from beadrod.models.ladder import first_order
    from beadrod.models.tables.powerlaw_backbone import backbone_shift_fast

    x_grid = numbers.THEORY_X
    fitted_laws = {getattr(spec, "law", None) for spec in specs.values()}
    curves = theory_curves(scene, x_grid, figure_laws(fitted_laws))
    for name, run in runs.items():
        if name not in specs:
            continue
        pre = (run.figure_data or {}).get("fitted_curve")  # computed with the fit
        q05, q50, q95 = pre if pre is not None else numbers.fitted_curve(
            specs[name], run.idata, x_grid, inputs)
        # the law-free baseline has no rung (its delta0 is the Hertz overlap from f0)
        rung = "" if "baseline" in (name, getattr(specs[name], "law", "")) else \
            f", {getattr(specs[name], 'rung', '').replace('_', ' ')}"
        curves[f"{_label(run)}: fit{rung} (median, 90 %)"] = Curve(
            q50, name, _BB, band=(q05, q95), width=2.0)
    save(gallery.fig_shift_curves(x_grid, curves), "theory_shift",
         "Delta f/f0 versus delta_a/delta0: thin lines, each law at its nominal parameters "
         "(the scene's value, else its prior median; paper Fig. 4; dashed: the paper's "
         "first order, solid: the exact backbone, dotted: the paper's Eq. 25 where it "
         "differs from first order; a rung without a fast path is left out); laws whose "
         "curves coincide share one label. Thick "
         "lines, each fitted law's posterior median with its 90 % band. Curves that "
         "coincide are drawn in alternating dashes.", "theory")
    law = exponent_law(fitted_laws)
    if law is None:
        return
    n = np.linspace(1.01, 3.0, 120)
    fitted = None
    if law.name in runs:
        fitted = numbers.posterior_interval(runs[law.name].idata, "n")
    save(gallery.fig_max_shift_vs_n(n, np.asarray(first_order.first_order_powerlaw(1.0, n)),
                                  np.asarray(backbone_shift_fast(np.ones_like(n), n)),
                                  fitted=fitted, model=law.name),
         "max_shift_vs_n", "Delta f/f0 at delta_a = delta0 versus the power-law exponent n: "
         "the paper's first order (dashed; paper Fig. 5), which hardens for n > 2, and the "
         "exact backbone (solid), which softens for every n > 1"
         + (f", with the {law.presentation.label} fit's n (median and 90 % interval)."
            if fitted else "."),
         "theory")


def f0_ranges(scene: Any, laws: Any = None) -> dict[str, tuple[float, float]]:
    """Linear resonance f0 [Hz] of each law of ``laws`` (default :func:`figure_laws`) at
    its nominal parameters, at both ends of the scene's Young's modulus range: label ->
    (lo, hi); laws with equal ranges share one label ('A' over '= B'). A law whose
    nominal f0 does not depend on E gets no range."""
    from beadrod.workflows.commands.shift import scene_keywords

    sc = scene_keywords(scene)
    ends = scene.young_range or (scene.bead_material.young, scene.bead_material.young)
    groups: list[tuple[list[str], tuple[float, float]]] = []
    for law in figure_laws() if laws is None else laws:
        states = [_nominal_state(law, {**sc, "young": float(e)}) for e in ends]
        if any(st is None for st in states):
            continue
        vals = [st["f0_Hz"] for st in states]
        rng = (min(vals), max(vals))
        if len(ends) > 1 and ends[0] != ends[1] and rng[0] == rng[1]:
            # its nominal f0 does not depend on E (a law parametrised by its overlap): a
            # band of zero width would only clutter the legend
            log.info("figures: the nominal f0 of %s does not depend on E; no range drawn",
                     law.name)
            continue
        for labels, other in groups:
            if np.allclose(rng, other, rtol=1e-9):
                labels.append(law.presentation.label)
                break
        else:
            groups.append(([law.presentation.label], rng))
    return {"\n= ".join(labels): rng for labels, rng in groups}


def _data_figures(save, ds, names: Any = ()) -> None:
    scene = ds.scene
    ranges = f0_ranges(scene, figure_laws(names))
    save(gallery.fig_f0_ranges(ds.f0, ranges, protocol_ids=list(ds.protocol_ids)), "f0_ranges",
         "Measured linear resonance of each protocol against each law's range at its "
         "nominal parameters (the scene's value, else its prior median) for the scene's "
         "Young's modulus range (paper Fig. 6).", "data")
    save(gallery.fig_q_vs_f0(ds.f0, ds.q_ref), "q_vs_f0",
         "Reference Q versus linear resonance per protocol (paper Fig. 8).", "data")
    save(gallery.fig_inv_q_shift(ds.normalized_amplitude("weight"), ds.drive_inv_q_shift,
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
        save(gallery.fig_eta_tension({shift_label: np.log10(z["shift"]),
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
    save(gallery.fig_evidence(
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
        save(gallery.fig_pair(idata, names, units={p["name"]: p["unit"] for p in params}),
             "pair_preferred", f"Pair plot of the {pref} posterior (divergences in red).",
             "diagnostics")
    if cfg.get("rank_plots", True) and names:
        save(gallery.fig_rank(idata, names), "rank_preferred",
             f"Rank plots per chain of the {pref} posterior (uniform if chains agree).",
             "diagnostics")
    try:
        sites = [v for v in ("shift_obs", "amp_obs") if v in idata.observed_data]
        save(gallery.fig_loo_pit(idata, sites), "loo_pit_preferred",
             f"LOO-PIT of the {pref} fit to the shift and, where fitted, the amplitude "
             "ratios (uniform if calibrated; each sweep's predictive given its protocol's "
             "other sweeps).", "diagnostics")
    except Exception as exc:  # LOO-PIT can fail on degenerate tiny runs; say so
        log.warning("LOO-PIT figure skipped: %s", exc)


def make_figures(runs: dict[str, Any], inputs: dict[str, Any], ds: Any, result: dict[str, Any],
                 out: Path, processes: int = 1) -> list[dict[str, Any]]:
    """Write every figure into ``out/figures`` and return their report entries; with
    ``processes`` > 1 the files are written by that many worker processes while the next
    figures are drawn (:mod:`workflows.figures.pool`: the same files)."""
    fig_dir = out / "figures"
    entries: list[dict[str, Any]] = []
    with FigureWriter(processes) as writer:

        def save(fig, name: str, caption: str, section: str) -> None:
            writer.save(fig, fig_dir / name)
            entries.append({"path": f"figures/{name}.png", "caption": caption,
                            "section": section})

        draw_figures(save, runs, inputs, ds, result, out)
    return entries


def draw_figures(save: Any, runs: dict[str, Any], inputs: dict[str, Any], ds: Any,
                 result: dict[str, Any], out: Path) -> None:
    """Draw every figure of the report, handing each to ``save(fig, name, caption,
    section)`` (:func:`make_figures` writes them; ``beadrod.compare(...).figures()``
    keeps them). ``out``: the run's folder, whose idata/ holds the tension's draws."""
    specs = fitted_specs(runs, result.get("config", {}))
    _theory_figures(save, runs, specs, inputs, ds.scene)
    _data_figures(save, ds, {getattr(spec, "law", None) for spec in specs.values()})
    _shift_figures(save, runs, specs, inputs, ds, result.get("preferred"))
    _damping_figures(save, runs, inputs, ds)
    _tension_figures(save, result, out)
    _evidence_figure(save, result)
    _diagnostic_figures(save, runs, result)
