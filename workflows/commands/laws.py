"""``beadrod laws [--json]``: every contact law with its parameters, rungs and source."""

from __future__ import annotations

import argparse
import json

from beadrod.workflows import lawfiles

__all__ = ["register", "describe_laws"]


def describe_laws(paths: list[str]) -> list[dict]:
    """Descriptions of every registered law (built in, then the law files ``paths``):
    ``beadrod laws`` prints them, ``beadrod.laws()`` (workflows.api) tabulates them."""
    from beadrod.models import registry

    lawfiles.load(paths)
    return [law.describe() for law in registry.laws()]


def _text(rows: list[dict]) -> str:
    out = []
    for r in rows:
        src = "built-in" if r["source"] == "built-in" else r["source"]
        out.append(f"{r['name']}: {r['label']}  [{src}]")
        out.append(f"  rungs: {', '.join(r['rungs'])}"
                   + ("; predicts the linear Q" if r["predicts_q"] else ""))
        out.append(f"  reference: {r['reference']}")
        if r["description"]:
            out.append(f"  {r['description']}")
        for p in r["params"]:
            dom = "" if p["domain_text"] is None else f", defined on {p['domain_text']}"
            if p["bounds"] is not None:
                dom += (f", physically in [{p['bounds'][0]:g}, {p['bounds'][1]:g}] "
                        f"{p['unit']}")
            if p.get("sampled_as"):
                dom += (f"; NUTS moves in {p['sampled_as']} (its value times a scale the "
                        "law sets, the prior unchanged)")
            out.append(f"  - {p['name']} [{p['unit']}]: prior {p['prior']}{dom}")
    return "\n".join(out)


def _run(args: argparse.Namespace) -> int:
    rows = describe_laws(lawfiles.paths_of(args))
    print(json.dumps(rows, indent=2, allow_nan=False) if args.json else _text(rows))
    return 0


def register(sub) -> None:
    p = sub.add_parser("laws", help="list every contact law: parameters, priors, rungs",
                       description=__doc__)
    p.add_argument("--json", action="store_true", help="machine-readable output")
    lawfiles.add_argument(p)
    p.set_defaults(func=_run)
