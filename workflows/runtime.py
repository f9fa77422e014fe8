"""Process set-up for the command line and its worker processes, done once per process.

Float64, the host device count, the persistent XLA compilation cache, library warnings and
the ``beadrod`` logger. ``workflows.cli`` calls these in the main process and
``workflows.pipeline.parallel`` in each worker, so that neither reaches into the other.

Nothing here imports JAX: float64 and the compilation cache are set through JAX's
environment variables (read when JAX is first imported) and, if JAX is already imported,
through ``jax.config`` as well; the host device count is an XLA flag that must be set
before the backend starts. ``beadrod --help`` therefore never pays for importing JAX.
"""

from __future__ import annotations

import logging
import logging.handlers
import os
import sys
import warnings
from pathlib import Path
from typing import Any, Protocol

__all__ = ["UserError", "LOGGER", "host_devices", "enable_x64", "quiet_libraries",
           "setup_logging", "log_to_queue", "console_handler", "log_to_file", "init_worker",
           "Display", "exit_with_parent"]

LOGGER = "beadrod"
LOG_FILE = "beadrod.log"


class UserError(Exception):
    """An error the user can act on (bad data, bad config, refused overwrite): printed as
    one line, exit status 2."""


def host_devices(n: int) -> None:
    """Ask XLA for ``n`` host (CPU) devices so NUTS chains run in parallel.

    Must run before anything initialises the JAX backend (importing ``inference`` does,
    through its module-level distributions). A count already in XLA_FLAGS is left alone.
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_force_host_platform_device_count" not in flags:
        os.environ["XLA_FLAGS"] = f"{flags} --xla_force_host_platform_device_count={int(n)}"


def enable_x64() -> None:
    """Float64 everywhere, and the persistent compilation cache.

    The cache lets a second run skip most XLA compilation (the first run on a machine
    pays it in full); BEADROD_JAX_CACHE="" switches it off, a path moves it.
    """
    os.environ["JAX_ENABLE_X64"] = "1"
    cache = os.environ.get("BEADROD_JAX_CACHE",
                           os.path.join(os.path.expanduser("~"), ".cache", "beadrod", "jax"))
    if cache:
        os.environ.setdefault("JAX_COMPILATION_CACHE_DIR", cache)
        # every program, however quick to compile: a warm run otherwise recompiles some
        # hundreds of small ones
        os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")
    if "jax" in sys.modules:  # imported already (a test, an embedding program)
        import jax

        jax.config.update("jax_enable_x64", True)
        if cache:
            jax.config.update("jax_compilation_cache_dir",
                              os.environ["JAX_COMPILATION_CACHE_DIR"])
            jax.config.update("jax_persistent_cache_min_compile_time_secs",
                              float(os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"]))


_SEEN: set[str] = set()


def _one_line(message: Warning | str, category: type[Warning], filename: str, lineno: int,
              file: Any = None, line: str | None = None) -> None:
    # a library warning as one line, once per run (no source line, no banner)
    first = next((s.strip() for s in str(message).splitlines() if s.strip()), "")
    text = f"warning: {category.__name__}: {first}"
    if text in _SEEN:
        return
    _SEEN.add(text)
    log = logging.getLogger(LOGGER)
    if log.handlers:
        log.warning(text)
    else:
        print(f"beadrod: {text}", file=sys.stderr)


def quiet_libraries() -> None:
    """Silence the known library noise and print any other warning as one line, once.

    Silenced: ArviZ's refactoring banner (a FutureWarning on every import), jaxns'
    deprecation warnings, and the gate's own RuntimeWarning (the failure is already
    logged once, with its numbers, by inference.sampling.diagnostics).
    """
    warnings.filterwarnings("ignore", message=r"(?s)\s*ArviZ is undergoing",
                            category=FutureWarning)
    warnings.filterwarnings("ignore", category=DeprecationWarning, module=r"jaxns(\.|$)")
    warnings.filterwarnings("ignore", message=r"(?s).*FAILED its diagnostics",
                            category=RuntimeWarning)
    warnings.showwarning = _one_line


class Display(Protocol):
    """What a progress display gives the console handler (workflows.progress)."""

    def console(self, record: logging.LogRecord, text: str) -> str | None:
        """The text to print for ``record`` (None: print nothing)."""

    def write(self, text: str) -> None:
        """Print one line without breaking the display."""


def exit_with_parent(poll_s: float = 0.5) -> None:
    """In a worker process: end it when its parent dies. A parent killed with SIGKILL
    cannot shut its pool down, and its workers would run on as orphans; an orphan is
    adopted by another process, so its parent id changes, which a daemon thread watches."""
    import threading
    import time

    parent = os.getppid()

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(poll_s)
        os._exit(1)

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


class _LogFile(logging.FileHandler):
    """The run's log file. A write that fails (a full disk, the folder gone read-only)
    stops the file log with one line on the console instead of a traceback per record;
    the error that follows names the folder."""

    def handleError(self, record: logging.LogRecord) -> None:  # noqa: N802 (logging's name)
        exc = sys.exc_info()[1]
        logging.getLogger(LOGGER).removeHandler(self)
        sys.stderr.write(f"beadrod: the log file {self.baseFilename} can no longer be "
                         f"written ({getattr(exc, 'strerror', None) or exc}); logging to "
                         "the console only\n")


class _Console(logging.Handler):
    """stderr, looked up at every record (so redirections and test captures work), through
    the active progress display if there is one."""

    def __init__(self) -> None:
        super().__init__()
        self.display: Display | None = None

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = self.format(record)
            if self.display is not None:
                out = self.display.console(record, text)
                if out is not None:
                    self.display.write(out)
                return
            sys.stderr.write(text + "\n")
            sys.stderr.flush()
        except Exception:  # noqa: BLE001 - logging must never raise
            self.handleError(record)


_MARK = "_beadrod_handler"


def _reset(logger: logging.Logger) -> None:
    for h in list(logger.handlers):
        if getattr(h, _MARK, False):
            logger.removeHandler(h)
            h.close()


def setup_logging(out: Path | None, quiet: bool) -> logging.Logger:
    """The ``beadrod`` logger: progress on stderr (warnings only if ``quiet``) and, with
    ``out``, the full log in OUT/beadrod.log (appended). Calling it again replaces the
    handlers it added before, so a process never logs a line twice."""
    logger = logging.getLogger(LOGGER)
    logger.setLevel(logging.INFO)
    logger.propagate = False
    _reset(logger)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        try:
            fh = _LogFile(out / LOG_FILE)
        except OSError as exc:
            raise UserError(f"cannot write to the output folder {out}: "
                            f"{exc.strerror or exc}") from None
        fh.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
        setattr(fh, _MARK, True)
        logger.addHandler(fh)
    sh = _Console()
    sh.setFormatter(logging.Formatter("beadrod: %(message)s"))
    sh.setLevel(logging.WARNING if quiet else logging.INFO)
    setattr(sh, _MARK, True)
    logger.addHandler(sh)
    return logger


def console_handler() -> _Console | None:
    """The stderr handler :func:`setup_logging` installed (None before it ran)."""
    return next((h for h in logging.getLogger(LOGGER).handlers if isinstance(h, _Console)),
                None)


def log_to_file(level: int, text: str) -> None:
    """Write one line to the log file only (the console already showed it)."""
    logger = logging.getLogger(LOGGER)
    record = logger.makeRecord(LOGGER, level, __file__, 0, text, None, None)
    for h in logger.handlers:
        if isinstance(h, logging.FileHandler):
            h.handle(record)


def log_to_queue(queue: Any) -> None:
    """In a worker process: send every ``beadrod`` record to the parent through ``queue``
    (the parent prints and files them, so lines from several workers never interleave)."""
    logger = logging.getLogger(LOGGER)
    logger.setLevel(logging.INFO)
    logger.propagate = False
    _reset(logger)
    qh = logging.handlers.QueueHandler(queue)
    setattr(qh, _MARK, True)
    logger.addHandler(qh)


def init_worker(n_devices: int, queue: Any) -> None:
    """Everything a worker process needs before its first job: the same set-up as the
    command line's (devices before the backend starts, float64, warnings, logging), and
    its end when the parent dies."""
    exit_with_parent()
    host_devices(n_devices)  # inherited from the parent's environment in practice
    enable_x64()
    quiet_libraries()
    log_to_queue(queue)
    from beadrod.inference.sampling.sample import configure

    configure(n_devices)
