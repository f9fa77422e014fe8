"""JKR and DMT adhesive contact (issue 2, item 5): paper numbers, independent mpmath/scipy
references for every inverse, Eq. 19 against autodiff of the parametric pair, and finite
implicit-function gradients up to the approach to pull-off."""

import math

import jax
import jax.numpy as jnp
import mpmath as mp
import numpy as np
import pytest
from scipy import integrate, optimize

from beadrod.models.laws import dmt, jkr

R_BEAD, RHO, NU, G, GAMMA = 7.938e-3, 7700.0, 0.27, 9.80665, 0.7
MASS = 4.0 / 3.0 * math.pi * R_BEAD**3 * RHO
LOAD = MASS * G


def estar(young):
    return young / (2 * (1 - NU**2))


P = dict(radius=R_BEAD, gamma=GAMMA)


# --- independent references (mpmath, typed from JKR 1971 in terms of a) ----------------------

def mp_delta(a, es, r=R_BEAD, g=GAMMA):
    return a**2 / r - mp.sqrt(4 * mp.pi * g * a / es)


def mp_force(a, es, r=R_BEAD, g=GAMMA):
    return 4 * es * a**3 / (3 * r) - mp.sqrt(16 * mp.pi * g * es * a**3)


def mp_state_under_load(load, es):
    """a, delta0, K0 = (dF/da)/(d delta/da) with a from findroot on F(a) = load."""
    with mp.workdps(30):
        a0 = (3 * R_BEAD * load / (4 * es)) ** (mp.mpf(1) / 3) * 1.5  # above the Hertz radius
        a = mp.findroot(lambda a: mp_force(a, es) - load, a0)
        k = mp.diff(lambda a: mp_force(a, es), a) / mp.diff(lambda a: mp_delta(a, es), a)
        return a, mp_delta(a, es), k


@pytest.mark.parametrize("young", [190e9, 210e9])
def test_paper_static_state(young):
    es = estar(young)
    a_ref, d_ref, k_ref = mp_state_under_load(LOAD, es)
    a = float(jkr.contact.contact_radius(LOAD, e_star=es, **P))
    d0 = float(jkr.contact.static_overlap(LOAD, e_star=es, **P))
    k0 = float(jkr.contact.linear_stiffness(LOAD, e_star=es, **P))
    f0 = float(jkr.contact.linear_frequency(LOAD, MASS, e_star=es, **P))
    assert a == pytest.approx(float(a_ref), rel=1e-12)
    assert d0 == pytest.approx(float(d_ref), rel=1e-11)
    assert k0 == pytest.approx(float(k_ref), rel=1e-10)
    assert f0 == pytest.approx(math.sqrt(float(k_ref) / MASS) / (2 * math.pi), rel=1e-10)
    # The paper's JKR delta0 = 67-62 nm, f0 = 2.74-2.86 kHz are NOT reproduced by its own
    # formulas (Eqs. 16-19 with the corrected Eq. 16): 63.8-59.7 nm and 2.70-2.79 kHz.
    expect = {190e9: (63.8, 2700), 210e9: (59.7, 2791)}[young]
    assert round(d0 * 1e9, 1) == expect[0]
    assert round(f0) == expect[1]


def test_paper_ranges_not_reproduced_with_e_over_two():
    """Dropping (1 - nu^2) (E* = E/2) hits the paper's delta0 range but not its f0 range."""
    d = [float(jkr.contact.static_overlap(LOAD, e_star=y / 2, **P)) * 1e9 for y in (190e9, 210e9)]
    f = [float(jkr.contact.linear_frequency(LOAD, MASS, e_star=y / 2, **P)) for y in (190e9, 210e9)]
    assert round(d[0]) == 67 and round(d[1]) == 63
    assert f[0] < 2740 and f[1] < 2860


