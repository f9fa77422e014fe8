"""Scenes: a concrete bead-rod setup read from a TOML file.

Layout (SI units, the unit is part of every key name)::

    name = "paper"
    description = "..."
    young_range_Pa = [190e9, 210e9]        # optional: E uncertainty of the bead material

    [materials.steel]                      # any number of named materials
    young_Pa = 200e9
    poisson = 0.27
    density_kg_m3 = 7700
    yield_strength_Pa = 6.12e9             # optional (plastic-limit check)

    [bead]     radius_m, material
    [rod]      diameter_m, length_m, material, first_resonance_Hz (optional, measured)
    [preload]  extra_force_N (default 0), gravity_m_s2 (default standard gravity)
    [surfaces] roughness_rms_m, surface_energy_J_m2, viscosity_Pa_s (optional),
               quality_factor (optional: measured/assumed linear Q of the bead resonance)
    [drive]    f_min_Hz, f_max_Hz, voltage_min_V, voltage_max_V, displacement_per_volt_m_V

``displacement_per_volt`` is the rod-end (base) displacement amplitude per drive volt.
Errors (:class:`SceneError`) name the file and the key; unknown keys are rejected with
the closest valid key suggested. Every number must lie within the physical bounds of
``BOUNDS`` (each with its reason; ``quality_factor`` strictly above its lower bound), so
that no derived quantity (mass, load, static overlap) can be infinite or zero. The file is
read by :func:`models.tomlfile.read_toml` (a UTF-8 byte-order mark is accepted; a folder,
non-UTF-8 bytes and nesting too deep to parse are one-line errors). ``young_range`` applies
to the bead material and, when the rod is made of the same named material, to the rod too
(paper: both are the steel); its ends lie within the bounds of ``young_Pa``.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jax

from beadrod.models.scene.materials import (
    G_STANDARD,
    Material,
    bead_mass,
    effective_modulus,
    effective_radius,
)
from beadrod.models.tomlfile import describe_value, read_toml

__all__ = [
    "Scene",
    "SceneError",
    "load_scene",
    "builtin_scene",
    "builtin_scene_names",
    "scene_from_dict",
    "scene_to_dict",
    "BUILTIN_DIR",
    "BOUNDS",
    "QUALITY_FACTOR_MAX",
]

BUILTIN_DIR = Path(__file__).parent / "presets"


class SceneError(ValueError):
    """A scene file or dict that cannot be read; the message names file and key."""


@dataclass(frozen=True)
class Scene:
    """A bead on a rod end, its surfaces, preload, frequency band and drive (SI units)."""

    name: str
    description: str
    bead_radius: float
    bead_material: Material
    rod_diameter: float
    rod_length: float
    rod_material: Material
    rod_first_resonance: float | None
    extra_force: float
    gravity: float
    roughness_rms: float
    surface_energy: float
    viscosity: float | None
    f_min: float
    f_max: float
    voltage_min: float
    voltage_max: float
    displacement_per_volt: float
    young_range: tuple[float, float] | None
    quality_factor: float | None = None

    @property
    def mass(self) -> float:
        """Bead mass m = (4/3) pi r^3 rho [kg]."""
        with jax.enable_x64(True):  # plain-float config values: exact whatever the global mode
            return float(bead_mass(self.bead_radius, self.bead_material.density))

    @property
    def weight(self) -> float:
        """m g [N]."""
        return self.mass * self.gravity

    @property
    def load(self) -> float:
        """Static compressive load on the contact, weight + extra force [N]."""
        return self.weight + self.extra_force

    @property
    def e_star(self) -> float:
        """Effective modulus E* [Pa] of bead on rod."""
        b, r = self.bead_material, self.rod_material
        with jax.enable_x64(True):
            return float(effective_modulus(b.young, b.poisson, r.young, r.poisson))

    @property
    def radius(self) -> float:
        """Effective radius R [m] (sphere on the flat rod end: R = bead radius)."""
        with jax.enable_x64(True):
            return float(effective_radius(self.bead_radius))

    @property
    def rod_radius(self) -> float:
        """Rod radius a = diameter/2 [m] (the a of Pochhammer-Chree and Rayleigh-Love)."""
        return 0.5 * self.rod_diameter

    @property
    def rod_mass(self) -> float:
        """pi a^2 L rho [kg]."""
        return math.pi * self.rod_radius**2 * self.rod_length * self.rod_material.density

    @property
    def yield_strength(self) -> float | None:
        """The smaller yield strength of the two bodies [Pa] (None if neither is known)."""
        ys = [m.yield_strength for m in (self.bead_material, self.rod_material)
              if m.yield_strength is not None]
        return min(ys) if ys else None

    @property
    def drive_displacement_max(self) -> float:
        """Largest base displacement amplitude U = voltage_max * displacement_per_volt [m]."""
        return self.voltage_max * self.displacement_per_volt

    def with_young(self, young: float) -> Scene:
        """A copy with the bead's Young's modulus (and the rod's, if the same material) set."""
        same = self.rod_material == self.bead_material
        bead = dataclasses.replace(self.bead_material, young=float(young))
        rod = dataclasses.replace(self.rod_material, young=float(young)) if same \
            else self.rod_material
        return dataclasses.replace(self, bead_material=bead, rod_material=rod)

    def young_values(self) -> tuple[float, ...]:
        """The E values [Pa] to report: the ends of ``young_range``, else the nominal E."""
        if self.young_range is None:
            return (self.bead_material.young,)
        return tuple(self.young_range)


# --- TOML schema --------------------------------------------------------------------------

QUALITY_FACTOR_MAX = 1e5
"""Largest credible Q of a bead resonance: ten times the Q of steel's own internal
friction (loss factor ~1e-4, Q ~ 1e4); a bead held in a lossy contact cannot ring
longer than its material does."""

_LENGTH = (1e-9, 10.0, "from 1 nm (a few atoms: continuum contact mechanics ends) to 10 m "
           "(a laboratory)")
_FREQ = (1e-2, 1e10, "from 10 mHz to 10 GHz (the highest acoustic resonators)")
BOUNDS: dict[str, tuple[float, float, str]] = {
    "young_Pa": (1e3, 1.2e12, "from soft gels (~1 kPa) to diamond (1.2 TPa), the stiffest "
                 "solid"),
    "density_kg_m3": (1.0, 2.3e4, "from aerogels (~1 kg/m^3) to osmium (22.6e3 kg/m^3), the "
                      "densest element"),
    "yield_strength_Pa": (1e3, 1.2e11, "at most the ideal strength, ~E/10, of the stiffest "
                          "solid"),
    "radius_m": _LENGTH, "diameter_m": _LENGTH, "length_m": _LENGTH,
    "first_resonance_Hz": _FREQ, "f_min_Hz": _FREQ, "f_max_Hz": _FREQ,
    "extra_force_N": (-1e6, 1e6, "|F| up to 1 MN, a hydraulic press"),
    "gravity_m_s2": (0.0, 1e7, "up to 1e6 g, an ultracentrifuge"),
    "roughness_rms_m": (0.0, 1e-3, "up to 1 mm rms, a rough casting rather than a contact "
                        "surface"),
    "surface_energy_J_m2": (0.0, 10.0, "up to 10 J/m^2; the highest metal surface energies "
                            "are ~3 J/m^2 (tungsten)"),
    "viscosity_Pa_s": (0.0, 1e15, "up to 1e15 Pa s; glass at its transition is 1e12 Pa s"),
    "quality_factor": (0.5, QUALITY_FACTOR_MAX, "above 1/2 (a resonance at all) and at most "
                       "ten times the Q of steel's own internal friction"),
    "voltage_min_V": (0.0, 1e4, "up to 10 kV, beyond any piezo amplifier"),
    "voltage_max_V": (0.0, 1e4, "up to 10 kV, beyond any piezo amplifier"),
    "displacement_per_volt_m_V": (0.0, 1e-3, "up to 1 mm/V; piezo stacks give ~0.1 um/V"),
}
"""Physical bounds [SI unit of the key] on every number of a scene, with the reason."""

_OPEN_LOW = frozenset({"quality_factor"})
"""Keys whose lower bound is excluded (Q = 1/2 is critical damping: no resonance)."""

_REQ, _OPT = True, False
_TOP = {"name": (_REQ, str), "description": (_OPT, str), "young_range_Pa": (_OPT, list),
        "materials": (_REQ, dict), "bead": (_REQ, dict), "rod": (_REQ, dict),
        "preload": (_OPT, dict), "surfaces": (_REQ, dict), "drive": (_REQ, dict)}
_MATERIAL = {"young_Pa": (_REQ, float), "poisson": (_REQ, float),
             "density_kg_m3": (_REQ, float), "yield_strength_Pa": (_OPT, float),
             "name": (_OPT, str)}
_TABLES = {
    "bead": {"radius_m": (_REQ, float), "material": (_REQ, str)},
    "rod": {"diameter_m": (_REQ, float), "length_m": (_REQ, float), "material": (_REQ, str),
            "first_resonance_Hz": (_OPT, float)},
    "preload": {"extra_force_N": (_OPT, float), "gravity_m_s2": (_OPT, float)},
    "surfaces": {"roughness_rms_m": (_REQ, float), "surface_energy_J_m2": (_REQ, float),
                 "viscosity_Pa_s": (_OPT, float), "quality_factor": (_OPT, float)},
    "drive": {"f_min_Hz": (_REQ, float), "f_max_Hz": (_REQ, float),
              "voltage_min_V": (_REQ, float), "voltage_max_V": (_REQ, float),
              "displacement_per_volt_m_V": (_REQ, float)},
}


def _label(key: Any) -> str:
    """A key or name from the file as it can stand in a one-line message (a quoted TOML
    key may hold a line break or be a page long)."""
    text = str(key)
    if text.isprintable() and len(text) <= 40:
        return text
    shown = repr(text)[1:-1]
    return shown if len(shown) <= 40 else shown[:37] + "..."


def _check_keys(table: dict, schema: dict, source: str, where: str) -> None:
    for key in table:
        if key not in schema:
            close = difflib.get_close_matches(key, list(schema), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else \
                f" (valid keys: {', '.join(schema)})"
            raise SceneError(f"{source}: {where}unknown key '{_label(key)}'{hint}")
    for key, (required, _) in schema.items():
        if required and key not in table:
            raise SceneError(f"{source}: {where}missing required key '{key}'")


def _num(table: dict, key: str, source: str, where: str, *, positive: bool = True,
         nonneg: bool = False, default: float | None = None) -> float | None:
    if key not in table:
        return default
    v = table[key]
    if isinstance(v, bool) or not isinstance(v, int | float) or not _finite(v):
        raise SceneError(f"{source}: {where}'{key}' must be a finite number, got "
                         f"{describe_value(v)}")
    v = float(v)
    if positive and not nonneg and v <= 0:
        raise SceneError(f"{source}: {where}'{key}' must be > 0, got {v!r}")
    if nonneg and v < 0:
        raise SceneError(f"{source}: {where}'{key}' must be >= 0, got {v!r}")
    if key in BOUNDS:
        lo, hi, why = BOUNDS[key]
        open_low = key in _OPEN_LOW
        if not ((lo < v if open_low else lo <= v) and v <= hi):
            raise SceneError(f"{source}: {where}'{key}' = {v!r} lies outside the physical "
                             f"bounds {'(' if open_low else '['}{lo:g}, {hi:g}] ({why})")
    return v


def _finite(v: int | float) -> bool:
    # a TOML integer has no size limit: one beyond the float range is not a finite number
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _str(table: dict, key: str, source: str, where: str) -> str:
    v = table[key]
    if not isinstance(v, str):
        raise SceneError(f"{source}: {where}'{key}' must be a string, got {describe_value(v)}")
    return v


def _material(name: str, table: Any, source: str) -> Material:
    name_txt = _label(name)
    where = f"[materials.{name_txt}] "
    if not isinstance(table, dict):
        raise SceneError(f"{source}: [materials] '{name_txt}' must be a table "
                         f"[materials.{name_txt}], got {describe_value(table)}")
    _check_keys(table, _MATERIAL, source, where)
    if "name" in table:
        _str(table, "name", source, where)
    nu = _num(table, "poisson", source, where, positive=False)
    if not -1.0 < nu < 0.5:
        raise SceneError(f"{source}: {where}'poisson' must lie in (-1, 0.5), got {nu!r}")
    return Material(
        name=table.get("name", name),
        young=_num(table, "young_Pa", source, where),
        poisson=nu,
        density=_num(table, "density_kg_m3", source, where),
        yield_strength=_num(table, "yield_strength_Pa", source, where),
    )


def scene_from_dict(d: dict, source: str = "<dict>") -> Scene:
    """Build a :class:`Scene` from the TOML layout (module docstring); ``source`` names it
    in error messages."""
    if not isinstance(d, dict):
        raise SceneError(f"{source}: a scene must be a table")
    _check_keys(d, _TOP, source, "")
    for key, (_, kind) in _TOP.items():
        if key in d and not isinstance(d[key], kind):
            shape = {str: "a string", list: "a list [lo, hi]",
                     dict: f"a table [{key}]"}[kind]
            raise SceneError(f"{source}: '{key}' must be {shape}, got {describe_value(d[key])}")
    for tname, schema in _TABLES.items():
        t = d.get(tname, {})
        if not isinstance(t, dict):
            raise SceneError(f"{source}: '{tname}' must be a table [{tname}]")
        _check_keys(t, schema, source, f"[{tname}] ")
    mats = d["materials"]
    if not mats:
        raise SceneError(f"{source}: [materials] must define at least one material")
    materials = {name: _material(name, t, source) for name, t in mats.items()}

    def pick(tname: str) -> Material:
        key = _str(d[tname], "material", source, f"[{tname}] ")
        if key not in materials:
            close = difflib.get_close_matches(key, list(materials), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise SceneError(f"{source}: [{tname}] material: no [materials.{_label(key)}]"
                             f"{hint}; defined: {', '.join(_label(m) for m in materials)}")
        return materials[key]

    bead, rod, pre, srf, drv = (d[k] if k in d else {} for k in
                                ("bead", "rod", "preload", "surfaces", "drive"))
    name = _str(d, "name", source, "")
    yr = d.get("young_range_Pa")
    young_range = None
    if yr is not None:
        if (not isinstance(yr, list) or len(yr) != 2
                or not all(isinstance(v, int | float) and not isinstance(v, bool)
                           and _finite(v) for v in yr)
                or not 0 < yr[0] <= yr[1]):
            raise SceneError(f"{source}: 'young_range_Pa' must be [lo, hi] with 0 < lo <= hi, "
                             f"got {describe_value(yr)}")
        lo, hi, why = BOUNDS["young_Pa"]  # a range of the same modulus
        if not lo <= yr[0] <= yr[1] <= hi:
            raise SceneError(f"{source}: 'young_range_Pa' = {describe_value(yr)} lies outside "
                             f"the physical bounds of 'young_Pa', [{lo:g}, {hi:g}] ({why})")
        young_range = (float(yr[0]), float(yr[1]))
    scene = Scene(
        name=name,
        description=str(d.get("description", "")),
        bead_radius=_num(bead, "radius_m", source, "[bead] "),
        bead_material=pick("bead"),
        rod_diameter=_num(rod, "diameter_m", source, "[rod] "),
        rod_length=_num(rod, "length_m", source, "[rod] "),
        rod_material=pick("rod"),
        rod_first_resonance=_num(rod, "first_resonance_Hz", source, "[rod] "),
        extra_force=_num(pre, "extra_force_N", source, "[preload] ", positive=False,
                         default=0.0),
        gravity=_num(pre, "gravity_m_s2", source, "[preload] ", nonneg=True,
                     default=G_STANDARD),
        roughness_rms=_num(srf, "roughness_rms_m", source, "[surfaces] ", nonneg=True),
        surface_energy=_num(srf, "surface_energy_J_m2", source, "[surfaces] ", nonneg=True),
        viscosity=_num(srf, "viscosity_Pa_s", source, "[surfaces] ", nonneg=True),
        quality_factor=_num(srf, "quality_factor", source, "[surfaces] "),
        f_min=_num(drv, "f_min_Hz", source, "[drive] "),
        f_max=_num(drv, "f_max_Hz", source, "[drive] "),
        voltage_min=_num(drv, "voltage_min_V", source, "[drive] ", nonneg=True),
        voltage_max=_num(drv, "voltage_max_V", source, "[drive] "),
        displacement_per_volt=_num(drv, "displacement_per_volt_m_V", source, "[drive] "),
        young_range=young_range,
    )
    if scene.f_min >= scene.f_max:
        raise SceneError(f"{source}: [drive] 'f_min_Hz' ({scene.f_min}) must be below "
                         f"'f_max_Hz' ({scene.f_max})")
    if scene.voltage_min > scene.voltage_max:
        raise SceneError(f"{source}: [drive] 'voltage_min_V' ({scene.voltage_min}) must not "
                         f"exceed 'voltage_max_V' ({scene.voltage_max})")
    if scene.load <= 0:
        raise SceneError(f"{source}: [preload] the load (weight + extra_force_N = "
                         f"{scene.load:g} N) must be compressive (> 0)")
    return scene


def load_scene(path: str | Path) -> Scene:
    """Read a scene TOML file; errors name the file and the offending key."""
    path = Path(path)
    hint = "give its .toml file; models/scene/presets/paper.toml shows the layout"
    d = read_toml(path, error=SceneError, what="scene file",
                  hint=hint if path.is_dir() else "")
    return scene_from_dict(d, str(path))


def builtin_scene_names() -> list[str]:
    """Names of the scenes shipped in ``models/scene/presets/*.toml``."""
    return sorted(p.stem for p in BUILTIN_DIR.glob("*.toml"))


def builtin_scene(name: str = "paper") -> Scene:
    """A shipped scene by name (``"paper"`` is the paper's setup)."""
    names = builtin_scene_names()
    if name not in names:
        close = difflib.get_close_matches(name, names, n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise SceneError(f"no built-in scene '{name}'{hint}; available: {', '.join(names)}")
    return load_scene(BUILTIN_DIR / f"{name}.toml")


def _material_dict(m: Material) -> dict:
    out = {"name": m.name, "young_Pa": m.young, "poisson": m.poisson,
           "density_kg_m3": m.density}
    if m.yield_strength is not None:
        out["yield_strength_Pa"] = m.yield_strength
    return out


def scene_to_dict(scene: Scene) -> dict:
    """The TOML layout of ``scene`` (``scene_from_dict(scene_to_dict(s)) == s``)."""
    mats = {"bead": _material_dict(scene.bead_material)}
    rod_key = "bead"
    if scene.rod_material != scene.bead_material:
        mats["rod"] = _material_dict(scene.rod_material)
        rod_key = "rod"
    rod = {"diameter_m": scene.rod_diameter, "length_m": scene.rod_length,
           "material": rod_key}
    if scene.rod_first_resonance is not None:
        rod["first_resonance_Hz"] = scene.rod_first_resonance
    surfaces = {"roughness_rms_m": scene.roughness_rms,
                "surface_energy_J_m2": scene.surface_energy}
    if scene.viscosity is not None:
        surfaces["viscosity_Pa_s"] = scene.viscosity
    if scene.quality_factor is not None:
        surfaces["quality_factor"] = scene.quality_factor
    d = {
        "name": scene.name,
        "description": scene.description,
        "materials": mats,
        "bead": {"radius_m": scene.bead_radius, "material": "bead"},
        "rod": rod,
        "preload": {"extra_force_N": scene.extra_force, "gravity_m_s2": scene.gravity},
        "surfaces": surfaces,
        "drive": {"f_min_Hz": scene.f_min, "f_max_Hz": scene.f_max,
                  "voltage_min_V": scene.voltage_min, "voltage_max_V": scene.voltage_max,
                  "displacement_per_volt_m_V": scene.displacement_per_volt},
    }
    if scene.young_range is not None:
        d["young_range_Pa"] = list(scene.young_range)
    return d
