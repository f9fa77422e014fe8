"""Rounding as an instrument prints its readings (the synthetic worlds' tables)."""

from __future__ import annotations

import numpy as np

__all__ = ["significant"]


def significant(x: np.ndarray, digits: int) -> np.ndarray:
    """Round to ``digits`` significant figures (as an instrument prints them)."""
    return np.array([float(f"{v:.{digits - 1}e}") for v in np.atleast_1d(x)])
