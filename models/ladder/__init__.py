"""The accuracy ladder and its numerics: the rungs from the first-order shift up to time
integration, for a power law (closed forms, :mod:`.powerlaw_ladder`) and for any law from
its force alone (:mod:`.generic`, :mod:`.generic_dynamics`).

No law is named here: a rung takes a law object or a law's functions.
"""
