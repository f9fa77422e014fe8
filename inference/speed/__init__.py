"""What makes a sampler step fast without changing its value: the folds of the sweep curve,
the branch with its own derivative, and programs compiled for a few calls."""
