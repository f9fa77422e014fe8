"""All beadrod figures, and :func:`save_figure` which writes them as PNG and PDF.

The figure functions live in :mod:`workflows.figures.physics` (the paper's figures, FRCs,
accuracy vs cost), :mod:`workflows.figures.ppc` (the posterior predictive shift, the
paper's Figs. 7 and 9) and :mod:`workflows.figures.posterior` (tension, evidence, pair,
rank, LOO-PIT); this module gathers them so callers import from one place. Colours and
labels: :mod:`workflows.figures.styles`.
"""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # headless before pyplot is imported anywhere below

import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from beadrod.data.io import atomic_path  # noqa: E402
from beadrod.workflows.figures.physics import (  # noqa: E402
    DIRECTION_NAMES,
    Curve,
    fig_accuracy_cost,
    fig_f0_ranges,
    fig_frc,
    fig_inv_q_shift,
    fig_max_shift_vs_n,
    fig_q_vs_f0,
    fig_shift_curves,
    law_color,
)
from beadrod.workflows.figures.posterior import (  # noqa: E402
    TENSION_COLORS,
    fig_eta_tension,
    fig_evidence,
    fig_loo_pit,
    fig_pair,
    fig_rank,
    posterior_columns,
)
from beadrod.workflows.figures.ppc import ShiftPanel, fig_shift_ppc  # noqa: E402

__all__ = [
    "save_figure",
    "FORMATS",
    "DIRECTION_NAMES",
    "Curve",
    "ShiftPanel",
    "TENSION_COLORS",
    "law_color",
    "posterior_columns",
    "fig_shift_curves",
    "fig_max_shift_vs_n",
    "fig_f0_ranges",
    "fig_shift_ppc",
    "fig_q_vs_f0",
    "fig_inv_q_shift",
    "fig_eta_tension",
    "fig_evidence",
    "fig_pair",
    "fig_rank",
    "fig_loo_pit",
    "fig_frc",
    "fig_accuracy_cost",
]

FORMATS: tuple[str, ...] = ("png", "pdf")


def save_figure(fig: Figure, path_without_suffix: str | os.PathLike, *, dpi: int = 150,
                formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Write ``fig`` as ``<path>.png`` and ``<path>.pdf`` atomically, then close it.

    Each file is written to a temporary name in the target folder and renamed, so an
    interrupted run leaves either the old figure or the complete new one. The figure is
    closed even when writing fails (pyplot otherwise keeps every figure alive).
    """
    base = Path(path_without_suffix)
    written: list[Path] = []
    try:
        if fig.get_layout_engine() is not None and len(formats) > 1:
            # solve the (constrained) layout once and freeze it: every savefig would
            # solve it again, and on the many-panel figures that is most of the cost
            fig.draw_without_rendering()
            fig.set_layout_engine("none")
        for fmt in formats:
            target = base.with_name(f"{base.name}.{fmt}")
            with atomic_path(target) as tmp:
                fig.savefig(tmp, format=fmt, dpi=dpi)
            written.append(target)
    finally:
        plt.close(fig)
    return written
