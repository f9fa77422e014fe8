"""Figures of the data and of the physics: the paper's Figs. 4-10, FRCs, accuracy vs cost.

Every function takes plain numpy arrays (SI units unless the docstring says otherwise)
and returns a :class:`matplotlib.figure.Figure`; none of them knows how the numbers were
produced. Colours are fixed per contact law and per sweep direction so that a law looks
the same in every figure of a report.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence

import matplotlib

matplotlib.use("Agg")  # headless: figures are only ever written to files

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = [
    "LAW_COLORS",
    "DIRECTION_COLORS",
    "DIRECTION_NAMES",
    "law_color",
    "fig_shift_curves",
    "fig_max_shift_vs_n",
    "fig_f0_ranges",
    "fig_shift_ppc",
    "fig_q_vs_f0",
    "fig_inv_q_shift",
    "fig_frc",
    "fig_accuracy_cost",
]

# Paper colours where it has them (Hertz red, JKR green, viscoelastic black); the rest
# from the colour-blind-safe tab palette.
LAW_COLORS: dict[str, str] = {
    "hertz": "#d62728",
    "jkr": "#2ca02c",
    "viscoelastic": "#000000",
    "viscoelastic_paper": "#7f7f7f",
    "dmt": "#9467bd",
    "powerlaw": "#1f77b4",
}
# Paper Fig. 10: grey for up sweeps, orange for down sweeps. Direction 0 = up, 1 = down,
# as in data.process.ProcessedDataset.drive_direction.
DIRECTION_COLORS: dict[int, str] = {0: "#7f7f7f", 1: "#ff7f0e"}
DIRECTION_NAMES: dict[int, str] = {0: "up sweep", 1: "down sweep"}

_FALLBACK = ("#8c564b", "#e377c2", "#17becf", "#bcbd22", "#393b79", "#637939")
_SMALL = (5.0, 3.6)
_X_LABEL = r"$\delta_a/\delta_0$ [-]"
_SHIFT_LABEL = r"$\Delta f/f_0$ [-]"


def law_color(label: str, index: int = 0) -> str:
    """Colour of a law from its name or label (``"Hertz"``, ``"JKR (γ=0.7)"``, ``"power law"``).

    Matching is on the normalised text so a label and the law name give the same colour;
    unknown labels cycle through a fallback palette by ``index``.
    """
    key = label.lower().replace(" ", "").replace("-", "").replace("_", "")
    if "paper" in key and "visco" in key:
        return LAW_COLORS["viscoelastic_paper"]
    for name in ("viscoelastic", "hertz", "jkr", "dmt"):
        if name in key:
            return LAW_COLORS[name]
    if "visc" in key or "kuwabara" in key or "brilliantov" in key:
        return LAW_COLORS["viscoelastic"]
    if "power" in key or "rough" in key:
        return LAW_COLORS["powerlaw"]
    return _FALLBACK[index % len(_FALLBACK)]


def _new(figsize: tuple[float, float] = _SMALL, ncols: int = 1) -> tuple[Figure, np.ndarray]:
    fig, axes = plt.subplots(1, ncols, figsize=figsize, squeeze=False, layout="constrained")
    return fig, axes[0]


def _directions(direction: np.ndarray | None, n: int) -> np.ndarray:
    if direction is None:
        return np.zeros(n, dtype=int)
    d = np.asarray(direction).astype(int)
    if d.shape != (n,):
        raise ValueError(f"direction has shape {d.shape}, expected ({n},)")
    return d


def _scatter_by_direction(ax, x: np.ndarray, y: np.ndarray, direction: np.ndarray) -> None:
    for d in np.unique(direction):
        sel = (direction == d) & np.isfinite(x) & np.isfinite(y)
        ax.scatter(x[sel], y[sel], s=12, alpha=0.8, color=DIRECTION_COLORS.get(int(d), "k"),
                   label=DIRECTION_NAMES.get(int(d), f"direction {d}"), zorder=3)


def fig_shift_curves(x: np.ndarray, curves: Mapping[str, np.ndarray], *,
                     title: str | None = None) -> Figure:
    """Theoretical Δf/f0 versus δa/δ0, one curve per law (paper Fig. 4)."""
    x = np.asarray(x, dtype=float)
    fig, (ax,) = _new()
    styles = itertools.cycle(["-", "--", ":", "-."])
    for i, (label, y) in enumerate(curves.items()):
        ax.plot(x, np.asarray(y, dtype=float), next(styles), color=law_color(label, i),
                lw=1.6, label=label)
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel(_X_LABEL)
    ax.set_ylabel(_SHIFT_LABEL)
    ax.set_xlim(x.min(), x.max())
    ax.legend(fontsize=8)
    ax.set_title(title or "First-order frequency shift per contact law", fontsize=10)
    return fig


def fig_max_shift_vs_n(n: np.ndarray, shift: np.ndarray) -> Figure:
    """Maximum shift Δf/f0 at δa = δ0 versus the force exponent n (paper Fig. 5)."""
    n = np.asarray(n, dtype=float)
    fig, (ax,) = _new()
    ax.plot(n, np.asarray(shift, dtype=float), color=LAW_COLORS["powerlaw"], lw=1.6)
    ax.axhline(0.0, color="k", lw=0.5)
    for n_mark, name in ((1.5, "Hertz, n = 3/2"), (2.0, "n = 2")):
        if n.min() <= n_mark <= n.max():
            ax.axvline(n_mark, color=law_color(name), ls=":", lw=1.0)
            ax.annotate(name, (n_mark, 0.0), xytext=(3, 4), textcoords="offset points",
                        fontsize=8, rotation=90, va="bottom")
    ax.set_xlabel(r"force exponent $n$ in $F = C\,\delta^n$ [-]")
    ax.set_ylabel(r"$\Delta f/f_0$ at $\delta_a = \delta_0$ [-]")
    ax.set_title("Maximum first-order shift versus exponent", fontsize=10)
    return fig


def fig_f0_ranges(f0_measured: np.ndarray,
                  ranges: Mapping[str, tuple[float, float]]) -> Figure:
    """Measured linear resonances [Hz] per protocol against each law's range (paper Fig. 6)."""
    f0 = np.asarray(f0_measured, dtype=float)
    fig, (ax,) = _new()
    for i, (label, (lo, hi)) in enumerate(ranges.items()):
        ax.axhspan(lo / 1e3, hi / 1e3, color=law_color(label, i), alpha=0.2,
                   label=f"{label}: {lo / 1e3:.3f}-{hi / 1e3:.3f} kHz")
    ax.plot(np.arange(1, f0.size + 1), f0 / 1e3, "o", color="k", ms=4,
            label="measured $f_0$")
    ax.set_xlabel("protocol [-]")
    ax.set_ylabel(r"linear resonance $f_0$ [kHz]")
    ax.legend(fontsize=8)
    ax.set_title("Measured linear resonances and predicted ranges", fontsize=10)
    return fig


