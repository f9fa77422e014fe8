"""``beadrod bench {physics,accuracy,inference,device}``: measured speed and accuracy tables.

Benchmarks are not timed tests: each writes what it measured (compile time
apart from run time) to a CSV and a Markdown table in the output folder.
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

__all__ = ["register", "BENCHES"]

BENCHES: dict[str, str] = {
    "physics": "workflows.bench_physics",
    "accuracy": "workflows.bench_accuracy",
    "inference": "workflows.bench_inference",
    "device": "workflows.bench_device",
}


def _run(args: argparse.Namespace) -> int:
    from .cli import host_devices

    host_devices(4)  # parallel chains: must precede anything that starts the JAX backend
    import jax

    # compile times are part of what a benchmark reports: no persistent cache here
    jax.config.update("jax_compilation_cache_dir", None)
    from inference.sample import configure

    configure(4)
    module = importlib.import_module(BENCHES[args.which])
    kw = {}
    if args.laws:
        if args.which != "device":
            from .cli import UserError

            raise UserError("--laws applies to 'beadrod bench device' only")
        kw["laws"] = [w.strip() for w in args.laws.split(",") if w.strip()]
    md = module.run(Path(args.out), quick=args.quick, **kw)
    if not args.quiet:
        print(Path(md).read_text())
        print(f"written: {md}")
    return 0


def register(sub) -> None:
    p = sub.add_parser(
        "bench",
        help="measure speed and accuracy (physics, accuracy ladder, inference, device)",
        description="Run a benchmark and write its results table (CSV + Markdown).",
    )
    p.add_argument("which", choices=sorted(BENCHES), help="which benchmark to run")
    p.add_argument("--out", default="bench-results", help="output folder (default: %(default)s)")
    p.add_argument("--quick", action="store_true",
                   help="tiny counts (smoke run; numbers not meaningful)")
    p.add_argument("--quiet", action="store_true", help="do not print the table")
    p.add_argument("--laws", default=None,
                   help="device only: comma-separated laws for the NUTS rows (default: all)")
    p.set_defaults(func=_run)