def test_eq19_equals_parametric_derivative():
    es = estar(200e9)
    ac = float(jkr.contact.critical_radius(e_star=es, **P))
    a = jnp.array([0.6, 0.9, 1.0, 1.3, 2.0, 5.0, 40.0]) * ac
    dfa = jax.jit(jax.vmap(jax.grad(lambda a: jkr.contact.force_from_contact_radius(a, e_star=es, **P))))(a)
    dda = jax.jit(jax.vmap(jax.grad(lambda a: jkr.contact.overlap_from_contact_radius(a, e_star=es, **P))))(a)
    k19 = jkr.contact.stiffness_from_contact_radius(a, e_star=es, **P)
    np.testing.assert_allclose(np.asarray(k19), np.asarray(dfa / dda), rtol=1e-12, atol=1e-6)
    assert float(k19[2]) == pytest.approx(0.0, abs=1e-6)  # K = 0 at ac (load-controlled pull-off)
    assert float(jkr.contact.force_from_contact_radius(ac, e_star=es, **P)) == pytest.approx(
        -3 * math.pi * GAMMA * R_BEAD, rel=1e-12)


def test_contact_radius_from_overlap_vs_findroot():
    es = estar(190e9)
    dmin = float(jkr.contact.minimum_overlap(e_star=es, **P))
    amin = float(jkr.contact.critical_radius(e_star=es, **P)) / 9 ** (1 / 3)
    assert float(mp_delta(mp.mpf(amin), es)) == pytest.approx(dmin, rel=1e-12)
    deltas = [dmin * (1 - 1e-6), dmin * 0.5, -1e-9, 0.0, 1e-9, 60e-9, 1e-6, 1e-4]
    got = np.asarray(jkr.contact.contact_radius_from_overlap(jnp.array(deltas), e_star=es, **P))
    for d, a in zip(deltas, got):
        with mp.workdps(30):
            # bracket on the monotone branch [a_min, large]
            ref = mp.findroot(lambda a, d=d: mp_delta(a, es) - d, (mp.mpf(amin), mp.mpf(1e-2)),
                              solver="anderson")
        assert a == pytest.approx(float(ref), rel=1e-9)
    # round trip delta -> a -> delta over 16 decades of the scaled overlap
    wide = jnp.concatenate([dmin * jnp.array([0.999999, 0.7, 0.2]), jnp.logspace(-12, 4, 33) * 1e-8])
    back = jkr.contact.overlap_from_contact_radius(
        jkr.contact.contact_radius_from_overlap(wide, e_star=es, **P), e_star=es, **P)
    np.testing.assert_allclose(np.asarray(back), np.asarray(wide), rtol=1e-12, atol=1e-22)
    # below the displacement-controlled pull-off: separated
    assert float(jkr.contact.contact_radius_from_overlap(2 * dmin, e_star=es, **P)) == 0.0
    assert float(jkr.contact.force(2 * dmin, e_star=es, **P)) == 0.0
    # F at delta_min is -(5/9) Fc
    fmin = float(jkr.contact.force(dmin * (1 - 1e-12), e_star=es, **P))
    assert fmin == pytest.approx(-5 / 9 * 3 * math.pi * GAMMA * R_BEAD, rel=1e-5)


def test_force_round_trip_and_root_gradient():
    es = estar(210e9)
    d0 = jkr.contact.static_overlap(LOAD, e_star=es, **P)
    assert float(jkr.contact.force(d0, e_star=es, **P)) == pytest.approx(LOAD, rel=1e-11)
    # d(delta0)/dF = 1/K0 (the closed-form static overlap differentiates consistently)
    dd = jax.grad(lambda F: jkr.contact.static_overlap(F, e_star=es, **P))(LOAD)
    assert float(dd) == pytest.approx(1 / float(jkr.contact.linear_stiffness(LOAD, e_star=es, **P)), rel=1e-10)
    # implicit gradient dF/d(delta) = K (Eq. 19) and vs. mpmath derivative of the inverse
    k = jax.grad(lambda d: jkr.contact.force(d, e_star=es, **P))(d0)
    assert float(k) == pytest.approx(float(jkr.contact.linear_stiffness(LOAD, e_star=es, **P)), rel=1e-10)
    da = jax.grad(lambda d: jkr.contact.contact_radius_from_overlap(d, e_star=es, **P))(d0)
    a = float(jkr.contact.contact_radius(LOAD, e_star=es, **P))
    ref = 1 / mp.diff(lambda a: mp_delta(a, es), mp.mpf(a))
    assert float(da) == pytest.approx(float(ref), rel=1e-9)
    # gradients w.r.t. the parameters: finite differences of the solve
    for name, val in (("e_star", es), ("gamma", GAMMA), ("radius", R_BEAD)):
        kw = dict(e_star=es, radius=R_BEAD, gamma=GAMMA)

        def fa(v, name=name, kw=kw):
            return jkr.contact.contact_radius_from_overlap(40e-9, **{**kw, name: v})

        g = float(jax.grad(fa)(val))
        h = val * 1e-6
        fd = (float(fa(val + h)) - float(fa(val - h))) / (2 * h)
        assert g == pytest.approx(fd, rel=1e-6), name


