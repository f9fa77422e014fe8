"""The hysteretic world (data.worlds_loss): a valid dataset whose noiseless amplitudes
follow the peak condition x = E Omega^2 / L(x) of its law, written out here independently
(Hertz's first-order shift by quadrature would not do: the world uses the exact backbone,
so the check reads its shifts from its own truth and recomputes the loss and drive)."""

import math

import numpy as np
import pytest
from scipy import special

import beadrod
from beadrod.data.process import process


@pytest.fixture(scope="module")
def world():
    return beadrod.simulate("hysteretic", seed=11)


def test_world_loads_and_its_loss_grows_with_the_amplitude(world):
    ds = process(world)
    assert not ds.warnings and ds.n_drive > 100
    x = ds.normalized_amplitude("f0")
    big, small = x > 0.6, x < 0.1
    # hysteresis widens the resonance: Eq. 31 grows by ~ h rho(2) x = 0.85 h at x ~ 1
    assert np.nanmean(ds.drive_inv_q_shift[big]) > 0.01 > abs(np.nanmean(
        ds.drive_inv_q_shift[small]))


def test_noiseless_drive_puts_the_peak_where_the_loss_says(world):
    t = world.truth
    par, drive = t["parameters"], t["observables"]["drive"]
    h, m, beta = par["strength"], par["exponent"], par["background_exponent"]
    rho = 2 * (m - 1) * special.gamma(m + 1) / (math.sqrt(math.pi) * m * special.gamma(m + 0.5))
    d = par["displacement_per_volt_m_V"]
    for i in range(0, len(drive["x"]), 7):
        p = t["protocols"][drive["protocol"][i]]
        x = drive["x"][i]
        omega = drive["f_res"][i] / p["f0_linear_Hz"]
        loss = omega**beta / p["q"] + h * rho * x ** (m - 1)
        e = drive["voltage"][i] * d / p["delta0_m"]
        assert x == pytest.approx(e * omega**2 / loss, rel=1e-9)
    # the hysteretic share of the shift at x = 0.5 lies in the range
    assert 0.01 <= h * 0.5 ** (m - 1) <= 0.03
