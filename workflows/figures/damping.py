"""Figures of the damping evidence (docs/damping.md): the paper's Fig. 10 with each law's
posterior predictive band, and the loss change against the frequency drop with what each
loss mechanism predicts for it.

The amplitude observable a_i = ln(δ_i/V_i) − ln(δ_ref/V_ref) is shown as the paper's
Eq. 31, Δ(1/Q) = (1/Q_ref,p)(exp(−a_i) − 1) (:func:`inference.model.amplitude.eq31`): the
transform is monotone, so the quantiles
of the transformed draws are the transformed quantiles and the band says what the
likelihood says. :func:`inv_q_panel` computes one law's numbers from its InferenceData;
the figure functions only draw.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import matplotlib

matplotlib.use("Agg")  # headless: figures are only ever written to files

import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.patheffects import withStroke  # noqa: E402

from beadrod.inference.model.amplitude import eq31  # noqa: E402
from beadrod.models.laws.masing import loss_to_shift_ratio  # noqa: E402
from beadrod.workflows.figures import styles  # noqa: E402
from beadrod.workflows.figures.numbers import data_overlap  # noqa: E402
from beadrod.workflows.figures.physics import (  # noqa: E402
    legend_outside,
    new_axes,
    plt,
    scatter_by_direction,
)

__all__ = ["InvQPanel", "inv_q_panel", "fig_inv_q_ppc", "fig_loss_vs_shift"]

_INV_Q_LABEL = r"$\Delta(1/Q)$ (Eq. 31) [-]"
# the three families of fig_loss_vs_shift: colour names the family (Tol high contrast)
_ELASTIC, _VISCOUS, _HYSTERETIC = "#004488", "#DDAA33", "#BB5566"
_BACKGROUND_NAMES = {0: "constant loss factor", 1: "constant dashpot",
                     2: "stiffness loss factor"}


@dataclass(frozen=True)
class InvQPanel:
    """One law's panel of :func:`fig_inv_q_ppc`, one entry per usable drive sweep.

    ``x``: δa/δ0,p with δ0,p this law's overlap of protocol p (posterior median);
    ``observed``: the measured Eq. 31 value; ``predictive`` = (q05, q50, q95) of the
    posterior predictive Eq. 31 value (noise included); ``median``: the noise-free
    median (from ``amp_pred``); ``direction``: 0 up, 1 down; ``q_measured``: False where
    the protocol has no measured reference Q and the plug-in (the median Q) scales it.
    ``band`` = (bin centre, q05, noise-free median, q95) of the draws of all sweeps in
    each log-spaced bin of x, pooled (see :func:`fig_inv_q_ppc`).
    """

    name: str
    label: str
    x: np.ndarray
    observed: np.ndarray
    predictive: tuple[np.ndarray, np.ndarray, np.ndarray]
    median: np.ndarray
    direction: np.ndarray
    q_measured: np.ndarray
    band: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _draws(group: Any, name: str) -> np.ndarray:
    a = np.asarray(group[name], float)
    return a.reshape(-1, *a.shape[2:])


def _pooled_band(x: np.ndarray, rep: np.ndarray, pred: np.ndarray, bins: int,
                 min_count: int = 3) -> tuple[np.ndarray, ...]:
    ok = np.isfinite(x) & (x > 0)
    if ok.sum() < min_count:
        return (np.array([]),) * 4
    edges = np.geomspace(x[ok].min(), x[ok].max() * (1 + 1e-12), bins + 1)
    idx = np.searchsorted(edges, x, side="right") - 1
    rows = [(np.sqrt(edges[b] * edges[b + 1]), *np.quantile(rep[:, sel], [0.05, 0.95]),
             np.median(pred[:, sel]))
            for b in range(bins) if (sel := ok & (idx == b)).sum() >= min_count]
    if not rows:
        return (np.array([]),) * 4
    c, lo, hi, med = np.array(rows).T
    return c, lo, med, hi


def inv_q_panel(name: str, label: str, idata: Any, inputs: dict[str, Any],
                ds: Any, *, bins: int = 10) -> InvQPanel | None:
    """The numbers of one law's Fig. 10 panel (see :class:`InvQPanel`); None where the fit
    has no amplitude observable (no ``amp_obs`` draws or no ``amp_pred``).

    Observed and predicted values are both scaled by the model's Q_ref,p
    (``inputs["q_plugin"]``), so that points and band share one scale; where a protocol
    has its measured Q this is ``ds.drive_inv_q_shift``.
    """
    pp = getattr(idata, "posterior_predictive", None)
    if pp is None or "amp_obs" not in pp or "amp_pred" not in idata.posterior:
        return None
    idx = np.asarray(inputs["amp_idx"]).astype(int)
    proto = np.asarray(inputs["amp_proto"]).astype(int)
    q = np.asarray(inputs["q_plugin"], float)[proto]
    x = np.asarray(inputs["amplitude"], float)[idx] / data_overlap(idata, ds)[proto]
    rep = eq31(_draws(pp, "amp_obs"), q)
    pred = eq31(_draws(idata.posterior, "amp_pred"), q)
    q05, q50, q95 = np.quantile(rep, [0.05, 0.5, 0.95], axis=0)
    return InvQPanel(
        name=name, label=label, x=x, observed=eq31(inputs["amp_obs"], q),
        predictive=(q05, q50, q95), median=np.median(pred, axis=0),
        direction=np.asarray(inputs["direction"])[idx].astype(int),
        q_measured=np.isfinite(np.asarray(ds.q_ref, float))[proto],
        band=_pooled_band(x, rep, pred, bins))


def fig_inv_q_ppc(panels: Sequence[InvQPanel], *, ncols: int = 3) -> Figure:
    """Δ(1/Q) of every usable sweep against δa/δ0,p (log x), one panel per law, with the
    law's posterior predictive band (paper Fig. 10).

    Each sweep's 90 % predictive interval is a faint vertical line. The band is binned
    (``InvQPanel.band``): in each log-spaced bin of x, the 5-95 % quantiles of the
    predictive draws of all the bin's sweeps pooled, and the pooled noise-free median as
    the line. Sweeps of one x come from protocols with different Q_ref and reference
    errors, so the per-sweep interval jumps from sweep to sweep: joined in x order it
    would draw that scatter, not the law. The bin's points are a sample of the mixture
    of its sweeps' predictive distributions, so about 90 % of them should lie in the
    pooled band; the median of the per-sweep intervals (the typical sweep's) is narrower
    than that mixture and would make a calibrated law look overconfident.
    """
    if not panels:
        raise ValueError("fig_inv_q_ppc needs at least one panel")
    n = len(panels)
    ncols = max(1, min(ncols, n))
    nrows = int(np.ceil(n / ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(max(3.9 * ncols + 0.4, 6.4),
                                                     3.0 * nrows + 1.0),
                             squeeze=False, sharex=True, sharey=True, layout="constrained")
    for i, p in enumerate(panels):
        ax = axes[i // ncols, i % ncols]
        col = styles.color(p.name)
        lo, _, hi = (np.asarray(v, float) for v in p.predictive)
        ok = np.isfinite(p.x) & (p.x > 0)
        ax.add_collection(LineCollection(
            [((x, a), (x, b)) for x, a, b in zip(p.x[ok], lo[ok], hi[ok])],
            colors=col, linewidths=0.6, alpha=0.15, zorder=1))
        c, q05, med, q95 = p.band
        if c.size:  # held flat from the outer bins' centres to the data's ends
            c = np.r_[p.x[ok].min(), c, p.x[ok].max()]
            q05, med, q95 = (np.r_[v[0], v, v[-1]] for v in (q05, med, q95))
            ax.fill_between(c, q05, q95, color=col, alpha=0.3, lw=0, zorder=2)
            ax.plot(c, med, color=col, lw=1.8, zorder=3,
                    path_effects=[withStroke(linewidth=3.2, foreground="white")])
        meas = ok & p.q_measured
        scatter_by_direction(ax, p.x[meas], p.observed[meas], p.direction[meas], size=10,
                             alpha=0.6, zorder=4)
        plug = ok & ~p.q_measured
        ax.scatter(p.x[plug], p.observed[plug], s=10, marker="x", color="0.55", lw=0.7,
                   zorder=4)
        ax.axhline(0.0, color="0.4", lw=0.6, zorder=2)
        ax.set_xscale("log")
        ax.set_title(styles.tex(p.label), fontsize=9, color=col)
        ax.tick_params(labelsize=7)
        if i % ncols == 0:
            ax.set_ylabel(_INV_Q_LABEL, fontsize=8)
        if i // ncols == nrows - 1 or i + ncols >= n:
            ax.xaxis.set_tick_params(labelbottom=True)
            ax.set_xlabel(r"$\delta_a/\delta_{0,p}$ [-]", fontsize=8)
    for i in range(n, nrows * ncols):
        axes[i // ncols, i % ncols].set_axis_off()
    xs = np.concatenate([p.x[np.isfinite(p.x) & (p.x > 0)] for p in panels])
    if xs.size:  # the data's range (an empty collection would pull the log axis to 0)
        axes[0, 0].set_xlim(0.8 * xs.min(), 1.25 * xs.max())
    grey = "0.35"
    handles = [Line2D([], [], color=grey, lw=1.8, label="noise-free median (binned)"),
               Patch(color=grey, alpha=0.3, lw=0,
                     label="90 % predictive band (sweeps of a bin pooled)"),
               Line2D([], [], color=grey, lw=0.6, alpha=0.5,
                      label="90 % predictive interval of each sweep")]
    for k, st in sorted(styles.DIRECTION_STYLES.items()):
        handles.append(Line2D([], [], ls="none", marker=st["marker"], mfc=st["facecolor"],
                              mec=st["edgecolor"], label=f"measured, {styles.DIRECTION_NAMES[k]}"))
    if any((~p.q_measured).any() for p in panels):
        handles.append(Line2D([], [], ls="none", marker="x", color="0.55",
                              label=r"no measured $Q_\mathrm{ref}$ (median $Q$ plugged in)"))
    legend_outside(fig, handles, ncols=3 if ncols > 1 else 2)
    fig.suptitle(r"Posterior predictive $\Delta(1/Q)$ (Eq. 31) per law; "
                 r"$\delta_{0,p}$: the law's overlap", fontsize=10)
    return fig


def fig_loss_vs_shift(shift: Any, inv_q: Any, q_ref: Any, *,
                      exponents: Sequence[float] = (1.6, 2.0, 2.6),
                      background: Sequence[float] = (0, 1, 3),
                      direction: Any = None) -> Figure:
    """Measured Δ(1/Q) (Eq. 31) against −Δf/f0 of each sweep, with what each loss
    mechanism predicts, drawn at the median reference Q0 of ``q_ref`` (per protocol).

    - Elastic laws with a background loss L0 Ω^β (``background``, thin blue): under base
      excitation Eq. 31 reads (1/Q0)(Ω^(β−2) − 1), Ω = 1 + Δf/f0 (docs/damping.md: the
      force grows as Ω²); β = 2 is the zero line. β = 3 is also the viscous
      Kuwabara–Kono contact and radiation into the rod (gold, dashed): one line.
    - Masing hysteresis of exponent m (``exponents``, red): Δ(1/Q) = ρ(m)|Δf/f0|, the
      pure-hysteresis line (the hysteretic share of both shift and loss). A real
      hysteretic law adds the elastic shift of its contact, which moves a point right
      without loss, and the base-excitation and background terms above (a few per cent
      of ρ): its points lie right of its line, not on it.

    ``direction`` (0 up, 1 down) sets the markers. Lines carry a ``gid`` ("background
    beta=0", "hysteretic m=2", ...) so that a reader can find them.
    """
    s = np.asarray(shift, float)
    y = np.asarray(inv_q, float)
    d = np.zeros(s.size, int) if direction is None else np.asarray(direction).astype(int)
    qr = np.asarray(q_ref, float)
    qr = qr[np.isfinite(qr) & (qr > 0)]
    if not qr.size:
        raise ValueError("fig_loss_vs_shift needs at least one finite reference Q")
    q0 = float(np.median(qr))
    ok = np.isfinite(s) & np.isfinite(y)
    x = -s
    fig, (ax,) = new_axes((8.4, 4.4))
    scatter_by_direction(ax, x[ok], y[ok], d[ok], size=10, alpha=0.5, zorder=5)
    top = max(float(x[ok].max()) if ok.any() else 0.0, 1e-6) * 1.05
    g = np.linspace(0.0, top, 200)
    omega = 1.0 - g
    lines = []
    for beta in background:
        if np.isclose(beta, 3.0):
            kw = {"color": _VISCOUS, "ls": "--", "lw": 2.0,
                  "label": r"viscous (Kuwabara–Kono) / rod radiation: $L_0\Omega^3$"}
        else:
            name = _BACKGROUND_NAMES.get(int(beta), "") if float(beta).is_integer() else ""
            kw = {"color": _ELASTIC, "ls": (0, (1 + 2 * len(lines), 1.5)), "lw": 1.0,
                  "label": rf"elastic + background $L_0\Omega^{{{beta:g}}}$" + (
                      f" ({name})" if name else "")}
        lines.append(ax.plot(g, (omega ** (beta - 2.0) - 1.0) / q0,
                             gid=f"background beta={beta:g}", **kw)[0])
    ax.axhline(0.0, color="0.4", lw=0.6, zorder=1,
               label=r"elastic + background $L_0\Omega^2$ (stiffness loss factor): 0")
    for j, m in enumerate(exponents):
        rho = float(loss_to_shift_ratio(float(m)))
        shade = 0.45 + 0.55 * (j + 1) / len(exponents)
        ax.plot(g, rho * g, color=_HYSTERETIC, lw=1.6, alpha=shade,
                ls=("-", "-.", (0, (5, 2)))[j % 3], gid=f"hysteretic m={m:g}",
                label=rf"Masing hysteresis alone, $m$ = {m:g}: $\rho$ = {rho:.2f}")
    # the data set the view; the steep hysteretic lines may leave it through the top
    ys = np.concatenate([np.percentile(y[ok], [0.5, 99.5]) if ok.any() else [0.0],
                         *[ln.get_ydata() for ln in lines], [0.0]])
    pad = 0.08 * (ys.max() - ys.min() or 1e-4)
    ax.set_ylim(ys.min() - pad, ys.max() + pad)
    ax.set_xlim(min(0.0, float(x[ok].min()) if ok.any() else 0.0) - 0.02 * top, top)
    ax.set_xlabel(r"$-\Delta f/f_0$ [-]")
    ax.set_ylabel(_INV_Q_LABEL)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0,
              frameon=False, title=f"lines at the median reference $Q_0$ = {q0:.3g}",
              title_fontsize=7)
    ax.set_title("Loss change against frequency drop: what each mechanism predicts",
                 fontsize=10)
    return fig
