"""The README stays a user's guide, and docstrings say what the code does and why.

Timings and history belong in docs/performance.md and in git: the README is at most
``README_MAX_LINES`` lines, and neither it nor any docstring of the project's modules
names a commit of this repository or quotes a speed figure. Docstrings are collected
with ast (nothing is imported): those of modules, classes and functions, and the string
statements that document an assignment.
"""

from __future__ import annotations

import ast
import functools
import re
import shutil
import subprocess
from collections.abc import Iterable, Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("models", "data", "inference", "workflows", "beadrod")
README = ROOT / "README.md"
README_MAX_LINES = 150

# a token that may be an abbreviated commit hash: git abbreviates to 7 or more hex digits
_HEX_TOKEN = re.compile(r"(?<![0-9A-Za-z_])[0-9a-fA-F]{7,40}(?![0-9A-Za-z_])")

# A speed figure: a number with a unit of computing time (µs, us, ns, ms), seconds in the
# company of what a measurement of the code says ("s per step", "s on one core", "s
# cold"), a before -> after pair, an ESS per second, or a factor faster or slower.
# Seconds as a physical unit stay allowed: "[s]", "tau = 0.5 s", "Pa s", Hz.
_NUMBER = r"\d+(?:\.\d+)?(?:e-?\d+)?"
_SPEED = re.compile(
    "|".join((
        rf"{_NUMBER}\s*(?:µs|μs|us|ns|ms)\b",
        rf"{_NUMBER}\s*s\s+(?:per|a|an)\s+(?:step|call|point|draw|fit|run|chain|program)",
        rf"{_NUMBER}\s*s\s+(?:on\s+(?:one|a|\d+)\s+(?:core|cpu|gpu)|cold|warm|wall)",
        rf"{_NUMBER}\s*s\s+(?:of|to)\s+(?:compil|trac|warm-?up)",
        rf"{_NUMBER}\s*(?:->|→)\s*{_NUMBER}\s*(?:s|µs|μs|us|ms)\b",
        rf"{_NUMBER}\s*(?:bulk\s+|tail\s+)?ESS\s*(?:/\s*s\b|per second)",
        rf"\bESS\s*(?:/\s*s|per second)\s*(?:of\s+|=\s*|:\s*|~\s*)?{_NUMBER}",
        rf"{_NUMBER}\s*(?:x|×|times)\s+(?:faster|slower|quicker|the speed)",
        rf"\bspeed-?ups?\s+of\s+{_NUMBER}",
        rf"\b(?:faster|slower)\s+by\s+(?:a\s+factor\s+(?:of\s+)?)?{_NUMBER}",
    )),
    re.IGNORECASE,
)


