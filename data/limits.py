"""Plausibility bounds on measured values, drawn from the scene and from physics.

A value outside these bounds is not a measurement the scene describes but a unit
slip, a wrong column or a corrupt cell, and it would flow into the fits as an
infinite or absurd number (Delta(1/Q) = inf at 1e308 V, x = 0 at delta0 = inf).
Each bound is checked with :func:`check_value`, for table cells and for the
values extracted from raw curves alike.

Bounds [unit] and why:

* ``f_res_Hz`` in the scene's sweep band [f_min, f_max] [Hz]: a swept-sine
  analyser cannot report a resonance outside the band it swept.
* ``amplitude_m`` at most AMPLITUDE_LIMIT_FACTOR x delta0 [m] (delta0: Hertz
  static overlap under the scene's load, ~53 nm for the paper's bead): above,
  at 2.7 kHz the bead would feel more than 1000 g while held by its weight.
* ``amplitude_m`` at least AMPLITUDE_MIN_M = 1e-15 m, the size of an atomic
  nucleus and far below any vibrometer's resolution at kHz (~1e-12 m): a smaller
  value is a double unit conversion (0.5 nm converted twice reads 5e-19 m).
* ``drive_voltage_V`` within a factor VOLTAGE_LIMIT_FACTOR = 10 of the scene's
  drive range [voltage_min_V, voltage_max_V]: the scene's range is often set
  loosely, so a modest overshoot is kept, but a decade beyond it is mV written
  as V (or V as mV), not a drive of that setup. Never below VOLTAGE_FLOOR_V =
  1e-9 V, under the Johnson noise of a 50 ohm source over 1 kHz (~30 nV): no
  set drive is that small.
* ``q_factor`` at most q_max (``models.scene.QUALITY_FACTOR_MAX`` = 1e5): the
  scene's bound, ten times the Q of steel's own internal friction; a bead held
  in a lossy contact cannot ring longer than its material does.
* ``step`` at most STEP_MAX = 1e6: a million sweeps of about a minute each are
  two years of measuring on one protocol; larger is a corrupt cell (and beyond
  2^63 it would overflow the integer column).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = [
    "AMPLITUDE_LIMIT_FACTOR",
    "AMPLITUDE_MIN_M",
    "VOLTAGE_LIMIT_FACTOR",
    "VOLTAGE_FLOOR_V",
    "STEP_MAX",
    "Limits",
    "check_value",
    "show",
]

AMPLITUDE_LIMIT_FACTOR = 1000.0
"""An amplitude above this many static overlaps delta0 (Hertz, under the scene's
load; ~50 um for the paper's bead) is taken as a unit slip (nm or um written as m):
at 2.7 kHz it would mean an acceleration above 1000 g on a bead held by its weight."""

AMPLITUDE_MIN_M = 1e-15
"""Smallest credible displacement amplitude [m]: an atomic nucleus (module docstring)."""

VOLTAGE_LIMIT_FACTOR = 10.0
"""How far beyond the scene's drive range a voltage may lie before it is refused."""

VOLTAGE_FLOOR_V = 1e-9
"""Smallest credible drive voltage [V]: below a 50 ohm source's thermal noise."""

STEP_MAX = 1_000_000
"""Largest credible step index within one protocol."""


def show(v: float | int) -> str:
    """A number as Python prints a plain float or int (no numpy repr: ``-0.0``, not
    ``np.float64(-0.0)``)."""
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, int) or (hasattr(v, "dtype") and getattr(v.dtype, "kind", "") in "iu"):
        return str(int(v))
    return repr(float(v))


@dataclass(frozen=True)
class Limits:
    """Plausibility limits drawn from the scene (module docstring): resonance band
    [Hz], amplitude range [m], the scene's drive range [V] and the largest Q."""

    f_min: float
    f_max: float
    amplitude_max: float
    voltage_min: float
    voltage_max: float
    q_max: float
    amplitude_min: float = AMPLITUDE_MIN_M


def check_value(column: str, v: float, limits: Limits) -> str | None:
    """What is wrong with value ``v`` of ``column`` under ``limits``, or None if it is
    plausible. ``v`` is finite and positive (the parser checked); NaN passes (empty)."""
    if math.isnan(v):
        return None
    if column == "f_res_Hz" and not limits.f_min <= v <= limits.f_max:
        return (f"{show(v)} Hz lies outside the scene's sweep band "
                f"[{limits.f_min:g}, {limits.f_max:g}] Hz (kHz written as Hz?)")
    if column == "amplitude_m" and v > limits.amplitude_max:
        return (f"{show(v)} m exceeds {limits.amplitude_max:.3g} m "
                f"({AMPLITUDE_LIMIT_FACTOR:g} static overlaps): nm or um written as m?")
    if column == "amplitude_m" and v < limits.amplitude_min:
        return (f"{show(v)} m is below {limits.amplitude_min:g} m, smaller than an atomic "
                "nucleus and any sensor's resolution: a unit converted twice?")
    if column == "drive_voltage_V":
        lo = max(limits.voltage_min / VOLTAGE_LIMIT_FACTOR, VOLTAGE_FLOOR_V)
        hi = limits.voltage_max * VOLTAGE_LIMIT_FACTOR
        if not lo <= v <= hi:
            return (f"{show(v)} V lies far outside the scene's drive range "
                    f"[{limits.voltage_min:g}, {limits.voltage_max:g}] V (accepted: "
                    f"[{lo:g}, {hi:g}] V): mV written as V, or a wrong column?")
    if column == "q_factor" and v > limits.q_max:
        return (f"Q = {show(v)} exceeds {limits.q_max:g}, beyond what a bead held in a "
                "contact can reach (ten times the Q of steel's own internal friction)")
    if column == "step" and v > STEP_MAX:
        return (f"step {show(v)} exceeds {STEP_MAX:g}: more sweeps than one protocol "
                "can hold (a corrupt cell?)")
    return None
