"""Test configuration: float64 everywhere, as at every beadrod entry point; and a private
persistent compilation cache.

The CLI entry points (run in-process by the tests) turn on JAX's persistent cache, by
default in the user's ``~/.cache/beadrod/jax``. The tests must neither read what other
runs left there (entries from other flags, other versions, experiments) nor write into a
user's home: every test session gets its own cache directory. The controlling process
sets it before xdist starts its workers, which inherit it, so a program compiled in one
worker is read by the others.
A cache the caller names in BEADROD_JAX_CACHE (a path, or "" for none) is respected.
"""

import os
import tempfile

import jax

jax.config.update("jax_enable_x64", True)

if "BEADROD_JAX_CACHE" not in os.environ:
    os.environ["BEADROD_JAX_CACHE"] = os.path.join(tempfile.gettempdir(),
                                                   f"beadrod-test-jax-pid{os.getpid()}")