def test_gradients_finite_near_smallest_stable_load():
    es = estar(200e9)
    fc = 3 * math.pi * GAMMA * R_BEAD
    loads = jnp.array([-fc * (1 - 1e-9), -fc * (1 - 1e-4), -0.5 * fc, 0.0, LOAD, 10.0])
    for fn in (jkr.contact.static_overlap, jkr.contact.linear_stiffness, jkr.contact.contact_radius):
        g = jax.jit(jax.vmap(jax.grad(lambda F, e, gm, fn=fn: fn(F, e_star=e, radius=R_BEAD, gamma=gm),
                                      argnums=(0, 1, 2))))(loads, jnp.full(6, es), jnp.full(6, GAMMA))
        for arr in g:
            assert np.all(np.isfinite(np.asarray(arr))), fn.__name__
    # at exactly -Fc (and below) there is no divergence escaping as NaN/inf
    g = jax.grad(lambda F: jkr.contact.static_overlap(F, e_star=es, **P))(-fc)
    assert np.isfinite(float(g))
    # overlap-side approach to displacement-controlled pull-off
    dmin = float(jkr.contact.minimum_overlap(e_star=es, **P))
    ds = jnp.array([dmin * (1 - 1e-6), dmin * 0.9, 0.0])
    g = jax.jit(jax.vmap(jax.grad(lambda d, e: jkr.contact.force(d, e_star=e, **P), argnums=(0, 1)),
                         in_axes=(0, None)))(ds, es)
    assert all(np.all(np.isfinite(np.asarray(v))) for v in g)


def test_inverse_from_frequency():
    for young in (190e9, 210e9):
        es = estar(young)
        f0 = jkr.contact.linear_frequency(LOAD, MASS, e_star=es, **P)
        assert float(jkr.contact.modulus_from_frequency(f0, LOAD, MASS, **P)) == pytest.approx(es, rel=1e-12)
        d0 = float(jkr.contact.overlap_from_frequency(f0, LOAD, MASS, **P))
        assert d0 == pytest.approx(float(jkr.contact.static_overlap(LOAD, e_star=es, **P)), rel=1e-12)
    g = jax.grad(lambda f: jkr.contact.overlap_from_frequency(f, LOAD, MASS, **P))(2750.0)
    assert np.isfinite(float(g)) and float(g) < 0


def _jkr_k_reference(delta, es):
    """Independent numpy/scipy tangent stiffness: brentq for a, analytic dF/da / d delta/da."""
    amin = (math.pi * GAMMA * R_BEAD**2 / (4 * es)) ** (1 / 3)
    f = lambda a: a**2 / R_BEAD - math.sqrt(4 * math.pi * GAMMA * a / es) - delta
    a = optimize.brentq(f, amin, 1e-2, xtol=1e-20, rtol=1e-15)
    dfa = 4 * es * a**2 / R_BEAD - 1.5 * math.sqrt(16 * math.pi * GAMMA * es * a)
    dda = 2 * a / R_BEAD - 0.5 * math.sqrt(4 * math.pi * GAMMA / (es * a))
    return dfa / dda


