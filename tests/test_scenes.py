"""Scenes: TOML loading, validation messages, derived properties, the `scene` command."""

import argparse
import json
import math

import pytest

from beadrod.models import scene
from beadrod.models.scene import SceneError

PAPER_R, PAPER_RHO, G = 7.938e-3, 7700.0, 9.80665


def _toml(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


BASE = """
name = "t"
[materials.steel]
young_Pa = 200e9
poisson = 0.27
density_kg_m3 = 7700
[bead]
radius_m = 7.938e-3
material = "steel"
[rod]
diameter_m = 0.012
length_m = 0.1
material = "steel"
[surfaces]
roughness_rms_m = 25e-9
surface_energy_J_m2 = 0.7
[drive]
f_min_Hz = 1500
f_max_Hz = 3500
voltage_min_V = 0.01
voltage_max_V = 1
displacement_per_volt_m_V = 1e-9
"""


def test_builtins_exist_and_round_trip():
    names = scene.builtin_scene_names()
    assert {"paper", "strong_drive", "large_soft_bead", "micro_bead"} <= set(names)
    for n in names:
        s = scene.builtin_scene(n)
        assert s.name == n
        assert scene.scene_from_dict(scene.scene_to_dict(s), n) == s


def test_paper_derived_properties_closed_form():
    s = scene.builtin_scene("paper")
    m = 4 / 3 * math.pi * PAPER_R**3 * PAPER_RHO
    assert s.mass == pytest.approx(m, rel=1e-14)
    assert s.weight == pytest.approx(m * G, rel=1e-14)
    assert s.load == s.weight
    assert s.e_star == pytest.approx(200e9 / (2 * (1 - 0.27**2)), rel=1e-14)
    assert s.radius == PAPER_R and s.rod_radius == 6e-3
    assert s.young_range == (190e9, 210e9)
    assert s.young_values() == (190e9, 210e9)
    s190 = s.with_young(190e9)
    assert s190.bead_material.young == s190.rod_material.young == 190e9
    assert s190.e_star == pytest.approx(190e9 / (2 * (1 - 0.27**2)), rel=1e-14)
    # displacement_per_volt documented choice: Q U_max ~ delta0 (53 nm) at the top drive
    assert s.quality_factor * s.drive_displacement_max == pytest.approx(54e-9)


def test_two_materials_and_extra_force(tmp_path):
    text = BASE.replace('material = "steel"\n[surfaces]', 'material = "pmma"\n[surfaces]')
    text += ("[materials.pmma]\nyoung_Pa = 3.3e9\npoisson = 0.37\ndensity_kg_m3 = 1190\n"
             "[preload]\nextra_force_N = 0.5\n")
    s = scene.load_scene(_toml(tmp_path, text))
    es = 1 / ((1 - 0.27**2) / 200e9 + (1 - 0.37**2) / 3.3e9)
    assert s.e_star == pytest.approx(es, rel=1e-14)
    assert s.load == pytest.approx(s.weight + 0.5)
    assert s.rod_material.name == "pmma"
    assert s.with_young(100e9).rod_material.young == 3.3e9  # different material: unchanged
    assert scene.scene_from_dict(scene.scene_to_dict(s)) == s


@pytest.mark.parametrize("old,new,needle", [
    ("radius_m = 7.938e-3", "radius = 7.938e-3", "did you mean 'radius_m'"),
    ("f_max_Hz = 3500", "f_max_hz = 3500", "did you mean 'f_max_Hz'"),
    ("poisson = 0.27", "poisson = 0.7", "'poisson' must lie in"),
    ("radius_m = 7.938e-3", "radius_m = -1.0", "'radius_m' must be > 0"),
    ("f_max_Hz = 3500", "f_max_Hz = 1000", "must be below"),
    ('material = "steel"\n[rod]', 'material = "stee"\n[rod]', "did you mean 'steel'"),
    ("length_m = 0.1\n", "", "missing required key 'length_m'"),
    ("[drive]", "colour = 1\n[drive]", "[surfaces] unknown key 'colour'"),
    ('name = "t"', 'name = "t"\nyoung_range_Pa = [210e9, 190e9]', "young_range_Pa"),
])
def test_errors_name_file_and_key(tmp_path, old, new, needle):
    assert old in BASE
    p = _toml(tmp_path, BASE.replace(old, new, 1), "bad_scene.toml")
    with pytest.raises(SceneError) as exc:
        scene.load_scene(p)
    assert "bad_scene.toml" in str(exc.value)
    assert needle in str(exc.value)


def test_bad_toml_and_missing_file(tmp_path):
    with pytest.raises(SceneError, match="not valid TOML"):
        scene.load_scene(_toml(tmp_path, "name = ", "broken.toml"))
    with pytest.raises(SceneError, match="no such scene file"):
        scene.load_scene(tmp_path / "nope.toml")
    with pytest.raises(SceneError, match="did you mean 'paper'"):
        scene.builtin_scene("papr")


def _run_cli(argv, capsys):
    from beadrod.workflows.commands import scene

    parser = argparse.ArgumentParser()
    scene.register(parser.add_subparsers())
    args = parser.parse_args(argv)
    rc = args.func(args)
    return rc, capsys.readouterr().out


def test_scene_command_json_paper_numbers(capsys):
    """The paper's Sec. 4 numbers, from the CLI's JSON (Hertz, JKR, viscous, adhesion)."""
    rc, out = _run_cli(["scene", "--json"], capsys)
    assert rc == 0
    q = json.loads(out)
    assert q["mass_kg"] == pytest.approx(4 / 3 * math.pi * PAPER_R**3 * PAPER_RHO)
    lo, hi = q["per_young"]
    assert (lo["young_Pa"], hi["young_Pa"]) == (190e9, 210e9)
    hz_lo, hz_hi = lo["laws"]["hertz"], hi["laws"]["hertz"]
    assert round(hz_lo["delta0_m"] * 1e9) == 55 and round(hz_hi["delta0_m"] * 1e9) == 52
    assert 2.55e3 < hz_lo["f0_Hz"] < hz_hi["f0_Hz"] < 2.75e3
    assert lo["laws"]["jkr"]["f0_Hz"] > hz_lo["f0_Hz"]
    # A = 1.23e-5 s (190 GPa) and 1.12e-5 s (210 GPa): the paper's 1.1e-5 is the 210 GPa end
    assert hi["damping"]["A_s"] == pytest.approx(1.1e-5, rel=0.03)
    # the viscoelastic law's linear Q at the scene's eta = 1.05e6 Pa s: the paper's Q ~ 5
    assert round(lo["laws"]["viscoelastic"]["Q"]) == 5
    assert lo["laws"]["viscoelastic"]["sources"]["eta"] == "scene (viscosity)"
    assert "Q" not in hz_lo  # no loss channel, no Q
    assert lo["adhesion"]["law"] == "JKR"
    # rod: bar velocity sqrt(E/rho); the PC branch equals it to 1e-4 at f0
    assert lo["rod"]["bar_velocity_m_s"] == pytest.approx(math.sqrt(190e9 / 7700))
    assert lo["rod"]["pochhammer_chree_group_velocity_at_f0_m_s"] == \
        pytest.approx(lo["rod"]["bar_velocity_m_s"], rel=1e-4)
    assert all(k.endswith(("_m", "_Hz", "_N_m", "_N", "_Pa", "_kg", "_s", "_m_s", "_m_s2"))
               or k in {"scene", "description", "per_young", "source"} for k in q)


def test_scene_command_covers_every_registered_law_at_nominal_values(capsys):
    """One block per registered law, a law registered at run time included; Hertz and the
    power law against their closed forms (Johnson 1985, Eq. 4.23: delta0 = (3 F0 / (4 E*
    sqrt R))^(2/3); F = C delta^n: K0 = n F0/delta0), with --param for the exponent."""
    import dataclasses

    from beadrod.models.laws import hertz
    from beadrod.models.registry import law_names, register, unregister

    copy = dataclasses.replace(
        hertz.LAW, name="hertz_copy_scene_test",
        presentation=dataclasses.replace(hertz.LAW.presentation, label="Hertz copy"),
        physics=dataclasses.replace(hertz.LAW.physics, static_overlap=None,
                                    overlap_from_frequency=None))
    register(copy)
    try:
        rc, out = _run_cli(["scene", "--json", "--param", "n=2.5"], capsys)
    finally:
        unregister(copy.name)
    assert rc == 0
    q = json.loads(out)
    lo = q["per_young"][0]
    assert set(lo["laws"]) == set(law_names()) | {copy.name}
    e_star = lo["e_star_Pa"]
    f0_load, m = q["load_N"], q["mass_kg"]
    d0 = (3 * f0_load / (4 * e_star * math.sqrt(q["radius_m"]))) ** (2 / 3)
    for name in ("hertz", copy.name):  # the copy's overlap is the generic root solve
        b = lo["laws"][name]
        assert b["delta0_m"] == pytest.approx(d0, rel=1e-9)
        assert b["K0_N_m"] == pytest.approx(1.5 * f0_load / d0, rel=1e-9)
        assert b["f0_Hz"] == pytest.approx(math.sqrt(1.5 * f0_load / d0 / m) / (2 * math.pi),
                                           rel=1e-9)
        assert b["sources"] == {"young": "scene (young)"}
    pl = lo["laws"]["powerlaw"]
    assert pl["params"]["n"] == 2.5 and pl["sources"]["n"] == "given"
    assert pl["sources"]["delta0_ref_log"] == "prior median"
    assert pl["delta0_m"] == pytest.approx(math.exp(pl["params"]["delta0_ref_log"]), rel=1e-9)
    assert pl["K0_N_m"] == pytest.approx(2.5 * f0_load / pl["delta0_m"], rel=1e-9)


def test_scene_command_refuses_unknown_or_absurd_parameters(capsys):
    from beadrod.workflows.cli import UserError

    with pytest.raises(UserError, match="no registered law has such a parameter"):
        _run_cli(["scene", "--param", "nope=1"], capsys)
    with pytest.raises(UserError, match="power-law exponent"):
        _run_cli(["scene", "--param", "n=4"], capsys)


def test_scene_command_text_and_error(tmp_path, capsys):
    rc, out = _run_cli(["scene", "--builtin", "micro_bead"], capsys)
    assert rc == 0 and "micro_bead" in out and "Maugis" in out
    from beadrod.workflows.cli import UserError

    with pytest.raises(UserError, match="did you mean"):
        _run_cli(["scene", str(_toml(tmp_path, BASE.replace("radius_m =", "radius =")))],
                 capsys)


@pytest.mark.parametrize("old,new,key", [
    ("radius_m = 7.938e-3", "radius_m = 1e300", "'radius_m'"),  # delta0 = inf before
    ("density_kg_m3 = 7700", "density_kg_m3 = 1e300", "'density_kg_m3'"),
    ("young_Pa = 200e9", "young_Pa = 1e300", "'young_Pa'"),
    ("voltage_max_V = 1", "voltage_max_V = 1e308", "'voltage_max_V'"),
    ("surface_energy_J_m2 = 0.7", "surface_energy_J_m2 = 0.7\nquality_factor = 1e308",
     "'quality_factor'"),
    ("length_m = 0.1", "length_m = 1e-300", "'length_m'"),
])
def test_values_outside_physical_bounds(tmp_path, old, new, key):
    assert old in BASE
    p = _toml(tmp_path, BASE.replace(old, new, 1), "absurd.toml")
    with pytest.raises(SceneError) as exc:
        scene.load_scene(p)
    msg = str(exc.value)
    assert msg.count(str(p)) == 1 and key in msg and "physical bounds" in msg, msg


def test_every_builtin_lies_within_the_bounds():
    # the bounds are checked on load, so loading is the test; the margins show they are
    # not drawn tight around the shipped scenes
    for n in scene.builtin_scene_names():
        d = scene.scene_to_dict(scene.builtin_scene(n))
        assert 1e-9 < d["bead"]["radius_m"] < 10.0
        assert 0 < d["drive"]["voltage_max_V"] <= 1e4


def test_scene_path_that_is_a_folder(tmp_path, capsys):
    with pytest.raises(SceneError, match="is a folder"):
        scene.load_scene(tmp_path)
    from beadrod.workflows.cli import main

    assert main(["scene", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("beadrod: error:") and "\n" not in err and str(tmp_path) in err
    assert "Traceback" not in err


def test_scene_file_that_is_not_text(tmp_path):
    p = tmp_path / "binary.toml"
    p.write_bytes(b"name = \"\xff\xfe\"\n")
    with pytest.raises(SceneError) as exc:
        scene.load_scene(p)
    assert str(exc.value).count(str(p)) == 1


# --- issue 47, item 19: scene files of the wrong shape, one line each ----------------------

STEEL = "[materials.steel]\nyoung_Pa = 200e9\npoisson = 0.27\ndensity_kg_m3 = 7700\n"


@pytest.mark.parametrize("old,new,needle", [
    (STEEL, "materials = 5\n", "'materials' must be a table [materials], got 5"),
    (STEEL, "materials = [1, 2]\n", "'materials' must be a table [materials], got [1, 2]"),
    ('name = "t"', "name = 7", "'name' must be a string, got 7"),
    ('name = "t"', 'name = "t"\ndescription = [1]', "'description' must be a string"),
    ('name = "t"', 'name = "t"\nyoung_range_Pa = 5', "'young_range_Pa' must be a list"),
    ("[materials.steel]\n", '[materials.steel]\nname = 3\n', "'name' must be a string"),
    ("young_Pa = 200e9", "young_Pa = " + "9" * 400, "'young_Pa' must be a finite number"),
    ("young_Pa = 200e9", "young_Pa = [[[[[[1]]]]]]", "'young_Pa' must be a finite number"),
])
def test_scene_values_of_the_wrong_type(tmp_path, old, new, needle):
    assert old in BASE
    p = _toml(tmp_path, BASE.replace(old, new, 1), "typed.toml")
    with pytest.raises(SceneError) as exc:
        scene.load_scene(p)
    msg = str(exc.value)
    assert needle in msg and "\n" not in msg and len(msg) < 400, msg


def test_scene_quality_factor_of_one_half_is_refused(tmp_path):
    text = BASE.replace("surface_energy_J_m2 = 0.7",
                        "surface_energy_J_m2 = 0.7\nquality_factor = 0.5")
    with pytest.raises(SceneError, match=r"'quality_factor' = 0\.5 lies outside the physical "
                                         r"bounds \(0\.5, 100000\] \(above 1/2"):
        scene.load_scene(_toml(tmp_path, text))
    ok = text.replace("quality_factor = 0.5", "quality_factor = 0.51")
    assert scene.load_scene(_toml(tmp_path, ok, "ok.toml")).quality_factor == 0.51


@pytest.mark.parametrize("value", ["[1, 1e300]", "[1, 2e11]", "[1e11, 1e13]"])
def test_scene_young_range_is_bounds_checked(tmp_path, value):
    text = BASE.replace('name = "t"', f'name = "t"\nyoung_range_Pa = {value}')
    with pytest.raises(SceneError) as exc:
        scene.load_scene(_toml(tmp_path, text))
    assert "'young_range_Pa'" in str(exc.value) and "[1000, 1.2e+12]" in str(exc.value)


def test_scene_with_a_byte_order_mark_loads_as_without(tmp_path):
    plain = scene.load_scene(_toml(tmp_path, BASE, "plain.toml"))
    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf" + BASE.encode())
    assert scene.load_scene(p) == plain


@pytest.mark.parametrize("text", ["a = " + "[" * 5000 + "]" * 5000,
                                  "a = " + "{b = " * 3000 + "1" + "}" * 3000])
def test_scene_nested_too_deeply_is_one_line(tmp_path, text):
    p = _toml(tmp_path, text, "deep.toml")
    with pytest.raises(SceneError) as exc:
        scene.load_scene(p)
    msg = str(exc.value)
    assert msg.startswith(str(p)) and "nested too deeply" in msg and "\n" not in msg


def test_read_toml_names_the_file_for_every_failure(tmp_path):
    # the one reader of user TOML, for scene and config files alike (models.tomlfile)
    from beadrod.models.tomlfile import read_toml

    class Mine(ValueError):
        pass

    cases = {"deep.toml": ("a = " + "[" * 3000 + "]" * 3000).encode(),
             "latin1.toml": b'a = 1\nb = "\xe9"\n', "bad.toml": b"a = = 1\n"}
    needles = {"deep.toml": "nested too deeply", "latin1.toml": "line 2: not UTF-8",
               "bad.toml": "not valid TOML"}
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(Mine) as exc:
            read_toml(tmp_path / name, error=Mine, what="config file")
        assert str(exc.value).startswith(str(tmp_path / name))
        assert needles[name] in str(exc.value) and "\n" not in str(exc.value)
    with pytest.raises(Mine, match="is a folder, not a config file"):
        read_toml(tmp_path, error=Mine, what="config file")
    with pytest.raises(Mine, match="no such config file"):
        read_toml(tmp_path / "none.toml", error=Mine, what="config file")
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbfa = 1\n")
    assert read_toml(tmp_path / "bom.toml") == {"a": 1}
