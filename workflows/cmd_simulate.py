"""``beadrod simulate --world NAME --out DIR --seed S``: write a synthetic dataset.

The embedded folders under data/ are regenerated bit for bit by this command with
the seed recorded in data/README.md.
"""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["register"]


def _run(args: argparse.Namespace) -> int:
    from beadrod.data.load import MEASUREMENTS, SCENE, TRUTH
    from beadrod.data.synth import DEFAULT_SEED, WORLDS, write_world

    from .outdir import check_out
    from .runtime import UserError

    if args.world not in WORLDS:
        raise UserError(f"unknown world '{args.world}'; choose from: "
                        + "; ".join(f"{k} ({v})" for k, v in WORLDS.items()))
    seed = DEFAULT_SEED if args.seed is None else args.seed
    if not 0 <= seed < 2**32:
        raise UserError(f"--seed must be an integer in [0, 2**32 - 1], got {seed}")
    out = Path(args.out)
    check_out(out, force=args.force, outputs=(MEASUREMENTS, SCENE, TRUTH),
              command="simulate")
    folder = write_world(args.world, out, seed=seed)
    print(f"world {args.world!r} (seed {seed}) written to {folder}")
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
    p.add_argument("--force", action="store_true", help="replace the files of a dataset an earlier "
                   "'beadrod simulate' wrote there (never a file beadrod did not write)")
    p.set_defaults(func=_run)
