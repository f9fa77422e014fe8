"""Every model of the default comparison passes its sampling gate on every embedded world
and on fresh synthetic worlds of seeds the project was never tuned on, at the default
sampling settings (workflows.config.DEFAULTS), every law at the comparison's default rung.

The gate is the one ``beadrod compare`` applies (inference.sampling.diagnostics.check: R-hat,
bulk and tail ESS, divergences, E-BFMI), after the same extensions of a run short of ESS
(``sampling.extensions``). Slow: one full-length NUTS run per model and
world (about 15 min on 2 cores for all of them).
"""

import pytest

SEEDS_NEVER_TUNED = (2027,)


def _worlds():
    out = [(w, None) for w in ("paper_like", "hertz_dynamics")]
    out += [(w, s) for s in SEEDS_NEVER_TUNED for w in ("paper_like", "hertz_dynamics")]
    return out


@pytest.fixture(scope="module")
def datasets(tmp_path_factory):
    """Processed datasets by (world, seed); seed None = the embedded folder."""
    from beadrod import data as bd
    from beadrod.data.synth import write_world

    cache = {}

    def get(world, seed):
        if (world, seed) not in cache:
            folder = (bd.default_path().parent / world if seed is None else
                      write_world(world, tmp_path_factory.mktemp(f"{world}_{seed}"), seed))
            cache[(world, seed)] = bd.process(bd.load_dataset(folder))
        return cache[(world, seed)]

    return get


def _model_names():
    from beadrod.workflows.pipeline.fits import default_model_names

    return default_model_names()


@pytest.mark.slow
@pytest.mark.parametrize("world,seed", _worlds(),
                         ids=[f"{w}-{'embedded' if s is None else s}" for w, s in _worlds()])
def test_every_default_model_passes_its_gate(datasets, world, seed):
    from beadrod.inference.model.likelihood import model_inputs
    from beadrod.inference.model.numpyro_models import build_model
    from beadrod.inference.sampling import diagnostics
    from beadrod.inference.sampling.sample import run_nuts
    from beadrod.models.registry import DEFAULT_RUNG
    from beadrod.workflows.config import DEFAULTS
    from beadrod.workflows.pipeline.fits import comparison_specs

    ds = datasets(world, seed)
    inputs = model_inputs(ds)
    s = DEFAULTS["sampling"]
    ess_min = diagnostics.gate_ess(s["samples"], s["chains"])
    failed = {}
    for name, spec in comparison_specs(_model_names(), DEFAULT_RUNG, "normal").items():
        fit = run_nuts(build_model(spec, scene=inputs.get("scene")), inputs,
                       num_warmup=s["warmup"], num_samples=s["samples"],
                       num_chains=s["chains"], target_accept=s["target_accept"],
                       seed=DEFAULTS["seed"], predictive=False,
                       coords={"protocol": list(ds.protocol_ids)}, ess_target=ess_min,
                       max_extensions=s["extensions"])
        verdict = diagnostics.check(fit.idata, ess_min=ess_min)
        if not verdict.passed:
            failed[name] = str(verdict)
    assert not failed, failed
