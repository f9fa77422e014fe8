"""What a scene's plan and simulator take from the contact laws: the contact the adhesion
map selects, and the viscous loss.

The adhesion map (:func:`beadrod.models.laws.adhesion_map.adhesion_regime`) names the
contact a scene calls for by the labels 'Hertz', 'DMT', 'Maugis-Dugdale' and 'JKR';
:func:`scene_contact` gives the functions of that contact which the plan
(:mod:`beadrod.models.scene.plan`) and the simulator (:mod:`beadrod.models.scene.simulate`)
evaluate: its static overlap and linear stiffness under the load, its force and, for an
adhesive contact, its first-order shift. The simulator has no Maugis-Dugdale force of its
own: it simulates that contact as JKR (``simulated_as``), and the plan bounds the
difference by the DMT-JKR bracket. Viscous losses are Kuwabara-Kono's
(:func:`viscous_damping_constant`, :func:`viscous_linear_q`).

This module is the one place where the scene's vocabulary meets the laws' modules, so
``beadrod.models.scene`` names no law.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from beadrod.models.laws import dmt, hertz, jkr, viscoelastic

__all__ = ["SceneContact", "scene_contact", "HERTZIAN", "viscous_damping_constant",
           "viscous_linear_q"]


@dataclass(frozen=True)
class SceneContact:
    """One contact of the adhesion map, as the plan and the simulator use it.

    The functions take the load [N] (or the overlap [m]) and the keywords ``e_star`` [Pa],
    ``radius`` [m] and, for an adhesive contact, ``gamma`` [J/m^2] (:meth:`keywords`).
    ``minimum_overlap``: the overlap [m] at which the contact lets go under tension
    (None where it parts at delta = 0). ``simulated_as``: the label of the contact the
    simulator integrates in its place.
    """

    label: str
    adhesive: bool
    static_overlap: Callable
    linear_stiffness: Callable
    force: Callable
    shift_first_order: Callable | None = None
    minimum_overlap: Callable | None = None
    simulated_as: str | None = None

    def keywords(self, *, e_star: float, radius: float, surface_energy: float) -> dict:
        """The keywords of this contact's functions, from a scene's quantities."""
        kw = {"e_star": e_star, "radius": radius}
        if self.adhesive:
            kw["gamma"] = surface_energy
        return kw


HERTZIAN = SceneContact("Hertz", False, hertz.static_overlap, hertz.linear_stiffness,
                        hertz.force)
"""The non-adhesive contact: the reference every adhesive contact is measured against."""

_jkr = jkr.contact
_JKR = SceneContact("JKR", True, _jkr.static_overlap, _jkr.linear_stiffness, _jkr.force,
                    _jkr.shift_first_order, _jkr.minimum_overlap)
_DMT = SceneContact("DMT", True, dmt.static_overlap, dmt.linear_stiffness, dmt.force,
                    dmt.shift_first_order)
# the plan takes Maugis-Dugdale's linear numbers from JKR and brackets it by DMT and JKR
_MD = SceneContact("Maugis-Dugdale", True, _jkr.static_overlap, _jkr.linear_stiffness,
                   _jkr.force, _jkr.shift_first_order, simulated_as="JKR")
_CONTACTS = {c.label: c for c in (HERTZIAN, _DMT, _MD, _JKR)}


def scene_contact(label: str) -> SceneContact:
    """The contact the adhesion map calls ``label`` ('Hertz', 'DMT', 'Maugis-Dugdale',
    'JKR')."""
    try:
        return _CONTACTS[label]
    except KeyError:
        raise ValueError(f"no scene contact {label!r}; the adhesion map names "
                         f"{list(_CONTACTS)}") from None


viscous_damping_constant = viscoelastic.damping_constant
"""Kuwabara-Kono damping constant A [s] of the softer material (see
:func:`beadrod.models.laws.viscoelastic.damping_constant`)."""
viscous_linear_q = viscoelastic.linear_q
"""Linear Q [-] of the Kuwabara-Kono contact at omega0 (see
:func:`beadrod.models.laws.viscoelastic.linear_q`)."""
