"""``beadrod bench accuracy``: what accuracy costs in time, rung by rung.

For each rung of models/ladder/powerlaw_ladder.py and each amplitude x in {0.1, 0.3, 0.5, 0.8,
0.95, 1.2}
(Hertz, Q = 50): the predicted resonance shift Delta f/f0, its error against the most
accurate rung (time integration by solve_ivp, DOP853, rtol 1e-10), and the time per
evaluation after compilation (compile time reported apart). Also measured: a 200-step
harmonic-balance frequency-response curve and a 200-frequency HBM up+down sweep, and the
JAX time integration against scipy's solve_ivp running the same stepped swept sine at
equal error.
"""

from __future__ import annotations

import csv
import io
import time
from pathlib import Path

import numpy as np

from beadrod.data.io import write_text

__all__ = ["run", "X_VALUES"]

X_VALUES = (0.1, 0.3, 0.5, 0.8, 0.95, 1.2)
Q_FACTOR = 50.0


def _timed(fn, repeats=3):
    t0 = time.perf_counter()
    out = np.asarray(fn())
    first = time.perf_counter() - t0
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = np.asarray(fn())
        runs.append(time.perf_counter() - t0)
    run_t = float(np.median(runs))
    return out, max(first - run_t, 0.0), run_t


def _ladder_rows(xs, quick):
    from functools import partial

    from beadrod.models.ladder import powerlaw_ladder

    rungs = dict(powerlaw_ladder.RUNGS)
    rungs["5 time integration"] = partial(powerlaw_ladder.rung5_timeint, steps_per_period=128)
    rungs["5 solve_ivp rtol=1e-6"] = partial(powerlaw_ladder.rung5_timeint, use_scipy=True,
                                              rtol=1e-6)
    rungs["5 solve_ivp rtol=1e-9"] = partial(powerlaw_ladder.rung5_timeint, use_scipy=True,
                                              rtol=1e-9)
    ref_fn = partial(powerlaw_ladder.rung5_timeint, use_scipy=True, rtol=1e-10)
    ref = np.array([float(np.asarray(ref_fn(np.array([x]), 1.5, q_factor=Q_FACTOR))[0])
                    for x in xs])
    rows = []
    for name, f in rungs.items():
        reps = 1 if ("5" in name[:1] or quick) else 3
        compile_t = None
        for i, x in enumerate(xs):
            val, c, t = _timed(lambda f=f, x=x: f(np.array([x]), 1.5, q_factor=Q_FACTOR),
                               repeats=reps)
            compile_t = c if compile_t is None else compile_t
            v = float(np.asarray(val).reshape(-1)[0])
            rows.append(dict(rung=name, x=x, shift=v, error=v - ref[i],
                             rel_error=(v - ref[i]) / abs(ref[i]), time_s=t,
                             compile_s=compile_t if i == 0 else 0.0))
    for i, x in enumerate(xs):
        rows.append(dict(rung="reference: solve_ivp rtol=1e-10", x=x, shift=ref[i], error=0.0,
                         rel_error=0.0, time_s=np.nan, compile_s=np.nan))
    return rows


def _frc_timing():
    import jax

    from beadrod.models.ladder import harmonic_balance
    from beadrod.models.ladder.oscillator import hertz_oscillator

    law = hertz_oscillator(0.01)
    out = []
    for h in (3, 7):
        f = jax.jit(lambda e, h=h: harmonic_balance.frf(law, e, 0.85, 1.1, harmonics=h,
                                                        n_steps=200))
        _, c, t = _timed(lambda f=f: jax.block_until_ready(f(0.01)).peak_omega)
        out.append((f"FRC by arclength continuation, 200 steps, H={h}", c, t))
        grid = np.linspace(0.85, 1.1, 200)

        def both(h=h, grid=grid):
            up, _ = harmonic_balance.sweep(law, 0.01, grid, harmonics=h)
            down, _ = harmonic_balance.sweep(law, 0.01, grid[::-1], harmonics=h)
            return jax.block_until_ready(down)[0]

        _, c, t = _timed(both)
        out.append((f"HBM stepped sweep, 200 frequencies up + 200 down, H={h}", c, t))
    return out


