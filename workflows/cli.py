"""The ``beadrod`` command line.

Each subcommand lives in its own ``workflows/cmd_*.py`` module exposing
``register(subparsers)``; :data:`COMMAND_MODULES` is the one list of them.
Float64 is switched on here, at the entry point, never on import of ``models``.
"""

from __future__ import annotations

import argparse
import importlib
import sys

__all__ = ["main", "build_parser", "host_devices", "COMMAND_MODULES"]

COMMAND_MODULES: tuple[str, ...] = (
    "workflows.cmd_compare",
    "workflows.cmd_rungs",
    "workflows.cmd_scene",
    "workflows.cmd_shift",
    "workflows.cmd_plan",
    "workflows.cmd_run_scene",
    "workflows.cmd_simulate",
    "workflows.cmd_validate",
    "workflows.cmd_bench",
)


def host_devices(n: int) -> None:
    """Ask XLA for ``n`` host (CPU) devices so NUTS chains run in parallel.

    Must run before anything initialises the JAX backend (importing ``inference``
    does, through its module-level distributions), so it sets the flag itself
    rather than importing numpyro. A count already in XLA_FLAGS is left alone.
    """
    import os

    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_force_host_platform_device_count" not in flags:
        os.environ["XLA_FLAGS"] = f"{flags} --xla_force_host_platform_device_count={int(n)}"


def _enable_x64() -> None:
    import jax

    jax.config.update("jax_enable_x64", True)
    # persistent compilation cache: a second run skips most XLA compilation (the first
    # run on a machine pays it in full). BEADROD_JAX_CACHE="" switches it off.
    import os

    cache = os.environ.get("BEADROD_JAX_CACHE",
                           os.path.join(os.path.expanduser("~"), ".cache", "beadrod", "jax"))
    if cache:
        jax.config.update("jax_compilation_cache_dir", cache)
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="beadrod",
        description="Bayesian model comparison and parameter inference for a bead resting "
        "on a rod: contact laws, their resonance-frequency shift, and the data.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    _enable_x64()
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print("beadrod: interrupted", file=sys.stderr)
        return 130
    except _user_errors() as exc:
        print(f"beadrod: error: {exc}", file=sys.stderr)
        return 2


class UserError(Exception):
    """An error the user can act on (bad data, bad config, refused overwrite)."""


def _user_errors() -> tuple[type[BaseException], ...]:
    """Errors printed as one actionable line (they name the file, row, column or key)."""
    from data.schema import DataError
    from models.scenes import SceneError

    from .config import ConfigError

    return (UserError, DataError, SceneError, ConfigError)


if __name__ == "__main__":
    sys.exit(main())
