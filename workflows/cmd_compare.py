"""``beadrod compare`` (every law) and ``beadrod fit --law LAW`` (one law)."""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Any

__all__ = ["register", "setup_logging"]


def setup_logging(out: Path, quiet: bool) -> None:
    """Progress on stderr (unless quiet) and a full log in OUT/beadrod.log."""
    logger = logging.getLogger("beadrod")
    logger.setLevel(logging.INFO)
    for h in list(logger.handlers):
        logger.removeHandler(h)
    out.mkdir(parents=True, exist_ok=True)
    fh = logging.FileHandler(out / "beadrod.log")
    fh.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
    logger.addHandler(fh)
    sh = logging.StreamHandler(sys.stderr)
    sh.setFormatter(logging.Formatter("beadrod: %(message)s"))
    sh.setLevel(logging.WARNING if quiet else logging.INFO)
    logger.addHandler(sh)
    logger.propagate = False


def _flags(args: argparse.Namespace) -> dict[str, Any]:
    sampling = {"chains": args.chains, "warmup": args.warmup, "samples": args.samples}
    evidence = {"live_points": args.live_points, "smc_particles": args.smc_particles,
                "smc_seeds": args.smc_seeds,
                "methods": None if args.evidence is None else args.evidence.split(",")}
    likelihood = {"robust": True if args.robust else None,
                  "two_percent_rule": False if args.no_two_percent_rule else None}
    return {"data": args.data, "out": args.out, "seed": args.seed, "rung": args.rung,
            "workers": args.workers,
            "quiet": True if args.quiet else None,
            "laws": _laws(args),
            "sampling": sampling, "evidence": evidence, "likelihood": likelihood}


def _laws(args: argparse.Namespace) -> list[str] | None:
    if getattr(args, "law", None):
        return [args.law]
    if getattr(args, "laws", None):
        return [s.strip() for s in args.laws.split(",") if s.strip()]
    return None


def _check_out(out: Path, force: bool, resume: bool) -> None:
    from .cli import UserError

    if out.exists() and any(out.iterdir()) and not (force or resume):
        raise UserError(f"output folder {out} exists and is not empty: pass --force to "
                        "overwrite it or --resume to reuse finished laws")


def _run(args: argparse.Namespace) -> int:
    from .cli import host_devices
    from .config import resolve

    cfg = resolve(args.config, _flags(args))
    host_devices(max(1, min(int(cfg["sampling"]["chains"]), 8)))  # before JAX starts
    from inference.sample import configure

    configure(max(1, min(int(cfg["sampling"]["chains"]), 8)))
    out = Path(cfg["out"])
    _check_out(out, args.force, args.resume)
    setup_logging(out, cfg["quiet"])
    from .pipeline import run_compare

    result = run_compare(cfg, out, resume=args.resume)
    log = logging.getLogger("beadrod")
    log.info("preferred law: %s (%s)", result["preferred"], result["preferred_reason"])
    log.info("report: %s", out / "report.html")
    if not cfg["quiet"]:
        print((out / "comparison.md").read_text())
    failed = [r["name"] for r in result["laws"] if r["status"] != "ok"]
    if failed:
        log.warning("FAILED diagnostics: %s (marked in every table)", ", ".join(failed))
    return 0


def add_sampling_args(p: argparse.ArgumentParser) -> None:
    """--seed, --chains, --workers, --warmup, --samples (compare, fit, rungs)."""
    p.add_argument("--seed", type=int, help="random seed (same seed, same numbers)")
    p.add_argument("--chains", type=int, help="NUTS chains (default 4)")
    p.add_argument("--workers", type=int, help="fits run side by side in this many worker "
                   "processes (default 0: one per two usable cores, at most 4; 1: no worker "
                   "processes); the results do not depend on it")
    p.add_argument("--warmup", type=int, help="NUTS warmup iterations per chain")
    p.add_argument("--samples", type=int, help="NUTS draws per chain")


def _common(p: argparse.ArgumentParser) -> None:
    from .rungs import RUNGS

    p.add_argument("--data", help="dataset folder (measurements.csv + scene.toml); "
                   "default: the embedded synthetic 'paper_like' dataset")
    p.add_argument("--config", help="TOML file setting any option below (flags win)")
    p.add_argument("--out", help="output folder (default: beadrod-out)")
    p.add_argument("--rung", choices=RUNGS,
                   help="forward model: exact backbone (default), the paper's first order, "
                   "or the paper's Eq. 25 for the viscoelastic law")
    add_sampling_args(p)
    p.add_argument("--live-points", type=int, help="nested-sampling live points")
    p.add_argument("--smc-particles", type=int, help="tempered-SMC particles")
    p.add_argument("--smc-seeds", type=int, help="independent SMC runs (their spread is the "
                   "error bar)")
    p.add_argument("--evidence", help="comma-separated evidence estimators among ns (nested "
                   "sampling), bridge (bridge sampling from the NUTS draws) and smc "
                   "(tempered SMC); the first is the one the table ranks by; default bridge "
                   "(add ,ns for the nested-sampling cross-check: ~3 min more on 2 cores)")
    p.add_argument("--robust", action="store_true", help="Student-t likelihood for the shift")
    p.add_argument("--no-two-percent-rule", action="store_true",
                   help="keep drive steps after the linear resonance drifted by > 2 %%")
    p.add_argument("--force", action="store_true", help="overwrite a non-empty output folder")
    p.add_argument("--resume", action="store_true", help="reuse laws already finished in the "
                   "output folder whose inputs (data hash, config, version) are unchanged")
    p.add_argument("--quiet", action="store_true", help="no progress output (log file only)")


def register(sub) -> None:
    p = sub.add_parser("compare", help="fit every contact law, compare them, write the report",
                       description="The main job: fit every law by NUTS, check diagnostics, "
                       "compute LOO and the evidence (bridge sampling; --evidence bridge,ns adds a "
                       "nested-sampling cross-check), quantify the "
                       "Q-versus-shift tension, and write tables, figures and a report.")
    from .pipeline import MODEL_SPECS

    p.add_argument("--laws", help="comma-separated subset of laws to fit (default: all of "
                   f"{', '.join(MODEL_SPECS)})")
    _common(p)
    p.set_defaults(func=_run)

    f = sub.add_parser("fit", help="fit one contact law (same outputs for that law)",
                       description="Fit one law: NUTS, diagnostics, LOO, evidence, figures "
                       "and a report for that law alone.")
    f.add_argument("--law", required=True, choices=list(MODEL_SPECS), help="which law")
    _common(f)
    f.set_defaults(func=_run)
