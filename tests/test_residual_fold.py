"""The residual fold (inference.speed.residual_fold) of Maugis-Dugdale's sweep likelihood, whose
curve depends on two parameters: its sums, log-likelihood and derivatives against the
exact ones, its fallback, the model's log density with and without it, and the
point-wise likelihood that LOO reads."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from numpyro import handlers
from numpyro.infer.util import log_density

from beadrod.inference.model.likelihood import model_inputs
from beadrod.inference.model.numpyro_models import ModelSpec, SweepCurve, build_model, step_fold
from beadrod.inference.model.priors import law_prior
from beadrod.inference.speed import residual_fold
from beadrod.models.registry import get_law
from beadrod.workflows.config import DEFAULTS
from beadrod.workflows.pipeline.fits import load_data

LAW = "maugis_dugdale"


@pytest.fixture(scope="module")
def inputs():
    return model_inputs(load_data(DEFAULTS))


@pytest.fixture(scope="module")
def folded(inputs):
    """The fold, built as a fit builds it: inside a compiled program's trace (the mode
    search's, which a fit traces first). There lambda's LogUniform prior, built under the
    trace, held traced log bounds, whose quantiles gave no range, and the fold was
    silently skipped in every fit."""
    from beadrod.inference.speed import fold as F

    law = get_law(LAW)
    sweeps = SweepCurve(law, ModelSpec(law=LAW, rung="backbone", shift_noise="constant"), inputs, inputs["f0"])
    F._CACHE.clear()
    got = []

    def traced(x):
        got.append(step_fold(sweeps, inputs))
        return x

    jax.jit(traced)(jnp.zeros(()))
    fold = got[0]
    assert isinstance(fold, residual_fold.ResidualFold)
    assert fold.params == ("gamma", "lam")
    base = {p.name: law_prior(p, {}).icdf(jnp.asarray(0.5)) for p in law.params}
    return sweeps, fold, base


def _points(fold, rng, n):
    # n points of the folded box: (z_a, z_b) and whether their cell is usable
    cells = np.array(fold.cells)
    pos = rng.uniform(0.0, 1.0, (n, 2)) * cells
    z = np.asarray(fold.z_lo) + pos * np.asarray(fold.width)
    ij = pos.astype(int)
    return z, fold.usable[ij[:, 0], ij[:, 1]]


def test_folded_log_likelihood_within_its_bound(folded, inputs):
    """At random points of usable cells the folded log-likelihood differs from the exact
    one by at most TOL at noise sigma_ref and offsets within offset_span of offset_ref,
    what the fold promises; outside its box the exact sums themselves."""
    sweeps, fold, base = folded
    assert fold.usable.mean() > 0.5 and fold.max_error <= residual_fold.TOL

    def both(z):
        theta = {**base, "gamma": jnp.exp(z[0]), "lam": jnp.exp(z[1])}
        return residual_fold.sums(fold, theta, sweeps.residual_sums), sweeps.residual_sums(theta)

    z, usable = _points(fold, np.random.default_rng(7), 120)
    # below the box in gamma (a larger load ratio, inside the law's domain)
    outside = np.array([[fold.z_lo[0] - 0.3, 0.5], [fold.z_lo[0] - 0.6, 1.5]])
    got, want = (np.asarray(a) for a in jax.jit(jax.vmap(both))(jnp.asarray(
        np.concatenate([z, outside]))))
    d = np.asarray(inputs["direction"])
    n, d2 = d.size, float(np.sum(d * d))
    for o in (fold.offset_ref - fold.offset_span, fold.offset_ref,
              fold.offset_ref + fold.offset_span):
        miss = np.abs(np.asarray(residual_fold.log_likelihood(got[:-2].T, o, fold.sigma_ref, n, d2))
                      - np.asarray(residual_fold.log_likelihood(want[:-2].T, o, fold.sigma_ref, n, d2)))
        assert np.all(miss[usable] <= residual_fold.TOL), np.max(miss[usable])
    assert np.allclose(got[-2:], want[-2:], rtol=1e-12, atol=0)


def test_folded_gradient_matches_the_exact_one(folded):
    """The fold's derivative (a rule of its own) in forward and reverse mode alike, and
    against the exact sums' where the cell is usable."""
    sweeps, fold, base = folded
    z, usable = _points(fold, np.random.default_rng(11), 12)

    def s(zz):
        return residual_fold.sums(fold, {**base, "gamma": jnp.exp(zz[0]), "lam": jnp.exp(zz[1])},
                      sweeps.residual_sums)

    fwd = np.asarray(jax.jit(jax.vmap(jax.jacfwd(s)))(jnp.asarray(z)))
    rev = np.asarray(jax.jit(jax.vmap(jax.jacrev(s)))(jnp.asarray(z)))
    ref = np.asarray(jax.jit(jax.vmap(jax.jacfwd(lambda zz: sweeps.residual_sums(
        {**base, "gamma": jnp.exp(zz[0]), "lam": jnp.exp(zz[1])}))))(jnp.asarray(z)))
    # (NaN where lambda lies outside its domain, in the box's margin: both alike)
    assert np.allclose(fwd, rev, rtol=1e-10, atol=1e-14, equal_nan=True)
    scale = np.max(np.abs(ref), axis=(1, 2), keepdims=True)
    assert np.all(np.abs(fwd - ref)[usable] <= 1e-3 * scale[usable])


