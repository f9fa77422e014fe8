"""Harmonic balance (rung 4) against closed forms, the exact backbone and finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from beadrod.models.ladder import harmonic_balance
from beadrod.models.ladder.backbone import backbone_shift
from beadrod.models.ladder.oscillator import PowerLaw, hertz_oscillator


@pytest.mark.slow  # in `-m slow`, run before an issue is resolved (keeps CI under 12 min)
def test_hbm_backbone_converges_to_energy_integral_backbone():
    # conservative Hertz oscillator, amplitudes with and without contact loss
    xs = jnp.array([0.3, 0.8, 1.2])
    exact = np.asarray(backbone_shift(xs))
    f = jax.jit(jax.vmap(lambda x: harmonic_balance.backbone_shift(hertz_oscillator(), x, harmonics=7, n_time=256)))
    h7 = np.asarray(f(xs))
    np.testing.assert_allclose(h7[:2], exact[:2], rtol=1e-6)
    # contact loss: the force has a kink, the harmonic series converges algebraically
    assert h7[2] == pytest.approx(exact[2], rel=2e-3)
    # one harmonic alone is a visibly worse approximation (the mean shift matters)
    h1 = float(harmonic_balance.backbone_shift(hertz_oscillator(), 0.3, harmonics=1))
    assert abs(h1 - exact[0]) > 20 * abs(h7[0] - exact[0])


def test_linear_limit_peak_matches_closed_form():
    # q'' + 2 zeta q' + q = -E Omega^2 sin: |q1| = E Omega^2 / |1 - Omega^2 + 2i zeta Omega|,
    # maximum at Omega^2 = 1/(1 - 2 zeta^2), value E / (2 zeta sqrt(1 - zeta^2))
    zeta, e = 0.05, 1e-7
    om, x, _ = harmonic_balance.peak_at_drive(PowerLaw(n=1.5, zeta=zeta), e, harmonics=2)
    assert float(om) == pytest.approx(1 / np.sqrt(1 - 2 * zeta**2), rel=1e-8)
    assert float(x) == pytest.approx(e / (2 * zeta * np.sqrt(1 - zeta**2)), rel=1e-7)


def test_frf_hysteresis_folds_and_peak():
    law = hertz_oscillator(0.01)
    r = harmonic_balance.frf(law, 0.015, 0.85, 1.1, harmonics=3, n_steps=200)
    assert bool(r.complete)
    om, amp = np.asarray(r.omega)[np.asarray(r.valid)], np.asarray(r.amplitude)[np.asarray(r.valid)]
    # softening: the down sweep jumps at a lower frequency than the up sweep
    up, down = float(r.up_jump_omega), float(r.down_jump_omega)
    assert down < up < 1.0
    # the curve really is multivalued between the folds
    mid = 0.5 * (up + down)
    crossings = np.sum(np.diff(np.sign(om - mid)) != 0)
    assert crossings == 3
    # the peak solve agrees with the densest point of the arc and lies near the down fold
    assert float(r.peak_amplitude) >= amp.max() - 1e-12
    assert float(r.peak_omega) == pytest.approx(down, abs=2e-3)
    # and a stepped HBM sweep falls off the branch right where the continuation says
    grid = np.linspace(0.85, 1.1, 251)
    xs, ok = harmonic_balance.sweep(law, 0.015, grid, harmonics=3)
    a = np.asarray(harmonic_balance.amplitude(xs))
    jump = grid[np.argmax(np.diff(a)) + 1]      # softening: the up sweep jumps up
    assert bool(np.all(ok)) and abs(jump - up) < 2e-3


def test_solve_ift_gradient_matches_finite_difference():
    # single-frequency solve: d amplitude / d(zeta, n, E) through custom_root
    def amp(p):
        x = harmonic_balance.solve(PowerLaw(n=p[0], zeta=p[1]), p[2], 0.995,
                      jnp.array([0.0, 0.2, 0.0, 0.0, 0.0]), harmonics=2)
        return harmonic_balance.amplitude(x)

    p0 = jnp.array([1.5, 0.02, 0.004])
    g = np.asarray(jax.grad(amp)(p0))
    for i, h in enumerate((1e-6, 1e-8, 1e-9)):
        d = jnp.zeros(3).at[i].set(h)
        fd = (float(amp(p0 + d)) - float(amp(p0 - d))) / (2 * h)
        assert g[i] == pytest.approx(fd, rel=1e-5)


@pytest.mark.slow
def test_peak_at_amplitude_ift_gradient_matches_finite_difference():
    def peak(zeta):
        om, e, _ = harmonic_balance.peak_at_amplitude(PowerLaw(n=1.5, zeta=zeta), 0.4,
                                         omega_guess=0.99, harmonics=3)
        return om

    g = float(jax.grad(peak)(0.02))
    fd = (float(peak(0.02 + 1e-6)) - float(peak(0.02 - 1e-6))) / 2e-6
    assert np.isfinite(g) and g == pytest.approx(fd, rel=1e-4)
    # and the peak amplitude really is the requested one at the solved drive
    om, e, x = harmonic_balance.peak_at_amplitude(PowerLaw(n=1.5, zeta=0.02), 0.4, omega_guess=0.99)
    om2, x2, _ = harmonic_balance.peak_at_drive(PowerLaw(n=1.5, zeta=0.02), e, omega_guess=om,
                                   amplitude_guess=0.4)
    assert float(x2) == pytest.approx(0.4, rel=1e-9)
    assert float(om2) == pytest.approx(float(om), rel=1e-12)
