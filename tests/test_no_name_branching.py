"""Outside a law's own module no code branches on a law's name: the registry is the list.

The source check walks models/ (outside models/laws/, the laws' own home), inference/,
data/ and workflows/ with ast and fails on any string literal equal to a registered law's
name, except the entries of :data:`ALLOWED`, each with its reason (an entry must still
occur, so the list can only shrink). Outside models/laws/ no module of models/ imports a
law's module either: the registry serves the laws (models.laws.BUILTIN is their one list). The other tests
register laws under new names and check that the places which used to list names (the
tension, the job order, ``beadrod scene``, the figures) serve them from their attributes.
"""

from __future__ import annotations

import ast
import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from beadrod.models.laws import hertz, powerlaw, viscoelastic
from beadrod.models.registry import law_names, register, tension_pair, unregister

ROOT = Path(__file__).resolve().parents[1]

# (module, law name): the only string literals naming a law outside the laws' modules
ALLOWED: dict[tuple[str, str], str] = {
    ("inference.model.numpyro_models", "hertz"):
        "ModelSpec's default law (a spec must name one)",
    ("inference.model.numpyro_models", "viscoelastic"):
        "ModelSpec(eta_mode='split') kept as a compatibility spelling of the split law",
    ("inference.model.numpyro_models", "viscoelastic_split"):
        "the same compatibility mapping, in the other direction",
    ("workflows.bench.inference", "hertz"):
        "the benchmark's reference law (ESS/s of the others is quoted against it)",
    ("workflows.bench.device", "hertz"):
        "the device benchmark times one reference law",
    ("workflows.figures.physics", "powerlaw"):
        "default colour of the paper's Fig. 5, a figure of the power law; callers pass "
        "the law (workflows.figures.comparison.exponent_law)",
    ("workflows.report.truth", "hertz"):
        "a synthetic world's truth says which law generated it (data.synth: Hertz worlds)",
}


def _sources(root: Path):
    """(module, path) of every module of the four packages, models/laws/ left out."""
    for pkg in ("models", "inference", "data", "workflows"):
        for path in sorted((root / pkg).rglob("*.py")):
            rel = path.relative_to(root)
            if rel.parts[:2] == ("models", "laws"):
                continue
            yield ".".join(rel.with_suffix("").parts), path


def _literals(names: set[str], root: Path = ROOT) -> set[tuple[str, str]]:
    """(module, literal) of every string literal in ``names`` under root's packages."""
    hits = set()
    for module, path in _sources(root):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Constant) and node.value in names:
                hits.add((module, node.value))
    return hits


def _law_modules(root: Path = ROOT) -> set[str]:
    """Dotted names of the laws' modules: every module of a law's folder, and each module
    of models/laws/ that defines LAW."""
    laws = root / "models" / "laws"
    out = set()
    for path in laws.rglob("*.py"):
        rel = path.relative_to(root).with_suffix("").parts
        dotted = ".".join(rel[:-1] if rel[-1] == "__init__" else rel)
        in_folder = len(rel) > 4 or (len(rel) == 4 and rel[-1] != "__init__")
        defines_law = any(isinstance(n, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "LAW" for t in n.targets)
            for n in ast.parse(path.read_text()).body)
        if in_folder or defines_law or (len(rel) == 4 and rel[-1] == "__init__"):
            out.add(dotted)
    return out


def _law_imports(root: Path = ROOT) -> set[tuple[str, str]]:
    """(module of models/ outside models/laws/, law module it imports)."""
    law_modules = _law_modules(root)
    hits = set()
    for module, path in _sources(root):
        if not module.startswith("models."):
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom) and node.module:
                base = node.module.removeprefix("beadrod.")
                targets = {base} | {f"{base}.{a.name}" for a in node.names}
            elif isinstance(node, ast.Import):
                targets = {a.name.removeprefix("beadrod.") for a in node.names}
            else:
                continue
            hits |= {(module, t) for t in targets & law_modules}
    return hits


def test_no_module_of_models_outside_the_laws_imports_a_law():
    hits = sorted(_law_imports())
    assert not hits, (f"modules of models/ importing a law's module: {hits}; take the law "
                      "from models.registry (or the law object) instead")


