"""The dynamic rungs for any law (models.ladder.generic_dynamics: series, harmonic balance, time
integration from the law's force) against the power-law ladder (models.ladder.powerlaw_ladder, whose
oscillator is models.ladder.oscillator.PowerLaw's closed force), the closed-form Lindstedt
coefficient, and the backbone limit of a lightly damped adhesive (JKR) oscillator."""

import math

import numpy as np
import pytest

from beadrod.models.ladder import generic_dynamics, powerlaw_ladder
from beadrod.models.laws import hertz, powerlaw, viscoelastic
from beadrod.models.rungs import LADDER, RUNGS

SCENE = {"radius": 7.938e-3, "young": 200e9, "poisson": 0.27, "load": 0.1582,
         "mass": 0.01613, "gravity": 9.81}


def _kw(law, **theta):
    kw = law.resolve(SCENE, theta)
    return kw, float(law.overlap(**kw))


def _power(n):
    return (powerlaw.LAW, *_kw(powerlaw.LAW, n=n, delta0_ref_log=math.log(55e-9)))


@pytest.mark.parametrize("n", [1.3, 1.5, 2.5])
def test_series_is_the_closed_form_lindstedt_coefficient(n):
    law, kw, d0 = _power(n) if n != 1.5 else (hertz.LAW, *_kw(hertz.LAW, young=200e9))
    x = np.array([0.0, 0.1, 0.5, 1.3])
    got = np.asarray(law.shift(x, rung="series", delta0=d0, **kw))
    # c = 3 a3/8 - 5 a2^2/12 with a2 = (n-1)/2, a3 = (n-1)(n-2)/6 (Nayfeh & Mook 4.1.1)
    np.testing.assert_allclose(got, -(n - 1) * (2 * n + 1) / 48 * x**2, rtol=1e-12, atol=0)
    np.testing.assert_allclose(got, powerlaw_ladder.rung1_series(x, n), rtol=1e-12, atol=0)


@pytest.mark.slow  # each law compiles its peak solve, 20-50 s on two shared cores
@pytest.mark.parametrize("name, n, x", [
    ("hertz", 1.5, [0.3, 0.8, 1.2]),     # 1.2: past contact loss
    ("powerlaw", 1.3, [0.3, 0.8]), ("powerlaw", 2.5, [0.3, 0.8, 1.2])])
def test_harmonic_balance_matches_the_power_law_ladder(name, n, x):
    law, kw, d0 = (hertz.LAW, *_kw(hertz.LAW, young=200e9)) if name == "hertz" else _power(n)
    x = np.asarray(x)
    got = law.shift(x, rung="harmonic_balance", delta0=d0, q_factor=40.0, **kw)
    want = powerlaw_ladder.rung4_hbm(x, n, q_factor=40.0, harmonics=3)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-10)
    assert np.all(np.diff(got) < 0)          # softening, growing with x


@pytest.mark.slow
@pytest.mark.parametrize("n", [1.5, 2.5])
def test_time_integration_matches_the_power_law_ladder(n):
    law, kw, d0 = (hertz.LAW, *_kw(hertz.LAW, young=200e9)) if n == 1.5 else _power(n)
    got = law.shift(np.array([0.5]), rung="time_integration", delta0=d0, q_factor=20.0, **kw)
    want = powerlaw_ladder.rung5_timeint(np.array([0.5]), n, q_factor=20.0)
    # same experiment, same integrator: only the backbone-slope correction's source (the
    # law's tabulated backbone here, the exact quadrature there) differs
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-7)
    # and the measured resonance is near the backbone: O(1/Q^2) and H = 3 drive errors
    bb = float(np.asarray(law.shift(np.array([0.5]), rung="backbone", delta0=d0, **kw))[0])
    assert abs(float(got[0]) - bb) < 1.0 / 20.0**2


@pytest.mark.slow
def test_viscoelastic_q_and_damping_are_the_kuwabara_kono_ones():
    # the law's own linear Q sets zeta, and the stiffness-proportional dashpot is KK's:
    # the generic HBM equals the peak of models.ladder.oscillator.Viscoelastic(A omega0 = 1/Q)
    from beadrod.models.ladder.oscillator import PowerLaw, Viscoelastic

    law = viscoelastic.LAW
    kw, d0 = _kw(law, young=200e9, eta=2e5)
    kw["omega0"] = 2 * math.pi * 2700.0
    q = generic_dynamics.quality_factor(law, delta0=d0, **kw)
    assert q == pytest.approx(float(law.quality_factor(**kw)), rel=1e-12)
    got = law.shift(np.array([0.6]), rung="harmonic_balance", delta0=d0, **kw)
    om, _, _ = powerlaw_ladder.hbm_peak(Viscoelastic(a_omega0=1.0 / q), PowerLaw(n=1.5), 0.6,
                               omega_guess=0.98, harmonics=3)
    assert float(got[0]) == pytest.approx(om - 1.0, abs=1e-10)


