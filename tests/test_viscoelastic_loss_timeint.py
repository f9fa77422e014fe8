"""The viscoelastic law's loss against time integration (issue 49): the resonance peak of
the base-excited Kuwabara-Kono oscillator, integrated in time, read as the amplitude
likelihood reads a drive sweep.

The oscillator (models/ladder/oscillator.py, Eq. (*)), written out here by hand:

    q'' = -(g(1 + q, q') - 1)/s - E Omega^2 sin(Omega tau),
    g(y, y') = max(y^(3/2) + (3/2) A omega0 y^(1/2) y', 0) for y > 0, else 0,  s = 3/2,

at A omega0 = 1/Q0, Q0 = 30. The reference is the steady state itself: the periodic orbit
at each frequency by shooting (scipy's DOP853 over one drive period, rtol 1e-11, with the
variational equations for Newton's Jacobian; the orbit's Floquet multipliers say it is the
stable one a sweep settles on), its first harmonic x = delta_a/delta0 by lock-in over 64
samples; the peak of x(Omega) at a fixed drive E by a stepped down sweep (steps 1.5e-3,
each orbit continued from the last) and Brent's method on the three steps around the
largest. Nothing of the code under test is used for it. The project's own integrator
(models/ladder/time_integration.py: swept_sine, RK4, a stepped down sweep from rest, and
its parabola ``resonance``) must find the same peaks.

Drives: E from the Kuwabara-Kono rows of the harmonic-balance table in docs/damping.md
(7 harmonics; x = 0.2, 0.5, 0.8 at the peak, E = (E Omega^2/x) x/Omega^2), and
E = X_REF/Q0 for the reference sweep (x = 0.050). Every orbit stays in contact, below
contact loss: the overlap's minimum is 0.14 delta0 at x = 0.8 (0.48 at x = 0.5).

What is compared. Measured, per drive sweep i, relative to the lowest drive (the reference
sweep): a_i = ln(x_i/E_i) - ln(x_ref/E_ref), with Omega_i = Omega_peak,i/Omega_peak,ref the
peak frequency ratio (f_res/f0 as the data define it). Predicted: the amplitude
likelihood's ``predicted_ratio`` with the viscoelastic law's ``loss`` (L0 Omega^3,
``Physics.loss_exponent`` = 3). Measured (2026-12, this module):

    x      Omega_i       a_i        predicted   a_i - predicted   loss change (units 1/Q0)
    0.2    0.998422    0.000522    0.001579      -0.00106         -0.00367 (pred -0.00473)
    0.5    0.989030    0.003423    0.011031      -0.00761         -0.02516 (pred -0.03255)
    0.8    0.968057    0.008455    0.032465      -0.02401         -0.07076 (pred -0.09280)

The harmonics make the apparent loss larger than L0 Omega^3, by 0.11 %, 0.74 % and
2.2 % of 1/Q0: the resonance narrows as the drive grows, as Kuwabara-Kono predicts, but
by 78 %, 77 % and 76 % of what one harmonic predicts (checked: within 70-85 %). That is
the harmonic-balance table's Kuwabara-Kono rows (their E Omega^2/x Q0 - Omega^3 is
0.07 %, 0.71 % and 2.17 %) plus the reference sweep's own O(1/Q0^2) offset, 3.5e-4: its peak lies at Omega = 1.00017, where E Omega^2/x Q0 =
1.00017 but Omega^3 = 1.00052). The doc's summary "0.2-0.7 % at x = 0.5-0.8" is the
constant dashpot's range; for Kuwabara-Kono it is 0.7 % at x = 0.5 and 2.2 % at x = 0.8.

Tolerance: |a_i - predicted| <= 1.25 |ln(E Omega^2/x Q0 / Omega^3)|_table + 5e-4 (the
table's single-harmonic error with 25 % headroom, plus the reference's offset with 40 %):
1.4e-3, 9.6e-3 and 3.0e-2, against the 1.1e-3, 7.6e-3 and 2.4e-2 measured; and the sign
(the measured ratio falls short of the prediction). Before it is used as the bound the
table itself is checked: the time-integrated peaks land on its x to 1e-6 and its Omega to
2e-6 (measured: 2e-7 and 3e-7). The project's RK4 sweep (64 steps a period, 150 settling
periods a frequency, steps of 5e-4 in Omega) finds the reference's peak amplitudes to
3e-6 and frequencies to 4e-5 (its parabola on the asymmetric peak at x = 0.8; 1e-6 below).

Cost: about 7 s on one core (the shooting 4.6 s, the project's sweep 1.9 s with compiling).
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from beadrod.inference.model.amplitude import predicted_ratio
from beadrod.models.ladder import time_integration
from beadrod.models.ladder.oscillator import Viscoelastic
from beadrod.models.laws.viscoelastic import LAW

Q0 = 30.0
A = 1.0 / Q0  # A omega0
SLOPE = 1.5
SAMPLES = 64  # lock-in samples per period

# docs/damping.md, harmonic-balance table, Kuwabara-Kono (Q0 = 30):
# (x, Omega at the peak, E Omega^2/x * Q0)
TABLE = ((0.2, 0.998595, 0.996499), (0.5, 0.989202, 0.975007), (0.8, 0.968225, 0.929405))
X_REF = 0.05


# --- the reference: periodic orbits of the hand-written oscillator -----------------------


def _rhs(e, om):
    """(q, q', and the 2x2 monodromy's two columns)' of the Kuwabara-Kono oscillator."""
    f2 = e * om * om

    def f(t, u):
        q, v = u[0], u[1]
        y = 1.0 + q
        g = gy = gv = 0.0
        if y > 0.0:
            r = math.sqrt(y)
            g = y * r + 1.5 * A * r * v
            if g > 0.0:
                gy, gv = 1.5 * r + 0.75 * A * v / r, 1.5 * A * r
            else:
                g = 0.0
        jy, jv = -gy / SLOPE, -gv / SLOPE
        return [v, -(g - 1.0) / SLOPE - f2 * math.sin(om * t),
                u[3], jy * u[2] + jv * u[3], u[5], jy * u[4] + jv * u[5]]

    return f


