"""The tabulated Maugis-Dugdale static state (models.laws.maugis_dugdale.static) against the
root solves of models.laws.maugis_dugdale (themselves tested against mpmath): values and
gradients on every piece, NaN outside the law's domain, and the law's overlap maps."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from beadrod.models.laws import maugis_dugdale
from beadrod.models.laws.maugis_dugdale import static

R_BEAD, NU = 7.938e-3, 0.27
MASS = 4.0 / 3.0 * math.pi * R_BEAD**3 * 7700.0
LOAD = MASS * 9.80665
ES = 200e9 / (2 * (1 - NU**2))
EXACT = jax.jit(jax.vmap(static.exact_state))


@pytest.mark.parametrize("piece", ["r -> 0", "ln r", "r -> inf"])
def test_tables_match_the_root_solves_over_their_grid(piece):
    """1000 random (r, lam) in each piece in r (and its ends, the lam breaks and corners):
    within 1e-13 (the module's stated bound; 2e-13 in ln n on the last piece, r up to 1e9,
    where the root solves themselves lose digits)."""
    rng = np.random.default_rng(11)
    lam = np.exp(rng.uniform(math.log(0.1), math.log(100.0), 1000))
    r, tol = {
        "r -> 0": (np.concatenate([rng.uniform(0.0, 0.3, 500),
                                   np.exp(rng.uniform(-30.0, math.log(0.3), 500))]), 1e-13),
        "ln r": (np.exp(rng.uniform(math.log(0.3), math.log(1000.0), 1000)), 1e-13),
        "r -> inf": (rng.uniform(0.0, 1000.0 ** -0.5, 1000) ** -2.0, 2e-13),
    }[piece]
    ends = {"r -> 0": [1e-12, 0.3], "ln r": [0.3, 10.0, 1000.0], "r -> inf": [1000.0, 1e9]}
    r = np.concatenate([r, ends[piece], ends[piece]])
    lam = np.concatenate([lam, [0.1, math.exp(-1.0), 100.0][:len(ends[piece])],
                          [math.e, 100.0, 0.1][:len(ends[piece])]])
    got = jax.jit(jax.vmap(static.state))(jnp.asarray(r), jnp.asarray(lam))
    for a, b in zip(got, EXACT(jnp.asarray(r), jnp.asarray(lam))):
        np.testing.assert_allclose(a, b, rtol=0, atol=tol)


def test_outside_the_laws_domain_the_state_is_nan():
    """lam outside [0.1, 100] (the law's parameter domain) or a load r <= 0: NaN, never a
    held value; gradients finite at the domain's edges."""
    r = jnp.array([3.0, 3.0, 0.0, -1.0])
    lam = jnp.array([0.05, 300.0, 1.0, 1.0])
    assert not bool(jnp.any(static.in_range(r, lam)))
    for a in static.state(r, lam)[:2]:
        assert bool(jnp.all(jnp.isnan(a)))
    g = jax.grad(lambda r, lam: sum(static.state(r, lam)), argnums=(0, 1))
    for lam_edge in (0.1, 100.0):
        assert all(np.isfinite(float(v)) for v in g(5.0, lam_edge))


def test_gradients_match_the_implicit_derivatives():
    f = jax.jit(jax.jacfwd(lambda r, lam: jnp.stack(static.state(r, lam)), argnums=(0, 1)))
    g = jax.jit(jax.jacfwd(lambda r, lam: jnp.stack(static.exact_state(r, lam)), argnums=(0, 1)))
    # reverse mode too (the sampler's), in every piece and at the piece ends (where a
    # clamp would halve the derivative)
    fr = jax.jit(jax.grad(lambda r, lam: sum(static.state(r, lam)), argnums=(0, 1)))
    gr = jax.jit(jax.grad(lambda r, lam: sum(static.exact_state(r, lam)), argnums=(0, 1)))
    for r, lam in ((1e-6, 0.2), (0.05, 1.0), (0.3, 3.0), (0.31, 0.11), (2.0, 0.9),
                   (10.0, 0.1), (50.0, 3.0), (900.0, 90.0), (1000.0, 100.0), (2000.0, 1.0),
                   (1e7, 5.0)):
        for a, b in zip(f(r, lam), g(r, lam)):
            np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-12)
        np.testing.assert_allclose(fr(r, lam), gr(r, lam), rtol=1e-8, atol=1e-12)


