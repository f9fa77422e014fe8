"""``beadrod compare`` and ``beadrod fit`` from the dataset to the files: the fits and their
cache, the worker processes, the outputs."""
