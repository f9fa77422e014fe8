"""The ``beadrod`` command line.

Each subcommand lives in its own ``workflows/cmd_*.py`` module exposing
``register(subparsers)``; :data:`COMMAND_MODULES` is the one list of them. Building the
parser imports neither JAX nor the models (``beadrod --help`` answers at once); float64,
the warnings and the logging are set up here, at the entry point (workflows.runtime),
never on import of ``models``.

Exit status: 0 done, 1 a fit failed its gate (compare, fit), 2 an error the user can fix
(printed as one line and written to the run's log), 130 interrupted, 141 the reader of
the output went away (``beadrod laws | head -1``; nothing printed about it).
"""

from __future__ import annotations

import argparse
import errno
import importlib
import logging
import os
import sys
import traceback

from beadrod.workflows import runtime
from beadrod.workflows.runtime import UserError, host_devices

__all__ = ["main", "build_parser", "host_devices", "COMMAND_MODULES", "UserError",
           "version_string", "EXIT_PIPE"]

COMMAND_MODULES: tuple[str, ...] = (
    "beadrod.workflows.commands.compare",
    "beadrod.workflows.commands.laws",
    "beadrod.workflows.commands.rungs",
    "beadrod.workflows.commands.scene",
    "beadrod.workflows.commands.shift",
    "beadrod.workflows.commands.plan",
    "beadrod.workflows.commands.sweep",
    "beadrod.workflows.commands.simulate",
    "beadrod.workflows.commands.validate",
    "beadrod.workflows.commands.bench",
    "beadrod.workflows.commands.campaign",
)


def version_string() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return f"beadrod {version('beadrod')}"
    except PackageNotFoundError:  # running from a source tree
        return "beadrod (version unknown: not installed)"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="beadrod",
        description="Bayesian model comparison and parameter inference for a bead resting "
        "on a rod: contact laws, their resonance-frequency shift, and the data.",
        epilog="beadrod COMMAND --help describes a command and its defaults.",
    )
    parser.add_argument("--version", action="version", version=version_string())
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def _user_errors() -> tuple[type[BaseException], ...]:
    """Errors printed as one actionable line (they name the file, row, column or key)."""
    from beadrod.data.schema import DataError
    from beadrod.models.law import RungUnavailable
    from beadrod.models.lawfile import LawFileError
    from beadrod.models.scene import SceneError
    from beadrod.workflows.config import ConfigError

    return (UserError, DataError, SceneError, ConfigError, LawFileError, RungUnavailable)


# the errors of writing that the user can act on, reported as one line
_WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM,
                           errno.EISDIR, errno.ENOTDIR})

EXIT_PIPE = 141
"""Exit status when stdout's reader went away: 128 + SIGPIPE, as a shell reports it."""


def _drop_stdout() -> None:
    """Point stdout at the null device, so that the flush at exit finds no closed pipe
    (the recipe of Python's signal module documentation)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # stdout is no file (a test's capture)
        pass


def main(argv: list[str] | None = None) -> int:
    runtime.quiet_libraries()
    runtime.setup_logging(None, quiet=False)  # console only, until a command opens its log
    parser = build_parser()
    args = parser.parse_args(argv)
    runtime.enable_x64()
    try:
        status = int(args.func(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, not at exit as "Exception ignored"
        return status
    except BrokenPipeError:
        # whoever read the output stopped (`beadrod laws | head -1`): nothing is wrong,
        # and nothing more can be written; the shell's status for a closed pipe
        _drop_stdout()
        return EXIT_PIPE
    except KeyboardInterrupt:
        print("beadrod: interrupted", file=sys.stderr)
        runtime.log_to_file(logging.ERROR, "interrupted")
        return 130
    except Exception as exc:
        if isinstance(exc, OSError) and exc.errno in _WRITE_ERRNOS:
            exc = UserError(f"cannot write {exc.filename or 'a file'}: "
                            f"{exc.strerror or exc}")  # a full disk, a read-only folder
        elif not isinstance(exc, _user_errors()):  # a bug: the traceback, here and in the log
            runtime.log_to_file(logging.ERROR, "unexpected error\n" + traceback.format_exc())
            raise
        print(f"beadrod: error: {exc}", file=sys.stderr)
        runtime.log_to_file(logging.ERROR, f"error: {exc}")
        return 2
    finally:
        from beadrod.workflows.outdir import release_all

        release_all()  # the output folder's lock, for the next command of this process


if __name__ == "__main__":
    sys.exit(main())
