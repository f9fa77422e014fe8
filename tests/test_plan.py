"""Scene plans: every built-in scene gives a valid plan, the plans differ as designed, and the
bound derivations agree with independent references (2-DOF eigenvalues, Lindstedt-Poincare,
exact linear resonance peaks)."""

import argparse
import json
import math

import numpy as np
import pytest

from beadrod.models import scene
from beadrod.models.scene import plan, plan_rod
from beadrod.models.scene.plan import EFFECT_NAMES, RUNGS, plan_scene


@pytest.fixture(scope="module")
def plans():
    return {n: plan_scene(scene.builtin_scene(n)) for n in scene.builtin_scene_names()}


def test_every_builtin_plan_is_valid(plans):
    assert len(plans) >= 4
    for name, p in plans.items():
        assert p.rung in RUNGS
        assert p.harmonics >= 1
        assert [e.name for e in p.effects] == list(EFFECT_NAMES)
        for e in p.effects:
            assert isinstance(e.included, bool) and e.reason
            assert e.error_bound >= 0
            assert p.included(e.name) is e.included
            if not e.included:
                # left out only when its bound is finite and within the tolerance
                assert math.isfinite(e.error_bound), (name, e.name)
                assert e.error_bound <= p.tolerance, (name, e.name)
            elif e.name not in ("contact_loss", "plasticity"):
                assert e.error_bound > p.tolerance, (name, e.name)
        json.dumps(p.to_dict(), allow_nan=False)
        with pytest.raises(KeyError):
            p.included("gravity waves")


def test_plans_differ_as_designed(plans):
    paper, strong = plans["paper"], plans["strong_drive"]
    soft, micro = plans["large_soft_bead"], plans["micro_bead"]
    # paper: JKR by the adhesion map (mu ~ 59, adhesion/load 0.22), no contact loss (the
    # overlap stays above JKR's pull-off overlap), bistable sweeps (Q = 20), forced
    # response by harmonic balance
    assert paper.contact_law == "JKR" and paper.included("adhesion")
    assert not paper.included("contact_loss") and paper.included("jumps")
    assert paper.rung == "harmonic_balance"
    assert not paper.included("rod_waveguide") and not paper.included("rod_dispersion")
    # strong drive: the bead bounces -> time integration
    assert strong.included("contact_loss") and strong.rung == "time_integration"
    assert strong.numbers["x_max"] > 4
    # large soft bead: Hertz, the rod strongly coupled -> waveguide
    assert soft.contact_law == "Hertz" and not soft.included("adhesion")
    assert soft.included("rod") and soft.included("rod_waveguide")
    assert soft.effect("rod").details["k0_cb"] > 1 / 3
    # micro bead: adhesion dominates (Maugis-Dugdale transition); f0 = 34 f_rod sits among
    # the rod's resonances, whose transmissibility moves the measured peak without bound
    # -> the rod is simulated (all modes), so the forced-response rung
    assert micro.contact_law == "Maugis-Dugdale" and micro.included("adhesion")
    assert micro.effect("adhesion").value > 1e4
    assert micro.included("rod") and micro.included("rod_waveguide")
    assert micro.effect("rod").error_bound == math.inf
    assert micro.rung == "harmonic_balance"
    assert len({p.rung for p in plans.values()}) >= 2
    assert len({tuple(e.included for e in p.effects) for p in plans.values()}) == 4


def test_amplitude_override_and_tolerance_monotone():
    s = scene.builtin_scene("paper")
    p = plan_scene(s)
    d0 = p.numbers["delta0_m"]
    big = plan_scene(s, amplitude_max=1.5 * d0)
    assert big.included("contact_loss") and big.rung == "time_integration"
    loose = plan_scene(s, tolerance=0.1)
    assert {e.name for e in loose.effects if e.included} < \
        {e.name for e in p.effects if e.included}


def test_rod_mass_loading_against_two_dof_eigenvalues():
    """Bead m on contact K0 on one rod mode (M, K_r): the plan's single-mode f0 lowering is
    the exact lower eigenfrequency of the 2-DOF system, and to first order K0 c_b/2."""
    p = plan_scene(scene.builtin_scene("paper"))
    rod = p.effect("rod").details
    m, k0 = p.numbers["mass_kg"], p.numbers["K0_N_m"]
    big_m, kr = rod["modal_mass_kg"], rod["modal_mass_kg"] * (2 * math.pi * rod["f_rod_Hz"]) ** 2
    stiff = np.array([[k0, -k0], [-k0, k0 + kr]])
    mass = np.diag([m, big_m])
    w2 = np.sort(np.linalg.eigvals(np.linalg.solve(mass, stiff)).real)
    rel = math.sqrt(w2[0] * m / k0) - 1
    assert rel < 0
    assert -rel == pytest.approx(rod["f0_relative_error_single_mode"], rel=1e-9)
    assert -rel == pytest.approx(rod["k0_cb_first_mode"] / 2, rel=0.1)


