"""``beadrod campaign {sbc,recovery,datasets}``: many fits or comparisons as tasks on a Dask
cluster (workflows.campaign).

- ``sbc --law L --n N``: N simulation-based-calibration replicates of one law;
- ``recovery --worlds SPEC.toml``: one comparison per synthetic world and seed of a grid;
- ``datasets DIR...``: one comparison per dataset folder.

Each task's record is written to ``OUT/tasks/`` as it finishes; ``OUT/campaign.csv``,
``OUT/summary.md`` and ``OUT/figures/`` are rebuilt from the records. Rerunning the same
command skips the finished tasks whose inputs are unchanged. Exit status: 0 every task
finished, 1 a task FAILED (its record holds the error; the others finished), 2 an error
to fix, 130 interrupted (finished records kept).

Building the parser imports neither Dask nor JAX.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from beadrod.workflows.config import DEFAULTS, RUNGS

__all__ = ["register", "EXIT_TASK_FAILED", "INSTALL_HINT"]

EXIT_TASK_FAILED = 1
INSTALL_HINT = 'pip install "beadrod[campaign]"'


def _need_dask() -> None:
    from beadrod.workflows.runtime import UserError

    try:
        import dask  # noqa: F401
        import distributed  # noqa: F401
    except ImportError as exc:
        raise UserError(f"beadrod campaign runs on Dask, which is not installed ({exc}): "
                        f"{INSTALL_HINT}") from None


def _sampling(args: argparse.Namespace) -> dict[str, Any]:
    return {k: getattr(args, k) for k in ("chains", "warmup", "samples")
            if getattr(args, k) is not None}


def _cfg(args: argparse.Namespace) -> dict[str, Any]:
    # the comparison options of a recovery or datasets campaign, checked as compare's are
    from beadrod.workflows.commands.compare import check_laws
    from beadrod.workflows.config import resolve

    flags: dict[str, Any] = {"seed": args.seed, "rung": args.rung, "sampling": _sampling(args)}
    if args.laws:
        flags["laws"] = [s.strip() for s in args.laws.split(",") if s.strip()]
    cfg = resolve(args.config, flags)
    check_laws(cfg)
    return cfg


def _tasks(args: argparse.Namespace) -> tuple[list[Any], dict[str, Any]]:
    from beadrod.workflows.campaign import tasks as t
    from beadrod.workflows.config import resolve
    from beadrod.workflows.runtime import UserError

    if args.kind == "sbc":
        from beadrod.workflows.pipeline.fits import comparison_specs

        if args.n < 1:
            raise UserError(f"--n must be at least 1, got {args.n}")
        if args.thin < 1:
            raise UserError(f"--thin must be at least 1, got {args.thin}")
        cfg = resolve(None, {"seed": args.seed, "rung": args.rung,
                             "sampling": _sampling(args)})
        try:
            comparison_specs([args.law], cfg["rung"], "normal")  # the name and its rung
        except ValueError as exc:
            raise UserError(str(exc)) from None
        design = dict(t.SBC_DESIGN, n_protocols=args.protocols,
                      amplitude_ratios=args.amplitude_ratios)
        tasks = t.sbc_tasks(args.law, args.n, rung=cfg["rung"], sampling=cfg["sampling"],
                            seed=cfg["seed"], thin=args.thin, design=design)
        return tasks, {"law": args.law, "n": args.n, "rung": cfg["rung"],
                       "sampling": cfg["sampling"], "seed": cfg["seed"], "thin": args.thin,
                       "design": design}
    cfg = _cfg(args)
    if args.kind == "datasets":
        return t.dataset_tasks(args.dirs, cfg), {"datasets": [str(Path(d).resolve())
                                                             for d in args.dirs], "cfg": cfg}
    from beadrod.workflows.campaign.recovery import read_grid
    from beadrod.workflows.commands.compare import check_laws

    grid = read_grid(args.worlds)
    if grid.get("laws") and not args.laws:
        cfg["laws"] = grid["laws"]
        check_laws(cfg)
    return t.recovery_tasks(grid["worlds"], cfg), {"grid": str(Path(args.worlds).resolve()),
                                                    "worlds": grid["worlds"], "cfg": cfg}


def _run(args: argparse.Namespace) -> int:
    import logging

    from beadrod.workflows.campaign.run import run_campaign
    from beadrod.workflows.runtime import UserError

    _need_dask()
    if args.workers < 1:
        raise UserError(f"--workers must be at least 1, got {args.workers}")
    if args.retries < 0:
        raise UserError(f"--retries must be at least 0, got {args.retries}")
    tasks, options = _tasks(args)
    out = Path(args.out)
    run = run_campaign(args.kind, tasks, out, options=options, workers=args.workers,
                       scheduler=args.scheduler, retries=args.retries, cache=args.cache,
                       quiet=args.quiet, force=args.force)
    log = logging.getLogger("beadrod")
    log.info("%d tasks: %d run now, %d reused; summary in %s", len(tasks), len(run.ran),
             len(run.reused), out / "summary.md")
    if run.failed:
        log.error("%d task(s) FAILED (their records in %s hold the error): %s; exit "
                  "status %d", len(run.failed), out / "tasks", ", ".join(run.failed[:10]),
                  EXIT_TASK_FAILED)
        return EXIT_TASK_FAILED
    return 0


def _common(p: argparse.ArgumentParser, out: str) -> None:
    s = DEFAULTS["sampling"]
    p.add_argument("--chains", type=int, help=f"NUTS chains per fit (default: {s['chains']})")
    p.add_argument("--warmup", type=int, help="NUTS warmup iterations per chain, >= 20 "
                   f"(default: {s['warmup']})")
    p.add_argument("--samples", type=int, help="NUTS draws per chain, >= 20 (default: "
                   f"{s['samples']})")
    p.add_argument("--seed", type=int, help="random seed in [0, 2**32 - 1] (default: "
                   f"{DEFAULTS['seed']})")
    p.add_argument("--rung", choices=RUNGS, help="forward model of every law (default: "
                   f"{DEFAULTS['rung']})")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the local "
                   "Dask cluster, one core and one JAX process of 1-3 GB each (default: "
                   "%(default)s; ignored with --scheduler)")
    p.add_argument("--scheduler", help="run on the Dask cluster whose scheduler is at "
                   "tcp://HOST:PORT (started with `dask scheduler`; docs/campaigns.md) "
                   "instead of a local one")
    p.add_argument("--retries", type=int, default=2, help="times a task whose worker was "
                   "lost (killed, out of memory) runs again on another worker before it "
                   "is marked FAILED (default: %(default)s)")
    p.add_argument("--cache", choices=("own", "off"), default="own",
                   help="each worker's persistent XLA compilation cache: its own, in its "
                   "scratch folder, or none (default: %(default)s; never one shared)")
    p.add_argument("--out", default=out, help="campaign folder (default: %(default)s); "
                   "rerunning the same command there skips the finished tasks")
    p.add_argument("--force", action="store_true", help="delete the earlier campaign's "
                   "records and summary in --out first (only files beadrod wrote)")
    p.add_argument("--quiet", action="store_true", help="no progress output (log file only)")


def _compare_opts(p: argparse.ArgumentParser) -> None:
    p.add_argument("--laws", help="comma-separated laws to compare, e.g. hertz,jkr,baseline "
                   "(default: the default comparison's)")
    p.add_argument("--config", help="TOML file setting compare's options (flags win)")


def register(sub) -> None:
    epilog = (f"exit status: 0 every task finished, {EXIT_TASK_FAILED} a task FAILED (the "
              "others finished), 2 an error to fix, 130 interrupted (finished tasks kept). "
              f"Needs Dask: {INSTALL_HINT}. docs/campaigns.md")
    p = sub.add_parser("campaign", help="many fits or comparisons on a Dask cluster: SBC, "
                       "recovery studies, many datasets",
                       description="Run many fits or comparisons as tasks on Dask "
                       "(a local cluster, or an existing one with --scheduler); one record "
                       "per task in OUT/tasks/, a summary rebuilt from them.", epilog=epilog)
    kinds = p.add_subparsers(dest="kind", metavar="KIND", required=True)
    s = kinds.add_parser("sbc", help="simulation-based calibration of one law",
                         description="N replicates: draw a truth from the prior, simulate "
                         "a dataset on a fixed design, fit it, rank the truth among the "
                         "draws; summary: rank histograms, ECDF difference, uniformity "
                         "tests, gate failures.", epilog=epilog)
    s.add_argument("--law", required=True, help="which law, e.g. hertz")
    s.add_argument("--n", type=int, required=True, help="number of replicates")
    s.add_argument("--thin", type=int, default=1, help="keep every THIN-th draw (ranks need "
                   "near-independent draws; --samples counts the kept ones; default: "
                   "%(default)s)")
    s.add_argument("--protocols", type=int, default=4, help="protocols of the simulated "
                   "design, each swept up and down at 4 drive amplitudes 8-40 nm "
                   "(default: %(default)s)")
    s.add_argument("--amplitude-ratios", action="store_true", help="every simulated sweep "
                   "also reads its amplitude per volt against its protocol's reference, "
                   "the amplitude likelihood compare fits where the data have amplitudes "
                   "(default: the shift, f0 and Q only)")
    _common(s, "beadrod-campaign-sbc")
    r = kinds.add_parser("recovery", help="which law the comparison prefers, over a grid of "
                         "synthetic worlds", description="One comparison per world and seed "
                         "of the grid (worlds made as `beadrod simulate` makes them); "
                         "summary: confusion table, 90 %% interval coverage, Δ log Z.",
                         epilog=epilog)
    r.add_argument("--worlds", required=True, help="TOML grid of worlds (docs/campaigns.md)")
    _compare_opts(r)
    _common(r, "beadrod-campaign-recovery")
    d = kinds.add_parser("datasets", help="one comparison per dataset folder",
                         description="One comparison per dataset folder; summary: log Z "
                         "per dataset and law, a forest plot of shared parameters, a flag "
                         "where the preferred law differs from the majority.", epilog=epilog)
    d.add_argument("dirs", nargs="+", metavar="DIR", help="dataset folders")
    _compare_opts(d)
    _common(d, "beadrod-campaign-datasets")
    for q in (s, r, d):
        q.set_defaults(func=_run)
