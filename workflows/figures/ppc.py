"""The posterior predictive frequency shift (the paper's Figs. 7 and 9): the central figure.

One panel per law (small multiples, shared axes), each with the law's fitted curve on a
smooth grid, its 90 % credible band and its 90 % predictive band, the measured sweeps
drawn on top (up ▲ filled, down ▽ open, black), and under it the standardised
residuals of every sweep, protocol by protocol. The numbers come from
:func:`workflows.figures.numbers.shift_panel`; this module only draws.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from beadrod.workflows.figures import styles
from beadrod.workflows.figures.physics import directions, legend_outside, plt, scatter_by_direction

__all__ = ["ShiftPanel", "fig_shift_ppc", "RESIDUAL_LIMIT"]

RESIDUAL_LIMIT = 5.0
"""Standardised residuals beyond ±this are drawn on the panel's edge (open markers)."""


@dataclass(frozen=True)
class ShiftPanel:
    """What one law's panel shows. Arrays on ``grid`` have the grid's length, per-sweep
    arrays the data's.

    ``x``: δa/δ0,p of each sweep with δ0,p this law's overlap of protocol p (posterior
    median); ``curve`` = (q05, q50, q95) of the noise-free up-sweep shift; ``predictive``
    = (q05, q95) with the likelihood's noise added; ``down``: median curve of down sweeps
    (offset included) or None; ``residual``: (y − E[y_rep]) / sd(y_rep) per sweep;
    ``sigma``: posterior median σ_shift [-].
    """

    name: str
    label: str
    x: np.ndarray
    grid: np.ndarray
    curve: tuple[np.ndarray, np.ndarray, np.ndarray]
    predictive: tuple[np.ndarray, np.ndarray]
    down: np.ndarray | None
    residual: np.ndarray | None
    sigma: float
    status: str = "ok"


def _band(ax, x, lo, hi, *, sign: float, floor: float | None, **kw) -> None:
    a, b = sign * np.asarray(lo, float), sign * np.asarray(hi, float)
    a, b = np.minimum(a, b), np.maximum(a, b)
    if floor is not None:  # on log axes: clip at the floor, never dive to where y <= 0
        a, b = np.maximum(a, floor), np.maximum(b, floor)
    ax.fill_between(x, a, b, lw=0, **kw)


def _line(y, *, sign: float, floor: float | None) -> np.ndarray:
    y = sign * np.asarray(y, float)
    return y if floor is None else np.where(y > floor, y, np.nan)


def _residuals(ax, p: ShiftPanel, d: np.ndarray, proto: np.ndarray | None) -> None:
    r = np.asarray(p.residual, float)
    ax.axhspan(-2.0, 2.0, color="0.92", lw=0, zorder=0)
    ax.axhline(0.0, color="0.4", lw=0.6, zorder=1)
    if proto is not None:
        # each protocol's sweeps joined in amplitude order: a misfit that follows a
        # protocol shows as a track, a misfit of the law's shape as a common trend
        tracks = []
        for key in np.unique(np.stack([proto, d]), axis=1).T:
            sel = (proto == key[0]) & (d == key[1]) & np.isfinite(r)
            o = np.argsort(p.x[sel])
            tracks.append(np.column_stack([p.x[sel][o], np.clip(r[sel][o], -RESIDUAL_LIMIT,
                                                                RESIDUAL_LIMIT)]))
        ax.add_collection(LineCollection(tracks, colors="0.6", linewidths=0.5, alpha=0.6,
                                         zorder=2))
    inside = np.abs(r) <= RESIDUAL_LIMIT
    scatter_by_direction(ax, p.x[inside], r[inside], d[inside], size=7, alpha=0.8,
                         label=False)
    out = ~inside & np.isfinite(r)
    if out.any():
        ax.scatter(p.x[out], np.sign(r[out]) * RESIDUAL_LIMIT, s=12, marker="d",
                   facecolors="none", edgecolors=styles.color(p.name), lw=0.8, zorder=6)
    ax.set_ylim(-RESIDUAL_LIMIT * 1.1, RESIDUAL_LIMIT * 1.1)
    ax.set_yticks([-4, -2, 0, 2, 4])
    ax.tick_params(labelsize=7)


