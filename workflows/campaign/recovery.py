"""The grid of a recovery campaign: a TOML file of synthetic worlds.

::

    laws = ["hertz", "powerlaw", "baseline"]   # the laws every world is compared with
                                               # (optional; --laws wins)
    [[world]]
    world = "hertz_dynamics"   # a world of `beadrod simulate` (data.synth.WORLDS)
    law = "hertz"              # the law that generated it: the confusion table's row
    seeds = [1, 2, 3]          # one task per seed

Each world is made by data.synth.write_world, the code of ``beadrod simulate --world W
--seed S``. The worlds fix their own truths and noise levels (data/README.md): a grid
varies the world and its seed; a truth or noise level of its own needs a world that
takes one.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["read_grid"]


def read_grid(path: str | Path) -> dict[str, Any]:
    """``{"laws": [...] | None, "worlds": [{"world", "law", "seeds"}, ...]}`` from the
    TOML grid at ``path``; an error names the entry and key."""
    import tomllib

    from beadrod.data.synth import WORLDS
    from beadrod.workflows.pipeline.fits import model_names
    from beadrod.workflows.runtime import UserError

    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UserError(f"cannot read the grid {path}: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"{path}: not valid TOML: {exc}") from None
    unknown = sorted(set(doc) - {"laws", "world"})
    if unknown:
        raise UserError(f"{path}: unknown key(s) {unknown}; a grid has 'laws' and "
                        "[[world]] entries")
    entries = doc.get("world")
    if not isinstance(entries, list) or not entries:
        raise UserError(f"{path}: no [[world]] entry")
    known = model_names()
    worlds = []
    for i, w in enumerate(entries, 1):
        where = f"{path}: [[world]] entry {i}"
        extra = sorted(set(w) - {"world", "law", "seeds"})
        if extra:
            raise UserError(f"{where}: unknown key(s) {extra} (world, law, seeds)")
        if w.get("world") not in WORLDS:
            raise UserError(f"{where}: world = {w.get('world')!r} is not one of "
                            f"{', '.join(WORLDS)}")
        if w.get("law") not in known:
            raise UserError(f"{where}: law = {w.get('law')!r} is not one of "
                            f"{', '.join(known)}")
        seeds = w.get("seeds")
        if not (isinstance(seeds, list) and seeds and all(
                isinstance(s, int) and not isinstance(s, bool) and 0 <= s < 2**32
                for s in seeds)):
            raise UserError(f"{where}: seeds must be a non-empty list of integers in "
                            "[0, 2**32 - 1]")
        worlds.append({"world": w["world"], "law": w["law"], "seeds": sorted(set(seeds))})
    laws = doc.get("laws")
    if laws is not None and not (isinstance(laws, list) and all(isinstance(x, str)
                                                                for x in laws)):
        raise UserError(f"{path}: laws must be a list of law names")
    return {"laws": laws, "worlds": worlds}
