"""One progress display for a whole run, fed by the ``beadrod`` log records.

A step of work announces itself with :func:`begin` and reports its end with :func:`done`;
both are ordinary INFO log records (the log file gets them as plain lines) carrying a
:class:`Step` under the record attribute ``beadrod_step``. Records from worker processes
reach the parent through a queue (workflows.runtime), so the same display sees every fit.

:class:`RunProgress` turns them into
- on a terminal: one tqdm bar for the run (steps done out of total, laws done, the
  current step of each running fit, elapsed time and ETA); the step lines themselves go
  only to the log file, other messages are printed above the bar;
- elsewhere (a pipe, a CI log): the step lines as plain lines, each end prefixed with
  ``[done/total]``, the elapsed time and the ETA;
- with ``--quiet``: nothing (the console handler passes warnings only).

The steps are coarse and honest: a fit is NUTS (compilation, warmup and draws in one
compiled program, so no finer count exists without recompiling), then diagnostics and
LOO, then one step per evidence estimator. The ETA assumes the remaining steps take the
mean time of those done.
"""

from __future__ import annotations

import logging
import shutil
import sys
import time
from dataclasses import dataclass
from typing import Any, TextIO

from beadrod.workflows.runtime import console_handler

__all__ = ["STEP_ATTR", "Step", "begin", "done", "RunProgress", "format_seconds"]

STEP_ATTR = "beadrod_step"


@dataclass(frozen=True)
class Step:
    """``job``: which unit of work; ``steps``: how many steps this record completes (0 when
    a step begins); ``final``: the job is finished."""

    job: str
    steps: int = 0
    final: bool = False


def begin(log: logging.Logger, job: str, msg: str, *args: Any) -> None:
    """Announce that a step of ``job`` starts (an INFO record)."""
    log.info(msg, *args, extra={STEP_ATTR: Step(job)})


def done(log: logging.Logger, job: str, msg: str, *args: Any, steps: int = 1,
         final: bool = False) -> None:
    """Report that ``steps`` steps of ``job`` are done (``final``: the job is)."""
    log.info(msg, *args, extra={STEP_ATTR: Step(job, steps, final)})


def format_seconds(s: float) -> str:
    s = int(round(max(s, 0.0)))
    h, rem = divmod(s, 3600)
    return f"{h}:{rem // 60:02d}:{rem % 60:02d}" if h else f"{rem // 60}:{rem % 60:02d}"


class RunProgress:
    """Context manager: the display of one run of ``total`` steps in ``jobs`` jobs.

    ``stream`` defaults to stderr; ``tty`` to ``stream.isatty()``. Outside the context (or
    without the console handler of workflows.runtime.setup_logging) it does nothing.
    """

    def __init__(self, total: int, jobs: int, *, what: str = "laws",
                 stream: TextIO | None = None, tty: bool | None = None) -> None:
        self.total, self.jobs, self.what = int(total), int(jobs), what
        self._stream = stream
        self._tty = tty
        self.n_done = 0
        self.jobs_done = 0
        self.current: dict[str, str] = {}
        self._t0 = time.perf_counter()
        self._bar: Any = None
        self._handler = None

    @property
    def stream(self) -> TextIO:
        return self._stream if self._stream is not None else sys.stderr

    def __enter__(self) -> RunProgress:
        self._handler = console_handler()
        if self._handler is None or self._handler.level > logging.INFO:
            self._handler = None  # quiet, or no console: no display
            return self
        tty = self._tty if self._tty is not None else bool(
            getattr(self.stream, "isatty", lambda: False)())
        self._t0 = time.perf_counter()
        if tty:
            from tqdm import tqdm

            # a terminal that reports no width (a bare pty) would get an empty bar
            sized = shutil.get_terminal_size((0, 0)).columns > 0
            self._bar = tqdm(total=self.total, file=self.stream, unit="step", leave=True,
                             dynamic_ncols=sized, ncols=None if sized else 100, desc="beadrod",
                             bar_format="{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt}"
                             " steps [{elapsed}<{remaining}]{postfix}")
            self._refresh()
        self._handler.display = self
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._handler is not None:
            self._handler.display = None
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def write(self, text: str) -> None:
        if self._bar is not None:
            self._bar.write(text, file=self.stream)
        else:
            self.stream.write(text + "\n")
            self.stream.flush()

    def _eta(self) -> str:
        el = time.perf_counter() - self._t0
        if self.n_done <= 0:
            return f"elapsed {format_seconds(el)}"
        left = el / self.n_done * max(self.total - self.n_done, 0)
        return f"elapsed {format_seconds(el)}, ETA {format_seconds(left)}"

    def _refresh(self) -> None:
        if self._bar is None:
            return
        running = "; ".join(self.current.values())
        self._bar.set_postfix_str(f"{self.what} {self.jobs_done}/{self.jobs}"
                                  + (f" | {running}" if running else ""), refresh=False)
        self._bar.refresh()

    def console(self, record: logging.LogRecord, text: str) -> str | None:
        step = getattr(record, STEP_ATTR, None)
        if step is None:
            return text  # an ordinary message: printed (above the bar on a terminal)
        starts = step.steps == 0 and not step.final
        if starts:
            self.current[step.job] = record.getMessage()
        else:
            self.n_done = min(self.total, self.n_done + step.steps)
            if step.final:
                self.jobs_done += 1
                self.current.pop(step.job, None)
        if self._bar is not None:
            self._bar.n = self.n_done
            self._refresh()
            return None  # the bar shows it; the log file has the line
        if starts:
            return text
        return f"beadrod: [{self.n_done}/{self.total}] {record.getMessage()} ({self._eta()})"
