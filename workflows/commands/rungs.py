"""``beadrod rungs``: fit every law at two or more forward-model rungs and report how much
the rung moves each posterior and each evidence (see :mod:`workflows.pipeline.rung_effects`)."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

__all__ = ["register"]


def _run(args: argparse.Namespace) -> int:
    from beadrod.workflows import runtime
    from beadrod.workflows.commands.compare import EXIT_FAILED, check_laws, flags
    from beadrod.workflows.config import DEFAULTS, resolve
    from beadrod.workflows.outdir import check_out
    from beadrod.workflows.pipeline.run import n_devices
    from beadrod.workflows.pipeline.rung_effects import check_rungs

    rungs = [r.strip() for r in args.rungs.split(",") if r.strip()]
    try:
        check_rungs(rungs)
    except ValueError as exc:
        raise runtime.UserError(f"--rungs: {exc}") from None
    cfg = resolve(args.config, flags(args))
    if cfg["out"] == DEFAULTS["out"]:  # set neither by flag nor by the config file
        cfg["out"] = "beadrod-rungs"
    out = Path(cfg["out"])
    check_out(out, force=args.force, command="rungs")
    runtime.setup_logging(out, cfg["quiet"])
    runtime.host_devices(n_devices(cfg))  # before JAX starts
    from beadrod.inference.sampling.sample import configure

    configure(n_devices(cfg))
    from beadrod.workflows import lawfiles

    lawfiles.load(cfg["law_files"])
    check_laws(cfg)
    from beadrod.data.io import write_text
    from beadrod.workflows.config import to_toml
    from beadrod.workflows.pipeline.rung_effects import run_rungs

    write_text(out / "config.resolved.toml", to_toml(cfg))
    result = run_rungs(cfg, out, rungs)
    log = logging.getLogger("beadrod")
    log.info("written: %s", out / "rungs.md")
    if not cfg["quiet"]:
        print((out / "rungs.md").read_text())
    bad = sorted({f"{r['law']} ({r['rung']})" for r in result["evidence"]
                  if r["status"] != "ok"})
    if bad and not args.allow_failed:
        log.error("fits FAILED their gate: %s (marked FAILED in rungs.md); exit status %d "
                  "(--allow-failed: 0)", ", ".join(bad), EXIT_FAILED)
        return EXIT_FAILED
    return 0


def register(sub) -> None:
    from beadrod.workflows.commands.compare import add_sampling_args
    from beadrod.workflows.config import RUNGS

    p = sub.add_parser(
        "rungs", help="how much the forward-model rung moves each posterior and evidence",
        description="Fit every law at each given rung (first order: the paper's analysis; "
        "backbone: exact; paper_eq25: the paper's viscoelastic curve) on the same data and "
        "write rungs.md/.csv/.json: per parameter the posterior under each rung and its move "
        "in posterior sds, per law log Z under each rung and its change, and the preferred "
        "law under each rung.")
    p.add_argument("--rungs", default="first_order,backbone",
                   help=f"comma-separated rungs among {', '.join(RUNGS)}; the first is the "
                   "reference (default: %(default)s)")
    p.add_argument("--laws", help="comma-separated laws, e.g. hertz,jkr (default: every law "
                   "but the baseline, which has no rung; a wrong name lists them)")
    p.add_argument("--data", help="dataset folder (default: the embedded paper_like world)")
    p.add_argument("--config", help="TOML file setting any option (flags win)")
    p.add_argument("--out", help="output folder (default: beadrod-rungs)")
    add_sampling_args(p)
    p.add_argument("--evidence", help="evidence estimators, as for compare (default: bridge)")
    p.add_argument("--robust", action="store_true", help="Student-t likelihood for the shift")
    p.add_argument("--force", action="store_true", help="overwrite a non-empty output folder")
    p.add_argument("--allow-failed", action="store_true",
                   help="exit status 0 even when a fit fails its gate (default: 1)")
    from beadrod.workflows import lawfiles

    lawfiles.add_argument(p)
    p.add_argument("--quiet", action="store_true", help="no progress output (log file only)")
    p.set_defaults(func=_run)
