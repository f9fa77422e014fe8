"""What :mod:`models.scene.plan` and :mod:`models.scene.plan_rod` share: the records a plan is made
of
(:class:`Effect`, :class:`Plan`) and the shift estimate |S|max that scales several bounds.

They live here, not in models.scene.plan, so that the rod's bounds (models.scene.plan_rod) can build
:class:`Effect` records without importing models.scene.plan, which imports them. models.scene.plan
re-exports both classes; import them from there.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

from beadrod.models.ladder.backbone import lindstedt_shift

__all__ = ["Effect", "Plan", "shift_estimate"]


@dataclass(frozen=True)
class Effect:
    """One effect: included or not, the deciding number and threshold, and the error bound
    on Delta f/f0 of leaving it out (see module docstring)."""

    name: str
    included: bool
    quantity: str
    value: float
    threshold: float
    reason: str
    error_bound: float
    details: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Plan:
    """What the simulator must include for a scene, and why."""

    scene_name: str
    tolerance: float
    contact_law: str
    rung: str
    harmonics: int
    effects: list[Effect]
    numbers: dict

    def effect(self, name: str) -> Effect:
        for e in self.effects:
            if e.name == name:
                return e
        raise KeyError(f"no effect '{name}' in the plan (have: "
                       f"{', '.join(e.name for e in self.effects)})")

    def included(self, name: str) -> bool:
        """Whether the effect ``name`` (one of :data:`EFFECT_NAMES`) must be simulated."""
        return self.effect(name).included

    def to_dict(self) -> dict:
        """JSON-ready dict; infinite bounds become the string "inf"."""
        def clean(v):
            if isinstance(v, float) and not math.isfinite(v):
                return "inf" if v > 0 else ("-inf" if v < 0 else "nan")
            if isinstance(v, dict):
                return {k: clean(w) for k, w in v.items()}
            if isinstance(v, list | tuple):
                return [clean(w) for w in v]
            return v
        return clean({"scene": self.scene_name, "tolerance": self.tolerance,
                      "contact_law": self.contact_law, "rung": self.rung,
                      "harmonics": self.harmonics, "numbers": self.numbers,
                      "effects": [asdict(e) for e in self.effects]})


def shift_estimate(x: float) -> float:
    """Upper estimate of the Hertz |Delta f/f0| [-] at x = delta_a/delta0: the Lindstedt
    term |S(x)| inflated by (1 + x^2), capped at 1 (shared by models.scene.plan and
    models.scene.plan_rod)."""
    s = abs(float(lindstedt_shift(x, 1.5)))
    return min(1.0, s * (1.0 + x * x))

