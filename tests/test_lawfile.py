"""Laws users write themselves (models.lawfile): the contract's errors name the file and
what is wrong; a Hertz written from scratch reproduces the built-in Hertz."""

import textwrap

import numpy as np
import pytest

from beadrod.inference.model.likelihood import scene_quantities
from beadrod.models import registry
from beadrod.models.lawfile import LawFileError, load_law_file
from beadrod.models.scene import builtin_scene

SCENE = scene_quantities(builtin_scene("paper"))
HERE = __import__("pathlib").Path(__file__).parent

GOOD = """
import jax.numpy as jnp
import numpyro.distributions as dist
NAME = "{name}"
PRIORS = {priors}
def force(delta, *, {args}):
    t = delta > 0
    d = jnp.where(t, delta, 1.0)
    return {body}
"""


def _write(tmp_path, name="mylaw", priors='{"young": dist.Uniform(150e9, 250e9)}',
           args="young, poisson, radius",
           body="jnp.where(t, 4/3 * young/(2*(1-poisson**2)) * jnp.sqrt(radius) * d**1.5, 0.0)",
           text=None):
    f = tmp_path / f"{name or 'law'}.py"
    f.write_text(text if text is not None else textwrap.dedent(GOOD.format(
        name=name, priors=priors, args=args, body=body)))
    return f


@pytest.mark.parametrize("kw,match", [
    ({"name": ""}, "NAME is missing"),
    ({"name": "2bad"}, "NAME is missing or not a name"),
    ({"text": "NAME = 'x'\n"}, "PRIORS is missing"),
    ({"text": "NAME = 'x'\nPRIORS = {}\n"}, "force"),
    ({"args": "young, poisson, radius, stiffness_k"}, "'stiffness_k' has no prior"),
    ({"priors": '{"young": dist.Uniform(150e9, 250e9), "k": dist.Normal(0, 1)}'},
     r"PRIORS\['k'\] is not an argument of force"),
    ({"priors": '{"young": 3.0}'}, "not a distribution"),
    ({"body": "jnp.nan * d"}, "NaN or infinite force"),
    ({"body": "-d"}, "no static overlap"),
    ({"body": "4/3 * young/(2*(1-poisson**2)) * jnp.sqrt(radius) * jnp.abs(delta)**1.5"},
     "must be zero for delta <= 0"),
    ({"body": "1/0"}, "raised ZeroDivisionError"),
])
def test_contract_errors_name_the_file(tmp_path, kw, match):
    f = _write(tmp_path, **kw)
    with pytest.raises(LawFileError, match=match) as err:
        load_law_file(f, SCENE)
    assert str(f) in str(err.value)


def test_missing_file():
    with pytest.raises(LawFileError, match="no such file"):
        load_law_file(HERE / "laws" / "nope.py", SCENE)


@pytest.mark.slow
def test_hertz_from_scratch_matches_builtin_hertz():
    """The example law file: its first order is the closed form to 1e-12 and its backbone,
    tabulated on load, is within 1e-7 of the built-in table (slow: the table is built from
    the generic quadrature, about a minute)."""
    law = load_law_file(HERE / "laws" / "hertz_scratch.py", SCENE)
    hertz = registry.get_law("hertz")
    x = np.linspace(0.0, 2.0, 81)
    for young in (160e9, 240e9):
        kw, kh = law.resolve(SCENE, {"young": young}), hertz.resolve(SCENE, {"young": young})
        assert float(law.overlap(**kw)) == pytest.approx(float(hertz.overlap(**kh)), rel=1e-12)
        f0 = 2700.0
        assert float(law.overlap_at(f0, **kw)) == pytest.approx(
            float(hertz.overlap_at(f0, **kh)), rel=1e-12)
        for rung, tol in (("first_order", 1e-12), ("backbone", 1e-7)):
            np.testing.assert_allclose(law.shift(x, rung=rung, **kw),
                                       hertz.shift(x, rung=rung, **kh), atol=tol)
    assert "tabulated" in law.presentation.description
