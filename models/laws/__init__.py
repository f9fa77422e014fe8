"""The contact laws, one module each; a law with several modules has a folder of its own.

Each module defines ``LAW`` (a :class:`beadrod.models.law.ContactLaw`); :data:`BUILTIN`
lists them in the order every table shows them, and :mod:`beadrod.models.registry` serves
them (with the laws users load from files). This folder is the only place in
``beadrod.models`` that names a law.
"""
