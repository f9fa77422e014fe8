"""Figures of the inference: η tension, evidence, pair and rank plots, LOO-PIT.

Inputs are plain numpy arrays or an ``arviz.InferenceData``. The pair and rank plots are
drawn by hand from the posterior draws: far cheaper than the generic plotting
back-ends. Colours, labels and symbols:
:mod:`workflows.figures.styles`.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from beadrod.workflows.figures import styles
from beadrod.workflows.figures.physics import legend_outside, new_axes, plt

__all__ = [
    "TENSION_COLORS",
    "fig_eta_tension",
    "fig_evidence",
    "fig_pair",
    "fig_rank",
    "fig_loo_pit",
    "posterior_columns",
]

TENSION_COLORS: dict[str, str] = {k: v["color"] for k, v in styles.TENSION_STYLES.items()}
_ETA_LABEL = r"$\log_{10}\,\eta$ [$\eta$ in Pa s]"
_EXTRA = ("#666666", "#997700", "#994455", "#6699CC")  # labels that name no estimate


def _tension_kind(label: str) -> str | None:
    """Which η estimate a label names: ``"joint"``, ``"shift"``, ``"q"`` or None."""
    key = label.lower()
    if re.search(r"joint|shared|both", key):
        return "joint"
    if "shift" in key:
        return "shift"
    if re.search(r"\bq\b|q[-_ ]?factor", key):
        return "q"
    return None


def _tension_style(label: str, index: int) -> dict:
    kind = _tension_kind(label)
    if kind:
        return styles.TENSION_STYLES[kind]
    return {"color": _EXTRA[index % len(_EXTRA)], "ls": "-.", "lw": 1.4, "fill": False}


def fig_eta_tension(samples: Mapping[str, np.ndarray], *,
                    ranges: Mapping[str, tuple[float, float]] | None = None) -> Figure:
    """Posteriors of log10 η [Pa s] from the shift, from Q, and joint, on one axis.

    ``ranges`` (log10 η bounds) are shaded; by default they are the 90 % intervals of
    the sample sets whose label names the shift or Q, i.e. the shift-implied and the
    Q-implied viscosity. Disjoint shaded spans are the tension. Q alone is drawn filled
    and the joint posterior dashed over it, so neither hides the other when they agree.
    """
    fig, (ax,) = new_axes((6.0, 4.2))
    arrays = {k: np.asarray(v, dtype=float).ravel() for k, v in samples.items()}
    arrays = {k: v[np.isfinite(v)] for k, v in arrays.items()}
    if ranges is None:
        ranges = {}
        for label, v in arrays.items():
            if v.size and _tension_kind(label) in ("shift", "q"):
                lo, hi = np.quantile(v, [0.05, 0.95])
                ranges[f"{label}: 90 % interval"] = (float(lo), float(hi))
    for i, (label, (lo, hi)) in enumerate(ranges.items()):
        ax.axvspan(lo, hi, color=_tension_style(label, i)["color"], alpha=0.10, lw=0,
                   label=styles.tex(label))
    finite = [v for v in arrays.values() if v.size]
    if finite:
        allv = np.concatenate(finite)
        edges = np.linspace(allv.min(), allv.max(), 61) if np.ptp(allv) > 0 else 20
    else:
        edges = 20
    for i, (label, v) in enumerate(arrays.items()):
        if not v.size:
            continue
        st = _tension_style(label, i)
        q05, q50, q95 = np.quantile(v, [0.05, 0.5, 0.95])
        text = f"{styles.tex(label)}: {q50:.2f} [{q05:.2f}, {q95:.2f}]"
        if st["fill"]:
            ax.hist(v, bins=edges, density=True, histtype="stepfilled", color=st["color"],
                    alpha=0.35, lw=0, zorder=2)
        ax.hist(v, bins=edges, density=True, histtype="step", lw=st["lw"], ls=st["ls"],
                color=st["color"], label=text, zorder=3 + i)
    ax.set_xlabel(_ETA_LABEL)
    ax.set_ylabel("posterior density [per decade]")
    legend_outside(fig, ncols=2, title=r"median [90 % interval] of $\log_{10}\,\eta$")
    ax.set_title("Viscosity from the shift, from Q, and jointly", fontsize=10)
    return fig


def _value_text(v: float, e: float) -> str:
    if not np.isfinite(v):
        return "n/a"
    if not np.isfinite(e) or e <= 0:
        return f"{v:.1f}"
    digits = max(0, min(6, 1 - int(np.floor(np.log10(e)))))
    return f"{v:.{digits}f} ± {e:.{digits}f}"


def fig_evidence(laws: Sequence[str], logz: Sequence[float], logz_err: Sequence[float],
                 logz2: Sequence[float] | None = None,
                 logz2_err: Sequence[float] | None = None, *,
                 estimators: tuple[str, str] = ("estimator 1", "estimator 2"),
                 failed: Sequence[bool] | None = None, names: Sequence[str] | None = None,
                 preferred: str | None = None, reference: str | None = None) -> Figure:
    """log Z per law relative to a reference, ± 1σ, for one or two evidence estimators.

    ``names`` gives each entry's model name (``laws``: their labels). The reference (Δ = 0)
    is ``reference``, else the ``preferred`` law, else the largest log Z. Each value is
    written beside its point as "Δ ± σ" with as many digits as its error, because most
    errors are far smaller than a marker. The preferred law is starred; failed laws are
    shaded and say FAILED under their name. Marker shape names the estimator (legend,
    in black), colour the law (tick labels).
    """
    n = len(laws)
    names = list(names) if names is not None else list(laws)
    z1 = np.asarray(logz, dtype=float)
    e1 = np.asarray(logz_err, dtype=float)
    ref_name = reference if reference in names else preferred
    ref_i = names.index(ref_name) if ref_name in names else (
        int(np.nanargmax(z1)) if np.isfinite(z1).any() else None)
    ref = z1[ref_i] if ref_i is not None and np.isfinite(z1[ref_i]) else 0.0
    fail = np.zeros(n, bool) if failed is None else np.asarray(failed, bool)
    pos = np.arange(n)
    fig, (ax,) = new_axes((max(5.0, 1.3 * n + 2.5), 4.2))
    off = 0.14 if logz2 is not None else 0.0
    cols = [styles.color(nm) for nm in names]
    sets = [(z1, e1, "o", -off)]
    if logz2 is not None:
        z2 = np.asarray(logz2, dtype=float)
        e2 = np.zeros(n) if logz2_err is None else np.asarray(logz2_err, dtype=float)
        sets.append((z2, e2, "s", off))
    for k, (z, e, m, dx) in enumerate(sets):
        for i in range(n):
            ax.errorbar(pos[i] + dx, z[i] - ref, yerr=e[i], fmt=m, color=cols[i], ms=6,
                        mfc=cols[i] if k == 0 else "white", capsize=4, elinewidth=1.5,
                        zorder=3)
            ax.annotate(_value_text(z[i] - ref, e[i]), (pos[i] + dx, z[i] - ref),
                        xytext=(6, 6 if k == 0 else -11), textcoords="offset points",
                        fontsize=6.5, color="0.1", zorder=5,
                        bbox={"boxstyle": "square,pad=0.1", "fc": "white", "ec": "none",
                              "alpha": 0.8})
    if preferred in names:
        i = names.index(preferred)
        ax.plot(pos[i] - off, z1[i] - ref, marker="*", ms=15, color=cols[i], mec="k",
                mew=0.6, ls="none", zorder=4)
    ax.margins(x=0.12, y=0.14)  # room for the printed values
    ylo, yhi = ax.get_ylim()
    errs = np.concatenate([e[np.isfinite(e)] for _, e, _, _ in sets])
    if errs.size and errs.max() < 0.01 * (yhi - ylo):  # under ~2 pt on a 4 in axis
        ax.text(0.01, 0.98, "1σ error bars are smaller than the markers: see the printed "
                "values", transform=ax.transAxes, fontsize=7, va="top", color="0.3")
    for i in np.flatnonzero(fail):  # light, behind the points: the values stay legible
        ax.axvspan(pos[i] - 0.4, pos[i] + 0.4, facecolor="#fbe3e3", edgecolor="#e8a0a0",
                   hatch="//", lw=0.0, zorder=0)
    ax.axhline(0.0, color="0.4", lw=0.6)
    ticks = [styles.tex(t) + (" ★" if nm == preferred else "") + ("\nFAILED" if f else "")
             for t, nm, f in zip(laws, names, fail)]
    ax.set_xticks(pos, ticks, rotation=20, ha="right", fontsize=8)
    for t, c, nm in zip(ax.get_xticklabels(), cols, names):
        t.set_color(c)
        if nm == preferred:
            t.set_fontweight("bold")
    ref_name = laws[ref_i] if ref_i is not None else "best"
    ax.set_ylabel(r"$\log Z - \log Z_\mathrm{ref}$ [nats]")
    handles = [Line2D([], [], marker="o", color="k", ls="none", label=estimators[0])]
    if logz2 is not None:
        handles.append(Line2D([], [], marker="s", mfc="white", color="k", ls="none",
                              label=estimators[1]))
    if preferred in names:
        handles.append(Line2D([], [], ls="none", marker="*", color="k", ms=8,
                              label="preferred law"))
    if fail.any():
        handles.append(Patch(facecolor="#fbe3e3", edgecolor="#e8a0a0", hatch="//",
                             label="failed its sampling gate"))
    legend_outside(fig, handles, ncols=3)
    ax.set_title(f"Evidence per model relative to {styles.tex(ref_name)}", fontsize=10)
    return fig


def posterior_columns(idata, var_names: Sequence[str], *, group: str = "posterior"
                      ) -> tuple[list[str], np.ndarray]:
    """Flatten named variables to scalar columns: (names, draws of shape (chain, draw, k)).

    Vector-valued variables give one column per element, named ``var[i,j]``.
    """
    ds = getattr(idata, group)
    names: list[str] = []
    cols: list[np.ndarray] = []
    for v in var_names:
        if v not in ds:
            raise KeyError(f"variable {v!r} not in the {group} group "
                           f"(has: {', '.join(map(str, ds.data_vars))})")
        arr = np.asarray(ds[v].values, dtype=float)
        chain, draw = arr.shape[:2]
        flat = arr.reshape(chain, draw, -1)
        if flat.shape[-1] == 1 and arr.ndim == 2:
            names.append(v)
        else:
            names.extend(f"{v}[{','.join(map(str, idx))}]" for idx in np.ndindex(arr.shape[2:]))
        cols.append(flat)
    return names, np.concatenate(cols, axis=-1)


def fig_pair(idata, var_names: Sequence[str], *, units: Mapping[str, str] | None = None,
             max_points: int = 2000, seed: int = 0) -> Figure:
    """Scatter matrix of the posterior: histograms on the diagonal, draws below it.

    Divergent transitions (``sample_stats.diverging``) are overdrawn in red. At most
    ``max_points`` draws are scattered (a random, reproducible subset). ``units`` maps a
    variable name to the unit written on its axis label.
    """
    names, draws = posterior_columns(idata, var_names)
    units = units or {}
    labels = [styles.axis_label(n, units[n.split("[")[0]]) if n.split("[")[0] in units
              else styles.param_label(n)
              for n in names]
    k = len(names)
    flat = draws.reshape(-1, k)
    div = np.zeros(flat.shape[0], bool)
    ss = getattr(idata, "sample_stats", None)
    if ss is not None and "diverging" in ss:
        div = np.asarray(ss["diverging"].values, bool).reshape(-1)
    rng = np.random.default_rng(seed)
    idx = np.arange(flat.shape[0])
    if idx.size > max_points:
        idx = np.sort(rng.choice(idx, max_points, replace=False))
    size = min(1.6 * k + 0.8, 11.0)
    fig, axes = plt.subplots(k, k, figsize=(size, size), squeeze=False, layout="constrained")
    for i in range(k):
        for j in range(k):
            ax = axes[i, j]
            if j > i:
                ax.set_axis_off()
                continue
            if i == j:
                ax.hist(flat[:, i], bins=30, color="#1f77b4", alpha=0.7)
                ax.set_yticks([])
            else:
                ax.scatter(flat[idx, j], flat[idx, i], s=2, alpha=0.3, color="#1f77b4")
                d = idx[div[idx]]
                if d.size:
                    ax.scatter(flat[d, j], flat[d, i], s=6, color="red")
            if i == k - 1:
                ax.set_xlabel(labels[j], fontsize=8)
            else:
                ax.set_xticklabels([])
            if j == 0 and i > 0:
                ax.set_ylabel(labels[i], fontsize=8)
            ax.tick_params(labelsize=6)
    fig.suptitle(f"Posterior pair plot ({int(div.sum())} divergences in red)", fontsize=10)
    return fig


def fig_rank(idata, var_names: Sequence[str], *, bins: int = 20) -> Figure:
    """Rank histograms per chain (Vehtari et al. 2021): flat and alike when chains mix.

    All draws of a variable are ranked together; each chain's ranks are histogrammed.
    The grey band is the 99 % range of a bin count under perfect mixing (binomial).
    """
    names, draws = posterior_columns(idata, var_names)
    chains, n_draw, k = draws.shape
    ncols = min(k, 3)
    nrows = int(np.ceil(k / ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.0 * ncols + 0.5, 2.3 * nrows),
                             squeeze=False, layout="constrained")
    edges = np.linspace(0, chains * n_draw, bins + 1)
    p = 1.0 / bins
    mean = n_draw * p
    half = 2.576 * np.sqrt(n_draw * p * (1 - p))
    cmap = plt.get_cmap("tab10")
    for c in range(k):
        ax = axes.flat[c]
        ranks = np.argsort(np.argsort(draws[:, :, c].ravel(), kind="stable"))
        ranks = ranks.reshape(chains, n_draw)
        ax.axhspan(mean - half, mean + half, color="0.85", lw=0)
        for ch in range(chains):
            counts, _ = np.histogram(ranks[ch], bins=edges)
            ax.stairs(counts, edges, color=cmap(ch % 10), lw=1.2, label=f"chain {ch}")
        ax.axhline(mean, color="k", lw=0.6, ls="--")
        ax.set_title(styles.param_label(names[c]), fontsize=9)
        ax.set_xlabel("rank of draw (all chains) [-]", fontsize=8)
        ax.set_ylabel("draws per bin [-]", fontsize=8)
        ax.tick_params(labelsize=7)
    for c in range(k, nrows * ncols):
        axes.flat[c].set_axis_off()
    axes.flat[0].legend(fontsize=6)
    return fig


def fig_loo_pit(idata, y: str | Sequence[str] | None = None) -> Figure:
    """LOO-PIT ECDF minus the uniform CDF, one panel per observed variable.

    Calibrated predictions give PIT values uniform on [0, 1], so the curve stays inside
    the grey pointwise 95 % band; an S shape means over- or under-dispersion, a one-sided
    excursion a bias. Needs the observed_data, posterior_predictive and log_likelihood
    groups.
    """
    from beadrod.inference.evidence.ranking import loo_pit_values

    for group in ("observed_data", "posterior_predictive", "log_likelihood"):
        if not hasattr(idata, group):
            raise ValueError(f"LOO-PIT needs the {group!r} group in the InferenceData")
    if y is None:
        names = [v for v in idata.observed_data.data_vars
                 if v in idata.posterior_predictive and v in idata.log_likelihood]
    else:
        names = [y] if isinstance(y, str) else list(y)
    if not names:
        raise ValueError("no observed variable has both posterior_predictive and "
                         "log_likelihood draws")
    fig, axes = plt.subplots(1, len(names), figsize=(3.8 * len(names) + 0.4, 3.2),
                             squeeze=False, layout="constrained")
    u = np.linspace(0.0, 1.0, 201)
    for ax, name in zip(axes[0], names):
        with warnings.catch_warnings():
            # Small test posteriors trip the Pareto-k warning; k is reported elsewhere.
            warnings.simplefilter("ignore", UserWarning)
            pit = loo_pit_values(idata, name)
        pit = pit[np.isfinite(pit)]
        n = max(pit.size, 1)
        ecdf = np.searchsorted(np.sort(pit), u, side="right") / n
        band = 1.96 * np.sqrt(u * (1 - u) / n)
        ax.fill_between(u, -band, band, color="0.85", lw=0, label="95 % band (pointwise)")
        ax.plot(u, ecdf - u, color="#1f77b4", lw=1.4, label="LOO-PIT ECDF − uniform")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_xlabel("PIT value [-]")
        ax.set_ylabel("ECDF difference [-]")
        ax.set_title(f"LOO-PIT: {name} ({pit.size} points)", fontsize=9)
    axes[0, 0].legend(fontsize=7)
    return fig
