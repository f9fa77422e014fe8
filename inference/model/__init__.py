"""The NumPyro model of a law on the data: priors, the overlap map, the observation models
and the law-free baseline."""
