"""beadrod installs under one import name: a user's own data/ or models/ folder next to a
notebook never shadows it, and nothing is importable as a bare ``models``, ``data``,
``inference`` or ``workflows``."""

from __future__ import annotations

import ast
import subprocess
import sys
import sysconfig
import zipfile
from importlib.metadata import entry_points
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("models", "data", "inference", "workflows")
# what a notebook next to a user's own data/ and models/ folders runs
PROBE = ("import beadrod.data, beadrod.models, beadrod.workflows.cli as cli; "
         "from beadrod.data import load_dataset; from beadrod.models.laws import hertz; "
         "import beadrod; print(beadrod.__file__); print(beadrod.data.__file__)")


def _bare_imports(path: Path) -> list[tuple[int, str]]:
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                 else [node.module or ""] if isinstance(node, ast.ImportFrom)
                 and not node.level else [])
        out += [(node.lineno, n) for n in names if n.split(".")[0] in PACKAGES]
    return out


def test_no_bare_import_of_the_four_packages():
    """A module loaded as both ``models.x`` and ``beadrod.models.x`` would be two modules
    (two registries, two caches): every import names ``beadrod.``."""
    found = [f"{p.relative_to(ROOT)}:{line}: {name}"
             for d in (*PACKAGES, "tests", "beadrod") for p in sorted((ROOT / d).rglob("*.py"))
             for line, name in _bare_imports(p)]
    assert not found, "bare imports (use beadrod.NAME):\n" + "\n".join(found)


def test_the_check_sees_a_bare_import(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("import data\nfrom models.law import x\nfrom beadrod.data import y\n"
                 "from . import z\nimport datasets\n")
    assert _bare_imports(f) == [(1, "data"), (2, "models.law")]


def test_console_script_points_into_beadrod():
    (ep,) = entry_points(group="console_scripts", name="beadrod")
    assert ep.value == "beadrod.workflows.cli:main"


def _user_folder(tmp_path: Path, with_init: bool) -> Path:
    user = tmp_path / ("with_init" if with_init else "plain")
    for name in ("data", "models"):
        (user / name).mkdir(parents=True)
        (user / name / "measurements.csv").write_text("my,own\n1,2\n")
        if with_init:
            (user / name / "__init__.py").write_text("raise ImportError('the user folder')\n")
    return user


@pytest.mark.parametrize("with_init", [False, True])
def test_import_next_to_a_users_data_and_models_folders(tmp_path, with_init):
    user = _user_folder(tmp_path, with_init)
    r = subprocess.run([sys.executable, "-c", PROBE], cwd=user, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert str(user) not in r.stdout


def test_bare_names_are_not_importable_after_install(tmp_path):
    for name in PACKAGES:
        r = subprocess.run([sys.executable, "-c", f"import {name}"], cwd=tmp_path,
                           capture_output=True, text=True, timeout=60)
        assert r.returncode != 0 and "ModuleNotFoundError" in r.stderr, name


def test_a_built_wheel_imports_next_to_a_users_folders(tmp_path):
    """``pip install .``: the wheel holds beadrod/models, ... and nothing at the top level
    but beadrod; imported from it (site's .pth files, the editable finder among them, off)
    next to a user's data/ and models/ folders."""
    wheels = tmp_path / "wheels"
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w",
                        str(wheels), str(ROOT)], capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        pytest.skip(f"no wheel could be built here (pip wheel: {r.stderr.strip()[-200:]})")
    (wheel,) = wheels.glob("beadrod-*.whl")
    site = tmp_path / "site"
    with zipfile.ZipFile(wheel) as z:
        tops = {n.split("/")[0] for n in z.namelist() if not n.split("/")[0].endswith(
            (".dist-info", ".data"))}
        z.extractall(site)
    assert tops == {"beadrod"}
    assert (site / "beadrod" / "models" / "scene" / "presets" / "paper.toml").is_file()
    # every stored table travels with the package, a law folder's own ones too
    stored = {p.relative_to(ROOT) for p in (ROOT / "models").rglob("*.npz")}
    assert stored and all((site / "beadrod" / p).is_file() for p in stored), stored
    assert (site / "beadrod" / "data" / "paper_like" / "measurements.csv").is_file()
    deps = sysconfig.get_paths()["purelib"]
    code = f"import sys; sys.path[:0] = [{str(site)!r}, {deps!r}]; " + PROBE
    for with_init in (False, True):
        user = _user_folder(tmp_path, with_init)
        r = subprocess.run([sys.executable, "-S", "-c", code], cwd=user, capture_output=True,
                           text=True, timeout=120)
        assert r.returncode == 0, r.stderr
        assert r.stdout.splitlines()[0].startswith(str(site)), r.stdout
