"""The fold of a sweep curve in its one shape parameter (inference.speed.fold) against the exact
curve it stands in for, its refusals, and its fallback where a cubic would miss."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from numpyro.infer.util import log_density

from beadrod.inference.model.likelihood import model_inputs
from beadrod.inference.model.numpyro_models import ModelSpec, SweepCurve, build_model, step_fold
from beadrod.inference.model.priors import law_prior
from beadrod.inference.speed import fold as F
from beadrod.inference.speed.residual_fold import ResidualFold
from beadrod.models.registry import get_law, law_names
from beadrod.workflows.config import DEFAULTS
from beadrod.workflows.pipeline.fits import load_data


@pytest.fixture(scope="module")
def inputs():
    return model_inputs(load_data(DEFAULTS))


# laws whose sweep likelihood is folded in two parameters: tests/test_residual_fold.py
# builds that fold as a fit does and checks it (its parameters included)
RESIDUAL_FOLDED = ("maugis_dugdale",)


def _backbone_laws():
    return [n for n in law_names() if "backbone" in get_law(n).physics.shifts
            and n not in RESIDUAL_FOLDED]


def _backbone_params():
    # by default the first law without a table and the first with one; the rest in
    # `-m slow` (CI time)
    names = _backbone_laws()
    first = {next(n for n in names if get_law(n).physics.table is None),
             next(n for n in names if get_law(n).physics.table is not None)}
    return [n if n in first else pytest.param(n, marks=pytest.mark.slow) for n in names]


@pytest.mark.parametrize("name", _backbone_params())
def test_fold_matches_the_exact_quantities(name, inputs):
    """Wherever the fold is used its values (the sweep curve, and the overlap map with its
    log-Jacobian where folded with it) are the exact ones to TOL; a law whose curve depends
    on no parameter, or on several, is not folded; the overlap map is folded exactly when
    it depends on the curve's one parameter."""
    law = get_law(name)
    spec = ModelSpec(law=name, rung="backbone")
    sweeps = SweepCurve(law, spec, inputs, inputs["f0"])
    step = step_fold(sweeps, inputs)
    priors = {p.name: law_prior(p, {}) for p in law.params}
    base = {k: d.icdf(jnp.asarray(0.5)) for k, d in priors.items()}
    if step is None:
        # then the exact curve truly does not depend on exactly one parameter
        assert F.shape_parameter(sweeps.of_theta, [base]) is None
        return
    if isinstance(step, ResidualFold):
        # two parameters: the sweeps' likelihood is folded instead (tests/test_residual_fold)
        assert set(step.params) == set(F.shape_parameters(sweeps.of_theta, [base]))
        return
    fold = step.fold
    assert step.with_protocols == (F.shape_parameter(sweeps.everything, [base]) == fold.param)
    exact = sweeps.everything if step.with_protocols else sweeps.of_theta

    def both(zz):
        theta = {**base, fold.param: jnp.exp(zz)}
        return F.evaluate(fold, theta, exact), exact(theta), sweeps.counted(theta)

    rng = np.random.default_rng(3)
    top = fold.z_lo + fold.cells * fold.width
    z = np.concatenate([rng.uniform(fold.z_lo, top, 60), [fold.z_lo - 0.5, top + 0.5]])
    got, want, counted = (np.asarray(a) for a in jax.jit(jax.vmap(both))(jnp.asarray(z)))
    assert got.shape[1] == inputs["shift"].size + 2 * step.with_protocols * inputs["f0"].size
    miss = np.max(np.abs(got - want), axis=1)
    assert np.all(miss[:-2][counted[:-2]] <= F.TOL)
    # outside the folded range the exact values (to rounding: XLA may fuse the two
    # evaluations differently)
    assert np.all(miss[-2:] <= 1e-12)
    # its derivative (a rule of its own, inference.speed.fold._evaluate) is the exact one's to
    # the cubics' accuracy, in forward and reverse mode alike
    zs = jnp.asarray(z[:20])

    def fold_z(zz):
        return F.evaluate(fold, {**base, fold.param: jnp.exp(zz)}, exact)

    fwd = np.asarray(jax.jit(jax.vmap(jax.jacfwd(fold_z)))(zs))
    rev = np.asarray(jax.jit(jax.vmap(jax.jacrev(fold_z)))(zs))
    ref = np.asarray(jax.jit(jax.vmap(jax.jacfwd(
        lambda zz: exact({**base, fold.param: jnp.exp(zz)}))))(zs))
    assert np.allclose(fwd, rev, rtol=0, atol=1e-12)
    assert np.max(np.abs(fwd - ref)[counted[:20]]) <= 1e-3 * max(1.0, np.max(np.abs(ref)))


@pytest.mark.parametrize("name,use_shift", [("jkr", True), ("greenwood_williamson", True),
                                            ("powerlaw", True), ("dmt", False)])
