"""A law file's own loss (issue 49, "law files can carry their own loss"): LOSS_EXPONENT and
loss_increment(x, *, ...) end on the law's Physics as a built-in law's do; its loss is the
closed form; the amplitude model fits no background exponent for a law that gives its own;
and each malformed declaration is refused on load, naming the file. Nothing here samples."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import jax
import numpy as np
import pytest
from numpyro import handlers

from beadrod.inference.model.likelihood import scene_quantities
from beadrod.models import registry
from beadrod.models.lawfile import LawFileError, load_law_file
from beadrod.models.scene import builtin_scene

SCENE = scene_quantities(builtin_scene("paper"))
HERE = Path(__file__).parent
EXAMPLE = HERE / "laws" / "hertz_masing.py"   # docs/adding-a-law.md's example

LAW = """
import jax.numpy as jnp
import numpyro.distributions as dist
NAME = {name!r}
PRIORS = {priors}
{top}
def force(delta, *, young, poisson, radius):
    t = delta > 0
    d = jnp.where(t, delta, 1.0)
    return jnp.where(t, 4/3 * young/(2*(1-poisson**2)) * jnp.sqrt(radius) * d**1.5, 0.0)

def loss_increment({args}):
    moving = x > 0
    xs = jnp.where(moving, x, 1.0)
    return {body}
