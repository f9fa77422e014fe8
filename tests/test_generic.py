"""The generic numerics (models.ladder.generic: any force law) against the fast paths: closed
forms to 1e-10, the power-law backbone quadrature to 1e-10, the JKR first-order table."""

import jax.numpy as jnp
import numpy as np
import pytest

from beadrod.models import registry
from beadrod.models.ladder import backbone, first_order, generic
from beadrod.models.law import RungUnavailable
from beadrod.models.laws import jkr

SCENE = {"radius": 7.938e-3, "young": 200e9, "poisson": 0.27, "load": 0.1582,
         "mass": 0.01613, "gravity": 9.81}
X = jnp.array([0.02, 0.3, 0.8, 0.99, 0.999, 1.0, 1.3, 1.9])


def _kw(name, **theta):
    law = registry.get_law(name)
    kw = law.resolve(SCENE, theta)
    return law, kw, law.overlap(**kw)


def test_static_overlap_and_frequency_map_against_closed_forms():
    law, kw, d0 = _kw("hertz", young=200e9)
    assert float(generic.static_overlap(law, **kw)) == pytest.approx(float(d0), rel=1e-12)
    for f0 in (2400.0, 2700.0, 3100.0):
        assert float(generic.overlap_from_frequency(law, f0, **kw)) == pytest.approx(
            1.5 * SCENE["load"] / (SCENE["mass"] * (2 * np.pi * f0) ** 2), rel=1e-12)


@pytest.mark.parametrize("n", [1.05, 1.3, 1.5, 2.0, 2.6, 3.0])
def test_first_order_powerlaw_closed_form(n):
    law, kw, d0 = _kw("powerlaw", n=n, delta0_ref_log=np.log(55e-9))
    got = generic.first_order_shift(law, X, delta0=d0, **kw)
    np.testing.assert_allclose(got, first_order.first_order_powerlaw(X, n), rtol=0, atol=1e-10)


def test_first_order_hertz_and_jkr():
    law, kw, d0 = _kw("hertz", young=200e9)
    np.testing.assert_allclose(generic.first_order_shift(law, X, delta0=d0, **kw),
                               first_order.first_order_hertz(X), atol=1e-10)
    law, kw, d0 = _kw("jkr", young=200e9, gamma=0.7)
    ref = jkr.contact.shift_first_order(X, load=kw["load"], e_star=kw["e_star"], radius=kw["radius"],
                                gamma=0.7)
    np.testing.assert_allclose(generic.first_order_shift(law, X, delta0=d0, **kw), ref,
                               atol=1e-10)
    # the tabulated fast path, to the table's stated error (2e-7)
    np.testing.assert_allclose(law.shift(X, rung="first_order", **kw), ref, atol=2e-7)


@pytest.mark.slow  # the generic backbone compiles for about a minute
@pytest.mark.parametrize("n", [1.5, pytest.param(1.05, marks=pytest.mark.slow),
                               pytest.param(2.2, marks=pytest.mark.slow),
                               pytest.param(3.0, marks=pytest.mark.slow)])
def test_backbone_generic_against_powerlaw_quadrature(n):
    law, kw, d0 = _kw("powerlaw", n=n, delta0_ref_log=np.log(55e-9))
    got = generic.backbone_shift(law, X, delta0=d0, **kw)
    np.testing.assert_allclose(got, backbone.backbone_shift(X, n), atol=1e-10)
    # the table (fast path) to its stated error, 1e-6
    np.testing.assert_allclose(law.shift(X, rung="backbone", **kw), got, atol=1e-6)


def test_lindstedt_coefficient_generic():
    for n in (1.5, 2.5):
        law, kw, d0 = _kw("powerlaw", n=n, delta0_ref_log=np.log(55e-9))
        c = float(generic.lindstedt_coefficient(law, delta0=d0, **kw))
        assert c == pytest.approx(-(n - 1) * (2 * n + 1) / 48, rel=1e-10)


def test_rung_refused_not_swapped():
    law, kw, d0 = _kw("dmt", young=200e9, gamma=0.7)
    with pytest.raises(RungUnavailable, match="paper_eq25"):
        law.shift(X, rung="paper_eq25", **kw)


FULL_SCENE = {**SCENE, "roughness_rms": 25e-9, "surface_energy": 0.05}


@pytest.mark.parametrize("name", registry.law_names())
def test_frequency_at_inverts_overlap_at(name):
    # the f0 -> delta0 map every model conditions on, and its inverse (predictive f0)
    from beadrod.models.law import prior_median

    law = registry.get_law(name)
    kw = law.resolve(FULL_SCENE, {p.name: prior_median(p.prior) for p in law.params})
    f0 = jnp.array([2400.0, 2700.0, 3100.0])
    back = law.frequency_at(law.overlap_at(f0, **kw), **kw)
    np.testing.assert_allclose(back, f0, rtol=1e-10)


def test_inverse_frequency_maps_against_the_hertz_closed_form():
    law, kw, _ = _kw("hertz", young=200e9)
    d = jnp.array([30e-9, 55e-9, 90e-9])
    exact = np.sqrt(1.5 * SCENE["load"] / (SCENE["mass"] * d)) / (2 * np.pi)
    np.testing.assert_allclose(generic.stiffness_scale_frequency(law, d, **kw), exact,
                               rtol=1e-12)
    np.testing.assert_allclose(generic.frequency_from_overlap(law, d, **kw), exact,
                               rtol=1e-12)