def _ti_vs_scipy(quick):
    import jax

    from beadrod.models.ladder import time_integration
    from beadrod.models.ladder.oscillator import hertz_oscillator

    law, e = hertz_oscillator(0.025), 0.06        # Q = 20, drive with contact loss at resonance
    om = np.linspace(0.88, 1.02, 8 if quick else 26)
    kw = dict(settle_periods=40, measure_periods=2)
    # the lock-in of a not-quite-settled point depends on the samples per period, so each
    # JAX run is compared with a reference sampled identically (RK4: one sample per step)
    refs = {m: time_integration.swept_sine_scipy(law, e, om, rtol=1e-11, atol=1e-13,
                                        samples_per_period=m, **kw).amplitude
            for m in (64, 128, 256)}
    ref = refs[128]
    rows = []
    for m in (64, 128, 256):
        f = jax.jit(lambda m=m: time_integration.swept_sine(law, e, om, steps_per_period=m,
                                                             **kw).amplitude)
        a, c, t = _timed(f)
        rows.append((f"JAX RK4, {m} steps/period", float(np.max(np.abs(a - refs[m]))), c, t))
    for rtol in (1e-5, 1e-6, 1e-8):
        a, _, t = _timed(lambda rtol=rtol: time_integration.swept_sine_scipy(
            law, e, om, rtol=rtol, atol=rtol * 1e-2, samples_per_period=128, **kw).amplitude,
            repeats=1)
        rows.append((f"solve_ivp DOP853, rtol={rtol:g}", float(np.max(np.abs(a - ref))),
                     0.0, t))
    return rows, om.size


def _plot(rows, path: Path) -> None:
    """accuracy.png and accuracy.pdf: |error| against time per evaluation, per rung."""
    from beadrod.workflows.figures.gallery import fig_accuracy_cost, save_figure

    table = [{**r, "error": abs(r["error"])} for r in rows
             if not str(r["rung"]).startswith("reference")]
    fig = fig_accuracy_cost(table)
    xs = [float(r["x"]) for r in table]
    fig.axes[0].set_title(f"What accuracy costs in time: Hertz, Q = {Q_FACTOR:g}, "
                          f"x = {min(xs):g} ... {max(xs):g}", fontsize=10)
    save_figure(fig, Path(path).with_suffix(""))


def run(out_dir: Path, quick: bool = False) -> Path:
    """Measure the ladder; write accuracy.csv, accuracy.md, accuracy.png/.pdf into out_dir."""
    import jax

    jax.config.update("jax_enable_x64", True)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    xs = (0.3, 1.2) if quick else X_VALUES
    rows = _ladder_rows(xs, quick)
    frc = _frc_timing()
    ti, n_freq = _ti_vs_scipy(quick)

    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]))
    w.writeheader()
    w.writerows(rows)
    write_text(out_dir / "accuracy.csv", buf.getvalue())
    _plot(rows, out_dir / "accuracy.png")

    names = list(dict.fromkeys(r["rung"] for r in rows))
    lines = [f"# Accuracy ladder: Delta f/f0 of a Hertz contact, Q = {Q_FACTOR:g}", "",
             "Error = shift - reference (time integration of the stepped down-sweep by "
             "solve_ivp DOP853, rtol 1e-10); time = seconds per evaluation at one x after "
             "compilation; compile = first call minus a warm call (0 where an earlier row "
             "already compiled the same function). Rungs 1-3 are conservative; 4-5 are the "
             "driven, damped experiment (peak frequency at the drive whose peak amplitude "
             "is x).", "",
             "| rung | " + " | ".join(f"x={x:g}" for x in xs) + " | time/eval [s] | compile [s] |",
             "|---|" + "---|" * (len(xs) + 2)]
    for name in names:
        sel = [r for r in rows if r["rung"] == name]
        if name.startswith("reference"):
            cells = [f"{r['shift']:.6f}" for r in sel]
            lines.append(f"| {name} (Delta f/f0) | " + " | ".join(cells) + " | | |")
            continue
        cells = [f"{r['error']:+.1e}" for r in sel]
        t = np.median([r["time_s"] for r in sel])
        lines.append(f"| {name} | " + " | ".join(cells)
                     + f" | {t:.2g} | {sel[0]['compile_s']:.1f} |")
    lines += ["", "## Frequency-response curves by harmonic balance (Hertz, Q = 50, E = 0.01)",
              "", "| task | compile [s] | run [s] |", "|---|---|---|"]
    lines += [f"| {n} | {c:.1f} | {t:.3f} |" for n, c, t in frc]
    lines += ["", f"## Time integration: JAX against solve_ivp ({n_freq}-frequency stepped "
              "sweep, 40 settle + 2 lock-in periods each, Hertz, Q = 20, E = 0.06: contact loss)",
              "", "max error = largest |amplitude - reference| over the sweep "
              "(reference: solve_ivp rtol 1e-11, lock-in sampled as the row; solve_ivp rows 128 "
              "samples/period)", "",
              "| integrator | max error | compile [s] | run [s] |", "|---|---|---|---|"]
    lines += [f"| {n} | {e:.1e} | {c:.1f} | {t:.3f} |" for n, e, c, t in ti]
    md = out_dir / "accuracy.md"
    write_text(md, "\n".join(lines) + "\n")
    return md
