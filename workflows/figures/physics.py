"""Figures of the data and of the physics: the paper's Figs. 4-6, 8 and 10, FRCs, accuracy
versus cost.

Every function takes plain numpy arrays (SI units unless the docstring says otherwise)
and returns a :class:`matplotlib.figure.Figure`; none of them knows how the numbers were
produced. Colours, labels and markers come from :mod:`workflows.figures.styles`, so a law looks
the same in every figure of a report and the data (black) never look like a law.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")  # headless: figures are only ever written to files

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from beadrod.workflows.figures import styles  # noqa: E402

__all__ = [
    "DIRECTION_NAMES",
    "Curve",
    "law_color",
    "new_axes",
    "directions",
    "scatter_by_direction",
    "legend_outside",
    "binned_trend",
    "fig_shift_curves",
    "fig_max_shift_vs_n",
    "fig_f0_ranges",
    "fig_q_vs_f0",
    "fig_inv_q_shift",
    "fig_frc",
    "fig_accuracy_cost",
]

DIRECTION_NAMES = styles.DIRECTION_NAMES
_SMALL = (5.0, 3.6)
_X_LABEL = r"$\delta_a/\delta_0$ [-]"
_SHIFT_LABEL = r"$\Delta f/f_0$ [-]"


def law_color(label: str, index: int = 0) -> str:
    """Colour of a law from its name or label (:func:`workflows.figures.styles.color`); ``index``
    is ignored: a label's colour never depends on order."""
    del index
    return styles.color(label)


def new_axes(figsize: tuple[float, float] = _SMALL, ncols: int = 1) -> tuple[Figure, np.ndarray]:
    """A constrained-layout figure with one row of ``ncols`` axes."""
    fig, axes = plt.subplots(1, ncols, figsize=figsize, squeeze=False, layout="constrained")
    return fig, axes[0]


def directions(direction: np.ndarray | None, n: int) -> np.ndarray:
    """Sweep directions as ints (0 up, 1 down); all up when ``direction`` is None."""
    if direction is None:
        return np.zeros(n, dtype=int)
    d = np.asarray(direction).astype(int)
    if d.shape != (n,):
        raise ValueError(f"direction has shape {d.shape}, expected ({n},)")
    return d


def scatter_by_direction(ax: Axes, x: np.ndarray, y: np.ndarray, direction: np.ndarray, *,
                         size: float = 16, alpha: float = 0.85, zorder: float = 5,
                         label: bool = True) -> None:
    """Measured points, up sweeps as filled ▲ and down sweeps as open ▽, over everything."""
    for d in np.unique(direction):
        sel = (direction == d) & np.isfinite(x) & np.isfinite(y)
        st = styles.DIRECTION_STYLES.get(int(d), styles.DIRECTION_STYLES[0])
        ax.scatter(x[sel], y[sel], s=size, alpha=alpha, marker=st["marker"],
                   facecolors=st["facecolor"], edgecolors=st["edgecolor"], linewidths=0.7,
                   label=DIRECTION_NAMES.get(int(d), f"direction {d}") if label else None,
                   zorder=zorder)


def legend_outside(fig: Figure, handles=None, labels=None, *, where: str = "lower center",
                   ncols: int = 3, fontsize: float = 7, title: str | None = None, **kw):
    """One figure legend outside every axes (constrained layout makes room for it)."""
    if handles is None:
        handles, labels = [], []
        for ax in fig.axes:
            for h, lab in zip(*ax.get_legend_handles_labels()):
                if lab not in labels and not lab.startswith("_"):
                    handles.append(h)
                    labels.append(lab)
    if labels is None:
        labels = [h.get_label() for h in handles]
    return fig.legend(handles, labels, loc=f"outside {where}", ncols=ncols, fontsize=fontsize,
                      title=title, title_fontsize=fontsize, frameon=False, **kw)


def binned_trend(x: np.ndarray, y: np.ndarray, *, bins: int = 8, log: bool = True,
                 min_count: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Median and interquartile range of ``y`` in ``bins`` bins of ``x`` (log-spaced with
    ``log``): (bin centre, median, q25, q75); bins with fewer than ``min_count`` points
    are left out."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y) & ((x > 0) if log else True)
    x, y = x[ok], y[ok]
    empty = (np.array([]),) * 4
    if x.size < min_count or np.ptp(x) == 0:
        return empty
    edges = (np.geomspace(x.min(), x.max(), bins + 1) if log
             else np.linspace(x.min(), x.max(), bins + 1))
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, bins - 1)
    rows = []
    for b in range(bins):
        v = y[idx == b]
        if v.size >= min_count:
            c = np.sqrt(edges[b] * edges[b + 1]) if log else 0.5 * (edges[b] + edges[b + 1])
            rows.append((c, *np.percentile(v, [50, 25, 75])))
    if not rows:
        return empty
    a = np.array(rows)
    return a[:, 0], a[:, 1], a[:, 2], a[:, 3]