def test_the_import_check_sees_a_law_import(tmp_path):
    (tmp_path / "models" / "laws" / "jkr").mkdir(parents=True)
    (tmp_path / "models" / "laws" / "jkr" / "__init__.py").write_text("LAW = 1\n")
    (tmp_path / "models" / "laws" / "jkr" / "table.py").write_text("X = 1\n")
    (tmp_path / "models" / "laws" / "hertz.py").write_text("LAW = 1\n")
    (tmp_path / "models" / "laws" / "adhesion_map.py").write_text("X = 1\n")
    (tmp_path / "models" / "scene").mkdir()
    (tmp_path / "models" / "scene" / "plan.py").write_text(
        "from beadrod.models.laws import adhesion_map, hertz\n"
        "from beadrod.models.laws.jkr.table import X\n")
    for pkg in ("inference", "data", "workflows"):
        (tmp_path / pkg).mkdir()
    assert _law_imports(tmp_path) == {("models.scene.plan", "models.laws.hertz"),
                                      ("models.scene.plan", "models.laws.jkr.table")}


def test_no_law_name_is_spelled_outside_the_laws_modules():
    hits = _literals(set(law_names()))
    unexpected = sorted(hits - set(ALLOWED))
    assert not unexpected, (
        f"string literals naming a law outside its module: {unexpected}; iterate over "
        "models.registry.laws() or read a law attribute instead")
    stale = sorted(set(ALLOWED) - hits)
    assert not stale, f"allow-list entries that no longer occur (remove them): {stale}"


def test_the_source_check_sees_a_literal(tmp_path):
    # the walker itself: a module spelling a law's name is caught, other strings are not
    for pkg in ("models", "inference", "data", "workflows"):
        (tmp_path / pkg).mkdir()
    (tmp_path / "workflows" / "bad.py").write_text(
        'LAW = "jkr"\nif x == "dmt":\n    y = "jkr adhesion"\n')
    assert _literals({"jkr", "dmt", "hertz"}, tmp_path) == {("workflows.bad", "jkr"),
                                                             ("workflows.bad", "dmt")}


# ----------------------------------------------------------- laws under new names


@pytest.fixture
def renamed():
    """Copies of the tension pair, of Hertz (costly) and of the power law under new names."""
    made = [dataclasses.replace(viscoelastic.LAW, name="kv_test"),
            dataclasses.replace(viscoelastic.SPLIT_LAW, name="kv_test_split"),
            dataclasses.replace(hertz.LAW, name="hertz_costly_test",
                                sampler=dataclasses.replace(hertz.LAW.sampler, cost=10.0)),
            dataclasses.replace(powerlaw.LAW, name="exponent_test",
                                presentation=dataclasses.replace(powerlaw.LAW.presentation,
                                                                 label="exponent test"))]
    for law in made:
        register(law)
    yield {law.name: law for law in made}
    for law in made:
        unregister(law.name)


def test_tension_pair_is_found_by_role(renamed):
    assert tension_pair() == ("viscoelastic", "viscoelastic_split")  # registry order
    assert tension_pair(["hertz", "kv_test_split", "kv_test"]) == ("kv_test", "kv_test_split")
    assert tension_pair(["hertz", "kv_test"]) is None  # no split partner among the names
    assert tension_pair(["viscoelastic_split"]) is None


def test_tension_jobs_fit_the_pair_they_are_given(renamed):
    from beadrod.workflows.config import DEFAULTS
    from beadrod.workflows.pipeline import outputs

    jobs = outputs.tension_jobs(DEFAULTS, Path("/nonexistent"), "backbone",
                                        "normal", ("kv_test", "kv_test_split"))
    keys = [j.key for j in jobs]
    assert keys == ["tension:eta_q", "tension:kv_test", "tension:kv_test_split",
                    "tension:eta_shift:paper_eq25"]
    fits = {j.key: j.spec for j in jobs if j.kind == "fit"}
    assert fits["tension:kv_test"].law == "kv_test"
    assert fits["tension:kv_test_split"].law == "kv_test_split"
    assert {j.spec["law"] for j in jobs if j.kind == "eta"} == {"kv_test"}


