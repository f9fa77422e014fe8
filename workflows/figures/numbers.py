"""The numbers behind the fit figures, from the InferenceData of each law.

Every curve comes from :func:`inference.model.numpyro_models.curve_draws`, the same forward
functions the models sampled with; nothing here re-implements a law.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from beadrod.workflows.figures.ppc import ShiftPanel

__all__ = ["thin", "posterior_interval", "data_overlap", "shift_panel",
           "standardised_residuals", "fitted_curve", "noise_floor", "THEORY_X",
           "law_figure_data"]

THEORY_X = np.linspace(1e-3, 1.3, 200)
"""x = delta_a/delta0 of the theory figure (nominal and fitted shift curves)."""


def thin(idata: Any, max_draws: int) -> Any:
    """InferenceData with only its posterior, every k-th draw so that at most about
    ``max_draws`` remain over all chains (quantiles of a few hundred draws suffice)."""
    import arviz as az

    post = idata.posterior
    total = int(post.sizes["chain"] * post.sizes["draw"])
    step = max(1, int(np.ceil(total / max_draws)))
    return az.InferenceData(posterior=post.isel(draw=slice(None, None, step)))


def _flat(post: Any, name: str) -> np.ndarray:
    a = np.asarray(post[name], dtype=float)
    return a.reshape(-1, *a.shape[2:])


def posterior_interval(idata: Any, name: str, level: float = 0.9
                       ) -> tuple[float, float, float] | None:
    """(median, lo, hi) of scalar ``name``'s central ``level`` interval, None if absent."""
    post = idata.posterior
    if name not in post:
        return None
    v = _flat(post, name).ravel()
    lo, med, hi = np.quantile(v, [(1 - level) / 2, 0.5, (1 + level) / 2])
    return float(med), float(lo), float(hi)


def data_overlap(idata: Any, ds: Any) -> np.ndarray:
    """δ0,p [m] per protocol under this law: the posterior median of its ``delta0`` site;
    for a model without one (the law-free baseline) the Hertz overlap the measured f0
    implies, the scale :func:`inference.model.numpyro_models.curve_draws` gives it."""
    post = idata.posterior
    if "delta0" in post:
        return np.median(_flat(post, "delta0"), axis=0)
    return np.asarray(ds.delta0("f0"), dtype=float)


def shift_panel(name: str, label: str, spec: Any, idata: Any, inputs: dict[str, Any],
                ds: Any, *, n_grid: int = 160, max_draws: int = 600, replicates: int = 8,
                seed: int = 0, status: str = "ok") -> ShiftPanel:
    """One law's panel of the shift PPC figure (see :class:`ShiftPanel`).

    The curve is the noise-free up-sweep shift on a log-spaced grid of x = δa/δ0 (plus
    x = 0); the predictive band adds the likelihood's noise (Normal or Student-t with
    the draw's sd, ``replicates`` noise values per draw: sqrt(σ² + (κ s)² + τ²) under the
    protocol noise model, σ_shift under the constant one); down sweeps add the draw's
    ``offset_down``. Residuals are standardised by the posterior predictive draws of each
    sweep.
    """
    from beadrod.inference.model.numpyro_models import curve_draws

    small = thin(idata, max_draws)
    post = small.posterior
    amp = np.asarray(inputs["amplitude"], float)
    proto = np.asarray(inputs["proto"]).astype(int)
    x = amp / data_overlap(idata, ds)[proto]
    grid = np.concatenate([[0.0], np.geomspace(0.5 * x.min(), 1.05 * x.max(), n_grid - 1)])
    curves = np.asarray(curve_draws(spec, small, grid, inputs), float)
    sigma = _flat(post, "sigma_shift").ravel()
    offset = _flat(post, "offset_down").ravel() if "offset_down" in post else None
    # one noise value per (draw, replicate), the same along the grid: the band's edges
    # are then as smooth as the curves (fresh noise per grid point makes them jagged)
    rng = np.random.default_rng(seed)
    shape = (replicates, curves.shape[0], 1)
    if getattr(spec, "likelihood", "normal") == "student_t":
        eps = rng.standard_t(float(getattr(spec, "student_df", 4.0)), size=shape)
    else:
        eps = rng.standard_normal(shape)
    # the noise model's sd along the curve: a floor, a part growing with the shift and
    # (a new protocol's) shared offset (inference.model.shift_noise); 0 where absent
    kappa = _flat(post, "kappa_shift").ravel() if "kappa_shift" in post else 0.0 * sigma
    tau = _flat(post, "tau_shift").ravel() if "tau_shift" in post else 0.0 * sigma
    scale = np.sqrt(sigma[:, None] ** 2 + (kappa[:, None] * curves) ** 2 + tau[:, None] ** 2)
    pred = (curves[None] + scale[None] * eps).reshape(-1, curves.shape[1])
    q05, q50, q95 = np.quantile(curves, [0.05, 0.5, 0.95], axis=0)
    p05, p95 = np.quantile(pred, [0.05, 0.95], axis=0)
    down = None if offset is None else np.median(curves + offset[:, None], axis=0)
    return ShiftPanel(name=name, label=label, x=x, grid=grid, curve=(q05, q50, q95),
                      predictive=(p05, p95), down=down,
                      residual=standardised_residuals(idata, np.asarray(inputs["shift"])),
                      sigma=float(np.median(sigma)), status=status)


def standardised_residuals(idata: Any, y: np.ndarray) -> np.ndarray | None:
    """(y − mean of y_rep) / sd of y_rep per sweep, from the posterior predictive draws of
    ``shift_obs`` (noise and parameter uncertainty both in the scale); None without them."""
    pp = getattr(idata, "posterior_predictive", None)
    if pp is None or "shift_obs" not in pp:
        return None
    rep = _flat(pp, "shift_obs")
    sd = rep.std(axis=0)
    return np.where(sd > 0, (np.asarray(y, float) - rep.mean(axis=0)) / np.where(sd > 0, sd, 1),
                    np.nan)


def fitted_curve(spec: Any, idata: Any, x: np.ndarray, inputs: dict[str, Any], *,
                 max_draws: int = 600) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q05, median, q95) of a fitted law's noise-free up-sweep shift on ``x``."""
    from beadrod.inference.model.numpyro_models import curve_draws

    c = np.asarray(curve_draws(spec, thin(idata, max_draws), np.asarray(x, float), inputs))
    q05, q50, q95 = np.quantile(c, [0.05, 0.5, 0.95], axis=0)
    return q05, q50, q95


def noise_floor(panels: list[ShiftPanel]) -> float:
    """Bottom of the log-log shift axis: a tenth of the smallest fitted σ_shift, one
    significant figure (below it every sweep is noise for every law)."""
    s = 0.1 * min(p.sigma for p in panels)
    e = np.floor(np.log10(s))
    return float(np.floor(s / 10**e) * 10**e)


def law_figure_data(name: str, spec: Any, idata: Any, inputs: dict[str, Any],
                    ds: Any) -> dict[str, Any]:
    """What the comparison's figures compute from one fit: its fitted curve on
    :data:`THEORY_X` ('fitted_curve') and its shift panel ('shift_panel', labelled with
    the law's name; the figure relabels it). Computed where the fit ran (a worker
    process), so that the figures' serial part only draws."""
    out: dict[str, Any] = {"fitted_curve": fitted_curve(spec, idata, THEORY_X, inputs)}
    pp = getattr(idata, "posterior_predictive", None)
    if pp is not None and "shift_obs" in pp:
        out["shift_panel"] = shift_panel(name, name, spec, idata, inputs, ds)
    return out