@dataclass(frozen=True)
class Curve:
    """One curve of :func:`fig_shift_curves`: values on the shared x, the model whose
    colour it takes (None: resolved from its label), its line style, an optional band."""

    y: np.ndarray
    model: str | None = None
    linestyle: str = "-"
    band: tuple[np.ndarray, np.ndarray] | None = None
    width: float = 1.6


def _coincident_groups(curves: list[tuple[str, Curve]]) -> list[list[int]]:
    groups: list[list[int]] = []
    for i, (_, c) in enumerate(curves):
        y = np.asarray(c.y, dtype=float)
        for g in groups:
            _, first = curves[g[0]]
            if first.linestyle == c.linestyle and np.allclose(
                    y, first.y, rtol=1e-6, atol=1e-9 * max(1e-30, np.nanmax(np.abs(y))),
                    equal_nan=True):
                g.append(i)
                break
        else:
            groups.append([i])
    return groups


def fig_shift_curves(x: np.ndarray, curves: Mapping[str, np.ndarray | Curve], *,
                     title: str | None = None) -> Figure:
    """Δf/f0 versus δa/δ0, one curve per law and rung (paper Fig. 4), fitted laws with
    their 90 % band.

    Colour names the law, the line style the rung or the source (nominal theory or
    fit). Curves that coincide (Hertz and the viscoelastic law share one conservative
    backbone) are drawn in alternating dashes of their colours, so none hides another.
    """
    x = np.asarray(x, dtype=float)
    items = [(lab, c if isinstance(c, Curve) else Curve(np.asarray(c, dtype=float)))
             for lab, c in curves.items()]
    fig, (ax,) = new_axes((7.6, 4.0))
    any_shared = False
    handles = [None] * len(items)
    for group in _coincident_groups(items):
        k = len(group)
        any_shared |= k > 1
        for j, i in enumerate(group):
            lab, c = items[i]
            col = styles.color(c.model or lab)
            if c.band is not None:
                ax.fill_between(x, c.band[0], c.band[1], color=col, alpha=0.15, lw=0)
            ls = c.linestyle if k == 1 else (j * 4.0, (4.0, 4.0 * (k - 1)))
            ax.plot(x, np.asarray(c.y, dtype=float), color=col, ls=ls, lw=c.width)
            # the legend shows each curve's own style, not its share of the dashes
            handles[i] = Line2D([], [], color=col, ls=c.linestyle, lw=c.width,
                                label=styles.tex(lab) + (" (coincides)" if k > 1 else ""))
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel(_X_LABEL)
    ax.set_ylabel(_SHIFT_LABEL)
    ax.set_xlim(x.min(), x.max())
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0),
              borderaxespad=0, frameon=False,
              title="coinciding curves: alternating dashes" if any_shared else None,
              title_fontsize=7)
    ax.set_title(title or "Frequency shift per contact law: theory and fits", fontsize=10)
    return fig


