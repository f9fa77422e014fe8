"""``beadrod scene``: every derived quantity of a scene, per Young's modulus of its range.

Default: the paper's setup (E = 190 and 210 GPa). JSON keys carry their SI unit. The
contact laws are the registry's (models.registry), each at its nominal parameters
(models.nominal); the forces, damping, adhesion-map and rod blocks are the scene's own.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from beadrod.workflows.commands.shift import resolve_scene

__all__ = ["register", "scene_quantities", "resolve_scene", "check_given"]


def register(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "scene",
        help="print every derived quantity of a scene (default: the paper's setup)",
        description="Derived quantities of a bead-rod scene for each Young's modulus of its "
        "range (the paper: E = 190 and 210 GPa): mass, weight, E*; for every registered "
        "contact law at its nominal parameters (the scene's value, else the prior median) "
        "the static overlap, stiffness, linear resonance and, for a law with losses, its "
        "linear Q; viscous damping constant A, adhesion map (Muller mu, Tabor lambda, "
        "regime), plastic-limit and dynamic forces, and rod wave velocities.",
    )
    p.add_argument("scene", nargs="?", type=Path, default=None,
                   help="scene TOML file (see models/scene/presets/paper.toml for the layout)")
    p.add_argument("--builtin", metavar="NAME", default=None,
                   help="a built-in scene instead of a file (paper, strong_drive, "
                   "large_soft_bead, micro_bead)")
    p.add_argument("--param", action="append", metavar="KEY=VALUE",
                   help="a law parameter by the name `beadrod laws` gives, e.g. --param n=2.5, "
                   "for every law that has it (repeatable); a parameter not given takes the "
                   "scene's value where it has one, else its prior median")
    p.add_argument("--json", action="store_true", help="machine-readable output (SI keys)")
    p.set_defaults(func=run)
    return p


def _f(x) -> float:
    return float(x)


def _law_blocks(scene, given: dict[str, float]) -> dict:
    """Every registered law at its nominal parameters (models.nominal: given, else the
    scene's value, else the prior median; ``sources`` says which): static overlap, tangent
    stiffness and linear resonance under the load, and the linear Q where the law has a
    loss channel."""
    from beadrod.models.nominal import checked_parameters, linear_state
    from beadrod.models.registry import laws
    from beadrod.workflows.commands.shift import scene_keywords

    sc = scene_keywords(scene)
    out: dict = {}
    for law in laws():
        mine = {k: v for k, v in given.items() if k in law.param_names}
        try:
            theta, sources = checked_parameters(law, sc, mine)
        except ValueError as exc:
            if mine:
                raise       # a value the user gave: refused, as by `beadrod shift`
            # the scene's own value is outside this law's domain (a surface energy of 0:
            # the adhesive laws are Hertz's there): the law is not defined here, the
            # scene is
            out[law.name] = {"label": law.presentation.label, "params": {}, "sources": {},
                             "not_defined": str(exc)}
            continue
        st = linear_state(law, sc, theta)
        block = {"label": law.presentation.label, "params": theta, "sources": sources,
                 "delta0_m": st["delta0_m"], "K0_N_m": st["K0_N_m"], "f0_Hz": st["f0_Hz"]}
        if st["Q"] is not None:
            block["Q"] = st["Q"]
        out[law.name] = block
    return out


def _per_young(scene, given: dict[str, float]) -> dict:
    # the elastic sphere (Hertz) is the reference state of the non-law quantities (forces,
    # rod, damping), as in the paper's Sec. 4
    from beadrod.models.laws import adhesion_map, hertz, viscoelastic
    from beadrod.models.scene import rod

    m, load, es, r = scene.mass, scene.load, scene.e_star, scene.radius
    gamma = scene.surface_energy
    out: dict = {"young_Pa": scene.bead_material.young, "e_star_Pa": es,
                 "laws": _law_blocks(scene, given)}
    d0 = _f(hertz.static_overlap(load, e_star=es, radius=r))
    f0 = _f(hertz.linear_frequency(load, m, e_star=es, radius=r))
    omega0 = 2 * math.pi * f0
    if scene.viscosity is not None:
        soft = min((scene.bead_material, scene.rod_material), key=lambda mt: mt.young)
        a = _f(viscoelastic.damping_constant(eta1=scene.viscosity, young=soft.young,
                                             poisson=soft.poisson))
        out["damping"] = {
            "eta_Pa_s": scene.viscosity, "A_s": a,
            "gamma_n_kg_m-1/2_s-1": _f(viscoelastic.kuwabara_kono_gamma(
                e_star=es, radius=r, damping_constant=a)),
            "k_n_N_m-3/2": _f(hertz.stiffness_constant(e_star=es, radius=r)),
        }
    regime = adhesion_map.adhesion_regime(load, gamma=gamma, radius=r, e_star=es)
    out["adhesion"] = {
        "muller_mu": regime["mu"],
        "tabor_lambda": _f(adhesion_map.tabor_parameter(gamma=gamma, radius=r, e_star=es)),
        "adhesion_to_load": regime["ratio"],
        "load_to_adhesion": 1.0 / regime["ratio"] if regime["ratio"] > 0 else math.inf,
        "law": regime["law"], "reason": regime["reason"]}
    forces = {"dynamic_force_at_f0_N": _f(adhesion_map.dynamic_force(m, omega0, d0)),
              "dynamic_force_at_f_max_N": _f(adhesion_map.dynamic_force(
                  m, 2 * math.pi * scene.f_max, d0))}
    if scene.yield_strength is not None:
        for conv in ("paper", "johnson"):
            forces[f"plastic_limit_{conv}_N"] = _f(adhesion_map.plastic_limit_force(
                yield_strength=scene.yield_strength, radius=r, e_star=es, convention=conv))
    out["forces"] = forces
    mat = scene.rod_material
    kw = {"young": mat.young, "poisson": mat.poisson, "density": mat.density,
          "radius": scene.rod_radius}
    _, vt, _ = (float(v) for v in _speeds(mat))
    rod_out = {
        "bar_velocity_m_s": _f(rod.bar_velocity(mat.young, mat.density)),
        "rayleigh_phase_velocity_at_f0_m_s": _f(rod.rayleigh_velocity(f0, **kw)),
        "rayleigh_group_velocity_at_f0_m_s": _f(rod.rayleigh_group_velocity(f0, **kw)),
        "ka_at_f0": 2 * math.pi * f0 / _f(rod.bar_velocity(mat.young, mat.density))
        * scene.rod_radius,
        "free_free_resonance_Hz": _f(rod.first_resonance_free_free(
            scene.rod_length, young=mat.young, density=mat.density)),
        "fixed_free_resonance_Hz": _f(rod.first_resonance_fixed_free(
            scene.rod_length, young=mat.young, density=mat.density)),
        "measured_first_resonance_Hz": scene.rod_first_resonance,
    }
    if 2 * math.pi * f0 * scene.rod_radius / vt < rod.OMEGA_MAX:
        rod_out["pochhammer_chree_phase_velocity_at_f0_m_s"] = _f(
            rod.first_branch_phase_velocity(f0, **kw))
        rod_out["pochhammer_chree_group_velocity_at_f0_m_s"] = _f(
            rod.first_branch_group_velocity(f0, **kw))
    else:
        rod_out["pochhammer_chree_note"] = "f0 above the first-branch solver's range"
    out["rod"] = rod_out
    return out


def _speeds(mat):
    from beadrod.models.scene.materials import wave_speeds
    return wave_speeds(mat.young, mat.poisson, mat.density)


def check_given(given: dict[str, float]) -> dict[str, float]:
    """``given`` (as floats) if every key is a parameter of some registered law and each
    value is a value of that parameter for every law that has it
    (workflows.commands.shift.check_param); ValueError otherwise."""
    from beadrod.models.registry import laws
    from beadrod.workflows.commands.shift import check_param

    known = {p for law in laws() for p in law.param_names}
    unknown = sorted(set(given) - known)
    if unknown:
        raise ValueError(f"--param {', '.join(unknown)}: no registered law has such a "
                         f"parameter; the laws' parameters: {sorted(known)}")
    out = {k: float(v) for k, v in given.items()}
    for law in laws():
        for k, v in given.items():
            check_param(law, k, v)
    return out


def scene_quantities(scene, given: dict[str, float] | None = None) -> dict:
    """All derived quantities of ``scene``, one block per Young's modulus (JSON-ready);
    ``given``: law parameters set by hand (:func:`check_given`), for every law that has
    them."""
    import jax

    with jax.enable_x64(True):
        return {
            "scene": scene.name, "description": scene.description,
            "mass_kg": scene.mass, "weight_N": scene.weight, "load_N": scene.load,
            "radius_m": scene.radius, "gravity_m_s2": scene.gravity,
            "drive_displacement_max_m": scene.drive_displacement_max,
            "per_young": [_per_young(scene.with_young(e), check_given(dict(given or {})))
                          for e in scene.young_values()],
        }


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def _text(q: dict) -> str:
    lines = [f"scene: {q['scene']} - {q['description']}"]
    for k in ("mass_kg", "weight_N", "load_N", "radius_m", "drive_displacement_max_m"):
        lines.append(f"  {k:<34} {_fmt(q[k])}")
    for block in q["per_young"]:
        lines.append(f"E = {block['young_Pa'] / 1e9:g} GPa   (E* = {block['e_star_Pa']:.6g} Pa)")
        for name, law in block["laws"].items():
            lines.append(f"  [{name}] {law['label']}")
            lines += [f"    {k:<42} {_fmt(v)} ({law['sources'][k]})"
                      for k, v in law["params"].items()]
            lines += [f"    {k:<42} {_fmt(v)}" for k, v in law.items()
                      if k not in ("label", "params", "sources")]
        for sec in ("damping", "adhesion", "forces", "rod"):
            if sec not in block:
                continue
            lines.append(f"  [{sec}]")
            lines += [f"    {k:<42} {_fmt(v)}" for k, v in block[sec].items()]
    return "\n".join(lines)


def _json_safe(v):
    if isinstance(v, float) and not math.isfinite(v):
        return "inf" if v > 0 else "nan"
    if isinstance(v, dict):
        return {k: _json_safe(w) for k, w in v.items()}
    if isinstance(v, list):
        return [_json_safe(w) for w in v]
    return v


def run(args: argparse.Namespace) -> int:
    from beadrod.models.scene import SceneError
    from beadrod.workflows.cli import UserError
    from beadrod.workflows.commands.shift import parse_params

    try:
        scene, source = resolve_scene(args.scene, args.builtin)
        q = scene_quantities(scene, parse_params(args.param))
    except (SceneError, ValueError) as exc:
        raise UserError(str(exc)) from None
    q["source"] = source
    if args.json:
        print(json.dumps(_json_safe(q), indent=2))
    else:
        print(_text(q))
    return 0