def fig_shift_ppc(x: np.ndarray, shift: np.ndarray, direction: np.ndarray | None,
                  x_grid: np.ndarray,
                  bands: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray]], *,
                  log: bool = False) -> Figure:
    """Posterior predictive Δf/f0 versus δa/δ0 with 90 % bands (paper Figs. 7 and 9).

    ``bands[label] = (q05, q50, q95)`` on ``x_grid``. With ``log=True`` both axes are
    logarithmic and −Δf/f0 is plotted (the shift is a softening); points and band parts
    that are not negative shifts cannot be shown there and are left out.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(shift, dtype=float)
    xg = np.asarray(x_grid, dtype=float)
    d = _directions(direction, x.size)
    sign = -1.0 if log else 1.0
    fig, (ax,) = _new()
    for i, (label, (q05, q50, q95)) in enumerate(bands.items()):
        lo, mid, hi = (sign * np.asarray(q, dtype=float) for q in (q05, q50, q95))
        lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
        if log:
            floor = np.nan
            lo = np.where(lo > 0, lo, np.where(hi > 0, hi * 1e-3, floor))
            hi = np.where(hi > 0, hi, floor)
            mid = np.where(mid > 0, mid, np.nan)
        c = law_color(label, i)
        ax.fill_between(xg, lo, hi, color=c, alpha=0.2, lw=0)
        ax.plot(xg, mid, color=c, lw=1.5, label=f"{label} (median, 90 % band)")
    if log:
        keep = (y < 0) & (x > 0)
        _scatter_by_direction(ax, x[keep], -y[keep], d[keep])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel(r"$-\Delta f/f_0$ [-]")
    else:
        _scatter_by_direction(ax, x, y, d)
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylabel(_SHIFT_LABEL)
    ax.set_xlabel(_X_LABEL)
    ax.legend(fontsize=7)
    ax.set_title("Posterior predictive frequency shift" + (" (log-log)" if log else ""),
                 fontsize=10)
    return fig


def fig_q_vs_f0(f0: np.ndarray, q: np.ndarray) -> Figure:
    """Q factor of each reference resonance versus its f0 [Hz] (paper Fig. 8)."""
    f0 = np.asarray(f0, dtype=float)
    q = np.asarray(q, dtype=float)
    ok = np.isfinite(f0) & np.isfinite(q)
    fig, (ax,) = _new()
    ax.plot(f0[ok] / 1e3, q[ok], "o", color="k", ms=4)
    ax.set_xlabel(r"linear resonance $f_0$ [kHz]")
    ax.set_ylabel(r"quality factor $Q$ [-]")
    ax.set_title(f"Q of the reference sweeps ({int(ok.sum())} protocols)", fontsize=10)
    return fig


def fig_inv_q_shift(x: np.ndarray, dinvq: np.ndarray, direction: np.ndarray | None) -> Figure:
    """Δ(1/Q) versus δa/δ0 on a log x axis, sweeps coloured by direction (paper Fig. 10)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(dinvq, dtype=float)
    d = _directions(direction, x.size)
    keep = np.isfinite(x) & np.isfinite(y) & (x > 0)
    fig, (ax,) = _new()
    _scatter_by_direction(ax, x[keep], y[keep], d[keep])
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xscale("log")
    ax.set_xlabel(_X_LABEL)
    ax.set_ylabel(r"$\Delta(1/Q)$ [-]")
    ax.legend(fontsize=8)
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
    fig, (ax,) = _new()
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
    fig, (ax,) = _new()
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
