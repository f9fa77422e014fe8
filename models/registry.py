"""The one registry of contact laws and of rungs.

Every consumer (inference, the comparison, ``beadrod laws/shift/scene``, the figures, the
report, the tests) iterates over :func:`laws`; nothing outside a law's own module
branches on its name. A law is a :class:`models.law.ContactLaw` defined in its module
(``LAW``) and listed once, in :data:`beadrod.models.laws.BUILTIN`; laws a user writes in a
file are added at run time by :func:`register`.

Rungs (:data:`RUNGS`, one spelling everywhere) are the levels of the accuracy ladder;
:data:`FIT_RUNGS` are those a sampler can afford for every law that has them.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

from beadrod.models.law import ContactLaw, RungUnavailable
from beadrod.models.laws import BUILTIN
from beadrod.models.rungs import DEFAULT_RUNG, FIT_RUNGS, RUNGS, check_rung

__all__ = ["RUNGS", "FIT_RUNGS", "DEFAULT_RUNG", "laws", "law_names", "get_law", "register",
           "unregister", "tension_pair", "check_rung", "ContactLaw", "RungUnavailable"]

_LAWS: dict[str, ContactLaw] = {law.name: law for law in BUILTIN}


def laws() -> tuple[ContactLaw, ...]:
    """Every registered law, built-in first, in registration order."""
    return tuple(_LAWS.values())


def law_names() -> list[str]:
    return list(_LAWS)


def get_law(name: str) -> ContactLaw:
    try:
        return _LAWS[name]
    except KeyError:
        close = difflib.get_close_matches(name, list(_LAWS), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise ValueError(f"unknown contact law '{name}'{hint}; choose from "
                         f"{list(_LAWS)}") from None


def tension_pair(names: Iterable[str] | None = None) -> tuple[str, str] | None:
    """(shared, split): the names of the laws behind the Q-versus-shift tension, the
    first registered law whose ``presentation.tension_role`` is 'shared' and the first
    'split' law with the same ``tension_param``, both among ``names`` (default: every law);
    None if ``names`` lack either."""
    wanted = None if names is None else set(names)
    pool = [law for law in laws() if wanted is None or law.name in wanted]
    for shared in (law for law in pool if law.presentation.tension_role == "shared"):
        param = shared.presentation.tension_param
        split = next((law for law in pool if law.presentation.tension_role == "split"
                      and law.presentation.tension_param == param), None)
        if split is not None and param is not None:
            return shared.name, split.name
    return None


def register(law: ContactLaw, *, replace: bool = False) -> ContactLaw:
    """Add ``law`` (e.g. one loaded from a user's file); its name must be new."""
    if law.name in _LAWS and not replace and _LAWS[law.name] is not law:
        raise ValueError(f"a contact law named '{law.name}' exists already "
                         f"({_LAWS[law.name].source}); choose another NAME")
    _LAWS[law.name] = law
    return law


def unregister(name: str) -> None:
    """Remove a law added by :func:`register` (built-in laws stay)."""
    if any(b.name == name for b in BUILTIN):
        raise ValueError(f"'{name}' is a built-in law")
    _LAWS.pop(name, None)
