"""``beadrod shift``: the predicted Delta f/f0 of a contact law at given amplitudes."""

from __future__ import annotations

import argparse
import json

import numpy as np

__all__ = ["register", "shift_table"]


def shift_table(law: str, x: list[float], *, method: str, n: float | None, scene_path: str | None,
                builtin: str, young: float | None, eta: float | None) -> dict:
    """Delta f/f0 at each x for ``law`` with the scene's parameters (SI units in keys)."""
    from models import hertz, viscoelastic
    from models.registry import get_law
    from models.scenes import builtin_scene, load_scene

    scene = load_scene(scene_path) if scene_path else builtin_scene(builtin)
    if young is not None:
        scene = scene.with_young(young)
    contact = get_law(law)
    p = {"e_star": scene.e_star, "radius": scene.radius, "load": scene.load,
         "mass": scene.mass, "gamma": scene.surface_energy, "n": n}
    if law == "powerlaw" and n is None:
        raise ValueError("law 'powerlaw' needs --n (the exponent, 1 < n <= 3)")
    eta = eta if eta is not None else scene.viscosity
    omega0 = 2 * np.pi * float(hertz.linear_frequency(scene.load, scene.mass, e_star=scene.e_star,
                                                      radius=scene.radius))
    if eta is not None:
        mat = scene.bead_material
        p["damping_constant"] = float(viscoelastic.damping_constant(
            eta1=eta, eta2=eta, young=mat.young, poisson=mat.poisson))
        p["omega"] = omega0
    values = np.asarray(contact.shift(np.asarray(x, float), method=method, **p))
    out = {"law": law, "method": method, "scene": scene.name, "x": list(map(float, x)),
           "delta_f_over_f0": values.tolist()}
    if n is not None:
        out["n"] = n
    if "damping_constant" in p and law.startswith("viscoelastic"):
        out["eta_Pa_s"] = eta
        out["damping_constant_s"] = p["damping_constant"]
    return out


def _run(args: argparse.Namespace) -> int:
    from .cli import UserError

    try:
        table = shift_table(args.law, args.x, method=args.method, n=args.n,
                            scene_path=args.scene, builtin=args.builtin, young=args.young,
                            eta=args.eta)
    except ValueError as exc:  # a law/method/parameter combination that does not exist
        raise UserError(str(exc)) from exc
    if args.json:
        print(json.dumps(table, indent=2))
        return 0
    print(f"law {table['law']}, method {table['method']}, scene {table['scene']}")
    print(f"{'x = delta_a/delta0':>20}  {'Delta f/f0':>14}")
    for xv, v in zip(table["x"], table["delta_f_over_f0"]):
        print(f"{xv:>20.6g}  {v:>14.8f}")
    return 0


def register(sub) -> None:
    from models.registry import SHIFT_METHODS, law_names

    p = sub.add_parser("shift", help="predicted resonance shift Delta f/f0 of a contact law",
                       description="Delta f/f0 at normalised amplitudes x = delta_a/delta0 for "
                       "one contact law, by the paper's first-order average or the exact "
                       "conservative backbone. x > 1 means the contact opens during the cycle.")
    p.add_argument("--law", required=True, choices=law_names(), help="contact law")
    p.add_argument("--x", required=True, type=float, nargs="+", help="amplitudes delta_a/delta0")
    p.add_argument("--n", type=float, help="power-law exponent (law powerlaw)")
    p.add_argument("--method", default="first-order", choices=SHIFT_METHODS,
                   help="first-order (the paper's averaged stiffness) or backbone (exact)")
    p.add_argument("--scene", help="scene TOML (default: the built-in scene)")
    p.add_argument("--builtin", default="paper", help="built-in scene name (default: paper)")
    p.add_argument("--young", type=float, help="Young's modulus [Pa] overriding the scene's")
    p.add_argument("--eta", type=float, help="viscosity [Pa s] for viscoelastic laws")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_run)
