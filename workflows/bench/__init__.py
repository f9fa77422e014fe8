"""``beadrod bench``: the measured tables of speed and accuracy (docs/performance.md)."""
