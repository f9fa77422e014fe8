"""Test configuration: float64 everywhere, as at every beadrod entry point; XLA's CPU
backend at optimisation level 0 for the default suite (compiling dominates it); and a
private persistent compilation cache.

The CLI entry points (run in-process by the tests) turn on JAX's persistent cache, by
default in the user's ``~/.cache/beadrod/jax``. The tests must neither read what other
runs left there (entries from other flags, other versions, experiments) nor write into a
user's home: every test session gets its own cache directory. The controlling process
sets it before xdist starts its workers, which inherit it, so a program compiled in one
worker is read by the others.
A cache the caller names in BEADROD_JAX_CACHE (a path, or "" for none) is respected.
Every worker uses it from its first program on, not only once a test has run a command:
the suite compiles the same programs again and again (a law's fit on the same data; the
sampler's seed is an argument), and reading one costs a small part of compiling it.
Only programs that took 0.5 s or more to compile are kept (a command keeps every one):
JAX writes an entry in place, without a lock, so a process can read an entry another is
still writing (the comparison's worker processes start in step and compile the same
small programs op by op), which costs a recompile and a warning on the command's stderr.
"""

import gc
import os
import tempfile

import jax
import pytest

jax.config.update("jax_enable_x64", True)

if "BEADROD_JAX_CACHE" not in os.environ:
    os.environ["BEADROD_JAX_CACHE"] = os.path.join(tempfile.gettempdir(),
                                                   f"beadrod-test-jax-pid{os.getpid()}")
_CACHE_DIR = os.environ["BEADROD_JAX_CACHE"] or None
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.5")


def _use_the_cache() -> None:
    # as workflows.runtime.enable_x64 sets it for a command (which keeps the threshold
    # above); `beadrod bench` switches it off in its process, this switches it back
    if _CACHE_DIR and jax.config.jax_compilation_cache_dir != _CACHE_DIR:
        jax.config.update("jax_compilation_cache_dir", _CACHE_DIR)
        jax.config.update("jax_persistent_cache_min_compile_time_secs",
                          float(os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"]))


_use_the_cache()


def pytest_configure(config):
    # XLA's CPU backend without LLVM's optimisation passes for the default suite: it runs
    # tiny fits and many small programs, so compiling is most of its time (on the 2-core
    # machine the suite took 15:39 with them, 11:44 without; the numbers are the same
    # code's to rounding). What it cannot see: rounding only optimised code has (fused
    # multiply-adds); the slow checks keep the optimisations, as every command and
    # benchmark does. Set before any backend starts (jax reads it then), in the
    # controlling process: xdist workers and the comparison's worker processes inherit
    # it. A caller's own setting is kept.
    opt = "--xla_backend_optimization_level"
    if "not slow" in (config.option.markexpr or "") and opt not in os.environ.get(
            "XLA_FLAGS", ""):
        os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {opt}=0".strip()


# Each compiled XLA:CPU program holds a few memory mappings until JAX drops it, and a long
# test worker compiles thousands of programs (every test builds fresh closures). Linux
# caps a process at vm.max_map_count mappings (65,530 by default), and past it every mmap
# fails, LLVM's JIT and the cache deserializer's included; slow-suite workers reached
# 37,000 within one test. Dropping JAX's caches once the count passes 16,000 releases
# them (measured: 1,400 -> 510 maps after 300 programs; 37,120 -> 1,584 in the suite);
# it costs a recompile, or a persistent-cache read, of what the next test uses.
def _map_count() -> int:
    try:
        with open("/proc/self/maps", "rb") as maps:
            return sum(1 for _ in maps)
    except OSError:  # not Linux: no such cap to guard
        return 0


_MAP_GUARD = 16_000


@pytest.fixture(autouse=True)
def _release_compiled_programs(request):
    yield
    _use_the_cache()
    before = after = _map_count()
    if before > _MAP_GUARD:
        jax.clear_caches()
        gc.collect()
        after = _map_count()
    log = os.environ.get("BEADROD_TEST_MAPLOG")  # to watch the guard work
    if log:
        with open(log, "a") as out:
            out.write(f"{os.getpid()} {request.node.nodeid} {before} {after}\n")
