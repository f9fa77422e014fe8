"""A law at its nominal parameters: where each value comes from, and the linear state.

The nominal value of a law parameter (``beadrod shift`` when it is not given, ``beadrod
scene``, the figures' theory curves) is, in this order: the value given; the scene's value
of the parameter's ``scene_key`` (or of a scene quantity of the parameter's own name);
the median of its prior. At those values the linear state under the static load ``load``
[N] follows from the law alone:

    delta0 from F(delta0) = load (the law's static overlap),
    K0 = F'(delta0) [N/m] (autodiff, :func:`models.ladder.generic.stiffness`),
    omega0 = sqrt(K0 / m) [rad/s], f0 = omega0 / (2 pi) [Hz],
    Q = the law's linear Q at omega0 (only for a law with a loss channel).

A scene quantity set by hand (``beadrod shift --param radius=...``) is held to the rules
of ``scene.toml`` (:func:`check_scene_values`): the value goes into the scene's own layout
and the scene's checks (:data:`models.scene.BOUNDS` and the rules between its keys) run
on it, so the bounds live in one place. ``mass`` and ``load`` have no key of their own
there: a mass is checked as the bead density it implies at the bead's radius, a load as
the extra force it implies on the bead's weight. Which scene quantities a law takes
(:func:`scene_names`): those with a ``scene.toml`` key that its functions may read by
name (:data:`models.law.SCENE_KEYS`) and those its parameters take their nominal value
from (``scene_key``); ``e_star`` is not one, :meth:`models.law.ContactLaw.resolve`
computes it from ``young`` and ``poisson``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from beadrod.models.law import SCENE_KEYS, ContactLaw, prior_median

__all__ = ["nominal_parameters", "checked_parameters", "linear_state", "scene_names",
           "check_scene_values", "SCENE_PATHS"]

SCENE_PATHS: dict[str, tuple[str, ...]] = {
    "radius": ("bead", "radius_m"),
    "young": ("materials", "bead", "young_Pa"),
    "poisson": ("materials", "bead", "poisson"),
    "gravity": ("preload", "gravity_m_s2"),
    "roughness_rms": ("surfaces", "roughness_rms_m"),
    "surface_energy": ("surfaces", "surface_energy_J_m2"),
    "viscosity": ("surfaces", "viscosity_Pa_s"),
    # derived there (module docstring): checked as the key they imply
    "mass": ("materials", "bead", "density_kg_m3"),
    "load": ("preload", "extra_force_N"),
}
"""Scene quantity -> its key in the layout of :func:`models.scene.scene_to_dict` (the
bead's material is ``materials.bead`` there)."""
_DERIVED = ("mass", "load")


def nominal_parameters(law: ContactLaw, scene: Mapping[str, float],
                       given: Mapping[str, float] | None = None
                       ) -> tuple[dict[str, float], dict[str, str]]:
    """(theta, sources): each parameter of ``law`` and where it comes from ('given',
    'scene (KEY)' or 'prior median'). ``scene`` maps scene quantities by name
    (:data:`models.law.SCENE_KEYS`, plus e.g. ``viscosity`` [Pa s] where the scene has
    one); ``given`` the values set by hand. No value is checked here."""
    given = given or {}
    theta: dict[str, float] = {}
    sources: dict[str, str] = {}
    for p in law.params:
        key = p.scene_key or p.name  # its scene quantity, or one of its own name
        if p.name in given:
            theta[p.name], sources[p.name] = float(given[p.name]), "given"
        elif scene.get(key) is not None:
            theta[p.name], sources[p.name] = float(scene[key]), f"scene ({key})"
        else:
            theta[p.name], sources[p.name] = prior_median(p.prior), "prior median"
    return theta, sources


def checked_parameters(law: ContactLaw, scene: Mapping[str, float],
                       given: Mapping[str, float] | None = None
                       ) -> tuple[dict[str, float], dict[str, str]]:
    """:func:`nominal_parameters`, each value checked against its parameter's domain and
    physical bounds (:meth:`models.law.Param.problem`); ValueError naming the law and the
    problem (a scene's surface energy of 0 for an adhesive law, a value given by hand)."""
    theta, sources = nominal_parameters(law, scene, given)
    for name, value in theta.items():
        problem = law.param(name).problem(value)
        if problem is not None:
            raise ValueError(f"law '{law.name}': {problem}")
    return theta, sources


def linear_state(law: ContactLaw, scene: Mapping[str, float],
                 theta: Mapping[str, float]) -> dict[str, Any]:
    """The linear state of ``law`` at ``theta`` under the scene's load (module docstring):
    ``delta0_m``, ``K0_N_m``, ``f0_Hz``, ``Q`` (None without a loss channel) and ``kw``,
    the resolved keywords with ``delta0`` and ``omega0`` added (what :meth:`ContactLaw.shift`
    takes)."""
    from beadrod.models.ladder.generic import stiffness

    kw = law.resolve(scene, theta)
    d0 = float(law.overlap(**kw))
    k0 = float(stiffness(law, d0, **kw))
    omega0 = math.sqrt(k0 / float(kw["mass"]))
    kw.update(delta0=d0, omega0=omega0)
    q = float(law.quality_factor(**kw)) if law.predicts_q else None
    return {"delta0_m": d0, "K0_N_m": k0, "f0_Hz": omega0 / (2.0 * math.pi), "Q": q, "kw": kw}


def scene_names(law: ContactLaw) -> tuple[str, ...]:
    """The scene quantities a value set by hand reaches ``law`` through (module
    docstring), its own parameters' names left out (a value of that name is the
    parameter's)."""
    keys = set(SCENE_KEYS) | {p.scene_key for p in law.params if p.scene_key}
    return tuple(k for k in SCENE_PATHS if k in keys and k not in law.param_names)


def check_scene_values(scene: Any, values: Mapping[str, float]) -> None:
    """Check scene quantities set by hand (names of :data:`SCENE_PATHS`) by the rules of
    ``scene.toml``, all of them applied to ``scene`` (a :class:`models.scene.Scene`);
    models.scene.SceneError (a ValueError: the scene's message, naming its key) if the
    scene they make is not one."""
    from beadrod.models.scene import scene_from_dict, scene_to_dict

    if not values:
        return
    d = scene_to_dict(scene)
    shown = []
    for name, value in values.items():
        v = float(value)
        if not math.isfinite(v):
            raise ValueError(f"{name} = {value}: must be a finite number")
        shown.append(f"{name} = {v:g}")
        if name not in _DERIVED:
            _put(d, SCENE_PATHS[name], v)
    if "mass" in values:  # after the radius: the density of a bead of that radius
        rho = float(values["mass"]) / _bead_mass(d["bead"]["radius_m"], 1.0)
        _put(d, SCENE_PATHS["mass"], rho)
        shown[list(values).index("mass")] += f" (a bead density of {rho:.4g} kg/m^3)"
    made = scene_from_dict(d, f"scene '{scene.name}' with {', '.join(shown)}")
    if "load" in values:  # the force on top of the weight of the scene made so far
        extra = float(values["load"]) - made.weight
        _put(d, SCENE_PATHS["load"], extra)
        shown[list(values).index("load")] += f" (an extra force of {extra:.4g} N)"
        scene_from_dict(d, f"scene '{scene.name}' with {', '.join(shown)}")


def _bead_mass(radius: float, density: float) -> float:
    import jax

    from beadrod.models.scene.materials import bead_mass

    with jax.enable_x64(True):
        return float(bead_mass(radius, density))


def _put(d: dict, path: tuple[str, ...], value: float) -> None:
    for key in path[:-1]:
        d = d[key]
    d[path[-1]] = value
