"""The scene simulator (models/simulate.py) against independent references."""

import dataclasses

import numpy as np
import pytest

from models import ladder
from models.scenes import builtin_scene
from models.simulate import PlasticityError, build_simulator


def _hertz_scene(q=50.0):
    s = builtin_scene("paper")
    return dataclasses.replace(s, viscosity=None, quality_factor=q, surface_energy=0.0)


def test_hertz_with_losses_reproduces_ladder_rung4():
    # no rod, Hertz, Kuwabara-Kono losses of Q = 50 (A omega0 = 1/Q): the ladder's rung-4 law
    sim = build_simulator(_hertz_scene(50.0), exclude={"rod", "adhesion"},
                          include={"viscous_losses"}, harmonics=3)
    assert sim.law_name == "Hertz" and sim.dyn.rho.shape == (0,)
    x = 0.5
    got = sim.peak(x * sim.delta0, bead=False)["shift"]
    r = ladder.rung4_hbm(np.array([x, 1e-3]), q_factor=50.0, harmonics=3)
    assert got == pytest.approx((1 + r[0]) / (1 + r[1]) - 1, rel=1e-6)
    assert got < -0.01     # and it is a real softening, not a trivial zero


def test_rod_coupled_linear_resonance_is_the_2dof_eigenfrequency():
    sc = _hertz_scene(1e5)
    sim = build_simulator(sc, include={"rod"}, exclude={"rod_waveguide", "contact_loss"},
                          harmonics=1, rod_q=1e7)
    m, big_m = sc.mass, 0.5 * sc.rod_mass
    k0, kr = sim.k0, big_m * (2 * np.pi * sc.rod_first_resonance) ** 2
    stiff = np.array([[k0, -k0], [-k0, k0 + kr]])
    w2 = np.sort(np.linalg.eigvals(np.diag([1 / m, 1 / big_m]) @ stiff).real)
    f_eig = np.sqrt(w2[0]) / (2 * np.pi)
    f_sim = sim.linear_peak_ratio() * sim.f0
    assert f_sim == pytest.approx(f_eig, rel=1e-6)
    assert abs(f_eig / sim.f0 - 1) > 0.01    # the rod matters at this precision


def test_plasticity_refused_at_build():
    s = builtin_scene("paper")
    soft = dataclasses.replace(s.bead_material, yield_strength=1e8)
    s = dataclasses.replace(s, bead_material=soft, rod_material=soft)
    with pytest.raises(PlasticityError, match="plastic limit|yield"):
        build_simulator(s)


def test_plasticity_refused_when_a_drive_exceeds_the_limit():
    s = _hertz_scene(50.0)
    # Fl just above the static load: the plan (tiny drive) passes, a large amplitude yields
    y = 2.1e8                                   # Fl = 0.26 N; load 0.16 N
    soft = dataclasses.replace(s.bead_material, yield_strength=y)
    s = dataclasses.replace(s, bead_material=soft, rod_material=soft, voltage_max=0.01)
    sim = build_simulator(s, exclude={"rod"})
    sim.peak(0.01 * sim.delta0)                       # small: elastic, runs
    with pytest.raises(PlasticityError):
        sim.peak(0.9 * sim.delta0)


def test_effects_recorded_and_maugis_dugdale_noted():
    sim = build_simulator(builtin_scene("micro_bead"))
    assert sim.law_name == "JKR"
    assert any("Maugis-Dugdale" in n for n in sim.notes)
    # the plan includes the rod for this scene (its resonance sits among the rod's)
    assert "adhesion" in sim.built and "rod" in sim.built
    lo = sim.left_out()
    assert "viscous_losses" in lo and lo["viscous_losses"]["error_bound"] >= 0


def test_unknown_effect_rejected():
    with pytest.raises(ValueError, match="unknown effect"):
        build_simulator(builtin_scene("paper"), include={"magic"})


@pytest.mark.slow
def test_time_integration_agrees_with_harmonic_balance_on_rod_model():
    s = builtin_scene("paper")
    hb = build_simulator(s)
    ti = build_simulator(s, include={"contact_loss"})
    assert ti.method == "time-integration" and hb.method == "harmonic-balance"
    r_hb, r_ti = hb.run([0.1, 1.0]), ti.run([0.1, 1.0])
    np.testing.assert_allclose(r_ti.up_frequency, r_hb.up_frequency, rtol=2e-3)
    np.testing.assert_allclose(r_ti.up_amplitude, r_hb.up_amplitude, rtol=2e-2)