def test_job_order_follows_the_laws_cost(renamed):
    from beadrod.workflows.pipeline.fits import comparison_specs, job_order
    from beadrod.workflows.pipeline.parallel import Job

    specs = comparison_specs(["hertz", "jkr", "baseline", "hertz_costly_test",
                              "viscoelastic"], "backbone", "normal")
    jobs = [Job(n, "fit", n, s, {}) for n, s in specs.items()]
    jobs.append(Job("tension:eta_q", "eta", "eta_q", {"law": "viscoelastic"}, {}))
    order = [j.key for j in sorted(jobs, key=job_order)]
    # cost 10 > JKR's > the baseline's > Hertz's > the viscoelastic law's; draws last
    assert order == ["hertz_costly_test", "jkr", "baseline", "hertz", "viscoelastic",
                     "tension:eta_q"]


def test_nominal_parameters_say_where_each_value_comes_from():
    from beadrod.models.law import Param, Prior
    from beadrod.models.nominal import nominal_parameters

    law = dataclasses.replace(hertz.LAW, name="nominal_test", params=(
        hertz.LAW.params[0],
        Param("a", "-", "a", Prior("loguniform", 1.0, 100.0), "test"),
        Param("b", "-", "b", Prior("uniform", 2.0, 4.0), "test", scene_key="viscosity"),
        Param("c", "-", "c", Prior("halfnormal", 2.0), "test")))
    theta, src = nominal_parameters(law, {"young": 2e11, "viscosity": None}, {"c": 5.0})
    # LogUniform(1, 100): median sqrt(1 * 100); a scene key with no value: the prior median
    assert theta == pytest.approx({"young": 2e11, "a": 10.0, "b": 3.0, "c": 5.0})
    assert src == {"young": "scene (young)", "a": "prior median", "b": "prior median",
                   "c": "given"}
    theta, src = nominal_parameters(law, {"young": 2e11, "viscosity": 3.5})
    # HalfNormal(s): median s * sqrt(2) erfinv(1/2) = 0.67449 s
    assert theta["b"] == 3.5 and src["b"] == "scene (viscosity)"
    assert theta["c"] == pytest.approx(2.0 * 0.6744897501960817, rel=1e-12)


def test_theory_curves_and_f0_ranges_iterate_over_the_laws(renamed):
    """The nominal curves and f0 ranges come from each law's object: a power law at its
    prior median n = 2 has a tangent stiffness linear in delta, whose first-order average
    over a cycle that keeps contact (x <= 1) is K0 exactly (no shift); Hertz's f0 is
    sqrt(1.5 F0 / (m delta0)) / (2 pi) with delta0 = (3 F0 / (4 E* sqrt R))^(2/3)."""
    import jax

    from beadrod.models.scene import builtin_scene
    from beadrod.workflows.figures.comparison import exponent_law, f0_ranges, theory_curves

    scene = builtin_scene("paper")
    x = np.linspace(1e-3, 1.3, 27)
    with jax.enable_x64(True):
        curves = theory_curves(scene, x, [renamed["exponent_test"], hertz.LAW,
                                          viscoelastic.LAW])
        ranges = f0_ranges(scene, [hertz.LAW, renamed["exponent_test"]])
    fo = curves["exponent test, first order (nominal)"].y
    assert np.max(np.abs(fo[x <= 1.0])) < 1e-12 and fo[-1] > 0
    assert "exponent test, exact backbone (nominal)" in curves
    # the viscoelastic law's conservative rungs are Hertz's: one label each; its Eq. 25
    # (with damping) differs from its first order and is drawn, Hertz's (= its first
    # order) is not
    assert "Hertz, exact backbone (nominal)\n= viscoelastic" in curves
    assert "viscoelastic, paper Eq. 25 (nominal)" in curves
    assert not any(k.startswith("Hertz, paper Eq. 25") for k in curves)
    (label, (lo, hi)), = ranges.items()  # the power law's f0 does not depend on E: no band
    assert label == "Hertz"
    m, load, r = scene.mass, scene.load, scene.radius
    want = []
    for e in scene.young_range:
        e_star = e / (2 * (1 - scene.bead_material.poisson ** 2))
        d0 = (3 * load / (4 * e_star * math.sqrt(r))) ** (2 / 3)
        want.append(math.sqrt(1.5 * load / (m * d0)) / (2 * math.pi))
    assert (lo, hi) == pytest.approx(tuple(sorted(want)), rel=1e-9)
    assert exponent_law(["hertz", "exponent_test"]).name == "exponent_test"
    assert exponent_law(["hertz"]).name == "powerlaw"  # the first registered law with n
