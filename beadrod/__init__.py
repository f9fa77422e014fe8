"""beadrod: Bayesian model comparison and parameter inference for a bead resting on a rod.

The packages: ``beadrod.models`` (contact laws and their physics, pure JAX),
``beadrod.data`` (datasets: load, validate, simulate), ``beadrod.inference`` (NumPyro
models, sampling, evidence) and ``beadrod.workflows`` (the ``beadrod`` command line).
"""
