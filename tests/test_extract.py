"""Resonance extraction against curves with known peak and Q (closed forms)."""

import math

import numpy as np
import pytest

from beadrod.data.extract import extract_resonance, read_curve
from beadrod.data.schema import DataError


def lorentzian(f, f0, q, peak=1e-8):
    g = f0 / (2 * q)  # half width at half power
    return peak * g / np.sqrt((f - f0) ** 2 + g**2)


def oscillator(f, f0, q, static=1e-9):
    """Force-driven linear oscillator |x| = x_st / sqrt((1 - r^2)^2 + (r/Q)^2)."""
    r = f / f0
    return static / np.sqrt((1 - r**2) ** 2 + (r / q) ** 2)


def oscillator_exact(f0, q):
    """Exact peak frequency and -3 dB Q of ``oscillator`` (roots of quadratics in u = r^2)."""
    u_star = 1 - 1 / (2 * q**2)
    d_min = 1 / q**2 - 1 / (4 * q**4)
    b = 2 - 1 / q**2
    disc = math.sqrt(b**2 - 4 * (1 - 2 * d_min))
    u_lo, u_hi = (b - disc) / 2, (b + disc) / 2
    return f0 * math.sqrt(u_star), math.sqrt(u_star) / (math.sqrt(u_hi) - math.sqrt(u_lo))


@pytest.mark.parametrize("f0,q", [(2713.37, 20.0), (2588.9, 55.0), (2951.23, 100.0)])
def test_lorentzian_peak_and_q(f0, q):
    f = np.arange(2000.0, 3500.0, 2.0)
    fit = extract_resonance(f, lorentzian(f, f0, q))
    assert fit.f_res == pytest.approx(f0, abs=0.02)
    assert fit.amplitude == pytest.approx(1e-8, rel=1e-4)
    assert fit.q == pytest.approx(q, rel=5e-3)
    assert not fit.asymmetric


def test_local_fit_beats_grid_maximum():
    f0, q = 2703.3, 40.0
    f = np.arange(2000.0, 3500.0, 5.0)  # coarse grid: the grid maximum is 1.7 Hz off
    a = lorentzian(f, f0, q)
    fit = extract_resonance(f, a)
    grid_err = abs(f[np.argmax(a)] - f0)
    assert grid_err > 1.0
    assert abs(fit.f_res - f0) < 0.05 * grid_err
    assert fit.amplitude > a.max()  # the true peak lies between grid points


@pytest.mark.parametrize("q", [20.0, 100.0])
def test_linear_oscillator_exact_closed_forms(q):
    f0 = 2700.0
    f = np.arange(1500.0, 3500.0, 1.0)
    fit = extract_resonance(f, oscillator(f, f0, q))
    f_peak, q3 = oscillator_exact(f0, q)
    assert fit.f_res == pytest.approx(f_peak, abs=0.005)
    assert fit.q == pytest.approx(q3, rel=2e-3)
    assert not fit.asymmetric


def test_asymmetric_curve_is_flagged():
    # a softening-like peak: a narrow high-frequency flank, a broad low-frequency one
    f = np.arange(2000.0, 3500.0, 1.0)
    f0 = 2600.0
    g = np.where(f < f0, 60.0, 15.0)
    fit = extract_resonance(f, 1e-8 * g / np.sqrt((f - f0) ** 2 + g**2))
    assert fit.asymmetric and "trustworthy" in fit.note
    assert fit.asymmetry < -0.2  # the low side is the wide one


def test_crossing_outside_sweep_gives_nan_q():
    f = np.arange(2690.0, 2800.0, 1.0)
    fit = extract_resonance(f, lorentzian(f, 2700.0, 20.0))
    assert math.isnan(fit.q) and fit.asymmetric and "low-frequency side" in fit.note


def _write(tmp_path, text):
    p = tmp_path / "sweep.csv"
    p.write_text(text)
    return p


def _good_rows(n=10):
    return "".join(f"{2600 + 10 * i},{1e-9 * (1 + i)}\n" for i in range(n))


def test_read_curve_sorts_down_sweep(tmp_path):
    rows = "".join(f"{2700 - 10 * i},{1e-9 * (1 + i)}\n" for i in range(10))
    c = read_curve(_write(tmp_path, "frequency_Hz,amplitude_m\n" + rows))
    assert np.all(np.diff(c["frequency_Hz"]) > 0)


@pytest.mark.parametrize(
    "text,line,col",
    [
        ("frequency_Hz,amp\n" + _good_rows(), "line 1 (header)", "column 2"),
        ("frequency_Hz,phase_rad\n" + _good_rows(), "line 1 (header)", "column 'amplitude_m'"),
        ("frequency_Hz,amplitude_m\n" + _good_rows(3) + "2700,abc\n" + _good_rows(5)[:-1],
         "line 5", "column 'amplitude_m'"),
        ("frequency_Hz,amplitude_m\n" + _good_rows(4) + "2610,1e-9\n" + _good_rows(5)[:-1],
         "line 6", "column 'frequency_Hz'"),
        ("frequency_Hz,amplitude_m\n" + "2600,-1e-9\n" + _good_rows(8), "line 2",
         "column 'amplitude_m'"),
        ("frequency_Hz,amplitude_m\n" + _good_rows(3), "line 4", "column 'frequency_Hz'"),
        ("frequency_Hz,amplitude_m\n\n" + _good_rows(2) + "\n2700,abc\n" + _good_rows(5),
         "line 6", "column 'amplitude_m'"),  # blank lines count, as in an editor
    ],
)
def test_read_curve_errors_name_place(tmp_path, text, line, col):
    with pytest.raises(DataError) as e:
        read_curve(_write(tmp_path, text), label="sweep.csv")
    msg = str(e.value)
    assert f"sweep.csv, {line}, {col}" in msg, msg
    assert "abc" not in msg and "'amp'" not in msg  # the file's content is never echoed


def test_read_curve_header_hint_without_echo(tmp_path):
    with pytest.raises(DataError) as e:
        read_curve(_write(tmp_path, "frequency_Hz,amplitude_nm\n" + _good_rows()),
                   label="sweep.csv")
    assert "did you mean 'amplitude_m'" in str(e.value)
    assert "amplitude_nm" not in str(e.value)
