"""Programs compiled for a few calls: without LLVM's optimisation passes.

Why: a program that runs once or twice (the fold's numerical shape probe,
:func:`inference.speed.fold.shape_parameter`) costs mostly its compilation, most of which is
LLVM's optimisation passes on XLA's CPU backend. Without them it compiles faster and runs
slower; its values differ by rounding only (no fused multiply-adds). Not for a program
that loops, such as the mode search or the sampler.
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
