"""Files of a simulation-based calibration run (inference.evidence.sbc): the ECDF difference
plot with its DKW band, and the ranks and p-values as JSON. inference.evidence.sbc computes;
this module draws and writes (atomically, data.io)."""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from beadrod.data.io import atomic_path, write_json  # noqa: E402
from beadrod.inference.evidence.sbc import SBCResult, ecdf_difference  # noqa: E402

__all__ = ["plot_ecdf", "write_sbc_json"]


def plot_ecdf(result: SBCResult, path: str | os.PathLike, alpha: float = 0.05) -> Path:
    """ECDF - uniform of the fractional ranks per parameter, with the simultaneous
    (1 - alpha) DKW band (Säilynoja, Bürkner & Vehtari 2022's display); PNG at ``path``."""
    grid, diff, eps = ecdf_difference(result, alpha=alpha)
    names = list(diff)
    fig, axes = plt.subplots(1, len(names), figsize=(3.2 * len(names), 3.0), squeeze=False,
                             sharey=True)
    for ax, k in zip(axes[0], names):
        ax.fill_between(grid, -eps, eps, color="0.85", label=f"DKW {1 - alpha:.0%} band")
        ax.plot(grid, diff[k], color="C0", label="ECDF - uniform")
        ax.axhline(0, color="k", lw=0.5)
        ax.set_title(f"{k}  (KS p = {result.pvalues[k]:.2f})", fontsize=9)
        ax.set_xlabel("fractional rank")
    axes[0][0].set_ylabel("ECDF - uniform")
    fig.suptitle(f"SBC: {len(next(iter(result.ranks.values())))} replicates, "
                 f"{result.n_draws} posterior draws each", fontsize=9)
    # the legend below the panels, where it hides no curve
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120)
    plt.close(fig)
    return Path(path)


def write_sbc_json(result: SBCResult, path: str | os.PathLike) -> Path:
    """Ranks, draws per replicate, KS p-values, divergences and wall time as JSON."""
    return write_json(path, {
        "n_draws": int(result.n_draws),
        "ranks": {k: np.asarray(v, int).tolist() for k, v in result.ranks.items()},
        "pvalues": {k: float(v) for k, v in result.pvalues.items()},
        "divergences": np.asarray(result.divergences, int).tolist(),
        "wall_s": float(result.wall_s),
    })