"""
PRIORS = '{"young": dist.Uniform(150e9, 250e9), "h": dist.HalfNormal(0.01), "m": dist.Uniform(1.2, 3.0)}'
SAFE = "jnp.where(moving, h * xs ** (m - 1.0), 0.0)"


def _file(tmp_path: Path, *, name: str = "lf_loss", priors: str = PRIORS, top: str = "",
          args: str = "x, *, h, m", body: str = SAFE, tail: str = "",
          text: str | None = None) -> Path:
    f = tmp_path / f"{name}.py"
    f.write_text(text if text is not None else textwrap.dedent(LAW).format(
        name=name, priors=priors, top=top, args=args, body=body) + tail)
    return f


@pytest.fixture(scope="module")
def example():
    return load_law_file(EXAMPLE, SCENE)


# ----------------------------------------------------------------- it reaches the Physics
def test_the_example_carries_its_loss(example):
    assert example.physics.loss_exponent == 1.0 and example.has_own_loss
    assert example.physics.loss_increment is not None
    assert set(example.param_names) == {"young", "h", "m"}
    assert "tabulated" in example.presentation.description   # h, m leave the force alone


@pytest.mark.parametrize("h,m", [(0.01, 1.7), (0.003, 2.6)])
def test_loss_is_the_closed_form(example, h, m):
    """ContactLaw.loss of the file's law: L0 Omega^1 + h x^(m-1), whatever background
    exponent the caller passes (the law's own wins); 0 added at x = 0."""
    kw = example.resolve(SCENE, {"young": 200e9, "h": h, "m": m})
    x = np.array([0.0, 1e-4, 0.3, 1.0, 1.7])
    lin, om = 0.021, np.array([1.0, 0.9999, 0.995, 0.98, 0.95])
    got = example.loss(x, linear_loss=lin, omega_ratio=om, background_exponent=2.5, **kw)
    np.testing.assert_allclose(np.asarray(got), lin * om + h * x ** (m - 1), rtol=1e-13,
                               atol=0)


def test_without_loss_exponent_the_background_exponent_applies(tmp_path):
    law = load_law_file(_file(tmp_path), SCENE)
    assert law.physics.loss_exponent is None and not law.has_own_loss
    kw = law.resolve(SCENE, {"young": 200e9, "h": 0.01, "m": 2.0})
    x, om, beta = np.array([0.2, 0.9]), np.array([0.99, 0.97]), 2.5
    got = law.loss(x, linear_loss=0.02, omega_ratio=om, background_exponent=beta, **kw)
    np.testing.assert_allclose(np.asarray(got), 0.02 * om**beta + 0.01 * x, rtol=1e-13)


def test_loss_increment_may_ask_for_scene_quantities(tmp_path):
    """Its keywords are law parameters or scene quantities, as force's: the scene's
    value arrives."""
    law = load_law_file(_file(tmp_path, args="x, *, h, m, load, mass",
                              body=f"{SAFE} * load / (mass * 9.81)"), SCENE)
    kw = law.resolve(SCENE, {"young": 200e9, "h": 0.01, "m": 2.0})
    want = 0.01 * 0.5 * SCENE["load"] / (SCENE["mass"] * 9.81)
    assert float(law.physics.loss_increment(0.5, **kw)) == pytest.approx(want, rel=1e-13)


def test_a_loss_exponent_alone_is_enough(tmp_path):
    text = textwrap.dedent(LAW).format(name="lf_beta", priors='{"young": dist.Uniform(150e9, '
                                       '250e9)}', top="LOSS_EXPONENT = 3", args="x",
                                       body="0.0")
    text = text[:text.index("def loss_increment")]
    law = load_law_file(_file(tmp_path, text=text), SCENE)
    assert law.physics.loss_exponent == 3.0 and law.physics.loss_increment is None
    assert isinstance(law.physics.loss_exponent, float)


# ------------------------------------------------------------------ the amplitude model
@pytest.fixture
def registered():
    """Register law files for one test, and take them out again after it."""
    before = set(registry.law_names())
    yield lambda law: registry.register(law).name
    for name in set(registry.law_names()) - before:
        registry.unregister(name)


@pytest.fixture(scope="module")
def inputs():
    from beadrod.data.process import load_default
    from beadrod.inference.model.likelihood import model_inputs

    ds = load_default()
    return ds, model_inputs(ds)


def _trace(name, inputs, values):
    from beadrod.inference.model.numpyro_models import build_model

    model = build_model(name, rung="first_order")
    return handlers.trace(handlers.substitute(handlers.seed(model, jax.random.PRNGKey(0)),
                                              data=values)).get_trace(inputs)


def test_model_has_no_background_exponent_for_a_law_with_its_own(example, registered,
                                                                   inputs):
    """The model built for the example (LOSS_EXPONENT = 1) has no loss_exponent site, and
    its predicted amplitude ratios are the closed form: 2 ln Omega - ln L(x) + ln L(x_ref)
    with L = L0 Omega + h x^(m-1), L0 the measured reference 1/Q (a law file predicts no
    Q) and Omega Hertz's first-order resonance ratio."""
    from tests.test_amplitude_likelihood import COMMON, _omega

    ds, data = inputs
    h, m = 0.01, 1.7
    tr = _trace(registered(example), data, {"young": 200e9, "h": h, "m": m, **COMMON})
    latent = {k for k, s in tr.items() if s["type"] == "sample" and not s["is_observed"]}
    assert "loss_exponent" not in tr and {"young", "h", "m"} <= latent
    idx = np.asarray(data["amp_idx"])[:40]
    om, x, d0 = _omega(ds, data, idx)
    p = np.asarray(ds.drive_protocol)[idx]
    lin = 1 / np.asarray(ds.q_ref)[p]
    x_ref = np.asarray(ds.ref_amplitude)[p] / d0
    want = (2 * np.log(om) - np.log(lin * om + h * x ** (m - 1))
            + np.log(lin + h * x_ref ** (m - 1))
            + COMMON["offset_amp_down"] * ds.drive_direction[idx])
    np.testing.assert_allclose(np.asarray(tr["amp_pred"]["value"])[:40], want, rtol=1e-8)


def test_model_fits_the_background_exponent_where_the_file_gives_none(tmp_path, registered,
                                                                      inputs):
    from tests.test_amplitude_likelihood import COMMON

    _, data = inputs
    name = registered(load_law_file(_file(tmp_path), SCENE))
    tr = _trace(name, data, {"young": 200e9, "h": 0.01, "m": 1.7, "loss_exponent": 1.0,
                             **COMMON})
    assert tr["loss_exponent"]["type"] == "sample"
    assert not tr["loss_exponent"]["is_observed"]


# ------------------------------------------------------------------ malformed: refused
@pytest.mark.parametrize("kw,match", [
    ({"top": "LOSS_EXPONENT = -1.0"}, "LOSS_EXPONENT = -1.0: it must be a finite real"),
    ({"top": "LOSS_EXPONENT = float('nan')"}, "LOSS_EXPONENT = nan"),
    ({"top": "LOSS_EXPONENT = float('inf')"}, "LOSS_EXPONENT = inf"),
    ({"top": "LOSS_EXPONENT = '3'"}, "LOSS_EXPONENT = '3'"),
    ({"top": "LOSS_EXPONENT = True"}, "LOSS_EXPONENT = True"),
    ({"tail": "loss_increment = 0.01\n"}, "loss_increment must be a function"),
    ({"args": "x, *, h, m, q"}, "loss_increment's argument 'q' has no prior"),
    ({"args": "*, x, h, m"}, "loss_increment must take the amplitude x"),
    ({"priors": PRIORS[:-1] + ', "k": dist.Normal(0, 1)}'},
     r"PRIORS\['k'\] is not an argument of force or loss_increment"),
    ({"body": "jnp.where(moving, jnp.nan * h, 0.0)"}, "NaN or infinite loss_increment"),
    ({"body": "h / x"}, "NaN or infinite loss_increment"),
    ({"body": "-h * x"}, "negative loss_increment"),
    ({"body": "h * jnp.exp((m - 1.0) * jnp.log(x))"},
     r"NaN or infinite gradient in m at x = \[0.0\]"),
    ({"body": "jnp.where(moving, h * jnp.exp((m - 1.0) * jnp.log(x)), 0.0)"},
     r"NaN or infinite gradient in m at x = \[0.0\]"),
    ({"body": "h * x * jnp.sqrt(jnp.abs(x - 0.5))"},
     r"NaN or infinite gradient in x at x = \[0.5\]"),
    ({"body": "h + 0.0 * x"}, "must vanish at zero amplitude"),
    ({"body": "h * jnp.ones(3)"}, "returned shape"),
    ({"body": "h * float(m) * x"}, "loss_increment raised"),
    ({"body": "h / 0"}, "loss_increment raised ZeroDivisionError"),
])
def test_malformed_loss_is_refused_naming_the_file(tmp_path, kw, match):
    f = _file(tmp_path, **kw)
    with pytest.raises(LawFileError, match=match) as err:
        load_law_file(f, SCENE)
    assert str(f) in str(err.value)
    assert len(str(err.value).splitlines()) == 1


def test_the_double_where_keeps_gradients_finite_at_zero():
    """The contract's reason for the double where, in numbers: x^(m-1) written as
    exp((m-1) ln x) has a NaN gradient in m at x = 0 (a single where does not help: the
    masked branch's NaN reaches the gradient), the double where's is finite; so is its
    gradient in x at x = 0 for m < 2, where the bare power's slope is infinite."""
    import jax.numpy as jnp

    x = jnp.asarray(0.0)

    def naive(m, x=x):
        return jnp.where(x > 0, 0.01 * jnp.exp((m - 1.0) * jnp.log(x)), 0.0)

    def safe(m, x=x):
        moving = x > 0
        return jnp.where(moving, 0.01 * jnp.exp((m - 1.0) * jnp.log(jnp.where(moving, x, 1.0))),
                         0.0)

    assert math.isnan(float(jax.grad(naive)(2.1)))
    assert float(jax.grad(safe)(2.1)) == 0.0 and float(safe(2.1)) == 0.0
    assert math.isinf(float(jax.grad(lambda v: 0.01 * v ** 0.5)(x)))
    assert float(jax.grad(lambda v: safe(1.5, v))(x)) == 0.0
