"""``beadrod plan``: which effects a scene calls for, why, and the error of leaving each out."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

__all__ = ["register", "check_amplitude", "check_tolerance"]


def register(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "plan",
        help="the effects the simulator includes for a scene, and why",
        description="For a scene, decide each effect (rod dynamics, higher rod modes, rod "
        "dispersion, adhesion law, viscous losses, jumps, contact loss, plasticity, number "
        "of harmonics) and the rung of the accuracy ladder: the dimensionless number, its "
        "threshold, and a bound on the error in Delta f/f0 of leaving the effect out.",
    )
    p.add_argument("scene", nargs="?", type=Path, default=None,
                   help="scene TOML file (default: the paper's built-in scene)")
    p.add_argument("--builtin", metavar="NAME", default=None,
                   help="a built-in scene (paper, strong_drive, large_soft_bead, micro_bead)")
    p.add_argument("--amplitude-max", type=float, default=None, metavar="M",
                   help="largest first-harmonic amplitude delta_a [m] (default: Q times the "
                   "largest base displacement)")
    p.add_argument("--tolerance", type=float, default=None, metavar="T",
                   help="acceptable error in Delta f/f0 (default 5e-3)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=run)
    return p


def _fmt(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def _text(plan) -> str:
    n = plan.numbers
    lines = [f"scene {plan.scene_name}: contact law {plan.contact_law}, rung {plan.rung}, "
             f"H = {plan.harmonics} harmonics (tolerance {plan.tolerance:g} in Delta f/f0)",
             f"  f0 = {n['f0_Hz']:.5g} Hz, delta0 = {n['delta0_m']:.4g} m, Q = {_fmt(n['q'])}, "
             f"x_max = {n['x_max']:.3g} ({n['amplitude_source']})"]
    for e in plan.effects:
        mark = "INCLUDE" if e.included else "leave out"
        lines.append(f"  {e.name:<15} {mark:<9} {e.quantity} = {_fmt(e.value)} "
                     f"(threshold {_fmt(e.threshold)}), error bound {_fmt(e.error_bound)}")
        lines.append(f"      {e.reason}")
    return "\n".join(lines)


def check_amplitude(value: float | None, radius: float) -> float | None:
    """--amplitude-max [m]: None (estimate it), else finite, > 0 and below the bead radius
    ``radius`` [m] (a contact displacement larger than the bead itself is no contact)."""
    if value is None:
        return None
    v = float(value)
    if not math.isfinite(v) or v <= 0:
        raise ValueError(f"--amplitude-max {value:g}: the largest first-harmonic amplitude "
                         "delta_a is a displacement in metres, finite and > 0")
    if v >= radius:
        raise ValueError(f"--amplitude-max {v:g} m is not below the bead radius {radius:g} m: "
                         "no contact law describes a displacement that large")
    return v


def check_tolerance(value: float | None, default: float) -> float:
    """--tolerance: an acceptable error in Delta f/f0, finite with 0 < T < 1."""
    tol = default if value is None else float(value)
    if not (math.isfinite(tol) and 0 < tol < 1):
        raise ValueError(f"--tolerance {tol:g}: an acceptable error in Delta f/f0 lies "
                         "strictly between 0 and 1 (default 5e-3)")
    return tol


def run(args: argparse.Namespace) -> int:
    from beadrod.models.scene import SceneError
    from beadrod.models.scene.plan import DEFAULT_TOLERANCE, plan_scene
    from beadrod.workflows.commands.scene import resolve_scene
    from beadrod.workflows.runtime import UserError

    try:
        scene, _ = resolve_scene(args.scene, args.builtin)
        tol = check_tolerance(args.tolerance, DEFAULT_TOLERANCE)
        amp = check_amplitude(args.amplitude_max, float(scene.radius))
        plan = plan_scene(scene, amplitude_max=amp, tolerance=tol)
    except (SceneError, ValueError) as exc:
        raise UserError(str(exc)) from None
    if args.json:
        print(json.dumps(plan.to_dict(), indent=2))
    else:
        print(_text(plan))
    return 0