def test_folded_model_has_the_exact_log_density(folded, inputs):
    """The model's log joint with and without the fold at points of usable cells (noise
    and offset as the fold's bound states them): within TOL."""
    _, fold, _ = folded
    with_fold = build_model(ModelSpec(law=LAW, rung="backbone", shift_noise="constant"))
    exact = build_model(ModelSpec(law=LAW, rung="backbone", fold=False, shift_noise="constant"))
    z, usable = _points(fold, np.random.default_rng(13), 40)
    z = z[usable][:12]
    dens = [jax.jit(lambda p, m=m: log_density(m, (inputs,), {}, p)[0])
            for m in (with_fold, exact)]
    compared = 0
    for za, zb in z:
        params = {"young": 2e11, "gamma": float(np.exp(za)), "lam": float(np.exp(zb)),
                  "delta0_scatter": 0.1, "sigma_shift": fold.sigma_ref,
                  "offset_down": fold.offset_ref, "mu_logq": np.log(50.0), "tau_logq": 0.5,
                  "loss_exponent": 1.0, "sigma_amp": 0.02, "tau_amp": 0.01,
                  "offset_amp_down": 0.0}
        params = get_law(LAW).sampler_values(params)
        a, b = (float(d(params)) for d in dens)
        assert np.isfinite(a) == np.isfinite(b)
        if np.isfinite(b):
            compared += 1
            assert abs(a - b) <= residual_fold.TOL
    assert compared >= 10


def test_pointwise_likelihood_is_the_exact_one(inputs):
    """A model whose sweep likelihood is folded still gives LOO its per-sweep
    log-likelihood, when asked (data[POINTWISE]): the exact sites sum to the folded
    factor within TOL at a point of the fold."""
    model = build_model(ModelSpec(law=LAW, rung="backbone", shift_noise="constant"))
    values = get_law(LAW).sampler_values({"young": 2e11, "gamma": 0.03, "lam": 2.0})
    values.update(delta0_scatter=0.1, sigma_shift=0.0137, offset_down=0.0)

    def trace(data):
        sub = handlers.substitute(handlers.seed(model, 0), data=values)
        return handlers.trace(sub).get_trace(data)

    folded = trace(inputs)
    pointwise = trace({**inputs, residual_fold.POINTWISE: True})
    assert "shift_obs" not in folded and "shift_obs_folded" in folded
    assert "shift_obs" in pointwise and "shift_obs_folded" not in pointwise
    site = pointwise["shift_obs"]
    total = float(jnp.sum(site["fn"].log_prob(site["value"])))
    factor = folded["shift_obs_folded"]
    assert abs(total - float(factor["fn"].log_prob(factor["value"]))) <= residual_fold.TOL


def test_fold_of_a_kinked_toy_curve_keeps_its_bound():
    """Any two-parameter curve, not only a law's: sweeps whose curve turns at a corner
    (C1, as a backbone at contact loss) that moves with both parameters. The fold finds
    the plausible region (around the truth), keeps its promised bound at random points of
    usable cells, and is the exact sums elsewhere."""
    rng = np.random.default_rng(3)
    x = np.sort(rng.uniform(0.05, 1.5, 300))
    d = np.where(rng.uniform(size=x.size) < 0.5, 1.0, 0.0)

    def curve(a, b):
        # -a x^2 below the corner x = b, its tangent line above it
        return jnp.where(x < b, -a * x * x, -a * (2.0 * b * x - b * b))

    y = np.asarray(curve(0.04, 0.9)) + 0.002 * d + rng.normal(0.0, 1e-3, x.size)

    def exact(theta):
        r = y - curve(theta["a"], theta["b"])
        return jnp.stack([jnp.sum(r * r), jnp.sum(d * r)])

    fold = residual_fold.build_residual_fold(
        exact, {"a": 0.04, "b": 0.9}, ("a", "b"), ((0.01, 0.2), (0.3, 3.0)),
        lambda th: jnp.asarray(True), lambda th: -jnp.log(th["a"]) - jnp.log(th["b"]),
        x.size, float(np.sum(d * d)))
    assert fold is not None and fold.usable.mean() > 0.5
    lo = np.asarray(fold.z_lo)
    hi = lo + np.asarray(fold.width) * np.array(fold.cells)
    assert lo[0] < np.log(0.04) < hi[0] and lo[1] < np.log(0.9) < hi[1]
    z, usable = _points(fold, np.random.default_rng(4), 400)
    sums = jax.jit(jax.vmap(lambda zz: (residual_fold.sums(fold, {"a": jnp.exp(zz[0]), "b": jnp.exp(zz[1])},
                                               exact),
                                        exact({"a": jnp.exp(zz[0]), "b": jnp.exp(zz[1])}))))
    got, want = (np.asarray(v) for v in sums(jnp.asarray(z)))
    for o in (fold.offset_ref - fold.offset_span, fold.offset_ref + fold.offset_span):
        miss = np.abs(np.asarray(residual_fold.log_likelihood(got.T, o, fold.sigma_ref, x.size, np.sum(d)))
                      - np.asarray(residual_fold.log_likelihood(want.T, o, fold.sigma_ref, x.size,
                                                    np.sum(d))))
        assert np.all(miss[usable] <= residual_fold.TOL)
    assert np.array_equal(got[~usable], want[~usable])

