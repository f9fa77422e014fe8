"""``beadrod simulate --world NAME --out DIR --seed S``: write a synthetic dataset.

The embedded folders under data/ are regenerated bit for bit by this command with
the seed recorded in data/README.md. The command is ``beadrod.simulate`` with ``out``
(workflows.api.simulate).
"""

from __future__ import annotations

import argparse
import tomllib
from typing import Any

__all__ = ["register"]


def _parameter(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` with VALUE a TOML value: 1.6, 20, [20, 100]."""
    key, sep, value = text.partition("=")
    try:
        if not sep or not key.strip():
            raise ValueError
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except (ValueError, tomllib.TOMLDecodeError):
        raise argparse.ArgumentTypeError(
            f"--set takes KEY=VALUE with a number or a list such as [20, 100], got {text!r}"
        ) from None
    return key.strip(), parsed


def _run(args: argparse.Namespace) -> int:
    from beadrod.workflows import api

    ds = api.simulate(args.world, seed=args.seed, out=args.out, force=args.force,
                      **dict(args.set or []))
    print(f"world {args.world!r} (seed {ds.truth['seed']}) written to {ds.path}")
    return 0


def register(sub) -> None:
    # the world list lives in data.synth, which imports pandas: read it when run, not here
    p = sub.add_parser(
        "simulate",
        help="generate a synthetic dataset with a recorded ground truth",
        description="Generate a synthetic world and write it as a dataset folder "
        "(measurements.csv, scene.toml, truth.json): paper_like (a phenomenological "
        "stand-in for the paper's protocols), hertz_dynamics (harmonic-balance sweeps of a "
        "damped Hertz contact), ... (a wrong name lists them all)",
    )
    p.add_argument("--world", default="paper_like",
                   help="which synthetic world (default: %(default)s)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--seed", type=int, default=None,
                   help="random seed (default: the embedded folders' seed, data.synth."
                   "DEFAULT_SEED)")
    p.add_argument("--set", action="append", type=_parameter, metavar="KEY=VALUE",
                   help="replace a world parameter, e.g. --set exponent=1.6 --set "
                   "q_range=[20,100] for the hysteretic world (an unknown key lists them)")
    p.add_argument("--force", action="store_true", help="replace the files of a dataset an earlier "
                   "'beadrod simulate' wrote there (never a file beadrod did not write)")
    p.set_defaults(func=_run)
