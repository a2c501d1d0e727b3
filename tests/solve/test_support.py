"""solve/support.py: the rows of a set that can bind (`essential`, what budget's LPs are over)."""
import numpy as np
import pytest

from garant.verify.solve import hull, support


@pytest.mark.parametrize("seed", range(4))
def test_the_sides_essential_drops_bind_nowhere_and_the_ends_stay_what_they_were(seed):
    # An information set's rows (one a reading, two-sided) mostly bind nowhere on it; budget's LPs are over those
    # that can (support.essential). Each side dropped is proven redundant here on the set without it: its own end
    # over what is kept (an LP's end proven by duality, hull.upper) lies within its bound, so the set is the same.
    # And the ends of 40 random objectives over what is kept are those over all rows (to 1e-9 of the width). Red
    # with a side dropped when its end comes within 1e-3 of its bound (a binding side dropped: the ends move).
    rng = np.random.default_rng(seed)
    P, K = 6, 60
    B = rng.normal(size=(K, P))
    x0 = rng.uniform(-0.2, 0.2, P)
    centre = B @ x0 + rng.uniform(-0.05, 0.05, K)
    lo, hi = centre - 0.3, centre + 0.3
    box = -np.ones(P), np.ones(P)
    keep, lo_k, hi_k = support.essential(B, lo, hi, *box)
    assert 0 < len(keep) < K                                   # some rows bind somewhere, some nowhere
    Bk = B[keep]
    dropped_lo = np.setdiff1d(np.arange(K), keep[np.isfinite(lo_k)])
    dropped_hi = np.setdiff1d(np.arange(K), keep[np.isfinite(hi_k)])
    assert len(dropped_lo) and len(dropped_hi)
    end_lo, _ = hull.ranges(Bk, lo_k, hi_k, *box, B[dropped_lo])
    _, end_hi = hull.ranges(Bk, lo_k, hi_k, *box, B[dropped_hi])
    assert np.all(end_lo >= lo[dropped_lo]) and np.all(end_hi <= hi[dropped_hi])
    C = rng.normal(size=(40, P))
    a_lo, a_hi = hull.ranges(B, lo, hi, *box, C)
    b_lo, b_hi = hull.ranges(Bk, lo_k, hi_k, *box, C)
    width = a_hi - a_lo
    assert np.all(np.abs(b_lo - a_lo) <= 1e-9 * width) and np.all(np.abs(b_hi - a_hi) <= 1e-9 * width)
