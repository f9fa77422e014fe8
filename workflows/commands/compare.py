"""``beadrod compare`` (every law) and ``beadrod fit --law LAW`` (one law): the flags,
resolved to the run's configuration, and :func:`run`, which ``beadrod.compare`` and
``beadrod.fit`` (workflows.api) call too.

Exit status: 0 when every fit passed its gate, 1 when one did not (``--allow-failed``: 0;
the failure is marked in every table either way), 2 for an error the user can fix.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import Any

from beadrod.workflows import lawfiles
from beadrod.workflows.config import DEFAULTS, RUNGS, describe, leaf_keys
from beadrod.workflows.outdir import check_out

__all__ = ["register", "run", "add_sampling_args", "flags", "FLAG_KEYS", "config_only_keys",
           "failed_fits", "check_laws", "EXIT_FAILED"]

EXIT_FAILED = 1

# flag (argparse dest) -> the config key it sets; --help-config lists the other keys
FLAG_KEYS: dict[str, str] = {
    "data": "data", "out": "out", "seed": "seed", "rung": "rung", "workers": "workers",
    "quiet": "quiet", "laws": "laws", "law": "laws",
    "chains": "sampling.chains", "warmup": "sampling.warmup", "samples": "sampling.samples",
    "extensions": "sampling.extensions",
    "live_points": "evidence.live_points", "smc_particles": "evidence.smc_particles",
    "smc_seeds": "evidence.smc_seeds", "evidence": "evidence.methods",
    "robust": "likelihood.robust", "no_two_percent_rule": "likelihood.two_percent_rule",
    "observables": "likelihood.observables",
    "law_files": "law_files",
}

# store_true flags: what they set when given (absent: unset, the file or default decides)
_SWITCHES: dict[str, bool] = {"quiet": True, "robust": True, "no_two_percent_rule": False}


def config_only_keys() -> list[str]:
    """The config keys no flag sets (in DEFAULTS order)."""
    covered = set(FLAG_KEYS.values())
    return [k for k in leaf_keys() if k not in covered]


def _value(dest: str, raw: Any) -> Any:
    if raw is None or raw is False:
        return None
    if dest in _SWITCHES:
        return _SWITCHES[dest]
    if dest == "law":
        return [raw]
    if dest == "law_files":  # absolute paths: workers and --resume see the same files
        return [str(Path(f).resolve()) for f in raw] or None
    if dest in ("laws", "evidence"):
        return [s.strip() for s in raw.split(",") if s.strip()]
    return raw


def flags(args: argparse.Namespace) -> dict[str, Any]:
    """The nested config dict the command-line flags set (None: not given)."""
    out: dict[str, Any] = {}
    for dest, key in FLAG_KEYS.items():
        val = _value(dest, getattr(args, dest, None))
        if val is None:
            continue
        head, _, leaf = key.rpartition(".")
        (out.setdefault(head, {}) if head else out)[leaf] = val
    return out


def failed_fits(result: dict[str, Any]) -> list[tuple[str, str]]:
    """(fit, first reason) of every fit that failed its gate: the laws, then the tension's
    extra fits (the paper's Eq. 25 pair)."""
    bad = [(r["name"], (r.get("failures") or ["failed"])[0]) for r in result["laws"]
           if r["status"] != "ok"]
    paper = ((result.get("tension") or {}).get("paper") or {})
    bad += [(f"tension:{k}_paper_eq25", "failed its gate")
            for k, ok in (paper.get("fits_ok") or {}).items() if not ok]
    return bad


def check_laws(cfg: dict[str, Any]) -> None:
    """Law names of ``cfg`` against the registry (before any data are loaded), the law
    files loaded (workflows.lawfiles.load). Imports the models: call after the host device
    count is set.

    With ``laws`` given, a law file whose law they leave out is refused: its code ran for
    nothing, and whoever added it expects its law in the tables. It is not added
    silently either: ``laws`` says exactly what is fitted."""
    from beadrod.models.registry import laws
    from beadrod.workflows.config import normalise_laws
    from beadrod.workflows.pipeline.fits import model_names
    from beadrod.workflows.runtime import UserError

    cfg["laws"] = normalise_laws(cfg["laws"], model_names())
    if cfg["laws"] is None:
        return
    files = {str(Path(f).resolve()): f for f in cfg["law_files"]}
    for law in laws():
        if law.source in files and law.name not in cfg["laws"]:
            raise UserError(f"--law-file {files[law.source]} gives law '{law.name}', which "
                            f"the laws to fit ({', '.join(cfg['laws'])}) leave out: add "
                            f"'{law.name}' to them (--laws, or --law for fit) or leave the "
                            "file out")


def run(cfg: dict[str, Any], out: Path, *, force: bool = False, resume: bool = False,
        report: bool = True, dataset: Any = None) -> Any:
    """Fit the laws of the resolved configuration ``cfg`` into the output folder ``out``
    and, with ``report``, write the figures, tables and report there; return the
    workflows.pipeline.run.Comparison. ``beadrod compare``/``fit`` and
    ``beadrod.compare``/``fit`` (workflows.api, into a private folder) both run this.

    ``out`` is opened under workflows.outdir's rule (``force``, ``resume``) and given
    back at the end. ``dataset``: a loaded Dataset to fit instead of ``cfg['data']``
    (workflows.pipeline.run.dataset_folder). Law names are checked before any data are
    loaded."""
    from beadrod.workflows import runtime
    from beadrod.workflows.outdir import release
    from beadrod.workflows.pipeline.run import dataset_folder, n_devices, run_compare

    runtime.host_devices(n_devices(cfg))  # before JAX starts
    check_out(out, force=force, resume=resume)
    try:
        runtime.setup_logging(out, cfg["quiet"])
        from beadrod.inference.sampling.sample import configure

        configure(n_devices(cfg))
        lawfiles.load(cfg["law_files"])
        check_laws(cfg)
        if dataset is not None:
            cfg["data"] = dataset_folder(dataset, out)
        return run_compare(cfg, out, resume=resume, report=report)
    finally:
        release(out)


def _run(args: argparse.Namespace) -> int:
    from beadrod.workflows.config import resolve

    cfg = resolve(args.config, flags(args))
    out = Path(cfg["out"])
    result = run(cfg, out, force=args.force, resume=args.resume).result
    log = logging.getLogger("beadrod")
    log.info("preferred law: %s (%s)", result["preferred"], result["preferred_reason"])
    log.info("report: %s", out / "report.html")
    if not cfg["quiet"]:
        print((out / "comparison.md").read_text())
    bad = failed_fits(result)
    if not bad:
        return 0
    what = "; ".join(f"{name}: {why}" for name, why in bad)
    if args.allow_failed:
        log.warning("FAILED their gate (marked in every table; --allow-failed): %s", what)
        return 0
    log.error("%d fit(s) FAILED their gate (marked in every table): %s; exit status %d "
              "(--allow-failed: 0)", len(bad), what, EXIT_FAILED)
    return EXIT_FAILED


def add_sampling_args(p: argparse.ArgumentParser) -> None:
    """--seed, --chains, --workers, --warmup, --samples, --extensions (compare, fit,
    rungs)."""
    s = DEFAULTS["sampling"]
    p.add_argument("--seed", type=int, help="random seed in [0, 2**32 - 1]: same seed, "
                   f"same numbers (default: {DEFAULTS['seed']})")
    p.add_argument("--chains", type=int, help=f"NUTS chains (default: {s['chains']})")
    p.add_argument("--workers", type=int, help="fits run side by side in this many worker "
                   "processes, at most the usable cores, each a JAX process of 1-3 GB "
                   "(default: 0, two or one per two usable cores, at most 4; 1: no worker "
                   "processes); the results do not depend on it")
    p.add_argument("--warmup", type=int, help="NUTS warmup iterations per chain, >= 20 "
                   f"(default: {s['warmup']})")
    p.add_argument("--samples", type=int, help="NUTS draws per chain, >= 20 "
                   f"(default: {s['samples']})")
    p.add_argument("--extensions", type=int, help="times a run whose smallest ESS is below "
                   "the gate's goes on for as many draws again, >= 0 (default: "
                   f"{s['extensions']})")


class _HelpConfig(argparse.Action):
    """--help-config: the options only a config file sets, with defaults and meaning."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
                 help=None):  # noqa: A002 - argparse's own keyword
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print("Options set only in a config file (--config FILE.toml; the other options "
              "have flags, see --help), with their defaults:\n")
        print(describe(config_only_keys()))
        parser.exit(0)


def _common(p: argparse.ArgumentParser) -> None:
    ev = DEFAULTS["evidence"]
    p.add_argument("--data", help="dataset folder (measurements.csv + scene.toml); "
                   "default: the embedded synthetic 'paper_like' dataset")
    p.add_argument("--config", help="TOML file setting any option below and those of "
                   "--help-config (flags win)")
    p.add_argument("--help-config", action=_HelpConfig,
                   help="list the options only a config file sets, with their defaults")
    p.add_argument("--out", help=f"output folder (default: {DEFAULTS['out']})")
    p.add_argument("--rung", choices=RUNGS,
                   help="forward model: exact backbone, the paper's first order, or the "
                   f"paper's Eq. 25 for the viscoelastic law (default: {DEFAULTS['rung']})")
    add_sampling_args(p)
    p.add_argument("--live-points", type=int, help="nested-sampling live points "
                   f"(default: {ev['live_points']})")
    p.add_argument("--smc-particles", type=int, help="tempered-SMC particles "
                   f"(default: {ev['smc_particles']})")
    p.add_argument("--smc-seeds", type=int, help="independent SMC runs (their spread is the "
                   f"error bar; default: {ev['smc_seeds']})")
    p.add_argument("--evidence", help="comma-separated evidence estimators among ns (nested "
                   "sampling), bridge (bridge sampling from the NUTS draws) and smc "
                   "(tempered SMC); the first is the one the table ranks by (default: "
                   f"{','.join(ev['methods'])}; add ,ns for the nested-sampling cross-check: "
                   "~3 min more on 2 cores)")
    p.add_argument("--robust", action="store_true", help="Student-t likelihood for the shift")
    p.add_argument("--observables", choices=("all", "shift+q", "shift"),
                   help="what the likelihood reads besides f0: all (default: the shift, the "
                        "reference Q and each drive sweep's amplitude per volt), shift+q, "
                        "or shift alone")
    p.add_argument("--no-two-percent-rule", action="store_true",
                   help="keep drive steps after the linear resonance drifted by > 2 %%")
    p.add_argument("--force", action="store_true", help="overwrite a non-empty output folder "
                   "(the outputs of the earlier run are removed first)")
    p.add_argument("--resume", action="store_true", help="reuse laws already finished in the "
                   "output folder whose inputs (model, data, config, version) are unchanged")
    p.add_argument("--allow-failed", action="store_true", help="exit status 0 even when a "
                   f"fit fails its gate (default: {EXIT_FAILED}; failures are marked in every "
                   "table either way)")
    p.add_argument("--quiet", action="store_true", help="no progress output (log file only)")
    lawfiles.add_argument(p)


def register(sub) -> None:
    # no law registry here: it imports JAX, and building the parser must not
    epilog = (f"exit status: 0 all fits passed their gate, {EXIT_FAILED} a fit failed it "
              "(see --allow-failed), 2 an error to fix (the message names it)")
    p = sub.add_parser("compare", help="fit every contact law, compare them, write the report",
                       description="The main job: fit every law by NUTS, check diagnostics, "
                       "compute LOO and the evidence (bridge sampling; --evidence bridge,ns adds a "
                       "nested-sampling cross-check), quantify the "
                       "Q-versus-shift tension, and write tables, figures and a report.",
                       epilog=epilog)
    p.add_argument("--laws", help="comma-separated subset of laws to fit, e.g. hertz,jkr "
                   "(default: every law and the law-free baseline; a wrong name lists them)")
    _common(p)
    p.set_defaults(func=_run)

    f = sub.add_parser("fit", help="fit one contact law (same outputs for that law)",
                       description="Fit one law: NUTS, diagnostics, LOO, evidence, figures "
                       "and a report for that law alone.", epilog=epilog)
    f.add_argument("--law", required=True, help="which law, e.g. hertz (a wrong name lists "
                   "them)")
    _common(f)
    f.set_defaults(func=_run)
