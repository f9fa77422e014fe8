"""NUTS and what surrounds it: the start, the draws, the convergence statistics and the gate."""
