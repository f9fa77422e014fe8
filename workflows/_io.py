"""Atomic output for the CLI layer: a re-export of :mod:`data.io`, which owns files."""

from beadrod.data.io import atomic_path, write_bytes, write_json, write_text

__all__ = ["atomic_path", "write_text", "write_bytes", "write_json"]
