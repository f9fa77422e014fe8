"""Hertz with Masing hysteresis: at zero strength it is Hertz exactly; its hysteretic
share of the shift and its loss follow the element's closed forms (8/(3 pi) at m = 2,
independently of models.laws.masing); finite gradients over the prior region."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from beadrod.models.laws import hertz, hertz_hysteretic
from beadrod.models.registry import get_law

LAW = hertz_hysteretic.LAW
KW = dict(e_star=1.1e11, radius=7.9e-3, delta0=1e-7, omega0=2 * math.pi * 2700.0)
X = jnp.array([1e-3, 0.05, 0.3, 0.7, 1.0, 1.6])


@pytest.mark.parametrize("rung", ["first_order", "backbone"])
@pytest.mark.parametrize("exponent", [1.2, 2.0, 3.0])
def test_zero_strength_is_hertz_exactly(rung, exponent):
    got = LAW.physics.shifts[rung](X, strength=0.0, exponent=exponent, **KW)
    want = hertz.LAW.physics.shifts[rung](X, **KW)
    np.testing.assert_array_equal(np.asarray(got), np.asarray(want))
    loss = LAW.loss(X, linear_loss=0.02, omega_ratio=1.0 + want, background_exponent=1.0,
                    strength=0.0, exponent=exponent)
    np.testing.assert_array_equal(np.asarray(loss), 0.02 * (1.0 + np.asarray(want)))


def test_rayleigh_loop_loss_to_shift_ratio_is_8_over_3_pi():
    # m = 2: Delta k = -a U, q = 4 a U/(3 pi) (the loop's area over pi U^2), so the loss
    # over the first-order hysteretic shift |Delta k|/(2 k0) is 8/(3 pi)
    h = 1e-6
    hys = (LAW.physics.shifts["first_order"](X, strength=h, exponent=2.0, **KW)
           - hertz.LAW.physics.shifts["first_order"](X, **KW))
    loss = hertz_hysteretic.loss_increment(X, strength=h, exponent=2.0)
    np.testing.assert_allclose(np.asarray(loss) / -np.asarray(hys), 8 / (3 * math.pi),
                               rtol=1e-5)
    np.testing.assert_allclose(-np.asarray(hys), h * np.asarray(X), rtol=1e-5)


@pytest.mark.parametrize("exponent", [1.2, 1.6, 2.6, 3.0])
def test_hysteretic_share_grows_as_x_to_m_minus_1(exponent):
    h = 0.02
    base = hertz.LAW.physics.shifts["backbone"](X, **KW)
    got = LAW.physics.shifts["backbone"](X, strength=h, exponent=exponent, **KW)
    # Omega^2 = (1 + s_H)^2 - 2 h x^(m-1), written out independently
    want = np.sqrt((1 + np.asarray(base)) ** 2 - 2 * h * np.asarray(X) ** (exponent - 1)) - 1
    np.testing.assert_allclose(np.asarray(got), want, rtol=1e-12, atol=1e-15)


def test_gradients_finite_over_the_prior_region():
    def total(h, m, x):
        s = LAW.physics.shifts["backbone"](x, strength=h, exponent=m, **KW)
        return jnp.sum(s) + jnp.sum(hertz_hysteretic.loss_increment(x, strength=h, exponent=m))

    grad = jax.grad(total, argnums=(0, 1, 2))
    for h in (0.0, 1e-8, 0.05, 0.15):
        for m in (1.2, 1.2 + 1e-9, 2.0, 3.0):
            for x in (jnp.array([0.0, 1e-12, 0.5]), jnp.array([1e-6, 1.0, 1.9])):
                g = grad(h, m, x)
                assert all(np.all(np.isfinite(np.asarray(v))) for v in g), (h, m, x, g)


def test_registered_with_its_rungs_and_loss():
    law = get_law("hertz_hysteretic")
    assert law.physics.rungs == ("first_order", "backbone")
    assert not law.has_own_loss and law.physics.loss_increment is not None
    assert [p.name for p in law.params] == ["young", "strength", "exponent"]
