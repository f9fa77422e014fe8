"""Fast backbones for laws that come without one (laws from users' files).

The backbone depends on a law only through its dimensionless restoring force
P'(q) = [F(delta0 (1+q)) - F(delta0)]/(F'(delta0) delta0) and the flight acceleration
F(delta0)/(F'(delta0) delta0) (:mod:`models.ladder.generic`). If these do not change with the
law's parameters or with the overlap (checked at the prior's 10 % and 90 % points of each
parameter and at overlaps 0.6 and 1.6 times the static one), the law is shape-invariant
(every pure power of delta is: a Hertz written from scratch is), its backbone is one
curve S(x), and :func:`attach_fast_backbone` tabulates it once with the tool of the
built-in tables (:mod:`models.tables.surrogate`, constant in its shape coordinate). Otherwise
the law keeps the generic quadrature: exact, but slow in NUTS; the law's description says
so.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from beadrod.models.ladder import generic
from beadrod.models.law import ContactLaw, Prior, prior_median
from beadrod.models.tables import surrogate

__all__ = ["shape_invariant", "attach_fast_backbone"]

_Q = np.array([-0.95, -0.6, -0.2, 0.3, 1.0, 2.5])   # numpy: no JAX array on import
_TOL = 1e-9
_KNOTS = 40   # per region: 1e-7 of the exact curve for a Hertz law (tests/test_lawfile.py)
# orbit rule of the samples (spectral on the contact arc, as models.tables.shape_build)
_NODES = 24
_X_MAX = surrogate.X_MAX


def _quantile(prior: Any, q: float) -> float:
    if isinstance(prior, Prior):
        lo, hi = prior.bounds()
        if np.isfinite(lo) and np.isfinite(hi):
            return lo + q * (hi - lo) if prior.kind == "uniform" else lo * (hi / lo) ** q
        return prior.median() * (0.5 if q < 0.5 else 2.0)
    return float(prior.icdf(jnp.asarray(q)))


def _signature(law: ContactLaw, kw: dict, delta0) -> np.ndarray:
    dp, _, accel = generic.restoring_force(law, delta0=delta0, **kw)
    return np.append(np.asarray(dp(_Q)), float(accel))


def shape_invariant(law: ContactLaw, scene: dict, theta: dict) -> bool:
    """True if P'(q) and the flight acceleration are the same (to 1e-9) at every tested
    parameter value and overlap (module docstring)."""
    base_kw = law.resolve(scene, theta)
    d0 = law.overlap(**base_kw)
    ref = _signature(law, base_kw, d0)
    trials = [(base_kw, d0 * f) for f in (0.6, 1.6)]
    for p in law.params:
        for q in (0.1, 0.9):
            kw = law.resolve(scene, {**theta, p.name: _quantile(p.prior, q)})
            trials.append((kw, law.overlap(**kw)))
    for kw, d in trials:
        sig = _signature(law, kw, d)
        if not (np.all(np.isfinite(sig)) and np.max(np.abs(sig - ref)) < _TOL):
            return False
    return True


def attach_fast_backbone(law: ContactLaw, scene: dict) -> ContactLaw:
    """``law`` with a tabulated 'backbone' shift if it is shape-invariant (else as is)."""
    if "backbone" in law.physics.shifts:
        return law
    theta = {p.name: prior_median(p.prior) for p in law.params}
    if not shape_invariant(law, scene, theta):
        note = ("no fast backbone: its dimensionless shape depends on its parameters or the "
                "overlap, so the backbone is the generic quadrature (exact, slow for NUTS)")
        return _noted(law, note)
    kw = law.resolve(scene, theta)
    cache: dict[str, dict] = {}

    def table() -> dict:
        # built on first use (a fit or a shift at the backbone rung), not on load: a law
        # file used at first order never pays for it. The inputs are constants, so this
        # also works while a sampler's model is being traced.
        if "t" not in cache:
            cache["t"] = _build(law, kw)
        return cache["t"]

    def fast(x, **_):
        return surrogate.evaluate(table(), jnp.clip(jnp.asarray(x, float), 0.0, _X_MAX),
                                  jnp.asarray(0.5))

    note = "backbone tabulated on first use (shape-invariant law)"
    # the table holds its x = 2 value beyond; the inference counts no point there
    physics = dataclasses.replace(
        law.physics, shifts={**law.physics.shifts, "backbone": fast},
        domains={**law.physics.domains,
                 "backbone": lambda x, **_: surrogate.within_amplitude(x, _X_MAX)})
    return _noted(dataclasses.replace(law, physics=physics), note)


def _noted(law: ContactLaw, note: str) -> ContactLaw:
    """``law`` with ``note`` appended to its description."""
    text = f"{law.presentation.description}; {note}".strip("; ")
    return dataclasses.replace(
        law, presentation=dataclasses.replace(law.presentation, description=text))


def _build(law: ContactLaw, kw: dict) -> dict:
    d0 = law.overlap(**kw)
    exact_jit = jax.jit(lambda x: generic.backbone_shift(law, x, delta0=d0, nodes=_NODES, **kw))

    def exact(x):  # one padded shape: one compilation for both regions
        x = np.asarray(x, float)
        return np.asarray(exact_jit(jnp.asarray(np.resize(x, _KNOTS))))[:x.size]

    def kink(p):
        # on the flight side of the onset (generic.contact_loss_onset says why)
        a1, s1 = generic.contact_loss_onset(law, delta0=d0, **kw)
        return np.full(p.shape, float(a1)), np.full(p.shape, float(s1))

    c = float(generic.lindstedt_coefficient(law, delta0=d0, **kw))
    spec = surrogate.BackboneSpec(
        p_lo=0.0, p_hi=1.0, m_cheb=1, n_knots=_KNOTS, x_max=_X_MAX,
        exact=lambda x, p, xc: exact(x), kink=kink, lindstedt=lambda p: np.full(p.shape, c))
    with jax.ensure_compile_time_eval():
        return surrogate.build(spec)
