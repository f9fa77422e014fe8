"""``beadrod bench {physics,accuracy,inference,device}``: measured speed and accuracy tables.

Benchmarks are not timed tests: each writes what it measured (compile time
apart from run time) to a CSV and a Markdown table in the output folder.
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

__all__ = ["register", "BENCHES", "BENCH_EXTRAS", "BENCH_OUTPUTS"]

BENCHES: dict[str, str] = {
    "physics": "beadrod.workflows.bench.physics",
    "accuracy": "beadrod.workflows.bench.accuracy",
    "inference": "beadrod.workflows.bench.inference",
    "device": "beadrod.workflows.bench.device",
}


# the files each benchmark writes into --out ({platform}: JAX's backend, cpu or gpu)
BENCH_OUTPUTS: dict[str, tuple[str, ...]] = {
    "physics": ("bench_physics.csv", "bench_physics.md"),
    "accuracy": ("accuracy.csv", "accuracy.md", "accuracy.png", "accuracy.pdf"),
    "inference": ("bench_inference.csv", "bench_inference.md"),
    "device": ("bench_device_{platform}.csv", "bench_device_{platform}.md"),
}


# what a benchmark needs beyond the main install (the "bench" extra of pyproject.toml)
BENCH_EXTRAS: dict[str, tuple[str, ...]] = {"physics": ("mpmath",), "inference": ("emcee",)}


def _missing_extra(which: str) -> str | None:
    import importlib.util

    return next((m for m in BENCH_EXTRAS.get(which, ()) if importlib.util.find_spec(m) is None),
                None)


def _extra_error(which: str, module: str) -> Exception:
    from beadrod.workflows.runtime import UserError

    return UserError(f"beadrod bench {which} needs {module}, which the main install leaves "
                     "out: pip install -e \".[bench]\"")


def _run(args: argparse.Namespace) -> int:
    from beadrod.workflows.runtime import UserError, host_devices

    if args.laws and args.which != "device":
        raise UserError("--laws applies to 'beadrod bench device' only")
    missing = _missing_extra(args.which)
    if missing:
        raise _extra_error(args.which, missing)
    host_devices(4)  # parallel chains: must precede anything that starts the JAX backend
    import jax

    # compile times are part of what a benchmark reports: no persistent cache here
    jax.config.update("jax_compilation_cache_dir", None)
    from beadrod.workflows.outdir import check_out

    platform = jax.devices()[0].platform
    check_out(Path(args.out), force=args.force, command=f"bench {args.which}",
              outputs=[o.format(platform=platform) for o in BENCH_OUTPUTS[args.which]])
    from beadrod.inference.sampling.sample import configure

    configure(4)
    kw = {}
    if args.laws:
        kw["laws"] = [w.strip() for w in args.laws.split(",") if w.strip()]
    try:
        module = importlib.import_module(BENCHES[args.which])
        md = module.run(Path(args.out), quick=args.quick, **kw)
    except ModuleNotFoundError as exc:  # an extra imported deeper down
        extras = {m for ms in BENCH_EXTRAS.values() for m in ms}
        if exc.name not in extras:
            raise
        raise _extra_error(args.which, exc.name) from None
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
    p.add_argument("--force", action="store_true", help="replace this benchmark's files "
                   "that an earlier 'beadrod bench' wrote into --out (never a file beadrod "
                   "did not write)")
    p.add_argument("--laws", default=None,
                   help="device only: comma-separated laws for the NUTS rows (default: all)")
    p.set_defaults(func=_run)