@pytest.mark.parametrize("name", ["paper", "large_soft_bead"])
def test_rod_coupling_against_continuous_bar(name):
    """All modes: the bead on its contact on a continuous clamped-free bar (tip receptance
    tan(kL)/(EA k), EA/L = 8 M omega_r^2/pi^2 from the bar's modal mass M = m_rod/2) has its
    resonance where m w^2 (1 + K0 tan(kL)/(EA k)) = K0; and with a contact loss factor
    phi = w/(w0 Q), base drive u through T = sec(kL), the bead's peak |z/u| is the plan's
    Q_c |T| (viscous Q) or |T| Q (measured Q: Q is then the coupled one): solved directly."""
    from scipy.optimize import brentq

    sc = scene.builtin_scene(name)
    p = plan_scene(sc)
    rod = p.effect("rod").details
    m, k0, w0 = p.numbers["mass_kg"], p.numbers["K0_N_m"], 2 * math.pi * p.numbers["f0_Hz"]
    wr = 2 * math.pi * rod["f_rod_Hz"]
    ea_l = 8 * rod["modal_mass_kg"] * wr**2 / math.pi**2

    def comp(w):                           # tip compliance of the continuous bar
        u = 0.5 * math.pi * w / wr
        return math.tan(u) / (ea_l * u)

    wc = brentq(lambda w: m * w * w * (1 + k0 * comp(w)) - k0, 0.1 * w0, min(w0, 0.999 * wr))
    assert 1 - wc / w0 == pytest.approx(rod["f0_relative_error"], rel=1e-6)
    t_c = 1 / math.cos(0.5 * math.pi * wc / wr)
    assert 1.0 <= p.numbers["rod_transmissibility"] / t_c < 1.01   # (first-mode model: above)
    if sc.quality_factor is not None:
        assert p.numbers["amplitude_max_m"] == pytest.approx(
            sc.quality_factor * p.numbers["rod_transmissibility"] * sc.drive_displacement_max)
        return
    q = p.numbers["q"]
    ws = wc * np.linspace(0.9, 1.1, 200001)
    k = k0 * (1 + 1j * ws / (w0 * q))
    c = np.array([comp(w) for w in ws])
    t = 1 / np.cos(0.5 * np.pi * ws / wr)
    z = k * t / (k - m * ws**2 * (1 + k * c))
    peak = np.abs(z).max()
    ratio = p.numbers["amplitude_max_m"] / (sc.drive_displacement_max * peak)
    assert 1.0 <= ratio < 1.03             # an upper estimate, and not a loose one


@pytest.mark.parametrize("q,r", [(5.0, 0.7), (5.0, 0.4), (20.0, 0.8)])
def test_pull_of_a_drive_filter_on_the_peak(q, r):
    """_pull: the maximum of |T(W)| |H(W; W_r)| (H a linear resonance at W_r, quality Q,
    with fixed Q or fixed bandwidth) moves with W_r by dW_r (1 + F): F found here by brute
    force for T = sec(pi r W/2) is within the plan's bound, and the bound is not loose."""
    s = -0.002
    w = np.linspace(0.95, 1.05, 800001)   # one peak: T's pole 1/r stays outside
    lt = -np.log(np.cos(0.5 * np.pi * r * w))

    def peak(wr, scaled, filt):
        damp = w * wr / q if scaled else w / q
        return w[np.argmax(filt * lt - 0.5 * np.log((wr**2 - w**2) ** 2 + damp**2))]

    u = 0.5 * np.pi * r
    bound = plan_rod._pull((u / np.cos(u)) ** 2, u * np.tan(u), 4 * q * q)
    for scaled in (True, False):
        moved, bare = (peak(1 + s, scaled, v) - peak(1.0, scaled, v) for v in (1, 0))
        f = abs(moved - bare) / abs(s)
        assert f <= bound
        if scaled:
            assert f > 0.6 * bound
    assert plan_rod._pull(4 * q * q, 0.0, 4 * q * q) == math.inf