def repo_commits(root: Path = ROOT) -> list[str]:
    """Every commit of the git checkout at ``root`` (full hashes, lower case).

    Skips the calling test where there is no git or ``root`` is no checkout (an sdist)."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed: no commit list to check hashes against")
    res = subprocess.run(["git", "-C", str(root), "rev-list", "--all"],
                         capture_output=True, text=True, check=False)
    if res.returncode != 0 or not res.stdout.strip():
        pytest.skip(f"{root} is not a git checkout with commits: no hashes to check against")
    return [line.strip().lower() for line in res.stdout.split()]


def commit_hashes_in(text: str, commits: Iterable[str]) -> list[str]:
    """The tokens of ``text`` (7-40 hex digits) that abbreviate one of ``commits``."""
    commits = [c.lower() for c in commits]
    found = []
    for m in _HEX_TOKEN.finditer(text):
        token = m.group(0).lower()
        if any(c.startswith(token) for c in commits):
            found.append(m.group(0))
    return found


def speed_figures_in(text: str) -> list[str]:
    """The phrases of ``text`` that quote a speed figure of the code (see ``_SPEED``)."""
    return [m.group(0) for m in _SPEED.finditer(" ".join(text.split()))]


def docstrings(path: Path) -> Iterator[tuple[int, str]]:
    """(line, text) of each docstring in the module at ``path``: of the module, its classes
    and functions, and a string statement right after an assignment (an attribute's)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if not isinstance(body, list) or not body:
            continue
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            doc = ast.get_docstring(node, clean=False)
            if doc:
                yield body[0].lineno, doc
        for prev, stmt in zip(body, body[1:]):
            if (isinstance(prev, (ast.Assign, ast.AnnAssign)) and isinstance(stmt, ast.Expr)
                    and isinstance(stmt.value, ast.Constant)
                    and isinstance(stmt.value.value, str)):
                yield stmt.lineno, stmt.value.value


def project_modules() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


@functools.cache
def _all_docstrings() -> tuple[tuple[str, int, str], ...]:
    """(module path, line, text) of every docstring of the project's modules."""
    return tuple((str(path.relative_to(ROOT)), line, text)
                 for path in project_modules() for line, text in docstrings(path))


# --- the detectors ---------------------------------------------------------------------


def test_hash_detector_flags_a_planted_hash():
    commits = ["0123456789abcdef0123456789abcdef01234567", "fedcba9876543210fedcba9876543210fedcba98"]
    text = "Fixed in 0123456 (see FEDCBA98765); 1234567 and deadbeef are no commits."
    assert commit_hashes_in(text, commits) == ["0123456", "FEDCBA98765"]
    # shorter than git's abbreviation, or glued to other word characters: no hash
    assert commit_hashes_in("012345 x0123456 0123456_", commits) == []


def test_hash_detector_flags_a_real_commit_of_this_repository():
    commit = repo_commits()[0]
    doc = f'"""Shape tables (replaced in {commit[:9]})."""\n'
    assert commit_hashes_in(doc, repo_commits()) == [commit[:9]]


@pytest.mark.parametrize("text", [
    "a NUTS step 22.6 us against Hertz's 9.6",
    "(about 0.2 µs per point with gradient)",
    "the fold: 110 -> 75 us for 454 points",
    "JKR's shape probe 3.9 -> 3.2 s",
    "ESS/s 0.45-0.67 of Hertz's",
    "1200 ESS per second on the embedded data",
    "compiles in 2.5 s per program",
    "the probe: 0.6 s cold, 0.2 s warm",
    "a warm call takes 1.7 s on one core",
    "runs 6x faster than the loop",
    "the table is 30 times slower to build",
    "a compile of 12 ms",
])
def test_speed_detector_flags_timings(text: str):
    assert speed_figures_in(text), text


@pytest.mark.parametrize("text", [
    "t [s] the time, f [Hz] the frequency",
    "viscosity eta [Pa s] of the layer; relaxation time tau = 0.5 s",
    "a sweep at 10 Hz steps of 2 s each way",
    "the solver stops after 600 s of waiting for a worker",
    "speed of sound c0 [m/s] of the rod, 5000 m/s",
    "the tolerance 1e-9 (a 2x margin on the error bound)",
    "The inference benchmark: ESS per second of each law, sampled with 2 chains.",
    "4 chains x 400 draws: smallest bulk ESS, ESS per second",
])
def test_speed_detector_allows_physical_units(text: str):
    assert not speed_figures_in(text), speed_figures_in(text)


def test_docstrings_are_collected_from_every_kind_of_node(tmp_path: Path):
    src = tmp_path / "m.py"
    src.write_text('"""mod."""\nX = 1\n"""attr."""\n\nclass C:\n    """cls."""\n\n'
                   '    def f(self):\n        """fun."""\n', encoding="utf-8")
    assert [t for _, t in docstrings(src)] == ["mod.", "attr.", "cls.", "fun."]


# --- the tree --------------------------------------------------------------------------


def test_readme_is_short():
    n = len(README.read_text(encoding="utf-8").splitlines())
    assert n <= README_MAX_LINES, (
        f"README.md has {n} lines (at most {README_MAX_LINES}): timings go to "
        "docs/performance.md, results to docs/results.md")


def test_no_commit_hash_in_readme_or_docstrings():
    commits = repo_commits()
    found = [f"README.md: {h}" for h in commit_hashes_in(README.read_text(encoding="utf-8"),
                                                         commits)]
    for where, line, text in _all_docstrings():
        found += [f"{where}:{line}: {h}" for h in commit_hashes_in(text, commits)]
    assert not found, "commit hashes (history lives in git):\n" + "\n".join(found)


def test_no_speed_figure_in_docstrings():
    assert project_modules(), "no modules found: is ROOT the repository?"
    found = [f"{where}:{line}: {s!r}" for where, line, text in _all_docstrings()
             for s in speed_figures_in(text)]
    assert not found, ("speed figures in docstrings (they go to docs/performance.md):\n"
                       + "\n".join(found))
