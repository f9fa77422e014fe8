"""``beadrod bench device``: what JAX's default backend (CPU or an accelerator) buys.

The same measurements on whichever backend JAX picks (``JAX_PLATFORMS=cpu`` forces the
CPU), so that one command gives comparable rows on a laptop and on a GPU:

1. NUTS per law on the embedded dataset (4 chains x 400 + 400, as ``bench inference``):
   compile apart from sampling, smallest bulk ESS, ESS per second; chains run 'parallel'
   over host devices on the CPU and 'vectorized' on an accelerator (one device), and
   bridge-sampling evidence from the draws.
2. Nested sampling (jaxns, compare's live points) of the Hertz model: wall time, which
   includes jaxns compiling its program.
3. The simulator's time integration (``models.ladder.time_integration.swept_sine``: RK4, 128 steps
per
   period, 40 settle + 8 lock-in periods per frequency, 26 frequencies), vmapped over a
   batch of drive levels: compile and run time, sweeps per second. A sweep is a long
   sequential loop, so a single sweep gains nothing from an accelerator; a batch runs its
   sweeps side by side.

Not a CI dependency: CI runs ``--quick`` on the CPU only to check the table is written.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from beadrod.data.io import write_text

__all__ = ["run"]


def _timed(fn, *args):
    """(result, compile-and-first-run s, warm run s) of a jitted ``fn``."""
    import jax

    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    return out, first, time.perf_counter() - t0


def _simulator_rows(batches: tuple[int, ...], n_freq: int, budget_s: float) -> list[dict]:
    import jax
    import jax.numpy as jnp

    from beadrod.models.ladder import time_integration
    from beadrod.models.ladder.oscillator import hertz_oscillator

    law = hertz_oscillator(0.01)  # Q = 50
    om = jnp.linspace(0.85, 1.02, n_freq)
    f = jax.jit(jax.vmap(lambda e: time_integration.swept_sine(law, e, om, steps_per_period=128,
                                                       settle_periods=40,
                                                       measure_periods=8).amplitude))
    rows: list[dict] = []
    per_sweep = None
    for b in batches:
        if per_sweep is not None and per_sweep * b > budget_s:
            rows.append({"task": f"simulator: {b} sweeps", "note": "skipped: over budget"})
            continue
        drives = jnp.linspace(2e-4, 1.5e-2, b)  # x up to ~1 at Q = 50
        amp, first, warm = _timed(f, drives)
        if not np.all(np.isfinite(np.asarray(amp))):
            raise RuntimeError("time integration returned non-finite amplitudes")
        per_sweep = warm / b
        rows.append({"task": f"simulator: {b} sweeps x {n_freq} frequencies",
                     "compile_s": first - warm, "run_s": warm, "per_unit_s": per_sweep,
                     "rate": 1.0 / per_sweep, "rate_unit": "sweeps/s"})
    return rows


def _nuts_rows(names: list[str], inputs: dict, chains: int, warm: int, draws: int,
               method: str) -> list[dict]:
    from beadrod.inference.evidence.bridge import bridge_sampling_log_z
    from beadrod.inference.model.numpyro_models import build_model
    from beadrod.workflows.bench.inference import timed_nuts
    from beadrod.workflows.pipeline.fits import comparison_specs

    rows: list[dict] = []
    for name, spec in comparison_specs(names, "backbone", "normal").items():
        model = build_model(spec)
        fit, compile_s, sampling, ess = timed_nuts(model, inputs, chains, warm, draws, method)
        br = bridge_sampling_log_z(model, {"data": inputs}, fit.idata)
        rows.append({"task": f"NUTS {name} ({spec.rung}), {chains} chains {method}",
                     "compile_s": compile_s, "run_s": sampling,
                     "per_unit_s": sampling / ess, "rate": ess / sampling,
                     "rate_unit": "ESS/s", "log_z": br.log_z, "log_z_err": br.log_z_err,
                     "note": f"bridge evidence {br.wall_s:.1f} s"})
    return rows


def _ns_row(inputs: dict, live: int) -> dict:
    from beadrod.inference.evidence.log_z import nested_sampling_log_z
    from beadrod.inference.model.numpyro_models import build_model
    from beadrod.workflows.pipeline.fits import comparison_specs

    model = build_model(comparison_specs(["hertz"], "backbone", "normal")["hertz"])
    ns = nested_sampling_log_z(model, {"data": inputs}, num_live_points=live)
    return {"task": f"nested sampling hertz, {live} live points", "run_s": ns.wall_s,
            "log_z": ns.log_z, "log_z_err": ns.log_z_err,
            "note": "wall time includes jaxns compiling its program"}


def _write(path: Path, rows: list[dict], header: str) -> Path:
    """``path``.csv and ``path``.md (``header`` above the table), atomically."""
    import pandas as pd

    from beadrod.workflows.bench.inference import results_markdown

    table = pd.DataFrame(rows)
    write_text(path.with_suffix(".csv"), table.to_csv(index=False))
    return write_text(path.with_suffix(".md"), f"{header}\n\n{results_markdown(table)}\n")


def run(out_dir: Path, quick: bool = False, laws: list[str] | None = None) -> Path:
    """Measure on JAX's default backend; write ``bench_device_<platform>.csv`` / ``.md``
    (rewritten after each stage, so a run cut short keeps what it measured). ``laws``:
    the NUTS rows (default: every law of the comparison; quick: Hertz)."""
    import platform

    import jax

    from beadrod.inference.model.likelihood import model_inputs
    from beadrod.workflows.config import DEFAULTS
    from beadrod.workflows.pipeline.fits import default_model_names, load_data

    dev = jax.devices()[0]
    plat = dev.platform
    method = "parallel" if plat == "cpu" and jax.local_device_count() >= 4 else "vectorized"
    path = Path(out_dir) / f"bench_device_{plat}"
    header = (f"# Device benchmark: {plat} ({getattr(dev, 'device_kind', plat)})\n\n"
              f"JAX {jax.__version__} on {plat}, {jax.local_device_count()} device(s), host "
              f"{platform.machine()}; compile apart from run (run = a second, warm call for "
              "the simulator; sampling minus a 1+1-iteration compile probe for NUTS)."
              + (" QUICK RUN: numbers not meaningful." if quick else ""))
    inputs = model_inputs(load_data(DEFAULTS))
    if quick:
        batches, n_freq, budget = (2,), 4, 30.0   # one compiled shape, batched
        names, (chains, warm, draws) = laws or ["hertz"], (2, 30, 30)
    else:
        batches, n_freq, budget = (1, 32, 256, 2048), 26, 120.0
        names, (chains, warm, draws) = laws or default_model_names(), (4, 400, 400)
    rows = _simulator_rows(batches, n_freq, budget)
    md = _write(path, rows, header)
    for name in names:
        rows += _nuts_rows([name], inputs, chains, warm, draws, method)
        md = _write(path, rows, header)
    if not quick:  # nested sampling is slow to compile: not in the smoke run
        rows.append(_ns_row(inputs, DEFAULTS["evidence"]["live_points"]))
        md = _write(path, rows, header)
    return md