def test_jkr_first_order_shift_vs_scipy():
    es = estar(210e9)
    d0 = float(jkr.contact.static_overlap(LOAD, e_star=es, **P))
    k0 = _jkr_k_reference(d0, es)
    xs = [0.2, 0.6, 1.0]
    shift = jax.jit(lambda x, e, gm: jkr.contact.shift_first_order(x, load=LOAD, e_star=e, radius=R_BEAD,
                                                           gamma=gm))
    got = np.asarray(shift(jnp.array(xs), es, GAMMA))
    for x, v in zip(xs, got):
        ref, _ = integrate.quad(lambda t, x=x: _jkr_k_reference(d0 * (1 + x * math.sin(t)), es),
                                0, 2 * math.pi, limit=200, points=[3 * math.pi / 2])
        assert v == pytest.approx(ref / (4 * math.pi * k0) - 0.5, abs=1e-9)
    # close to Hertz (-0.0498 at x = 1; paper: "do not substantially differ")
    assert -0.06 < got[-1] < -0.03
    g = jax.jit(jax.grad(lambda *a: shift(*a)[0], argnums=(0, 1, 2)))(jnp.array([0.7]), es, GAMMA)
    assert all(np.all(np.isfinite(np.asarray(v))) for v in g)


# --- DMT --------------------------------------------------------------------------------------

def test_dmt_basics():
    es = estar(210e9)
    fc = 4 * math.pi * GAMMA * R_BEAD
    assert float(dmt.pull_off_force(**P)) == pytest.approx(fc)
    d0 = float(dmt.static_overlap(LOAD, e_star=es, **P))
    assert d0 == pytest.approx((3 * (LOAD + fc) / (4 * es * math.sqrt(R_BEAD))) ** (2 / 3), rel=1e-13)
    assert float(dmt.force(d0, e_star=es, **P)) == pytest.approx(LOAD, rel=1e-12)
    k = jax.grad(lambda d: dmt.force(d, e_star=es, **P))(d0)
    assert float(k) == pytest.approx(float(dmt.linear_stiffness(LOAD, e_star=es, **P)), rel=1e-12)
    a = dmt.contact_radius(LOAD, e_star=es, **P)
    assert float(dmt.overlap_from_contact_radius(a, e_star=es, **P)) == pytest.approx(d0, rel=1e-12)
    assert float(dmt.contact_radius_from_overlap(d0, e_star=es, **P)) == pytest.approx(float(a), rel=1e-12)
    assert float(dmt.force_from_contact_radius(a, e_star=es, **P)) == pytest.approx(LOAD, rel=1e-12)
    f0 = dmt.linear_frequency(LOAD, MASS, e_star=es, **P)
    assert float(dmt.overlap_from_frequency(f0, LOAD, MASS, **P)) == pytest.approx(d0, rel=1e-12)
    assert float(dmt.force(-1e-9, e_star=es, **P)) == 0.0
    # ordering at the paper's load: Hertz < JKR < DMT overlap (DMT adds the most attraction)
    d_jkr = float(jkr.contact.static_overlap(LOAD, e_star=es, **P))
    assert 51.7e-9 < d_jkr < d0


def test_dmt_shift_equals_hertz():
    es = estar(200e9)
    xs = jnp.array([0.3, 0.8, 1.0])
    shift = jax.jit(lambda x, gm: dmt.shift_first_order(x, load=LOAD, e_star=es, radius=R_BEAD,
                                                        gamma=gm))
    got = np.asarray(shift(xs, GAMMA))
    for x, v in zip([0.3, 0.8, 1.0], got):
        ref = mp.quad(lambda t, x=x: mp.sqrt(1 + x * mp.sin(t)), [0, mp.pi, 3 * mp.pi / 2, 2 * mp.pi])
        assert v == pytest.approx(float(ref / (4 * mp.pi) - 0.5), abs=1e-9)
    g = jax.jit(jax.grad(lambda gm: shift(xs, gm)[0]))(GAMMA)
    assert np.isfinite(float(g))
