"""``beadrod sweep``: simulate a scene with only the effects its plan includes."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

__all__ = ["register", "OUTPUTS", "N_FREQ"]

OUTPUTS = ("sweep.json", "frc.csv", "frc.png", "frc.pdf")
N_FREQ = (5, 2001)  # a peak needs a few points; past a few thousand the sweep takes hours


def register(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "sweep",
        help="simulate a scene's up/down swept sines with only the effects its plan includes",
        description="Build the scene's simulator from its plan (contact law per the adhesion "
        "map, losses, rod modes, contact loss -> time integration, harmonics) and sweep up "
        "and down at each drive level: resonance frequency, bead amplitude delta_a and "
        "Delta f/f0 against the lowest drive, plus each effect left out with its bound.",
    )
    p.add_argument("scene", nargs="?", type=Path, default=None,
                   help="scene TOML file (default: the paper's built-in scene)")
    p.add_argument("--builtin", metavar="NAME", default=None,
                   help="a built-in scene (paper, strong_drive, large_soft_bead, micro_bead)")
    p.add_argument("--drive", type=float, nargs="+", default=None, metavar="V",
                   help="drive levels [V] (default: 4 levels from the scene's voltage_min "
                   "to voltage_max, geometric)")
    p.add_argument("--n-freq", type=int, default=41,
                   help=f"coarse frequencies per sweep, {N_FREQ[0]} to {N_FREQ[1]} "
                   "(default: %(default)s)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--out", type=Path, default=None, metavar="DIR",
                   help="also write into DIR: sweep.json, and the frequency-response curves "
                   "(frc.csv; frc.png and frc.pdf: bead amplitude versus drive frequency, up "
                   "and down, at each drive level)")
    p.add_argument("--force", action="store_true", help="replace the files an earlier "
                   "'beadrod sweep' wrote into --out (never a file beadrod did not write)")
    p.set_defaults(func=run)
    return p


def _text(r) -> str:
    b = r.built
    lines = [f"scene {r.scene_name}: {b['contact_law']}, {r.method}"
             + (f", H = {b['harmonics']}" if b["harmonics"] else "")
             + f", rod modes {b['rod_modes']}; built: {', '.join(b['effects'])}",
             "  drive [V]   f_up [Hz]   f_down [Hz]   delta_a up [m]   df/f0 up   df/f0 down"]
    for i in range(len(r.drive_volts)):
        lines.append(f"  {r.drive_volts[i]:9.4g}  {r.up_frequency[i]:10.6g}  "
                     f"{r.down_frequency[i]:11.6g}  {r.up_amplitude[i]:14.4g}  "
                     f"{r.up_shift[i]:9.3g}  {r.down_shift[i]:10.3g}")
    lines.append("  left out (error bound on Delta f/f0):")
    for k, v in r.left_out.items():
        lines.append(f"    {k:<15} {v['error_bound']:.3g}")
    lines += [f"  note: {n}" for n in r.notes]
    return "\n".join(lines)


def _write_curves(out: Path, c: dict) -> None:
    import numpy as np
    import pandas as pd

    from beadrod.data.io import write_text
    from beadrod.workflows.figures.gallery import fig_frc, save_figure

    cols = {"frequency_Hz": c["frequency_hz"]}
    labels, amps = [], []
    for i, v in enumerate(c["drive_volts"]):
        for d in ("up", "down"):
            cols[f"delta_a_m_{d}_{v:.4g}V"] = c[d][i]
            labels.append(f"{v:.3g} V {d}")
            amps.append(c[d][i])
    write_text(out / "frc.csv", pd.DataFrame(cols).to_csv(index=False))
    save_figure(fig_frc(np.asarray(c["frequency_hz"]), amps, labels), out / "frc")


def _check_options(args: argparse.Namespace) -> None:
    import math

    from beadrod.workflows.runtime import UserError

    if not N_FREQ[0] <= args.n_freq <= N_FREQ[1]:
        raise UserError(f"--n-freq must be an integer from {N_FREQ[0]} to {N_FREQ[1]}, "
                        f"got {args.n_freq}")
    for v in args.drive or ():
        if not (math.isfinite(v) and v > 0):
            raise UserError(f"--drive: every drive level must be a finite voltage > 0 [V], "
                            f"got {v}")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from beadrod.data.io import write_json
    from beadrod.models.scene import SceneError
    from beadrod.models.scene.simulate import PlasticityError, build_simulator
    from beadrod.workflows.commands.scene import resolve_scene
    from beadrod.workflows.outdir import check_out
    from beadrod.workflows.runtime import UserError

    _check_options(args)
    if args.out is not None:
        check_out(args.out, force=args.force, outputs=OUTPUTS, command="sweep")
    try:
        scene, _ = resolve_scene(args.scene, args.builtin)
        drives = args.drive or list(np.geomspace(max(scene.voltage_min, 1e-3 *
                                                     scene.voltage_max), scene.voltage_max, 4))
        sim = build_simulator(scene)
        result = sim.run(drives, n_freq=args.n_freq)
        curves = sim.curves(drives, n_freq=2 * args.n_freq - 1) if args.out else None
    except (SceneError, ValueError, PlasticityError, RuntimeError) as exc:
        raise UserError(str(exc)) from None
    d = result.to_dict()
    if args.out is not None:
        write_json(args.out / "sweep.json", d)
        _write_curves(args.out, curves)
    print(json.dumps(d, indent=2) if args.json else _text(result))
    return 0
