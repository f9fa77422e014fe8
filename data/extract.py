"""Resonance extraction from a raw swept-sine curve (frequency, amplitude[, phase]).

The peak is located by a least-squares cubic through 1/A^2 in a window around
the grid maximum (the points within ``window`` of the maximum): for a Lorentzian
A^2 = c / ((f - f0)^2 + g^2) the reciprocal 1/A^2 is exactly quadratic in f, for
the linear oscillator exactly quadratic in f^2, and the cubic term absorbs that
skew; its minimum is a sub-grid estimate of the peak, not the raw grid maximum.
Q comes from the -3 dB (half-power) width, Q = f_res / (f_high - f_low), with
both crossings A = A_peak / sqrt(2) found by linear interpolation. The -3 dB
method assumes a symmetric peak; when the half-widths on the two sides differ
by more than ``asymmetry_tol`` of the full width (a softening curve bent by the
drive, a jump), the result is flagged.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from beadrod.data.io import read_csv_table
from beadrod.data.schema import DataError

__all__ = ["CurveFit", "extract_resonance", "read_curve", "CURVE_COLUMNS", "MIN_CURVE_POINTS"]

CURVE_COLUMNS: tuple[str, ...] = ("frequency_Hz", "amplitude_m", "phase_rad")
MIN_CURVE_POINTS = 7


@dataclass(frozen=True)
class CurveFit:
    """Resonance read off one sweep.

    ``f_res`` [Hz] and ``amplitude`` [m] at the fitted peak; ``q`` from the -3 dB
    width (NaN when a half-power crossing lies outside the sweep); ``f_low``,
    ``f_high`` [Hz] the crossings; ``asymmetry`` = (right - left half-width) /
    full width; ``asymmetric`` whether -3 dB Q should not be trusted;
    ``note`` says why, when something is off. ``peak_at_edge``: the largest amplitude is
    the sweep's first or last point, so the resonance lies outside the sweep (``f_res``
    is then that edge, not a resonance); ``grid_maximum``: the local fit failed inside the
    sweep and ``f_res`` is the grid maximum.
    """

    f_res: float
    amplitude: float
    q: float
    f_low: float
    f_high: float
    asymmetry: float
    asymmetric: bool
    note: str = ""
    peak_at_edge: bool = False
    grid_maximum: bool = False


def _crossing(f: np.ndarray, a: np.ndarray, i_peak: int, level: float, step: int) -> float:
    """Frequency where ``a`` first falls below ``level`` walking from the peak by ``step``."""
    i = i_peak
    while 0 <= i + step < len(a):
        j = i + step
        if a[j] < level:
            # linear interpolation between the last point above and the first below
            return float(f[i] + (level - a[i]) * (f[j] - f[i]) / (a[j] - a[i]))
        i = j
    return math.nan


def extract_resonance(
    frequency: np.ndarray,
    amplitude: np.ndarray,
    *,
    window: float = 0.8,
    asymmetry_tol: float = 0.2,
) -> CurveFit:
    """Peak frequency, peak amplitude and -3 dB Q of a resonance curve.

    Args:
        frequency: sweep frequencies [Hz], strictly increasing.
        amplitude: displacement amplitudes [m], positive.
        window: fit the points around the grid maximum whose amplitude is at least
            ``window`` times the maximum (at least 5 points).
        asymmetry_tol: flag the curve when |right - left half-width| exceeds this
            fraction of the full -3 dB width.
    """
    f = np.asarray(frequency, dtype=np.float64)
    a = np.asarray(amplitude, dtype=np.float64)
    if f.ndim != 1 or f.shape != a.shape or len(f) < MIN_CURVE_POINTS:
        raise ValueError(f"need two 1-D arrays of equal length >= {MIN_CURVE_POINTS}")
    k = int(np.argmax(a))
    edge = k in (0, len(a) - 1)
    lo, hi = k, k
    while lo > 0 and a[lo - 1] >= window * a[k]:
        lo -= 1
    while hi < len(a) - 1 and a[hi + 1] >= window * a[k]:
        hi += 1
    while hi - lo < 4 and (lo > 0 or hi < len(a) - 1):
        lo, hi = max(lo - 1, 0), min(hi + 1, len(a) - 1)
    note = ""
    fw, yw = f[lo:hi + 1], 1.0 / np.square(a[lo:hi + 1])
    scale = max(float(fw[-1] - fw[0]), 1e-12)
    u = (fw - f[k]) / scale
    # a cubic term absorbs the skew of a real oscillator's 1/A^2 (exactly quadratic in
    # f^2, not f), which would otherwise bias the vertex by ~f0/(10 Q^2)
    deg = 3 if len(u) >= 6 else 2
    coef = np.polyfit(u, yw, deg)
    d1 = np.polyder(coef)
    roots = np.roots(d1)
    roots = roots[np.abs(roots.imag) < 1e-12].real
    roots = roots[(np.polyval(np.polyder(d1), roots) > 0) & (roots >= u[0]) & (roots <= u[-1])]
    if roots.size:
        u_v = float(roots[np.argmin(np.abs(roots))])
        f_res = float(f[k] + u_v * scale)
        y_min = float(np.polyval(coef, u_v))
        a_peak = float(1.0 / math.sqrt(y_min)) if y_min > 0 else float(a[k])
        grid = False
    else:
        f_res, a_peak = float(f[k]), float(a[k])
        grid = True
        note = "local fit failed (no smooth peak about the grid maximum); grid maximum used"
    if edge:
        note = (f"largest amplitude at the sweep's edge ({f[k]:.6g} Hz): no resonance peak "
                "inside the sweep")
    level = a_peak / math.sqrt(2.0)
    f_low = _crossing(f, a, k, level, -1)
    f_high = _crossing(f, a, k, level, +1)
    if math.isnan(f_low) or math.isnan(f_high):
        side = "low" if math.isnan(f_low) else "high"
        return CurveFit(f_res, a_peak, math.nan, f_low, f_high, math.nan, True,
                        (note + "; " if note else "")
                        + f"no -3 dB crossing on the {side}-frequency side within the sweep",
                        edge, grid and not edge)
    width = f_high - f_low
    asym = ((f_high - f_res) - (f_res - f_low)) / width
    asymmetric = abs(asym) > asymmetry_tol
    if asymmetric:
        note = (note + "; " if note else "") + (
            f"half-widths differ by {abs(asym):.0%} of the -3 dB width: Q not trustworthy")
    return CurveFit(f_res, a_peak, f_res / width, f_low, f_high, float(asym), asymmetric, note,
                    edge, grid and not edge)


def read_curve(path: Path, *, label: str | None = None) -> pd.DataFrame:
    """Read and validate a raw sweep CSV; :class:`DataError` names file, line, column.

    Columns: ``frequency_Hz`` (> 0, strictly increasing or strictly decreasing:
    a down sweep may be stored in sweep order), ``amplitude_m`` (> 0), optional
    ``phase_rad``. Returned sorted by increasing frequency. Messages say what is
    wrong and where, but never quote the file's content (header names, cells): a
    curve file is read on the table's say-so and need not be the user's own text.
    """
    label = label or str(path)
    raw = read_csv_table(path, label=label, show_names=False)
    cols = list(raw.header)
    for k, c in enumerate(cols):
        if c not in CURVE_COLUMNS:
            near = difflib.get_close_matches(c, CURVE_COLUMNS, n=1, cutoff=0.6)
            hint = f"; did you mean '{near[0]}'?" if near else ""
            raise DataError(f"{label}, line {raw.header_line} (header), column {k + 1}: "
                            f"not a curve column (allowed: {', '.join(CURVE_COLUMNS)}){hint}")
        if cols.count(c) > 1:
            raise DataError(f"{label}, line {raw.header_line} (header), column '{c}': "
                            "column appears twice")
    for c in CURVE_COLUMNS[:2]:
        if c not in cols:
            raise DataError(f"{label}, line {raw.header_line} (header), column '{c}': "
                            "required column is missing")
    n = len(raw.records)
    if n < MIN_CURVE_POINTS:
        last = raw.lines[-1] if n else raw.header_line
        raise DataError(f"{label}, line {last}, column 'frequency_Hz': a curve needs at "
                        f"least {MIN_CURVE_POINTS} points, found {n}")
    lines = np.asarray(raw.lines)
    frame = raw.frame()
    out = {}
    for c in cols:
        vals = pd.to_numeric(frame[c], errors="coerce").to_numpy(np.float64)
        bad = np.flatnonzero(~np.isfinite(vals))
        if bad.size:
            raise DataError(f"{label}, line {lines[bad[0]]}, column '{c}': not a finite "
                            "number")
        if c != "phase_rad":
            nonpos = np.flatnonzero(vals <= 0)
            if nonpos.size:
                i = int(nonpos[0])
                raise DataError(f"{label}, line {lines[i]}, column '{c}': must be positive")
        out[c] = vals
    d = np.diff(out["frequency_Hz"])
    if not (np.all(d > 0) or np.all(d < 0)):
        i = int(np.flatnonzero(d <= 0)[0] if np.any(d > 0) else np.flatnonzero(d >= 0)[0])
        raise DataError(f"{label}, line {lines[i + 1]}, column 'frequency_Hz': frequencies "
                        "must be strictly monotonic (repeated or out-of-order value)")
    return pd.DataFrame(out).sort_values("frequency_Hz").reset_index(drop=True)
