"""Are the plan's error bounds honest? (issue 3, "Scenes")

For each built-in scene and each effect its plan leaves out that the simulator can add,
simulating WITH it must change Delta f/f0 (harmonic-balance resonance peak at equal bead
amplitude, the plan's largest amplitude unless noted) by less than the plan's
``error_bound``; for effects it includes, leaving one out must change the result by more
than the tolerance. Bounds found dishonest are marked xfail(strict) with the measured
numbers, so they flip to failures once models/plan.py is fixed: they are reported, not
loosened.
"""

import pytest

from models.plan import plan_scene
from models.scenes import builtin_scene
from models.simulate import build_simulator

_PLANS = {}


def _plan(name):
    if name not in _PLANS:
        _PLANS[name] = (builtin_scene(name), plan_scene(builtin_scene(name)))
    return _PLANS[name]


def _change(name, amplitude, base, alt, bead=True):
    scene, plan = _plan(name)
    a = plan.numbers["amplitude_max_m"] if amplitude is None else amplitude
    s0 = build_simulator(scene, plan, **base).peak(a, bead=bead)["shift"]
    s1 = build_simulator(scene, plan, **alt).peak(a, bead=bead)["shift"]
    return abs(s1 - s0)


# (scene, effect the plan leaves out, what adding it means, amplitude [m] or None = plan max)
LEFT_OUT_FAST = [
    ("large_soft_bead", "viscous_losses", {"include": {"viscous_losses"}}, None),
    ("micro_bead", "viscous_losses", {"include": {"viscous_losses"}}, None),
]
_DISHONEST = {
    ("large_soft_bead", "rod_dispersion"): "measured 4.7e-6 > bound 1.9e-6 (plan linearises "
    "at K0 c_b = 0.60, beyond its own 1/3 limit, and ignores the higher modes' dispersion)",
    ("micro_bead", "rod"): "measured 4.6e-5 > bound 2.2e-10: f0 = 34 f_rod, the finite rod's "
    "resonances (spacing 2 f_rod ~ f0/17, comparable to the bandwidth f0/Q) and its base-drive "
    "transmissibility 1/cos(kL) move the measured peak; the semi-infinite impedance misses both",
}
LEFT_OUT_SLOW = [
    ("paper", "rod_waveguide", {"include": {"rod_waveguide"}}, None),
    ("paper", "rod_dispersion", {"include": {"rod_dispersion"}}, None),
    ("large_soft_bead", "adhesion", {"include": {"adhesion"}}, None),
    ("large_soft_bead", "harmonics", {"harmonics": 7}, None),
    ("large_soft_bead", "rod_dispersion", {"include": {"rod_dispersion"}}, None),
    ("micro_bead", "harmonics", {"harmonics": 7}, None),
    ("micro_bead", "rod", {"include": {"rod", "rod_waveguide"}}, None),
    # the plan's largest amplitude (x = 4.4) is past contact loss: a moderate one
    ("strong_drive", "rod_dispersion", {"include": {"rod_dispersion"}}, 0.5 * 61.7e-9),
]


def _params(cases):
    out = []
    for c in cases:
        reason = _DISHONEST.get(c[:2])
        marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
        out.append(pytest.param(*c, marks=marks, id=f"{c[0]}-{c[1]}"))
    return out


def _check_left_out(name, effect, alt, amplitude):
    _, plan = _plan(name)
    e = plan.effect(effect)
    assert not e.included
    assert _change(name, amplitude, {}, alt) < e.error_bound


@pytest.mark.parametrize(("name", "effect", "alt", "amplitude"), _params(LEFT_OUT_FAST))
def test_left_out_effect_within_bound(name, effect, alt, amplitude):
    _check_left_out(name, effect, alt, amplitude)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "effect", "alt", "amplitude"), _params(LEFT_OUT_SLOW))
def test_left_out_effect_within_bound_slow(name, effect, alt, amplitude):
    _check_left_out(name, effect, alt, amplitude)


@pytest.mark.parametrize("name", ["paper", "large_soft_bead", "micro_bead"])
def test_contact_loss_left_out_is_exact(name):
    # bound 0: at the plan's largest amplitude the simulated orbit never opens the contact,
    # so the unilateral clip (and the time-integration rung built for it) cannot act
    scene, plan = _plan(name)
    assert not plan.included("contact_loss") and plan.effect("contact_loss").error_bound == 0
    p = build_simulator(scene, plan).peak(plan.numbers["amplitude_max_m"])
    assert p["min_overlap"] > 0.05


def test_included_adhesion_matters_paper():
    # JKR -> Hertz at equal bead amplitude (0.8 of the Hertz delta0 = 53 nm, below contact
    # loss for Hertz): more than the tolerance, less than the bound
    _, plan = _plan("paper")
    e = plan.effect("adhesion")
    assert e.included
    d = _change("paper", 0.8 * 53e-9, {}, {"exclude": {"adhesion"}})
    assert plan.tolerance < d < e.error_bound


@pytest.mark.slow
def test_included_rod_matters_large_soft_bead():
    _, plan = _plan("large_soft_bead")
    assert plan.included("rod")
    assert _change("large_soft_bead", None, {}, {"exclude": {"rod"}}) > plan.tolerance