def orbit(e, om, y0):
    """The periodic orbit through Newton from ``y0`` = (q, q') at tau = 0: (x, its state at
    tau = 0, the largest Floquet multiplier's modulus, the overlap's minimum 1 + min q)."""
    period = 2.0 * math.pi / om
    f = _rhs(e, om)
    t = period * np.arange(SAMPLES + 1) / SAMPLES
    y0 = np.asarray(y0, float)
    for _ in range(30):
        sol = solve_ivp(f, (0.0, period), np.r_[y0, 1.0, 0.0, 0.0, 1.0], method="DOP853",
                        rtol=1e-11, atol=1e-13, t_eval=t)
        mono = sol.y[2:, -1].reshape(2, 2, order="F")
        step = np.linalg.solve(mono - np.eye(2), y0 - sol.y[:2, -1])
        y0 = y0 + step
        if np.max(np.abs(step)) < 1e-11:
            break
    else:
        raise RuntimeError(f"shooting did not converge at E = {e}, Omega = {om}")
    q, ph = sol.y[0, :-1], om * t[:-1]
    x = math.hypot(2.0 * np.mean(q * np.cos(ph)), 2.0 * np.mean(q * np.sin(ph)))
    return x, y0, float(np.max(np.abs(np.linalg.eigvals(mono)))), 1.0 + float(q.min())


def peak(e, om_start, x_guess, step=1.5e-3):
    """The peak of the steady x(Omega) at drive E: a stepped down sweep from ``om_start``
    until x falls, then Brent's method on the three steps around the largest."""
    seen = []
    om, y = om_start, np.array([x_guess, 0.0])
    while len(seen) < 3 or seen[-1][1] >= seen[-2][1]:
        x, y, _, _ = orbit(e, om, y)
        seen.append((om, x, y))
        om -= step
    state = {"y": seen[-2][2]}

    def neg_x(w):
        x, state["y"], _, _ = orbit(e, w, state["y"])
        return -x

    res = minimize_scalar(neg_x, bracket=(seen[-1][0], seen[-2][0], seen[-3][0]),
                          method="brent", options={"xtol": 1e-8})
    x, y, mult, overlap_min = orbit(e, res.x, state["y"])
    return {"E": e, "omega": float(res.x), "x": x, "multiplier": mult,
            "overlap_min": overlap_min}