def test_first_branch_slows_monotonically_towards_rayleigh():
    """The dispersion bound takes e <= 1 - c_R/c0 above the branch solver's domain: the
    first branch's phase velocity falls from c0 towards the Rayleigh velocity c_R."""
    from beadrod.models.scene import rod

    nu, young, rho, a = 0.27, 200e9, 7700.0, 6e-3
    assert plan_rod._rayleigh_over_vt(0.25) == pytest.approx(0.919402, rel=1e-5)
    vt = math.sqrt(young / (2 * (1 + nu)) / rho)
    f = np.linspace(1e3, 0.99 * rod.OMEGA_MAX * vt / (2 * math.pi * a), 200)
    c = np.asarray(rod.first_branch_phase_velocity(f, young=young, poisson=nu, density=rho,
                                                    radius=a))
    assert np.all(np.diff(c) < 0)
    assert c[-1] > plan_rod._rayleigh_over_vt(nu) * vt


def _quadratic_law(alpha, k0=1.0, d0=1.0, f0=1.0):
    def force(d):
        q = np.asarray(d) / d0 - 1
        return f0 + k0 * d0 * (q + alpha * q * q)
    return {"force": force, "k0": k0, "delta0": d0}


@pytest.mark.parametrize("alpha,x", [(0.25, 0.2), (0.5, 0.4), (1.0, 0.1)])
def test_harmonic_bound_matches_lindstedt_quadratic(alpha, x):
    """q'' + q + alpha q^2 = 0: omega = 1 - (5/12)(alpha x)^2, of which the second harmonic
    carries +(1/12)(alpha x)^2 (Nayfeh & Mook Sec. 4.1); the plan's B(1) is twice it."""
    e, h = plan._effect_harmonics(_quadratic_law(alpha), x, tol=1e-30)
    assert e.value / 2 == pytest.approx((alpha * x) ** 2 / 12, rel=1e-10)
    assert h == 2 and e.details["bound_at_H"] < 1e-25


@pytest.mark.parametrize("alpha,x", [(0.25, 0.3), (0.5, 0.2)])
def test_contact_loss_margin_matches_lindstedt_quadratic(alpha, x):
    """Lindstedt orbit q = x sin t - alpha x^2/2 + (alpha x^2/6) cos 2t: min = -x - alpha x^2/3."""
    e = plan._effect_contact_loss(_quadratic_law(alpha), 1.0, x)
    assert e.threshold == pytest.approx(1 - alpha * x**2 / 3, rel=1e-12)
    assert e.details["mean_shift"] == pytest.approx(-alpha * x**2 / 2, rel=1e-12)


@pytest.mark.parametrize("q", [2.0, 5.0, 20.0, 100.0])
def test_viscous_bound_covers_exact_linear_peaks(q):
    zeta = 1 / (2 * q)
    r = np.linspace(0.5, 1.5, 400001)
    force_drive = 1 / np.sqrt((1 - r**2) ** 2 + (2 * zeta * r) ** 2)
    base_drive = np.sqrt(1 + (2 * zeta * r) ** 2) * force_drive
    bound = plan._effect_viscous(q, q, 5e-3).error_bound
    for resp in (force_drive, base_drive):
        assert abs(r[np.argmax(resp)] - 1) <= bound
    assert abs(r[np.argmax(force_drive)] - 1) > bound / 4  # and not vacuous


def test_plan_command_json(capsys):
    from beadrod.workflows.commands import plan

    parser = argparse.ArgumentParser()
    plan.register(parser.add_subparsers())
    args = parser.parse_args(["plan", "--builtin", "strong_drive", "--json"])
    assert args.func(args) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["rung"] == "time_integration"
    assert {e["name"] for e in d["effects"]} == set(EFFECT_NAMES)
    args = parser.parse_args(["plan", "--builtin", "paper"])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "contact_loss" in out and "harmonic_balance" in out


@pytest.mark.slow
def test_rung_error_estimates_cover_exact_backbone():
    """Against engineer D's exact Hertz backbone (energy integral): the plan's |S|max
    estimate and its series / first-order error estimates are upper bounds for x <= 0.9."""
    import jax.numpy as jnp

    from beadrod.models.ladder.backbone import backbone_shift, lindstedt_shift
    from beadrod.models.ladder.first_order import first_order_hertz

    xs = np.array([0.1, 0.3, 0.6, 0.9])
    exact = np.asarray(backbone_shift(jnp.asarray(xs), 1.5))
    for x, s in zip(xs, exact):
        assert plan.shift_estimate(float(x)) >= abs(s)
        s_lin = float(lindstedt_shift(x, 1.5))
        err_series = abs(s_lin) * x**2
        err_first = abs(float(first_order_hertz(x)) - s_lin) + err_series
        assert abs(s_lin - s) <= err_series
        assert abs(float(first_order_hertz(x)) - s) <= err_first