def fig_max_shift_vs_n(n: np.ndarray, shift: np.ndarray, backbone: np.ndarray | None = None,
                       *, fitted: tuple[float, float, float] | None = None,
                       model: str = "powerlaw") -> Figure:
    """Shift Δf/f0 at δa = δ0 versus the force exponent n (paper Fig. 5).

    ``shift``: the paper's first-order average (zero at n = 1 and 2, positive beyond 2:
    "hardening"); ``backbone``: the exact conservative backbone, which softens for every
    n > 1. ``fitted`` = (median, lo, hi) of the power-law fit's n, drawn as a line and
    its interval.
    """
    n = np.asarray(n, dtype=float)
    fig, (ax,) = new_axes((5.6, 3.8))
    col = styles.color(model)
    ax.plot(n, np.asarray(shift, dtype=float), color=col, lw=1.6,
            ls=styles.RUNG_LINESTYLES["first_order"], label="first order (the paper's)")
    if backbone is not None:
        ax.plot(n, np.asarray(backbone, dtype=float), color=col, lw=1.8,
                ls=styles.RUNG_LINESTYLES["backbone"], label="exact backbone")
    ax.axhline(0.0, color="k", lw=0.5)
    for n_mark, name in ((1.5, "Hertz, n = 3/2"), (2.0, "n = 2")):
        if n.min() <= n_mark <= n.max():
            ax.axvline(n_mark, color="0.5", ls=":", lw=1.0)
            ax.annotate(name, (n_mark, 1.0), xycoords=("data", "axes fraction"),
                        xytext=(3, -4), textcoords="offset points", fontsize=7, rotation=90,
                        va="top")
    if fitted is not None:
        med, lo, hi = fitted
        ax.axvspan(lo, hi, color=col, alpha=0.25, lw=0,
                   label=f"fitted $n$ = {med:.3g} [{lo:.3g}, {hi:.3g}] (90 %)")
        ax.axvline(med, color=col, lw=1.0)
    ax.set_xlabel(r"force exponent $n$ in $F = C\,\delta^n$ [-]")
    ax.set_ylabel(r"$\Delta f/f_0$ at $\delta_a = \delta_0$ [-]")
    ax.legend(fontsize=7, loc="lower left")
    ax.set_title("Shift at contact loss versus exponent", fontsize=10)
    return fig


def fig_f0_ranges(f0_measured: np.ndarray, ranges: Mapping[str, tuple[float, float]], *,
                  protocol_ids: Sequence[str] | None = None) -> Figure:
    """Measured linear resonances [Hz] per protocol against each law's range (paper Fig. 6).

    The legend sits below the axes, so no protocol is hidden under it."""
    f0 = np.asarray(f0_measured, dtype=float)
    fig, (ax,) = new_axes((6.0, 3.8))
    for label, (lo, hi) in ranges.items():
        ax.axhspan(lo / 1e3, hi / 1e3, color=styles.color(label), alpha=0.25, lw=0,
                   label=f"{styles.tex(label)}: {lo / 1e3:.3f}-{hi / 1e3:.3f} kHz")
    pos = np.arange(1, f0.size + 1)
    ax.plot(pos, f0 / 1e3, "o", color=styles.DATA_COLOR, ms=4, label="measured $f_0$")
    if protocol_ids is not None and len(protocol_ids) == f0.size:
        ax.set_xticks(pos, list(protocol_ids), rotation=90, fontsize=6)
    ax.set_xlabel("protocol [-]")
    ax.set_ylabel(r"linear resonance $f_0$ [kHz]")
    legend_outside(fig, ncols=min(3, len(ranges) + 1))
    ax.set_title("Measured linear resonances and predicted ranges", fontsize=10)
    return fig


def fig_q_vs_f0(f0: np.ndarray, q: np.ndarray) -> Figure:
    """Q factor of each reference resonance versus its f0 [Hz] (paper Fig. 8)."""
    f0 = np.asarray(f0, dtype=float)
    q = np.asarray(q, dtype=float)
    ok = np.isfinite(f0) & np.isfinite(q)
    fig, (ax,) = new_axes()
    ax.plot(f0[ok] / 1e3, q[ok], "o", color=styles.DATA_COLOR, ms=4)
    ax.set_xlabel(r"linear resonance $f_0$ [kHz]")
    ax.set_ylabel(r"quality factor $Q$ [-]")
    ax.set_title(f"Q of the reference sweeps ({int(ok.sum())} protocols)", fontsize=10)
    return fig


