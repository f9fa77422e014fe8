"""Does the scene describe the measured resonance? A check for unit slips in scene.toml.

The scene's bead, materials and load set the linear contact resonance f0 that every
contact law starts from: a bead of radius R and density rho on an elastic contact of
modulus E* under its weight resonates at f0 ~ E*^(1/3) rho^(-1/3) R^(-5/6) (Hertz). A
unit slip moves it by orders of magnitude: a radius written in millimetres as metres
(7.938 for 7.938e-3) divides f0 by 1000^(5/6) ~ 300, a density in g/cm^3 written as
kg/m^3 (7.7 for 7700) multiplies it by 10. The plausibility bounds of
:data:`models.scene.BOUNDS` cannot see either (7.938 m and 7.7 kg/m^3 are physical
values, just not this setup's).

The range the scene implies (:func:`implied_f0_range`) is taken over the contact laws'
prior ranges, not at one nominal point: E* from the scene's materials (and its
``young_range``) and from the Young's modulus prior the elastic laws fit
(:data:`models.law.YOUNG`); Hertz (:func:`models.laws.hertz.linear_frequency`) gives the
lower end. Adhesion stiffens the contact, by at most JKR's (DMT and Maugis-Dugdale lie
between Hertz and JKR), with the scene's surface energy and up to the 97.5 % quantile of
the surface energy prior (:data:`models.law.GAMMA`): JKR's contact radius under the load
F is Hertz's under F1 = F + 2 Fc + 2 (Fc (F + Fc))^(1/2), Fc its pull-off force
(:func:`models.laws.jkr.contact.contact_radius`), and its stiffness 2 E* a (3 - 3u)/(3 - u)
is at most Hertz's 2 E* a there, so Hertz under F1 bounds the upper end (one model
function, evaluated on one small grid). A law whose f0 is a free parameter (the rough
power law's reference overlap) implies nothing about the scene and is not used.

The check (:func:`check_scene_units`) refuses a dataset whose median reference f0 lies
more than a factor F0_TOLERANCE = 3 outside that range (a factor 9 in stiffness: far
beyond the laws' differences, a rod that is not rigid, or contact roughness), and names
the likely slip where rescaling one key by a unit factor brings f0 within the band.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from beadrod.data.schema import DataError

__all__ = ["F0_TOLERANCE", "implied_f0_range", "check_scene_units", "UNIT_SLIPS"]

F0_TOLERANCE = 3.0
"""How far [factor] the measured median f0 may lie outside the range the scene implies."""

GAMMA_QUANTILE_Z = 1.959963984540054
"""z of the 97.5 % quantile: the largest surface energy of the prior that is used."""

UNIT_SLIPS: tuple[tuple[str, str, float, str, str], ...] = (
    ("bead", "radius_m", 1e-3, "millimetres", "m"),
    ("bead", "radius_m", 1e-2, "centimetres", "m"),
    ("bead", "radius_m", 1e-6, "micrometres", "m"),
    ("material", "density_kg_m3", 1e3, "g/cm^3", "kg/m^3"),
)
"""(table, key, factor to SI, the unit it was likely written in, the SI unit): the slips
tried when naming the cause ('material' is the bead's material table)."""


def _with(scene: Any, table: str, factor: float) -> Any:
    if table == "bead":
        return dataclasses.replace(scene, bead_radius=scene.bead_radius * factor)
    mat = dataclasses.replace(scene.bead_material,
                              density=scene.bead_material.density * factor)
    return dataclasses.replace(scene, bead_material=mat)


@functools.lru_cache(maxsize=64)
def implied_f0_range(scene: Any) -> tuple[float, float] | None:
    """[lo, hi] [Hz]: the linear contact resonances the scene implies over the laws'
    prior ranges (module docstring); None when no finite value results."""
    import jax

    from beadrod.models.law import GAMMA, YOUNG
    from beadrod.models.laws import hertz
    from beadrod.models.laws.jkr import contact

    nu = float(scene.bead_material.poisson)
    same = 2.0 * (1.0 - nu * nu)  # E* of bead and rod of one material: E / (2 (1 - nu^2))
    e_star = [float(scene.e_star)]
    e_star += [float(scene.with_young(e).e_star) for e in scene.young_values()]
    e_star += [float(e) / same for e in YOUNG.prior.bounds()]
    gammas = [g for g in (float(scene.surface_energy),
                          GAMMA.prior.a * math.exp(GAMMA_QUANTILE_Z * GAMMA.prior.b)) if g > 0]
    load, mass, radius = float(scene.load), float(scene.mass), float(scene.radius)
    loads = [load]
    with jax.enable_x64(True), np.errstate(all="ignore"):
        for g in gammas:
            fc = float(contact.pull_off_force(gamma=g, radius=radius))
            loads.append(load + 2.0 * fc + 2.0 * math.sqrt(fc * (load + fc)))
        f = np.asarray(hertz.linear_frequency(np.asarray(loads)[None, :], mass,
                                              e_star=np.asarray(e_star)[:, None],
                                              radius=radius))
    f = f.astype(np.float64).ravel()
    f = f[np.isfinite(f) & (f > 0)]
    if f.size == 0:
        return None
    return float(f.min()), float(f.max())


def _outside(f0: float, rng: tuple[float, float] | None) -> bool:
    return rng is not None and not (rng[0] / F0_TOLERANCE <= f0 <= rng[1] * F0_TOLERANCE)


def _material_key(scene_file: Path) -> str:
    """The bead's material table name in the scene file, for the message."""
    from beadrod.models.tomlfile import read_toml

    try:
        name = read_toml(scene_file)["bead"]["material"]
    except (ValueError, KeyError, TypeError):
        return "materials.<the bead's>"
    return f"materials.{name}" if isinstance(name, str) else "materials.<the bead's>"


def check_scene_units(scene: Any, table: pd.DataFrame, *, scene_file: Path,
                      csv_name: str) -> None:
    """Refuse a scene that cannot produce the measured linear resonance (module
    docstring): :class:`DataError` naming the scene file, the key of the likely slip and
    the measured and implied f0."""
    ref = table.loc[table["kind"] == "reference", "f_res_Hz"].to_numpy(np.float64)
    ref = ref[np.isfinite(ref)]
    if ref.size == 0:
        return
    f0 = float(np.median(ref))
    rng = implied_f0_range(scene)
    if not _outside(f0, rng):
        return
    where = (f"the reference sweeps in {csv_name} resonate at {f0:.4g} Hz (median), the "
             f"scene implies {rng[0]:.3g}-{rng[1]:.3g} Hz for any contact law over its "
             f"prior range (more than a factor {F0_TOLERANCE:g} apart)")
    for table_name, key, factor, unit, si in UNIT_SLIPS:
        fixed = implied_f0_range(_with(scene, table_name, factor))
        if fixed is not None and not _outside(f0, fixed):
            value = scene.bead_radius if key == "radius_m" else scene.bead_material.density
            section = "bead" if table_name == "bead" else _material_key(scene_file)
            raise DataError(f"{scene_file}: [{section}] {key} = {value:g} looks like "
                            f"{unit} ({value:g} {unit} = {value * factor:g} {si}?): {where}")
    raise DataError(f"{scene_file}: the scene does not describe these measurements: {where}; "
                    "check the units of the bead's radius_m and density_kg_m3, its "
                    "young_Pa and the [preload]")
