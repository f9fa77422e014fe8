"""Every figure beadrod draws: the physics, the posterior predictive shift, the inference
checks, and the colours and labels they share (:mod:`.styles`)."""
