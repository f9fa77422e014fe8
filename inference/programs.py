"""Programs compiled for a few calls: without LLVM's optimisation passes.

Why. A program that runs once or twice (the fold's numerical shape probe,
:func:`inference.fold.shape_parameter`, where the curve's program leaves it open)
costs its compilation, and XLA's CPU backend spends most of a compilation in LLVM's
optimisation passes. Compiled without them (``xla_backend_optimization_level = 0``) it
compiles faster and runs slower (one core: JKR's shape probe 3.9 -> 3.2 s). The values
differ from optimised code's by rounding only (no fused multiply-adds). Not for a program
that loops: the multi-start mode search compiled so took 2.5 s less for JKR with an empty
compilation cache but 1.5-1.7 s more for every law with a warm one (its 16 x 200 Adam
steps ran slower), and the fold's probe of its cells 0.6 s less cold; the sampler's
program runs thousands of times.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax

__all__ = ["one_shot"]


def one_shot(fn: Callable, *example: Any) -> Callable:
    """``fn`` compiled without LLVM's optimisation passes for arguments shaped and typed as
    ``example`` (the compiled program: call it with such arguments)."""
    lowered = jax.jit(fn).lower(*example)
    return lowered.compile(compiler_options={"xla_backend_optimization_level": 0})