@pytest.fixture(scope="module")
def peaks():
    """The reference sweep's peak, then the table's three (drives in increasing order)."""
    drives = [X_REF / Q0] + [app * x / (Q0 * om**2) for x, om, app in TABLE]
    out, start = [], 1.004
    for e, x_guess in zip(drives, (X_REF, *(row[0] for row in TABLE)), strict=True):
        out.append(peak(e, start, x_guess))
        start = out[-1]["omega"] + 3e-3
    return out


# --- the checks ----------------------------------------------------------------------


def test_steady_peaks_reproduce_the_harmonic_balance_table(peaks):
    for p in peaks:
        assert p["multiplier"] < 0.95          # the stable orbit a sweep settles on
        assert p["overlap_min"] > 0.1          # in contact throughout: below contact loss
    assert peaks[0]["x"] == pytest.approx(X_REF, rel=1e-3)
    for p, (x, om, app) in zip(peaks[1:], TABLE, strict=True):
        assert p["x"] == pytest.approx(x, abs=1e-6)
        assert p["omega"] == pytest.approx(om, abs=2e-6)
        assert p["E"] * p["omega"] ** 2 / p["x"] * Q0 == pytest.approx(app, abs=1e-5)


def _measured_and_predicted(peaks):
    ref = peaks[0]
    rows = []
    for p in peaks[1:]:
        omega = p["omega"] / ref["omega"]
        measured = math.log(p["x"] / p["E"]) - math.log(ref["x"] / ref["E"])
        predicted = float(predicted_ratio(
            omega_ratio=omega,
            loss=LAW.loss(p["x"], linear_loss=1.0 / Q0, omega_ratio=omega),
            loss_ref=LAW.loss(ref["x"], linear_loss=1.0 / Q0, omega_ratio=1.0)))
        rows.append((omega, measured, predicted))
    return rows


def test_amplitude_ratio_matches_the_likelihood_within_the_harmonics(peaks):
    assert LAW.physics.loss_exponent == 3.0
    rows = _measured_and_predicted(peaks)
    errors = []
    for (omega, measured, predicted), (_, om_hb, app_hb) in zip(rows, TABLE, strict=True):
        single_harmonic_error = abs(math.log(app_hb / om_hb**3))
        error = measured - predicted
        assert abs(error) <= 1.25 * single_harmonic_error + 5e-4, (omega, measured, predicted)
        assert error < 0.0  # harmonics: the apparent loss exceeds L0 Omega^3
        errors.append(abs(error))
    assert errors == sorted(errors)  # and more so the larger the amplitude


def test_apparent_loss_falls_as_the_drive_grows(peaks):
    # the loss the peak reads once the base excitation's Omega^2 is out: E Omega^2/x
    loss = [p["E"] * p["omega"] ** 2 / p["x"] for p in peaks]
    assert all(b < a for a, b in zip(loss, loss[1:]))  # narrows at every step
    # and by most of what Kuwabara-Kono predicts in one harmonic, L0 (Omega^3 - 1)
    for omega, measured, _ in _measured_and_predicted(peaks):
        change = omega**2 * math.exp(-measured) - 1.0  # (L(x) - L(x_ref)) Q0
        assert 0.7 < change / (omega**3 - 1.0) < 0.85


def test_project_integrator_finds_the_same_peaks(peaks):
    law = Viscoelastic(a_omega0=A)
    offsets = 5e-4 * np.array([8.0, 4.0, 2.0, 1.0, 0.0, -1.0])  # a down sweep from rest
    for p in peaks:
        sweep = time_integration.swept_sine(law, p["E"], p["omega"] + offsets,
                                            steps_per_period=64, settle_periods=150,
                                            measure_periods=2)
        om, x = time_integration.resonance(sweep.omega, sweep.amplitude)
        assert float(x) == pytest.approx(p["x"], rel=1e-5)
        assert float(om) == pytest.approx(p["omega"], abs=1e-4)
