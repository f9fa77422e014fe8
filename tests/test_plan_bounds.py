"""Are the plan's error bounds honest? (issue 3, "Scenes")

For each built-in scene and each effect its plan leaves out that the simulator can add,
simulating WITH it must change Delta f/f0 (harmonic-balance resonance peak at equal bead
amplitude, the plan's largest amplitude unless noted) by less than the plan's
``error_bound``; for effects it includes, leaving one out must change the result by more
than the tolerance. Bounds found dishonest are marked xfail(strict) with the measured
numbers, so they flip to failures once models/scene/plan.py is fixed: they are reported, not
loosened. The plan's largest amplitude is also checked: the simulated bead reaches it only
at a base drive >= the scene's largest.
"""

import math

import pytest

from beadrod.models.scene import builtin_scene
from beadrod.models.scene.plan import plan_scene
from beadrod.models.scene.simulate import build_simulator

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
# Bounds found dishonest: (scene, effect) -> measured numbers (none at present). The two
# formerly here: large_soft_bead / rod_dispersion (the plan linearised at K0 c_b = 0.60 and
# ignored the higher modes' dispersion; now exact in K0 c_b, all modes summed) and
# micro_bead / rod (f0 = 34 f_rod among the rod's resonances; the plan now includes the rod,
# see test_included_rod_changes_micro_bead_shift).
_DISHONEST = {}
LEFT_OUT_SLOW = [
    # 0.99 of the plan's largest amplitude (6.16e-8 m): at exactly that amplitude the
    # simulator's 256-mode peak continuation misses its Newton tolerance (sporadically near
    # x = 1, e.g. also at 1.02 delta0, while 0.999 and 1.005 converge)
    ("paper", "rod_waveguide", {"include": {"rod_waveguide"}}, 0.99 * 6.16e-8),
    ("paper", "rod_dispersion", {"include": {"rod_dispersion"}}, None),
    ("large_soft_bead", "adhesion", {"include": {"adhesion"}}, None),
    ("large_soft_bead", "harmonics", {"harmonics": 7}, None),
    ("large_soft_bead", "rod_dispersion", {"include": {"rod_dispersion"}}, None),
    ("micro_bead", "harmonics", {"harmonics": 7}, None),
    # the plan's largest amplitude (x = 4.8) is past contact loss: a moderate one
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


@pytest.mark.slow  # in `-m slow`, run before an issue is resolved (keeps CI under 12 min)
@pytest.mark.parametrize(("name", "effect", "alt", "amplitude"), _params(LEFT_OUT_FAST))
def test_left_out_effect_within_bound(name, effect, alt, amplitude):
    _check_left_out(name, effect, alt, amplitude)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "effect", "alt", "amplitude"), _params(LEFT_OUT_SLOW))
def test_left_out_effect_within_bound_slow(name, effect, alt, amplitude):
    _check_left_out(name, effect, alt, amplitude)


@pytest.mark.slow  # in `-m slow`, run before an issue is resolved (keeps CI under 12 min)
@pytest.mark.parametrize("name", ["paper", "large_soft_bead", "micro_bead"])
def test_contact_loss_left_out_is_exact_and_amplitude_is_an_upper_bound(name):
    # bound 0: at the plan's largest amplitude the simulated orbit never reaches the law's
    # separation overlap (0, or JKR's pull-off overlap < 0), so the unilateral clip (and the
    # time-integration rung built for it) cannot act
    scene, plan = _plan(name)
    e = plan.effect("contact_loss")
    assert not e.included and e.error_bound == 0
    p = build_simulator(scene, plan).peak(plan.numbers["amplitude_max_m"])
    assert p["min_overlap"] > e.details["separation"] + 0.05
    # and the plan's amplitude (Q_c |T| U_max) is not reached below the largest drive
    assert abs(p["base_displacement_m"]) >= scene.drive_displacement_max


@pytest.mark.slow
def test_amplitude_estimate_is_tight_for_the_viscous_coupled_rod():
    # large soft bead: Q from the viscosity, raised by the rod to Q (1 + K0 c_b)^(3/2) ~ 42:
    # the simulated peak (rod Q 200, softening) needs just above U_max for the plan's amplitude
    scene, plan = _plan("large_soft_bead")
    p = build_simulator(scene, plan).peak(plan.numbers["amplitude_max_m"])
    assert 1.0 <= p["base_displacement_m"] / scene.drive_displacement_max < 1.15


@pytest.mark.slow  # in `-m slow`, run before an issue is resolved (keeps CI under 12 min)
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
    # at 0.8 delta0: the plan's largest bead amplitude (1.03 delta0) is past contact loss
    # on a rigid base, where the rod's compliance no longer lowers the overlap
    _, plan = _plan("large_soft_bead")
    assert plan.included("rod")
    a = 0.8 * plan.numbers["delta0_m"]
    assert _change("large_soft_bead", a, {}, {"exclude": {"rod"}}) > plan.tolerance


@pytest.mark.slow
def test_included_rod_changes_micro_bead_shift():
    # the plan includes the rod because f0 sits among its resonances (ln|T| curvature above
    # 4 Q^2): leaving it out changes the shift by more than the shift itself (here it even
    # flips its sign), though at this drive by less than the tolerance
    scene, plan = _plan("micro_bead")
    assert plan.included("rod") and plan.effect("rod").error_bound == math.inf
    a = plan.numbers["amplitude_max_m"]
    s_rod = build_simulator(scene, plan).peak(a)["shift"]
    s_rigid = build_simulator(scene, plan, exclude={"rod", "rod_waveguide",
                                                    "rod_dispersion"}).peak(a)["shift"]
    assert abs(s_rod - s_rigid) > abs(s_rigid)