@pytest.mark.parametrize("gamma,lam", [(0.05, 0.2), (0.7, 1.0), (2.0, 30.0), (20.0, 5.0)])
def test_law_overlap_maps_are_the_root_solves(gamma, lam):
    """The law's fast paths against models.laws.maugis_dugdale's root solves (gamma = 20 J/m^2
    puts r = F0/Fc on the piece below 0.3), and frequency_at inverts overlap_at."""
    law = maugis_dugdale.LAW
    kw = law.resolve({"radius": R_BEAD, "young": 200e9, "poisson": NU, "load": LOAD,
                      "mass": MASS}, {"young": 200e9, "gamma": gamma, "lam": lam})
    p = dict(e_star=kw["e_star"], radius=R_BEAD, gamma=gamma, lam=lam)
    assert float(law.overlap(**kw)) == pytest.approx(float(maugis_dugdale.contact.static_overlap(LOAD, **p)),
                                                     rel=1e-12)
    f0 = jnp.array([2400.0, 2700.0, 3100.0])
    d0 = law.overlap_at(f0, **kw)
    np.testing.assert_allclose(d0, maugis_dugdale.contact.overlap_from_frequency(f0, LOAD, MASS, radius=R_BEAD,
                                                             gamma=gamma, lam=lam), rtol=1e-12)
    np.testing.assert_allclose(law.frequency_at(d0, **kw), f0, rtol=1e-13)


def test_stored_table_is_what_the_builder_makes():
    """models/laws/maugis_dugdale/data/md_static.npz is reproduced by a fresh build (the node and coefficient
    helpers of models.tables.chebyshev it shares with the backbone tables): within 1e-13."""
    fresh, stored = static.build(), static.load()
    assert set(fresh) == set(stored)
    for k in fresh:
        np.testing.assert_allclose(fresh[k], stored[k], rtol=0.0, atol=1e-13)


def test_the_prepared_state_is_used_only_with_the_keywords_it_was_computed_from():
    """Physics.prepared (models.law.Prepared): resolve adds the static state once; the
    overlaps, the reference overlap and the backbone are the same with it as with keywords
    built by hand (bit for bit), and keywords whose gamma changed after resolve get the new gamma's
    values, not the held state's (a stale state would give the old ones)."""
    law = maugis_dugdale.LAW
    scene = {"radius": R_BEAD, "young": 200e9, "poisson": NU, "load": LOAD, "mass": MASS}
    kw = law.resolve(scene, {"young": 200e9, "gamma": 0.7, "lam": 3.0})
    assert "maugis_dugdale_state" in kw
    bare = {k: v for k, v in kw.items() if k != "maugis_dugdale_state"}
    f0, x = jnp.array([2500.0, 2800.0]), jnp.array([0.2, 0.9, 1.4])

    def values(k):
        d0 = law.overlap_at(f0, **k)
        return [law.overlap(**k), d0, law.frequency_at(jnp.array([4e-8, 6e-8]), **k),
                law.shift(x, rung="backbone", delta0=d0[0], omega0=1.0, **k)]

    for a, b in zip(values(kw), values(bare)):
        np.testing.assert_array_equal(a, b)
    changed = {**kw, "gamma": 2.0}
    fresh = law.resolve(scene, {"young": 200e9, "gamma": 2.0, "lam": 3.0})
    for a, b, c in zip(values(changed), values(fresh), values(kw)):
        np.testing.assert_array_equal(a, b)
        assert not np.allclose(a, c)
    # the sampler's case: one state in the traced log density, the same gradient
    def total(g, k0):
        k = law.resolve(scene, {"young": 200e9, "gamma": g, "lam": 3.0})
        if not k0:
            k = {key: v for key, v in k.items() if key != "maugis_dugdale_state"}
        d0 = law.overlap_at(f0, **k)
        return jnp.sum(jnp.log(d0)) + jnp.log(law.overlap(**k)) + jnp.sum(
            law.shift(x, rung="backbone", delta0=d0[0], omega0=1.0, **k))

    g1, g2 = (jax.grad(total)(0.7, k0) for k0 in (True, False))
    assert float(g1) == pytest.approx(float(g2), rel=1e-12)
