"""The tabulated backbones of JKR, DMT and the Greenwood-Williamson sphere
(models.shape_tables) against the generic exact backbone of each law's force, their
one-parameter structure (E* drops out), and their Hertz limits (gamma -> 0, sigma -> 0)."""

import jax.numpy as jnp
import numpy as np
import pytest

from models import backbone, generic, registry, shape_tables

SCENE = {"radius": 7.938e-3, "young": 200e9, "poisson": 0.27, "load": 0.1582,
         "mass": 0.01613, "gravity": 9.81, "roughness_rms": 25e-9, "surface_energy": 0.7}
X = jnp.array([0.05, 0.4, 0.85, 1.1, 1.6])


def _kw(name, **theta):
    law = registry.get_law(name)
    kw = law.resolve(SCENE, theta)
    return law, kw, law.overlap(**kw)


@pytest.mark.parametrize("name,theta", [("jkr", {"gamma": 0.7}), ("dmt", {"gamma": 0.7})])
def test_shape_does_not_depend_on_the_modulus(name, theta):
    """P'(q) and the flight acceleration at E = 150 and 250 GPa (the same load ratio
    F0/Fc): identical, so F0/Fc is the one shape parameter."""
    q = jnp.array([-0.9, -0.4, 0.3, 1.5])
    sig = []
    for young in (150e9, 250e9):
        law, kw, d0 = _kw(name, young=young, **theta)
        dp, _, acc = generic.restoring_force(law, delta0=d0, **kw)
        sig.append(np.append(np.asarray(dp(q)), float(acc)))
    np.testing.assert_allclose(sig[0], sig[1], rtol=1e-9, atol=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("name,theta", [("jkr", {"gamma": 0.7}), ("jkr", {"gamma": 2.5}),
                                        ("dmt", {"gamma": 0.7}),
                                        ("greenwood_williamson", {"roughness_factor": 1.0}),
                                        ("greenwood_williamson", {"roughness_factor": 3.0})])
def test_table_against_generic_exact_backbone(name, theta):
    """(slow: the generic backbone compiles for about a minute per law)"""
    law, kw, d0 = _kw(name, young=200e9, **theta)
    fast = law.shift(X, rung="backbone", delta0=d0, **kw)
    exact = generic.backbone_shift(law, X, delta0=d0, **kw)
    np.testing.assert_allclose(fast, exact, atol=2e-6)


@pytest.mark.slow
def test_adhesive_laws_tend_to_hertz_as_gamma_vanishes():
    """gamma -> 0: the JKR and DMT backbones tend to the Hertz backbone (exact generic path,
    and the tables held at their r = F0/Fc = 1000 end)."""
    hertz = np.asarray(backbone.backbone_shift(X, 1.5))
    gaps = {}
    for name in ("jkr", "dmt"):
        errs = []
        for gamma in (1e-2, 1e-4):
            law, kw, d0 = _kw(name, young=200e9, gamma=gamma)
            errs.append(np.max(np.abs(np.asarray(
                generic.backbone_shift(law, X, delta0=d0, **kw)) - hertz)))
        gaps[name] = errs
        assert errs[1] < 0.05 * errs[0] and errs[1] < 1e-4, (name, errs)
        law, kw, d0 = _kw(name, young=200e9, gamma=1e-6)   # beyond the table: held at its end
        np.testing.assert_allclose(law.shift(X, rung="backbone", delta0=d0, **kw), hertz,
                                   atol=5e-3)


def test_greenwood_williamson_tends_to_hertz_as_roughness_vanishes():
    hertz = np.asarray(backbone.backbone_shift(X, 1.5))
    errs = []
    for factor in (0.04, 4e-3):   # sigma = 1 nm, 0.1 nm
        law, kw, d0 = _kw("greenwood_williamson", young=200e9, roughness_factor=factor)
        errs.append(np.max(np.abs(np.asarray(law.shift(X, rung="backbone", delta0=d0,
                                                       **kw)) - hertz)))
    assert errs[1] < errs[0] and errs[1] < 2e-2, errs


def test_tables_are_finite_with_finite_gradients_over_the_prior_region():
    import jax

    for name, key, vals in (("jkr", "gamma", (0.05, 0.7, 5.0)), ("dmt", "gamma", (0.05, 5.0)),
                            ("greenwood_williamson", "roughness_factor", (0.04, 1.0, 8.0))):
        for v in vals:
            law, kw, d0 = _kw(name, young=200e9, **{key: v})

            def total(xx, vv, law=law, kw=kw, key=key):
                k = {**kw, key: vv}
                return jnp.sum(law.shift(xx, rung="backbone", delta0=law.overlap(**k), **k))

            g = jax.grad(total, argnums=(0, 1))(jnp.array([0.0, 0.5, 1.0, 1.9, 2.5]), v)
            assert all(np.all(np.isfinite(np.asarray(a))) for a in g), (name, v)
    assert set(shape_tables.TABLES) == {"jkr", "dmt", "greenwood_williamson"}


def test_tables_tend_to_the_hertz_table_as_adhesion_vanishes():
    """The JKR and DMT tables approach the Hertz backbone table as gamma -> 0 (r = F0/Fc
    grows), monotonically, to within 2e-3 at the table's end (r = 1000)."""
    from models.backbone_table import backbone_shift_fast

    hertz = np.asarray(backbone_shift_fast(X, 1.5))
    for name in ("jkr", "dmt"):
        gaps = [np.max(np.abs(np.asarray(shape_tables.backbone_fast(name, X, r)) - hertz))
                for r in (1.0, 10.0, 100.0, 1000.0)]
        assert all(b < a for a, b in zip(gaps, gaps[1:])), (name, gaps)
        assert gaps[-1] < 2e-3, (name, gaps)