def test_folded_model_has_the_exact_log_density(name, use_shift, inputs):
    """The model's log joint with and without the fold at prior draws: the difference is
    bounded by TOL times the sum of |residual|/sigma^2 (here well below 1e-3 nat); also
    where only the overlap map is folded (no shift observed)."""
    law = get_law(name)
    folded = build_model(ModelSpec(law=name, rung="backbone", use_shift=use_shift))
    exact = build_model(ModelSpec(law=name, rung="backbone", fold=False,
                                  use_shift=use_shift))
    priors = {p.name: law_prior(p, {}) for p in law.params}
    rng = np.random.default_rng(5)
    # compiled once each, as a fit evaluates them (op by op, each draw took seconds)
    dens = [jax.jit(lambda p, m=m: log_density(m, (inputs,), {}, p)[0])
            for m in (folded, exact)]
    compared = 0
    for _ in range(12):
        params = {k: float(d.icdf(jnp.asarray(rng.uniform(0.05, 0.95))))
                  for k, d in priors.items()}
        params.update(delta0_scatter=0.1, sigma_shift=0.0137, offset_down=0.0,
                      kappa_shift=0.1, tau_shift=1e-3, mu_logq=np.log(50.0), tau_logq=0.5,
                      loss_exponent=1.0, sigma_amp=0.02, tau_amp=0.01, offset_amp_down=0.0)
        a, b = (d(params) for d in dens)
        assert np.isfinite(a) == np.isfinite(b)
        if np.isfinite(b):
            compared += 1
            assert abs(float(a) - float(b)) < 1e-3
    assert compared >= 6


def test_shape_parameter_sees_every_dependence():
    x = jnp.linspace(0.1, 1.0, 7)
    one = lambda th: th["a"] * x**2 + 0.0 * th["b"]  # noqa: E731
    two = lambda th: th["a"] * x**2 + th["b"] * x  # noqa: E731
    none = lambda th: x**2  # noqa: E731
    only = lambda th: th["a"] * x**2  # noqa: E731
    # a dependence that shows at the second draw only
    later = lambda th: th["a"] * x**2 + jnp.where(th["b"] > 1.0, th["b"] - 1.0, 0.0) * x  # noqa: E731
    draws = [{"a": jnp.asarray(1.3), "b": jnp.asarray(0.7)}]
    assert F.shape_parameter(one, draws) == "a"      # b reaches it with a zero derivative
    assert F.shape_parameter(two, draws) is None
    assert F.shape_parameter(none, draws) is None     # decided from the program
    assert F.shape_parameter(only, draws) == "a"      # decided from the program
    assert F.shape_parameter(later, draws) == "a"
    assert F.shape_parameter(later, draws + [{"a": jnp.asarray(1.3),
                                              "b": jnp.asarray(1.4)}]) is None


def test_a_kink_is_refined_or_left_to_the_exact_curve():
    """A curve with a slope jump in ln theta (a cubic cannot follow it): every value the
    fold returns, in refined, unusable and ordinary cells alike, is the exact one to TOL."""
    x = jnp.linspace(0.0, 1.0, 5)

    def curve(th):
        z = jnp.log(th["a"])
        return 0.1 * x * jnp.abs(z - 0.3123) + 0.01 * jnp.sin(3.0 * z) * x

    fold = F.build_fold(curve, {"a": jnp.asarray(1.0)}, "a", 0.1, 10.0)
    assert fold is not None and np.any(fold.count > 1)
    def miss(zz):
        th = {"a": jnp.exp(zz)}
        return jnp.max(jnp.abs(F.evaluate(fold, th, curve) - curve(th)))

    z = np.linspace(np.log(0.1) + 1e-9, np.log(10.0) - 1e-9, 2001)
    assert float(jnp.max(jax.jit(jax.vmap(miss))(jnp.asarray(z)))) <= F.TOL


def test_known_overlap_map_is_used_only_at_its_f0():
    """MeasuredF0 with the map precomputed at the observed f0 (the fold's values) gives
    that density there and evaluates the map at any other value."""
    from beadrod.inference.model.likelihood import scene_quantities
    from beadrod.inference.model.overlap import MeasuredF0, log_overlap_and_slope
    from beadrod.models.scene import builtin_scene

    law = get_law("jkr")
    kw = law.resolve(scene_quantities(builtin_scene("paper")), {"young": 200e9, "gamma": 0.7})
    f0 = jnp.array([2500.0, 2700.0, 2950.0])
    logd, log_slope = log_overlap_and_slope("jkr", f0, kw)
    plain = MeasuredF0("jkr", jnp.log(55e-9), 0.1, kw)
    # a deliberately wrong "known" map: used at its f0, ignored elsewhere
    known = MeasuredF0("jkr", jnp.log(55e-9), 0.1, kw, known=(f0, logd + 0.01, log_slope))
    assert np.allclose(known.log_prob(f0), plain.log_prob(f0) - (logd + 0.005 - jnp.log(55e-9))
                       * 0.01 / 0.1**2, rtol=0, atol=1e-9)
    other = f0 + 1.0
    assert np.allclose(known.log_prob(other), plain.log_prob(other), rtol=0, atol=1e-12)
