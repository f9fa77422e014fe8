"""Stored interpolation tables and the surrogates read from them: how a backbone that costs
a quadrature per point becomes fast enough for a sampler.

:mod:`.surrogate` builds a law's backbone surrogate from its table specification
(``ContactLaw.physics.table``); :mod:`.shape_read` reads the stored tables, :mod:`.shape_build`
builds them for every law that has a specification. Each module says what it stores and the
error it was measured to.
"""
