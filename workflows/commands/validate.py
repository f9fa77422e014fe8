"""``beadrod validate DIR``: load and process a dataset, print what it holds.

Bad data raise :class:`data.DataError` naming the file, the line (as a text editor
numbers it) and the column; the CLI prints it and exits non-zero. Everything the
protocol leaves out is listed: excluded drive sweeps with their lines and reason,
unused cells, protocols without a reference Q, and the caveats of curve fits (the
``warning:`` lines are those a fit logs too).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

__all__ = ["register", "summary"]


def summary(pd_, dataset, *, convention: str = "weight", elapsed_s: float | None = None) -> str:
    """Human-readable summary of a processed dataset."""
    t = dataset.table
    lines = [f"dataset: {dataset.path}", f"scene: {getattr(pd_.scene, 'name', '?')}",
             f"sha256: {pd_.data_hash}",
             f"protocols: {pd_.n_protocols}   sweeps: {len(t)}"]
    counts = t.groupby(["kind", "direction"]).size()
    for (kind, direction), n in counts.items():
        lines.append(f"  {kind:9s} {direction:4s}: {n}")
    q = pd_.q_ref[np.isfinite(pd_.q_ref)]
    lines.append(f"f0: {pd_.f0.min():.1f} - {pd_.f0.max():.1f} Hz; Q_ref: "
                 + (f"{q.min():.1f} - {q.max():.1f} ({q.size} of {pd_.n_protocols})" if q.size
                    else "none"))
    opts = pd_.options
    lines.append(f"drive sweeps kept: {pd_.n_drive}; excluded: {len(pd_.excluded)}"
                 f" (2 % rule {'on' if opts.get('two_percent_rule') else 'off'}; shift "
                 f"relative to the {opts.get('shift_reference')} reference)")
    from beadrod.workflows.pipeline.outputs import exclusions  # one list, shared with the report

    for e in exclusions(pd_.excluded):
        lines.append(f"  {e['protocol']}: {e['n']} drive sweeps dropped "
                     f"({_lines(e['lines'])}): {e['reason']}")
    if pd_.n_drive:
        x = pd_.normalized_amplitude(convention)
        d0 = pd_.delta0(convention)
        how = "Hertz under the load" if convention == "weight" else "from f0"
        lines.append(f"delta_a/delta0 ({how}"
                     f", delta0 {d0.min() * 1e9:.1f}-{d0.max() * 1e9:.1f} nm): "
                     f"{x.min():.3g} - {x.max():.3g}")
        lines.append(f"Delta f/f0: {pd_.drive_shift.min():.4f} - {pd_.drive_shift.max():.4f}")
    for warning in getattr(pd_, "warnings", ()):
        lines.append(f"warning: {warning}")
    for note in dataset.curve_notes:
        lines.append(f"curve: {note}")
    for note in pd_.notes:
        lines.append(f"note: {note}")
    if dataset.truth is not None:
        lines.append(f"truth.json: synthetic world {dataset.truth.get('world', '?')!r}, "
                     f"seed {dataset.truth.get('seed', '?')}")
    if elapsed_s is not None:
        lines.append(f"loaded and processed in {elapsed_s * 1e3:.0f} ms")
    return "\n".join(lines)


def _lines(values) -> str:
    """``line 9`` or ``lines 9, 11, 13`` (the first ten, then a count)."""
    ls = sorted(int(v) for v in values)
    if len(ls) == 1:
        return f"line {ls[0]}"
    more = f" and {len(ls) - 10} more" if len(ls) > 10 else ""
    return "lines " + ", ".join(str(x) for x in ls[:10]) + more


def _run(args: argparse.Namespace) -> int:
    from beadrod.data.load import load_dataset
    from beadrod.data.process import process

    t0 = time.perf_counter()
    ds = load_dataset(args.dir)
    pd_ = process(ds, two_percent_rule=not args.no_two_percent_rule,
                  shift_reference=args.shift_reference)
    elapsed = time.perf_counter() - t0
    print(summary(pd_, ds, convention=args.delta0, elapsed_s=elapsed))
    return 0


def register(sub) -> None:
    p = sub.add_parser(
        "validate",
        help="check a dataset folder and summarise it",
        description="Load DIR (measurements.csv + scene.toml), validate every row, apply the "
        "paper's protocol (first reference gives f0 and Q; the 2 %% rule on later references), "
        "and print protocols, sweeps per kind and direction, exclusions with reasons and the "
        "amplitude range. Exits non-zero naming file, line and column when the data are bad.",
    )
    p.add_argument("dir", help="dataset folder (or its measurements.csv)")
    p.add_argument("--no-two-percent-rule", action="store_true",
                   help="keep drive steps after a reference drifted by more than 2 %%")
    p.add_argument("--shift-reference", choices=("first", "preceding"), default="first",
                   help="Delta f/f0 against the protocol's first reference (paper) or the "
                   "preceding one (default: %(default)s)")
    p.add_argument("--delta0", choices=("weight", "f0"), default="weight",
                   help="delta0 for delta_a/delta0: Hertz under the weight (paper) or from each "
                   "protocol's f0 (default: %(default)s)")
    p.set_defaults(func=_run)
