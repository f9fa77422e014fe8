"""Evidence and comparison: log Z by bridge sampling, nested sampling and SMC, the
ranking and LOO, the Q-versus-shift tension, and simulation-based calibration."""
