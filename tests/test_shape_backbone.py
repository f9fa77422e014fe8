"""The evaluation half of the shape tables (models.tables.shape_read): each stored table's own
ranges agree with the builder's TABLES (else the file is stale), values are held beyond
them, and the laws' backbone rungs read exactly these tables."""

import numpy as np
import pytest

from beadrod.models import registry
from beadrod.models.tables import shape_build, shape_read

X = np.array([0.05, 0.4, 0.85, 1.1, 1.6, 2.0])
# the second shape coordinate, where a table has one (Maugis-Dugdale's lam, inside its range)
T = {name: 1.0 for name, tab in shape_build.tabulated().items() if tab.q_range is not None}


def _fast(name, x, s):
    return np.asarray(shape_read.backbone_fast(name, x, s, T.get(name)))


@pytest.mark.parametrize("name", sorted(shape_build.tabulated()))
def test_stored_ranges_are_the_builders(name):
    tab = shape_build.tabulated()[name]
    assert shape_read.shape_range(name) == (tab.p_lo, tab.p_hi)
    assert float(shape_read.load_table(name)["x_max"]) == shape_read.X_MAX


@pytest.mark.parametrize("name", sorted(shape_build.tabulated()))
def test_values_are_held_beyond_the_ranges(name):
    p_lo, p_hi = shape_read.shape_range(name)
    for p_end, p_out in ((p_lo, p_lo - 2.0), (p_hi, p_hi + 3.0)):
        end = _fast(name, X, np.exp(p_end))
        np.testing.assert_array_equal(_fast(name, X, np.exp(p_out)), end)
    assert _fast(name, 3.5, np.exp(p_hi)) == _fast(name, 2.0, np.exp(p_hi))
    # inside the range the shape parameter matters (the table is not flat)
    mid = _fast(name, X, np.exp(0.5 * (p_lo + p_hi)))
    assert np.max(np.abs(mid - end)) > 1e-4



@pytest.mark.parametrize("name", sorted(shape_build.tabulated()))
def test_the_domain_ends_at_both_ends_of_the_shape_range(name):
    """Held values are not the law's at either end: past p_hi the tables stand 2e-4 to
    3.2e-4 from Hertz's backbone (module doc), ten times their stated errors."""
    p_lo, p_hi = shape_read.shape_range(name)
    extra = () if "q_range" not in shape_read.load_table(name) else (1.0,)
    inside = [bool(shape_read.in_table(name, 0.5, np.exp(p), *extra))
              for p in (p_lo - 0.1, p_lo, 0.5 * (p_lo + p_hi), p_hi, p_hi + 0.1, np.inf)]
    assert inside == [False, True, True, True, False, False]

def test_a_second_shape_coordinate_is_refused_outside_its_range_not_held():
    """Maugis-Dugdale's lam: the table has no limit to hold beyond [0.1, 100], so its
    domain (in_table) excludes those points; inside, lam changes the shape."""
    for name in T:
        q_lo, q_hi = shape_build.tabulated()[name].q_range
        s = 3.0
        ok = [bool(shape_read.in_table(name, 0.5, s, np.exp(q)))
              for q in (q_lo - 0.1, q_lo + 1e-9, q_hi - 1e-9, q_hi + 0.1)]
        assert ok == [False, True, True, False], (name, ok)
        lo, hi = (np.asarray(shape_read.backbone_fast(name, X, s, np.exp(q)))
                  for q in (q_lo, q_hi))
        assert np.max(np.abs(hi - lo)) > 1e-3


def test_laws_backbone_rungs_read_these_tables():
    """JKR's backbone rung at load ratio r = F0/Fc equals the table at r (Fc = 3 pi gamma R):
    the law module evaluates through shape_backbone, which the builder re-exports."""
    assert shape_build.backbone_fast is shape_read.backbone_fast
    law = registry.get_law("jkr")
    kw = {"load": 0.158, "radius": 7.938e-3, "e_star": 1.1e11, "mass": 0.016, "gamma": 0.7}
    r = kw["load"] / (3.0 * np.pi * kw["gamma"] * kw["radius"])
    got = law.shift(X, rung="backbone", delta0=law.overlap(**kw), **kw)
    np.testing.assert_allclose(got, shape_read.backbone_fast("jkr", X, r), rtol=0,
                               atol=1e-14)