def fig_inv_q_shift(x: np.ndarray, dinvq: np.ndarray, direction: np.ndarray | None, *,
                    bins: int = 8) -> Figure:
    """Δ(1/Q) versus δa/δ0 on a log x axis (paper Fig. 10), with the median and the
    interquartile range of each sweep direction in ``bins`` log-spaced amplitude bins."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(dinvq, dtype=float)
    d = directions(direction, x.size)
    keep = np.isfinite(x) & np.isfinite(y) & (x > 0)
    fig, (ax,) = new_axes((5.6, 4.0))
    scatter_by_direction(ax, x[keep], y[keep], d[keep], size=10, alpha=0.35, zorder=3)
    for k, dk in enumerate(np.unique(d[keep])):
        sel = keep & (d == dk)
        c, med, q25, q75 = binned_trend(x[sel], y[sel], bins=bins)
        if not c.size:
            continue
        st = styles.DIRECTION_STYLES.get(int(dk), styles.DIRECTION_STYLES[0])
        c = c * (1.0 + 0.05 * k)  # a small offset keeps the two sets of bars apart
        ax.errorbar(c, med, yerr=[med - q25, q75 - med], color=st["edgecolor"],
                    ls=st["ls"], marker=st["marker"], mfc=st["facecolor"], ms=5, lw=1.4,
                    capsize=2, zorder=6,
                    label=f"{DIRECTION_NAMES.get(int(dk), dk)}: median per bin (IQR)")
    ax.axhline(0.0, color="0.5", lw=0.5)
    ax.set_xscale("log")
    ax.set_xlabel(_X_LABEL)
    ax.set_ylabel(r"$\Delta(1/Q)$ [-]")
    legend_outside(fig, ncols=2)
    ax.set_title("Amplitude dependence of the inverse Q factor", fontsize=10)
    return fig


def fig_frc(freq: np.ndarray | Sequence[np.ndarray], amp: np.ndarray | Sequence[np.ndarray],
            labels: Sequence[str], *, amp_scale: float = 1e9,
            amp_label: str = r"bead amplitude $\delta_a$ [nm]") -> Figure:
    """Frequency-response curves: amplitude versus drive frequency [Hz], one per label.

    ``freq`` is one shared grid or one array per curve; ``amp`` one array per curve, in
    metres by default (``amp_scale`` converts to the plotted unit named by ``amp_label``).
    """
    amps = [np.asarray(a, dtype=float) for a in amp]
    if len(amps) != len(labels):
        raise ValueError(f"{len(amps)} amplitude curves but {len(labels)} labels")
    if _is_shared(freq):
        freqs = [np.asarray(freq, dtype=float)] * len(amps)
    else:
        freqs = [np.asarray(f, dtype=float) for f in freq]
    fig, (ax,) = new_axes()
    cmap = plt.get_cmap("viridis")
    for i, (f, a, lab) in enumerate(zip(freqs, amps, labels)):
        c = cmap(i / max(len(amps) - 1, 1))
        ax.plot(f / 1e3, a * amp_scale, color=c, lw=1.3, label=lab)
    ax.set_xlabel("drive frequency [kHz]")
    ax.set_ylabel(amp_label)
    ax.legend(fontsize=7)
    ax.set_title("Frequency-response curves", fontsize=10)
    return fig


def _is_shared(freq) -> bool:
    try:
        return np.asarray(freq, dtype=float).ndim == 1
    except (ValueError, TypeError):
        return False


def fig_accuracy_cost(table: Sequence[Mapping[str, float | str]]) -> Figure:
    """Error against the best rung versus time per evaluation [s], log-log, per rung.

    ``table`` rows have keys ``rung``, ``x`` (δa/δ0), ``error`` (|Δf/f0 − reference|) and
    ``time_s``. Zero errors (the reference rung itself) cannot sit on a log axis; they are
    drawn at the bottom edge with an open marker.
    """
    rungs: dict[str, list[Mapping]] = {}
    for row in table:
        rungs.setdefault(str(row["rung"]), []).append(row)
    err_all = np.array([float(r["error"]) for r in table], dtype=float)
    pos = err_all[np.isfinite(err_all) & (err_all > 0)]
    floor = pos.min() / 10 if pos.size else 1e-12
    fig, (ax,) = new_axes()
    markers = itertools.cycle("osD^v<>p")
    for i, (rung, rows) in enumerate(rungs.items()):
        t = np.array([float(r["time_s"]) for r in rows])
        e = np.array([float(r["error"]) for r in rows])
        m = next(markers)
        c = plt.get_cmap("tab10")(i % 10)
        ok = np.isfinite(e) & (e > 0) & (t > 0)
        ax.scatter(t[ok], e[ok], marker=m, color=c, s=22, label=rung)
        zero = (e == 0) & (t > 0)
        if zero.any():
            ax.scatter(t[zero], np.full(zero.sum(), floor), marker=m, facecolors="none",
                       edgecolors=c, s=22, label=f"{rung} (reference, error 0)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time per evaluation [s]")
    ax.set_ylabel(r"error $|\Delta f/f_0 - \mathrm{reference}|$ [-]")
    ax.legend(fontsize=7)
    ax.set_title("What accuracy costs in time", fontsize=10)
    return fig
