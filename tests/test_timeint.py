"""Time integration of the stepped swept sine (rung 5): closed forms, scipy, harmonic balance."""

import jax
import numpy as np
import pytest

from beadrod.models.ladder import harmonic_balance, time_integration
from beadrod.models.ladder.oscillator import hertz_oscillator


def test_low_drive_q_and_resonance_amplitude():
    # linear limit: -3 dB Q = 1/(2 zeta) (to O(zeta^2)); peak |q1| = E/(2 zeta sqrt(1-zeta^2))
    zeta, e = 0.025, 1e-5
    om = np.linspace(0.92, 1.08, 65)
    s = jax.jit(lambda: time_integration.swept_sine(hertz_oscillator(zeta), e, om, settle_periods=60,
                                           measure_periods=2, steps_per_period=32))()
    assert time_integration.q_factor_3db(s.omega, s.amplitude) == pytest.approx(1 / (2 * zeta), rel=1e-2)
    _, x = time_integration.resonance(s.omega, s.amplitude)
    assert float(x) == pytest.approx(e / (2 * zeta * np.sqrt(1 - zeta**2)), rel=2e-3)
    # the bead's own first harmonic differs from the overlap's by the base motion
    i = int(np.argmax(np.asarray(s.amplitude)))
    assert abs(float(s.bead[i]) - float(s.amplitude[i])) < 1.5 * e


def test_rk4_sweep_matches_scipy_through_contact_loss():
    law, e = hertz_oscillator(0.025), 0.06
    om = np.array([0.93, 0.925, 0.92])
    # same lock-in samples in both (the transient after 10 periods is not periodic)
    kw = dict(settle_periods=10, measure_periods=2, state0=(0.8, 0.0))
    j = time_integration.swept_sine(law, e, om, steps_per_period=256, **kw)
    s = time_integration.swept_sine_scipy(law, e, om, rtol=1e-10, atol=1e-12, samples_per_period=256,
                                 **kw)
    assert float(j.amplitude.max()) > 1.0          # the contact opens on these orbits
    np.testing.assert_allclose(np.asarray(j.amplitude), s.amplitude, atol=1e-5)


def _compare(law, e, om, settle, harmonics=5):
    up, down = time_integration.up_down(law, e, om, settle_periods=settle, measure_periods=2)
    worst = 0.0
    for sweep, grid in ((up, om), (down, om[::-1])):
        xs, ok = harmonic_balance.sweep(law, e, grid, harmonics=harmonics)
        assert bool(np.all(ok))
        a_hb, a_ti = np.asarray(harmonic_balance.amplitude(xs)), np.asarray(sweep.amplitude)
        # skip the points on either side of each jump: near a fold the transient decays
        # arbitrarily slowly (critical slowing down) and has not settled there
        jump = np.r_[False, np.abs(np.diff(a_hb)) > 0.1]
        near = jump | np.r_[jump[1:], False] | np.r_[False, jump[:-1]]
        worst = max(worst, np.max(np.abs(a_hb - a_ti)[~near]))
    return worst, float(np.max(up.amplitude))


@pytest.mark.parametrize("e,tol", [(0.005, 2e-4), (0.02, 1e-3), (0.08, 2e-3)])
def test_hbm_matches_time_integration_full_frc(e, tol):
    # three drive levels with Q = 20: linear-ish, softened, contact loss with hysteresis
    om = np.linspace(0.85, 1.1, 26)
    worst, peak = _compare(hertz_oscillator(0.025), e, om, settle=40)
    assert worst < tol
    if e == 0.08:
        assert peak > 1.0


@pytest.mark.slow
@pytest.mark.parametrize("e", [0.002, 0.006, 0.012])
def test_hbm_matches_time_integration_q50_fine(e):
    om = np.linspace(0.9, 1.05, 121)
    worst, _ = _compare(hertz_oscillator(0.01), e, om, settle=150, harmonics=7)
    assert worst < 2e-3
