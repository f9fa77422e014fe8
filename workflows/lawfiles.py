"""``--law-file FILE.py``: laws users write themselves, loaded and registered per process.

The contract is :mod:`models.lawfile` (docs/adding-a-law.md). Every command that takes
laws (``laws``, ``shift``, ``fit``, ``compare``, ``rungs``) calls :func:`add_argument` on
its parser and :func:`load` before it validates law names; worker processes call
:func:`load` again with the same paths (the registry is per process).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

__all__ = ["add_argument", "load", "paths_of"]


def add_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--law-file", action="append", default=[], metavar="FILE.py", dest="law_files",
        help="add the contact law that FILE defines (NAME, PRIORS, force(delta, *, ...); "
             "see docs/adding-a-law.md); repeatable")


def paths_of(args: Any) -> list[str]:
    return [str(Path(p).resolve()) for p in (getattr(args, "law_files", None) or [])]


def load(paths: list[str], scene: Any | None = None) -> list[str]:
    """Load and register each law file (once per process); returns the laws' names.

    ``scene``: the scene whose quantities the contract is checked at (default: the
    paper's). Raises models.lawfile.LawFileError naming the file and what is wrong.
    """
    if not paths:
        return []
    from inference.likelihood import scene_quantities
    from models import registry
    from models.lawfile import load_law_file
    from models.scenes import builtin_scene

    sq = scene_quantities(scene if scene is not None else builtin_scene("paper"))
    names = []
    for p in paths:
        src = str(Path(p).resolve())
        known = next((law for law in registry.laws() if law.source == src), None)
        if known is None:
            known = registry.register(load_law_file(src, sq))
        names.append(known.name)
    return names
