"""Shared command line of the stored interpolation tables
(``python -m beadrod.models.X --rebuild``)."""

from __future__ import annotations

import argparse
import pathlib
import time
from collections.abc import Callable, Sequence

import numpy as np

__all__ = ["rebuild_cli"]


def rebuild_cli(argv: list[str] | None, *, prog: str, description: str,
                build: Callable[..., dict[str, np.ndarray]], path: pathlib.Path,
                parts: Sequence[str] | None = None) -> int:
    """Parse ``--rebuild [--out FILE]``; rebuild the table with float64 JAX and write it
    atomically (temporary file, then rename)."""
    p = argparse.ArgumentParser(prog=prog, description=description)
    p.add_argument("--rebuild", action="store_true",
                   help=f"recompute the table and write {path}")
    p.add_argument("--out", type=pathlib.Path, default=path,
                   help="where to write the table (default: the packaged file)")
    if parts is not None:  # a file holding several laws' tables: rebuild some of them
        p.add_argument("--law", action="append", choices=list(parts),
                       help="rebuild only this law's table (repeatable; default: all)")
    args = p.parse_args(argv)
    if not args.rebuild:
        p.print_help()
        return 0
    import jax

    jax.config.update("jax_enable_x64", True)
    t0 = time.perf_counter()
    table = build() if parts is None else build(tuple(args.law or parts))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_name(args.out.name + ".tmp.npz")
    np.savez(tmp, **table)
    tmp.replace(args.out)
    print(f"wrote {args.out} ({args.out.stat().st_size / 1e6:.2f} MB) "
          f"in {time.perf_counter() - t0:.1f} s")
    return 0
