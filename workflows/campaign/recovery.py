"""The grid of a recovery campaign: a TOML file of synthetic worlds.

::

    laws = ["hertz", "powerlaw", "baseline"]   # the laws every world is compared with
                                               # (optional; --laws wins)
    [[world]]
    world = "hertz_dynamics"   # a world of `beadrod simulate` (data.synth.WORLDS)
    law = "hertz"              # the law that generated it: the confusion table's row
    seeds = [1, 2, 3]          # one task per seed

    [[world]]
    world = "hysteretic"
    law = "hertz_hysteretic"
    seeds = [1, 2]
    set = { exponent = [1.6, 2.0, 2.6], strength = 0.03, noise_f_Hz = [1.0, 4.0] }

Each world is made by data.synth.write_world, the code of ``beadrod simulate --world W
--seed S --set KEY=VALUE``. ``set`` (optional) replaces the world's parameters
(data.synth.world_parameters: truths such as a strength or an exponent, noise levels,
counts, ranges). A value of the parameter's own kind sets it; a **list** of such values
is a grid axis: the entry expands into every combination of its axes, each run at every
seed (above: 3 exponents x 2 noise levels x 2 seeds = 12 comparisons). A parameter that
is itself a range [low, high] takes ``[2500.0, 2800.0]`` as one value and a list of
ranges, ``[[2500.0, 2800.0], [2800.0, 3100.0]]``, as an axis. Every point is checked as
``beadrod simulate`` checks it (data.synth.check_overrides) before anything runs; an error
names the grid file, the entry and the parameter.

The world's truth.json records its parameters and overrides; where the world's own module
says which law parameter one of its parameters is (data.worlds_loss.LAW_PARAMETERS), that
value is the truth the coverage of the law's interval is measured against.
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

__all__ = ["read_grid", "expand_set"]

_KEYS = ("world", "law", "seeds", "set")


def _is_axis(default: Any, value: Any) -> bool:
    # a list is an axis of the grid, but for a list-valued parameter (a range) only a
    # list of lists is
    if not isinstance(value, list):
        return False
    if isinstance(default, list):
        return bool(value) and all(isinstance(v, list) for v in value)
    return True


def expand_set(world: str, values: dict[str, Any], where: str) -> list[dict[str, Any]]:
    """The override points of one grid entry's ``set`` table: the product of its axes
    (lists; module docstring), each point checked by data.synth.check_overrides.
    ``where`` starts an error's message (the grid file and entry)."""
    from beadrod.data.synth import WorldParameterError, check_overrides, world_parameters
    from beadrod.workflows.runtime import UserError

    if not isinstance(values, dict):
        raise UserError(f"{where}: set must be a table of world parameters, e.g. "
                        "set = { strength = 0.03, exponent = [1.6, 2.0] }")
    defaults = world_parameters(world)
    axes: list[tuple[str, list[Any]]] = []
    for key, value in values.items():
        if key in defaults and _is_axis(defaults[key], value):
            if not value:
                raise UserError(f"{where}: set.{key} is an empty list (a grid axis needs "
                                "at least one value)")
            axes.append((key, list(value)))
        else:
            axes.append((key, [value]))
    points = []
    for combo in itertools.product(*(vals for _, vals in axes)):
        point = dict(zip((k for k, _ in axes), combo))
        try:
            points.append(check_overrides(world, point))
        except WorldParameterError as exc:
            raise UserError(f"{where}: set: {exc}") from None
    return points


def read_grid(path: str | Path) -> dict[str, Any]:
    """``{"laws": [...] | None, "worlds": [{"world", "law", "seeds", "overrides"}, ...]}``
    from the TOML grid at ``path``, one item per override point of each entry (its
    ``set`` expanded; ``overrides`` {} without one); an error names the entry and key."""
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
    seen: dict[tuple, int] = {}
    for i, w in enumerate(entries, 1):
        where = f"{path}: [[world]] entry {i}"
        extra = sorted(set(w) - set(_KEYS))
        if extra:
            raise UserError(f"{where}: unknown key(s) {extra} ({', '.join(_KEYS)})")
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
        points: dict[str, dict[str, Any]] = {}  # a repeated point of one entry once
        for point in expand_set(w["world"], w.get("set", {}), where):
            points.setdefault(repr(sorted(point.items())), point)
        for ident, point in points.items():
            for s in seeds:
                j = seen.setdefault((w["world"], ident, s), i)
                if j != i:
                    raise UserError(f"{where}: world {w['world']!r} with overrides "
                                    f"{point} at seed {s} is in entry {j} too")
            worlds.append({"world": w["world"], "law": w["law"], "seeds": sorted(set(seeds)),
                           "overrides": point})
    laws = doc.get("laws")
    if laws is not None and not (isinstance(laws, list) and all(isinstance(x, str)
                                                                for x in laws)):
        raise UserError(f"{path}: laws must be a list of law names")
    return {"laws": laws, "worlds": worlds}