@pytest.mark.slow
def test_jkr_peak_tends_to_its_backbone_as_one_over_q_squared():
    from beadrod.models.laws import jkr

    law = jkr.LAW
    kw, d0 = _kw(law, young=200e9, gamma=0.7)
    x = np.array([0.2])
    bb = float(np.asarray(law.shift(x, rung="backbone", delta0=d0, **kw))[0])
    gap = {q: float(law.shift(x, rung="harmonic_balance", delta0=d0, q_factor=q, **kw)[0]) - bb
           for q in (25.0, 50.0)}
    # the lightly damped peak sits O(1/Q^2) above the backbone (linear: 1/(4 Q^2))
    for q, g in gap.items():
        assert 0 < g < 1.0 / q**2
    assert gap[25.0] / gap[50.0] == pytest.approx(4.0, rel=0.15)


@pytest.mark.slow
def test_contact_loss_gives_a_number_or_a_clear_error_never_nan():
    law, kw, d0 = hertz.LAW, *_kw(hertz.LAW, young=200e9)
    x = np.array([1.2, 1.5])
    got = law.shift(x, rung="harmonic_balance", delta0=d0, q_factor=40.0, **kw)
    bb = np.asarray(law.shift(x, rung="backbone", delta0=d0, **kw))
    assert np.all(np.isfinite(got)) and np.all(np.abs(got - bb) < 1e-3)
    plaw, pkw, pd0 = _power(2.5)
    for xv in (1.2, 1.5, 2.0):
        # past contact loss the peak system is nearly singular: a number near the
        # backbone, or an error naming x, never NaN
        try:
            v = plaw.shift(np.array([xv]), rung="harmonic_balance", delta0=pd0, **pkw)[0]
        except RuntimeError as exc:
            assert f"x = {xv}" in str(exc) and "harmonic balance" in str(exc)
            continue
        b = float(np.asarray(plaw.shift(np.array([xv]), rung="backbone", delta0=pd0,
                                        **pkw))[0])
        assert np.isfinite(v) and abs(v - b) < 5e-3


def test_every_builtin_law_lists_every_ladder_rung():
    from beadrod.models.registry import get_law, law_names

    for name in law_names():
        law = get_law(name)
        if law.physics.loss_increment is not None:
            # a loss that grows with the amplitude (hysteresis) is not in the force, which
            # is all the generic rungs integrate: such a law offers its closed forms only
            assert set(law.physics.rungs) == set(law.physics.shifts), name
            continue
        assert set(LADDER) <= set(law.physics.rungs), name


def test_a_law_without_loss_refuses_a_useless_q():
    law, kw, d0 = hertz.LAW, *_kw(hertz.LAW, young=200e9)
    assert generic_dynamics.quality_factor(law, delta0=d0, **kw) == generic_dynamics.DEFAULT_Q
    with pytest.raises(ValueError, match="Q > 2"):
        generic_dynamics.quality_factor(law, delta0=d0, q_factor=1.0, **kw)


# ------------------------------------------------------------------ beadrod shift --method


def test_shift_command_takes_every_rung_the_law_has(capsys):
    import json

    from beadrod.workflows.cli import main
    from beadrod.workflows.commands.shift import METHODS

    assert set(METHODS) == set(RUNGS)
    assert main(["shift", "--law", "hertz", "--x", "0.5", "1.5", "--method", "series",
                 "--json"]) == 0
    t = json.loads(capsys.readouterr().out)
    assert t["rung"] == "series"
    assert t["delta_f_over_f0"] == pytest.approx([-0.25 / 24, -2.25 / 24], rel=1e-12)
    # a rung the law does not list is refused with the law's rungs, never swapped
    assert main(["shift", "--law", "dmt", "--x", "0.5", "--method", "paper_eq25"]) == 2
    err = capsys.readouterr().err
    assert "no paper_eq25 rung" in err and "harmonic_balance" in err


@pytest.mark.slow
def test_shift_command_harmonic_balance_is_the_ladder_peak(capsys):
    import json

    from beadrod.workflows.cli import main

    assert main(["shift", "--law", "hertz", "--x", "0.4", "--method", "harmonic_balance",
                 "--json"]) == 0
    t = json.loads(capsys.readouterr().out)
    want = powerlaw_ladder.rung4_hbm(np.array([0.4]), 1.5, q_factor=generic_dynamics.DEFAULT_Q, harmonics=3)
    assert t["delta_f_over_f0"][0] == pytest.approx(float(want[0]), abs=1e-10)
