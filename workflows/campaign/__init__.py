"""Campaigns: many fits or comparisons as tasks on a Dask cluster (``beadrod campaign``).

- ``tasks``: what a task is (an SBC replicate, a dataset's or a world's comparison) and
  its key, from its resolved inputs and the code;
- ``execute``, ``sbc_task``, ``compare_task``: what a worker runs;
- ``engine``: the cluster (a LocalCluster, or an existing one), its workers' set-up,
  dispatch and collection;
- ``results``: one record per task, written atomically; what a rerun reuses;
- ``run``: a campaign from start to end, with its progress display;
- ``summary``, ``summary_compare``, ``tables``: the summary rebuilt from the records;
- ``recovery``: the TOML grid of a recovery campaign.

Nothing here is imported by ``import beadrod`` or by building the command-line parser:
Dask and JAX load when a campaign runs. How to run one: docs/campaigns.md.
"""

__all__ = ["tasks", "execute", "sbc_task", "compare_task", "engine", "results", "run",
           "summary", "summary_compare", "tables", "recovery"]
