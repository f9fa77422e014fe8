"""The accuracy ladder: rungs agree where they should and differ where physics says."""

import numpy as np
import pytest

from beadrod.models.ladder import powerlaw_ladder


def test_cheap_rungs_small_amplitude():
    x = np.array([0.05, 0.02])       # same shape as tests/test_backbone.py: one compile
    r1, r3 = float(powerlaw_ladder.rung1_series(x)[0]), float(powerlaw_ladder.rung3_backbone(x)[0])
    assert r1 == pytest.approx(-x[0] ** 2 / 24)
    assert r3 == pytest.approx(r1, rel=2e-3)
    pytest.importorskip("beadrod.models.ladder.first_order")
    r2 = float(powerlaw_ladder.rung2_first_order(x)[0])
    # first order misses the quadratic-force term: 3/4 of the exact small-x shift
    assert r2 / r3 == pytest.approx(0.75, rel=2e-3)


@pytest.mark.slow
def test_forced_peak_tends_to_backbone_at_high_q():
    # x = 0.5: the damped peak differs from the backbone by O(1/Q^2) only
    x = np.array([0.5])
    bb = float(powerlaw_ladder.rung3_backbone(x)[0])
    h3 = float(powerlaw_ladder.rung4_hbm(x, q_factor=1e3, harmonics=3)[0])
    assert h3 == pytest.approx(bb, abs=5e-6)
    assert abs(h3 - bb) < 1e-3 * abs(bb)


@pytest.mark.slow
def test_compare_rungs_hbm_matches_time_integration():
    # below contact loss; at x >~ 0.95 RK4 at 128 steps/period is itself only good to ~1e-4
    out = powerlaw_ladder.compare_rungs([0.3, 0.8], q_factor=20.0)
    assert set(out) == set(powerlaw_ladder.RUNGS)
    err7 = out["4 HBM H=7"]["error"]
    assert np.all(np.abs(err7) < 2e-5)
    # H = 1 misses the mean-overlap shift: clearly worse than H = 7
    assert np.all(np.abs(out["4 HBM H=1"]["error"]) > 10 * np.abs(err7))
