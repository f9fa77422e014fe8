"""A law at its nominal parameters: where each value comes from, and the linear state.

The nominal value of a law parameter (``beadrod shift`` when it is not given, ``beadrod
scene``, the figures' theory curves) is, in this order: the value given; the scene's value
of the parameter's ``scene_key`` (or of a scene quantity of the parameter's own name);
the median of its prior. At those values the linear state under the static load ``load``
[N] follows from the law alone:

    delta0 from F(delta0) = load (the law's static overlap),
    K0 = F'(delta0) [N/m] (autodiff, :func:`models.generic.stiffness`),
    omega0 = sqrt(K0 / m) [rad/s], f0 = omega0 / (2 pi) [Hz],
    Q = the law's linear Q at omega0 (only for a law with a loss channel).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from .law import ContactLaw, prior_median

__all__ = ["nominal_parameters", "checked_parameters", "linear_state"]


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
    from .generic import stiffness

    kw = law.resolve(scene, theta)
    d0 = float(law.overlap(**kw))
    k0 = float(stiffness(law, d0, **kw))
    omega0 = math.sqrt(k0 / float(kw["mass"]))
    kw.update(delta0=d0, omega0=omega0)
    q = float(law.quality_factor(**kw)) if law.predicts_q else None
    return {"delta0_m": d0, "K0_N_m": k0, "f0_Hz": omega0 / (2.0 * math.pi), "Q": q, "kw": kw}
