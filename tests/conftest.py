"""Test configuration: float64 everywhere, as at every beadrod entry point."""

import jax

jax.config.update("jax_enable_x64", True)
