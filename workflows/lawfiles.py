"""``--law-file FILE.py``: laws users write themselves, loaded and registered per process.

The contract is :mod:`models.lawfile` (docs/adding-a-law.md). Every command that takes
laws (``laws``, ``shift``, ``fit``, ``compare``, ``rungs``) calls :func:`add_argument` on
its parser and :func:`load` before it validates law names; worker processes call
:func:`load` again with the same paths (the registry is per process).

A law file is Python code that runs when it loads, for every command that is given it
(``beadrod laws`` too), with the user's rights: the option's help and the docs say so.
Here, on top of the models' contract, a file's law may not take the law-free baseline's
name, and its ``LABEL`` must be math text that the figures can draw (models/ does not
plot, so this check lives here).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

__all__ = ["add_argument", "load", "paths_of", "label_problem"]


def add_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--law-file", action="append", default=[], metavar="FILE.py", dest="law_files",
        help="add the contact law that FILE defines (NAME, PRIORS, force(delta, *, ...); "
             "see docs/adding-a-law.md); repeatable. A law file is Python code: it runs "
             "when it loads, for every command, with your rights; use only files from a "
             "source you trust")


def paths_of(args: Any) -> list[str]:
    return [str(Path(p).resolve()) for p in (getattr(args, "law_files", None) or [])]


def label_problem(label: str) -> str | None:
    """Why the figures cannot draw ``label`` (its ``$...$`` math fails matplotlib's mathtext
    parser, or a ``$`` is unmatched), or None."""
    if "$" not in label:  # plain text: no need to import matplotlib (workers load files too)
        return None
    from matplotlib import cbook
    from matplotlib.mathtext import MathTextParser

    dollars = label.count("$") - label.count(r"\$")
    if dollars % 2:
        return r"has an unmatched $ (math goes between two $; write \$ for a dollar sign)"
    if not cbook.is_math_text(label):
        return None
    try:
        MathTextParser("path").parse(label)
    except ValueError as exc:
        lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
        why = lines[-1].split(": ", 1)[-1] if lines else "parse error"
        return f"is not math text the figures can draw (matplotlib mathtext: {why})"
    return None


def load(paths: list[str], scene: Any | None = None) -> list[str]:
    """Load and register each law file (once per process); returns the laws' names.

    ``scene``: the scene whose quantities the contract is checked at (default: the
    paper's). Raises models.lawfile.LawFileError naming the file and what is wrong.
    """
    if not paths:
        return []
    from beadrod.inference.model.likelihood import scene_quantities
    from beadrod.inference.model.numpyro_models import BASELINE
    from beadrod.models import registry
    from beadrod.models.lawfile import LawFileError, load_law_file
    from beadrod.models.scene import builtin_scene

    sq = scene_quantities(scene if scene is not None else builtin_scene("paper"))
    names = []
    for p in paths:
        src = str(Path(p).resolve())
        known = next((law for law in registry.laws() if law.source == src), None)
        if known is None:
            law = load_law_file(src, sq, reserved={BASELINE: "the law-free baseline"})
            why = label_problem(law.presentation.label)
            if why is not None:
                raise LawFileError(f"law file {src}: LABEL {law.presentation.label!r} {why}")
            known = registry.register(law)
        names.append(known.name)
    return names
