"""InferenceData on disk: netCDF written atomically, read back fully loaded.

The inference layer returns InferenceData and writes nothing; the workflows persist it
here. Writing goes to a temporary file in the target folder and is renamed onto the
target (data.io.atomic_path), so an interrupted run never leaves a truncated .nc file.
"""

from __future__ import annotations

import os
from pathlib import Path

import arviz as az

from beadrod.data.io import atomic_path

__all__ = ["save_idata", "load_idata"]


def save_idata(idata: az.InferenceData, path: str | os.PathLike) -> Path:
    """Write ``idata`` to netCDF at ``path`` atomically; returns the path."""
    with atomic_path(path) as tmp:
        # uncompressed: float64 draws barely compress, and zlib slows the write
        idata.to_netcdf(str(tmp), compress=False)
    return Path(path)


def load_idata(path: str | os.PathLike) -> az.InferenceData:
    """Read an InferenceData written by :func:`save_idata` (fully loaded, file closed)."""
    idata = az.from_netcdf(str(path))
    idata.load()
    return idata
