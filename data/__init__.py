"""beadrod data: dataset format and validation, plausibility bounds, file I/O (atomic
writes, strict CSV reading), protocol processing, resonance extraction, and the
synthetic worlds shipped as the embedded datasets. Imports only ``models``."""

from beadrod.data.extract import CurveFit, extract_resonance, read_curve
from beadrod.data.load import Dataset, load_dataset, write_dataset
from beadrod.data.process import (
    ProcessedDataset,
    default_path,
    load_default,
    overlap_from_f0,
    process,
    static_overlap_weight,
)
from beadrod.data.schema import DataError
from beadrod.data.synth import DEFAULT_SEED, generate, world_names, write_world

__all__ = [
    "CurveFit",
    "DEFAULT_SEED",
    "DataError",
    "Dataset",
    "ProcessedDataset",
    "default_path",
    "extract_resonance",
    "generate",
    "load_dataset",
    "load_default",
    "overlap_from_f0",
    "process",
    "read_curve",
    "static_overlap_weight",
    "world_names",
    "write_dataset",
    "write_world",
]
