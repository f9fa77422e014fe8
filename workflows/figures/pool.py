"""Figures written to disk by worker processes while the next ones are drawn.

Why. After the fits, ``beadrod compare`` draws about twenty figures and writes each as
PNG and PDF. Writing (the layout solve, rasterising, the PDF) is most of that step, on
one core while the others idle. Here a figure is
pickled as soon as it is drawn (matplotlib figures pickle, layout engine included) and
written by :func:`workflows.figures.gallery.save_figure` in a worker, so drawing the next figure
(which computes posterior draws with JAX) and writing the last ones overlap.

The files are the same: the worker runs the same ``save_figure`` (atomic writes, one
layout solve) on an exact copy of the figure, under the parent's matplotlib rcParams
(tests/test_figure_pool.py compares the PNGs pixel for pixel). A figure that does not
pickle (an artist holding a lambda, say) is written here instead, as with one process.
A warning raised while a worker writes (matplotlib's "constrained_layout not applied",
say) is raised again here, so it reaches the run's log as an in-process one would. A
failed write is raised when the writer is closed, naming the figure.
"""

from __future__ import annotations

import logging
import multiprocessing
import pickle
import warnings
from concurrent.futures import Future, ProcessPoolExecutor
from pathlib import Path
from typing import Any

__all__ = ["FigureWriter"]

log = logging.getLogger("beadrod")


def _init(rc: dict[str, Any]) -> None:
    import matplotlib

    from beadrod.workflows.runtime import exit_with_parent

    exit_with_parent()  # a parent killed with SIGKILL leaves no orphan writing figures

    matplotlib.use("Agg")
    matplotlib.rcParams.update(rc)


def _write(blob: bytes, path: str) -> list[tuple[type[Warning], str]]:
    # the warnings the write raised, for the parent to raise again (a worker has no log)
    from beadrod.workflows.figures.gallery import save_figure  # Agg and pyplot, as in the parent

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        save_figure(pickle.loads(blob), path)
    return [(w.category, str(w.message)) for w in caught]


class FigureWriter:
    """``save(fig, path)`` writes ``fig`` as ``path.png`` and ``path.pdf`` (and closes it):
    in ``processes`` worker processes (spawned: no forked JAX state) when there are more
    than one, else here. Use as a context manager: leaving it waits for every write and
    raises the first failure."""

    def __init__(self, processes: int = 1) -> None:
        self.processes = int(processes)
        self._pool: ProcessPoolExecutor | None = None
        self._pending: list[tuple[str, Future]] = []

    def __enter__(self) -> FigureWriter:
        if self.processes > 1:
            import matplotlib

            self._pool = ProcessPoolExecutor(
                max_workers=self.processes, mp_context=multiprocessing.get_context("spawn"),
                initializer=_init, initargs=(dict(matplotlib.rcParams),))
        return self

    def save(self, fig: Any, path: str | Path) -> None:
        from beadrod.workflows.figures.gallery import plt, save_figure

        if self._pool is None:
            save_figure(fig, path)
            return
        try:
            blob = pickle.dumps(fig)
        except Exception as exc:  # noqa: BLE001 (any pickling failure: write it here)
            log.debug("figure %s does not pickle (%s); written in this process",
                      Path(path).name, exc)
            save_figure(fig, path)
            return
        plt.close(fig)
        self._pending.append((Path(path).name, self._pool.submit(_write, blob, str(path))))

    def __exit__(self, *exc_info: Any) -> None:
        if self._pool is None:
            return
        try:
            for name, fut in self._pending:
                if exc_info[0] is None:
                    try:
                        raised = fut.result()
                    except Exception as exc:
                        raise RuntimeError(f"figure {name}: writing failed: {exc}") from exc
                    for category, message in raised:
                        warnings.warn(f"figure {name}: {message}", category, stacklevel=2)
        finally:
            self._pool.shutdown(wait=True, cancel_futures=True)