def fig_shift_ppc(panels: Sequence[ShiftPanel], shift: np.ndarray,
                  direction: np.ndarray | None, protocol: np.ndarray | None = None, *,
                  log: bool = False, floor: float | None = None,
                  preferred: str | None = None, ncols: int = 3) -> Figure:
    """Measured Δf/f0 and each law's posterior predictive curve versus δa/δ0,p.

    With ``log=True`` both axes are logarithmic and −Δf/f0 is plotted (the shift is a
    softening); the y axis starts at ``floor`` (default: a tenth of the smallest
    σ_shift), bands are clipped there, and sweeps at or below it (noise, or a positive
    shift) sit on the floor line as grey markers. The predictive band is left out there:
    the dotted line, each law's σ_shift, shows the noise level.
    ``preferred`` names the law whose panel is marked ★.
    """
    if not panels:
        raise ValueError("fig_shift_ppc needs at least one panel")
    y = np.asarray(shift, float)
    d = directions(direction, y.size)
    proto = None if protocol is None else np.asarray(protocol).astype(int)
    for p in panels:
        if p.x.shape != y.shape:
            raise ValueError(f"panel {p.name}: x has shape {p.x.shape}, data {y.shape}")
    n = len(panels)
    ncols = max(1, min(ncols, n))
    nrows = int(np.ceil(n / ncols))
    with_resid = any(p.residual is not None for p in panels)
    rows_per = 2 if with_resid else 1
    fig, axes = plt.subplots(
        rows_per * nrows, ncols, figsize=(3.9 * ncols + 0.4, (3.9 if with_resid else 3.0)
                                          * nrows + 0.7),
        squeeze=False, sharex=True, layout="constrained",
        gridspec_kw={"height_ratios": [3, 1.25] * nrows if with_resid else [1] * nrows})
    sign = -1.0 if log else 1.0
    if log and floor is None:
        floor = 0.1 * min(p.sigma for p in panels)
    lim_floor = floor if log else None
    curve_axes = [axes[rows_per * (i // ncols), i % ncols] for i in range(n)]
    for ax in curve_axes[1:]:
        ax.sharey(curve_axes[0])
    if with_resid:
        res_axes = [axes[rows_per * (i // ncols) + 1, i % ncols] for i in range(n)]
        for ax in res_axes[1:]:
            ax.sharey(res_axes[0])
    for i, p in enumerate(panels):
        ax = curve_axes[i]
        col = styles.color(p.name)
        g = np.asarray(p.grid, float)
        g_ok = g > 0 if log else np.ones(g.size, bool)
        gx = g[g_ok]
        if not log:  # on log axes the noise band is the dotted sigma line
            _band(ax, gx, p.predictive[0][g_ok], p.predictive[1][g_ok], sign=sign,
                  floor=lim_floor, color=col, alpha=0.16, zorder=1)
        _band(ax, gx, p.curve[0][g_ok], p.curve[2][g_ok], sign=sign, floor=lim_floor,
              color=col, alpha=0.45, zorder=2)
        ax.plot(gx, _line(p.curve[1][g_ok], sign=sign, floor=lim_floor), color=col, lw=1.8,
                zorder=3)
        if p.down is not None:
            ax.plot(gx, _line(p.down[g_ok], sign=sign, floor=lim_floor), color=col, lw=1.2,
                    ls="--", zorder=3)
        if log:
            shown = (sign * y > floor) & (p.x > 0)
            scatter_by_direction(ax, p.x[shown], -y[shown], d[shown], size=12)
            low = ~shown & (p.x > 0)
            ax.scatter(p.x[low], np.full(low.sum(), floor), s=10, marker="_", color="0.45",
                       zorder=4)
            ax.axhline(p.sigma, color="0.3", ls=":", lw=0.9, zorder=2)
            ax.set_xscale("log")
            ax.set_yscale("log")
        else:
            scatter_by_direction(ax, p.x, y, d, size=12)
            ax.axhline(0.0, color="0.4", lw=0.5)
        star = " ★ preferred" if p.name == preferred else ""
        failed = "" if p.status == "ok" else "  (FAILED its gate)"
        ax.set_title(f"{styles.tex(p.label)}{star}{failed}", fontsize=9, color=col,
                     fontweight="bold" if star else "normal")
        # the corner the data leave empty: top right (linear), top left (log-log)
        ax.text(0.02 if log else 0.98, 0.96, rf"$\sigma_\mathrm{{shift}}$ = {p.sigma:.2g}",
                transform=ax.transAxes, fontsize=7, ha="left" if log else "right", va="top",
                color="0.25")
        ax.tick_params(labelsize=7)
        if i % ncols == 0:
            ax.set_ylabel(r"$-\Delta f/f_0$ [-]" if log else r"$\Delta f/f_0$ [-]", fontsize=8)
        if with_resid and p.residual is not None:
            _residuals(res_axes[i], p, d, proto)
            if i % ncols == 0:
                res_axes[i].set_ylabel("std. residual [-]", fontsize=8)
        elif with_resid:
            res_axes[i].set_axis_off()
    xs = np.concatenate([p.x[np.isfinite(p.x) & (p.x > 0)] for p in panels])
    if xs.size:  # the data's range, not the grids' (bands start below the data)
        curve_axes[0].set_xlim(*((0.7 * xs.min(), 1.3 * xs.max()) if log
                                 else (0.0, 1.05 * xs.max())))
    if log:
        curve_axes[0].set_ylim(bottom=floor)
    for i in range(n, nrows * ncols):
        for r in range(rows_per):
            axes[rows_per * (i // ncols) + r, i % ncols].set_axis_off()
    bottom = [axes[rows_per * (i // ncols) + rows_per - 1, i % ncols] for i in range(n)]
    for ax in bottom:
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.set_xlabel(r"$\delta_a/\delta_{0,p}$ [-]", fontsize=8)
    grey = "0.35"
    handles = [
        Line2D([], [], color=grey, lw=1.8, label="median curve, up sweeps"),
        Line2D([], [], color=grey, lw=1.2, ls="--", label="median curve, down sweeps"),
        Patch(color=grey, alpha=0.45, lw=0, label="90 % credible band of the curve"),
    ]
    if not log:
        handles.append(Patch(color=grey, alpha=0.16, lw=0,
                             label="90 % predictive band, up sweeps (with noise)"))
    for k, st in sorted(styles.DIRECTION_STYLES.items()):
        handles.append(Line2D([], [], ls="none", marker=st["marker"], mfc=st["facecolor"],
                              mec=st["edgecolor"], label=f"measured, {styles.DIRECTION_NAMES[k]}"))
    if log:
        handles += [Line2D([], [], color="0.3", ls=":", lw=0.9,
                           label=r"noise $\sigma_\mathrm{shift}$ (fitted)"),
                    Line2D([], [], ls="none", marker="_", color="0.45",
                           label=f"at or below the floor {floor:.1g} (incl. positive shifts)")]
    if with_resid:
        handles.append(Patch(color="0.92", label="residual within ±2"))
    legend_outside(fig, handles, ncols=4 if log else 4)
    fig.suptitle("Posterior predictive frequency shift" + (" (log-log)" if log else "")
                 + r": $\delta_{0,p}$ is each law's own overlap of protocol p", fontsize=10)
    return fig
