"""Importing models/ makes no JAX array: float64 is switched on at the entry points and in
tests/conftest.py, after the imports, so an array made on import would stay float32 (and
would start JAX's backend on import)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_PROBE = """
import importlib, pkgutil, jax, models
found = []
for m in pkgutil.iter_modules(models.__path__):
    mod = importlib.import_module("models." + m.name)
    for name, value in vars(mod).items():
        values = value if isinstance(value, (tuple, list)) else (value,)
        if any(isinstance(v, jax.Array) for v in values):
            found.append(f"models.{m.name}.{name}")
print("\\n".join(found))
"""


def test_no_jax_array_is_made_on_import():
    env = {**os.environ, "JAX_ENABLE_X64": "0"}
    out = subprocess.run([sys.executable, "-c", _PROBE], cwd=ROOT, env=env,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "", f"module-level JAX arrays: {out.stdout.split()}"
