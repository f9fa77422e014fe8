"""Programs compiled for a few calls: without LLVM's optimisation passes.

Why. Some of a fit's programs run once or a few times (building a fold, the multi-start
mode search): their compilation is most of their cost, and XLA's CPU backend spends most
of a compilation in LLVM's optimisation passes. Compiled without them
(``xla_backend_optimization_level = 0``), they compile faster and run slower, which for
these programs is a net gain (one core: the mode search of JKR on the embedded data 16.3
-> 13.8 s with its fold, the fold itself 11.3 -> 6.4 s with a compiled shape probe). The
values differ from optimised code's by rounding only (no fused multiply-adds). The
sampler's program keeps the optimisations: it runs thousands of times.
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
