"""``beadrod simulate --world NAME --out DIR --seed S``: write a synthetic dataset.

The embedded folders under data/ are regenerated bit for bit by this command with
the seed recorded in data/README.md.
"""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["register"]


def _run(args: argparse.Namespace) -> int:
    from data.load import MEASUREMENTS
    from data.synth import write_world
    from workflows.cli import UserError

    out = Path(args.out)
    if (out / MEASUREMENTS).exists() and not args.force:
        raise UserError(f"{out / MEASUREMENTS} exists; use --force to overwrite")
    folder = write_world(args.world, out, seed=args.seed)
    print(f"world {args.world!r} (seed {args.seed}) written to {folder}")
    return 0


def register(sub) -> None:
    from data.synth import DEFAULT_SEED, WORLDS

    p = sub.add_parser(
        "simulate",
        help="generate a synthetic dataset with a recorded ground truth",
        description="Generate a synthetic world and write it as a dataset folder "
        "(measurements.csv, scene.toml, truth.json). Worlds: "
        + "; ".join(f"{k}: {v}" for k, v in WORLDS.items()),
    )
    p.add_argument("--world", choices=sorted(WORLDS), default="paper_like",
                   help="which synthetic world (default: %(default)s)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--seed", type=int, default=DEFAULT_SEED,
                   help="random seed (default: %(default)s, the embedded folders' seed)")
    p.add_argument("--force", action="store_true", help="overwrite an existing dataset")
    p.set_defaults(func=_run)
