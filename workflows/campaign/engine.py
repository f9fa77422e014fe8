"""The Dask engine of a campaign: a cluster to run on, its workers set up, the tasks
dispatched and collected.

- **The cluster.** By default a ``LocalCluster`` on this machine: worker processes
  (spawned, not forked: JAX's threads do not survive a fork), one thread each, the
  count ``--workers``, each with a memory limit from the machine's memory, so that Dask's
  nanny restarts a runaway worker before the machine swaps. ``--scheduler
  tcp://HOST:PORT`` connects to a cluster started elsewhere (``dask scheduler``, ``dask
  worker``) instead; this module then starts and stops nothing but its client.
- **Threads.** XLA's host device count (one: chains run one after the other, so N workers
  use N cores) and the OpenMP/MKL/OpenBLAS threads are put in the workers' environment
  before they start (``distributed.nanny.pre-spawn-environ``, one dotted key per
  variable, so that Dask's own entries stay), where JAX reads them when it is imported.
- **Each worker** (:class:`BeadrodWorker`, registered with ``Client.register_plugin``, so
  workers of an external cluster get it too, and a restarted worker again): float64, the
  library warnings as in a command, and its own persistent XLA compilation cache in the
  worker's private scratch folder (or none): never two writers on one cache folder (JAX
  issue 22718), never an assumption of a file system shared with the driver.
- **Dispatch.** ``client.map(..., pure=False, retries=R)`` and ``as_completed(...,
  with_results=True)``; a task's own error comes back as a FAILED record
  (workflows.campaign.execute), a lost worker makes the scheduler run its task again on
  another worker, up to ``distributed.scheduler.allowed-failures`` = R times on the local
  cluster (an external scheduler keeps its own setting), then the task is recorded
  FAILED with Dask's ``KilledWorker``. Ctrl-C cancels what is left; the caller closes the
  cluster (:func:`open_client` is a context manager).
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import sys
from collections.abc import Callable, Iterator
from typing import Any

import dask
from distributed import Client, LocalCluster, WorkerPlugin, as_completed

from beadrod.workflows.campaign.tasks import Task

__all__ = ["BeadrodWorker", "open_client", "run_tasks", "worker_environ", "memory_limit",
           "dashboard_link", "CACHE_CHOICES", "GIB"]

log = logging.getLogger("beadrod")

GIB = 1024 ** 3
CACHE_CHOICES = ("own", "off")
_DEVICES = re.compile(r"--xla_force_host_platform_device_count=\S+")


def worker_environ() -> dict[str, str]:
    """The variables a worker needs before JAX starts: one XLA host device (this
    process's other XLA flags kept), one OpenMP/MKL/OpenBLAS thread, no progress bars,
    and no output-folder manifest of the driver (workers write no files of the
    campaign)."""
    flags = _DEVICES.sub("", os.environ.get("XLA_FLAGS", "")).strip()
    return {"XLA_FLAGS": f"{flags} --xla_force_host_platform_device_count=1".strip(),
            "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
            "TQDM_DISABLE": "1", "BEADROD_MANIFEST": ""}


def memory_limit(workers: int, total: int | None = None) -> int:
    """Bytes per worker: 85 % of the machine's memory shared among ``workers``, at most
    8 GiB (a fit holds 1-3 GB; one past 8 GiB is a runaway the nanny should restart)."""
    if total is None:
        import psutil

        total = int(psutil.virtual_memory().total)
    return int(min(0.85 * total / max(int(workers), 1), 8 * GIB))


class BeadrodWorker(WorkerPlugin):
    """Sets up a worker process before its first task: its environment (as
    :func:`worker_environ`, for workers that were not started by this module), float64,
    the library warnings, the ``beadrod`` logger (warnings only), and its compilation
    cache: ``cache`` "own" (a folder in the worker's scratch space, private to this worker
    process) or "off"."""

    name = "beadrod-worker"

    def __init__(self, cache: str = "own") -> None:
        if cache not in CACHE_CHOICES:
            raise ValueError(f"cache must be one of {CACHE_CHOICES}, got {cache!r}")
        self.cache = cache

    def setup(self, worker: Any) -> None:
        from beadrod.workflows import runtime

        if "jax" not in sys.modules:  # an external worker: its backend has not started
            for k, v in worker_environ().items():
                if k == "XLA_FLAGS" or k not in os.environ:
                    os.environ[k] = v
        os.environ.pop("BEADROD_MANIFEST", None)
        os.environ["TQDM_DISABLE"] = "1"
        folder = ""
        if self.cache == "own":
            folder = os.path.join(worker.local_directory, "jax-cache")
            os.makedirs(folder, exist_ok=True)
            os.environ["JAX_COMPILATION_CACHE_DIR"] = folder
        else:
            os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)
        os.environ["BEADROD_JAX_CACHE"] = folder
        runtime.enable_x64()
        runtime.quiet_libraries()
        runtime.setup_logging(None, quiet=True)
        import jax

        jax.config.update("jax_enable_x64", True)
        if folder:
            jax.config.update("jax_compilation_cache_dir", folder)


def dashboard_link(client: Client) -> str | None:
    """The address of the scheduler's dashboard, when it serves one; its pages need bokeh
    in the scheduler's environment (said after the address where this one lacks it)."""
    import importlib.util

    try:
        services = client.scheduler_info().get("services", {})
    except Exception:  # noqa: BLE001 - no dashboard to show is no error
        return None
    if "dashboard" not in services:
        return None
    hint = "" if importlib.util.find_spec("bokeh") else " (its pages need bokeh installed)"
    return client.dashboard_link + hint


@contextlib.contextmanager
def open_client(*, workers: int, scheduler: str | None = None, retries: int = 2,
                cache: str = "own", memory: int | None = None) -> Iterator[Client]:
    """A client on a new LocalCluster of ``workers`` processes (``scheduler`` None) or on
    the cluster at ``scheduler``, its workers set up (:class:`BeadrodWorker`); closed,
    with the local cluster, on exit (Ctrl-C included)."""
    env = {f"distributed.nanny.pre-spawn-environ.{k}": v for k, v in worker_environ().items()}
    settings = {**env, "distributed.scheduler.allowed-failures": int(retries)}
    with contextlib.ExitStack() as stack:
        stack.enter_context(dask.config.set(settings))
        if scheduler is None:
            cluster = stack.enter_context(LocalCluster(
                n_workers=int(workers), processes=True, threads_per_worker=1,
                memory_limit=memory or memory_limit(workers), dashboard_address=":0",
                silence_logs=logging.ERROR))
            client = stack.enter_context(Client(cluster))
        else:
            try:
                client = stack.enter_context(Client(scheduler, timeout="30s"))
            except (OSError, ValueError) as exc:  # refused, timed out, a malformed address
                from beadrod.workflows.runtime import UserError

                raise UserError(f"cannot reach the Dask scheduler at {scheduler} ({exc}): "
                                "start it with `dask scheduler` (docs/campaigns.md), or "
                                "leave --scheduler out to run on this machine") from None
        client.register_plugin(BeadrodWorker(cache), name=BeadrodWorker.name)
        yield client


def _lost(fut: Any) -> str:
    try:
        exc = fut.exception()
    except Exception as err:  # noqa: BLE001 - cancelled, or the scheduler went away
        exc = err
    return f"{type(exc).__name__}: {exc}"


def run_tasks(client: Client, tasks: list[Task], *, fn: Callable[[Task], dict[str, Any]],
              retries: int, on_result: Callable[[Task, dict[str, Any], int], None],
              lost: Callable[[Task, str], dict[str, Any]]) -> None:
    """Run ``fn`` on every task on ``client``'s cluster; call ``on_result(task, record,
    running)`` as each finishes (``running``: tasks of this call the workers hold now),
    with ``lost(task, error)``'s record for a task Dask gave up on. Ctrl-C cancels the
    tasks not finished and re-raises."""
    keys = [f"beadrod-{t.name}-{t.key[:12]}" for t in tasks]
    futures = client.map(fn, tasks, key=keys, pure=False, retries=int(retries))
    by_key = dict(zip(keys, tasks))
    try:
        for fut, value in as_completed(futures, with_results=True, raise_errors=False):
            task = by_key[fut.key]
            record = value if fut.status == "finished" else lost(task, _lost(fut))
            on_result(task, record, _running(client, by_key))
    except BaseException:
        client.cancel(futures, force=True)
        raise


def _running(client: Client, keys: dict[str, Task]) -> int:
    try:
        return sum(1 for ks in client.processing().values() for k in ks if k in keys)
    except Exception:  # noqa: BLE001 - a count for the display only
        return 0
