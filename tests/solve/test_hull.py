"""solve/hull.py: each linear function's least and largest value over a polytope, each end proven by weak duality
(the information set's hull, whose ends garant prints as bounds)."""
import itertools
from fractions import Fraction

import numpy as np
import pytest

from garant.verify.solve import highs, hull


def test_a_proof_from_any_multipliers_bounds_the_lp_and_fails_when_cut():
    # Weak duality: any lambda bounds max c^T x; the solver's own lambda gives the optimum. A bound a thousandth
    # below the optimum would be wrong, and a feasible point (the optimum HiGHS found) shows it.
    rng = np.random.default_rng(0)
    B = rng.normal(size=(40, 4))
    x0 = rng.normal(size=4)
    lo, hi = B @ x0 - 1.0, B @ x0 + 1.0
    c = rng.normal(size=4)
    out_lo, out_hi, pts = hull.ranges(B, lo, hi, x0 - 10, x0 + 10, c[None], points=True)
    x_max = pts[0][1]
    assert np.all(B @ x_max <= hi + 1e-7) and np.all(B @ x_max >= lo - 1e-7)
    assert c @ x_max <= out_hi[0] and out_hi[0] - c @ x_max <= 1e-6 * (1 + abs(out_hi[0]))
    assert hull.upper(c, B, lo, hi, x0 - 10, x0 + 10, np.zeros(40)) >= out_hi[0]       # lambda = 0: the box
    assert not c @ x_max <= out_hi[0] - 1e-3 * abs(out_hi[0])


def _exact_max(c, B, lo, hi, xl, xh):
    """max c^T x over {lo <= B x <= hi, xl <= x <= xh} in two dimensions, exactly: the best vertex, each the
    meeting of two of the constraint lines, solved in rationals."""
    F = Fraction
    lines = [(list(map(F, B[i])), F(v)) for i in range(len(B)) for v in (lo[i], hi[i])]
    lines += [([F(1), F(0)], F(v)) for v in (xl[0], xh[0])] + [([F(0), F(1)], F(v)) for v in (xl[1], xh[1])]
    best = None
    for (a, p), (b, q) in itertools.combinations(lines, 2):
        det = a[0] * b[1] - a[1] * b[0]
        if det == 0:
            continue
        x = ((p * b[1] - a[1] * q) / det, (a[0] * q - p * b[0]) / det)
        inside = all(F(lo[i]) <= F(B[i][0]) * x[0] + F(B[i][1]) * x[1] <= F(hi[i]) for i in range(len(B)))
        inside = inside and all(F(xl[k]) <= x[k] <= F(xh[k]) for k in range(2))
        if inside:
            value = F(c[0]) * x[0] + F(c[1]) * x[1]
            best = value if best is None or value > best else best
    return best


def _polytope(rng, rows, cols):
    """(B, x0, lo, hi): random rows around a random point x0, each of width 0.2 to 2 about it."""
    B = rng.normal(size=(rows, cols))
    x0 = rng.normal(size=cols)
    return B, x0, B @ x0 - rng.uniform(0.1, 1, rows), B @ x0 + rng.uniform(0.1, 1, rows)


@pytest.mark.parametrize("seed", range(5))
def test_each_end_is_above_the_exact_optimum_and_within_a_millionth_of_it(seed):
    # The exact optimum over the vertices in rationals: a proven end below it would be a wrong bound.
    rng = np.random.default_rng(seed)
    B, x0, lo, hi = _polytope(rng, 12, 2)
    xl, xh = x0 - 5, x0 + 5
    C = rng.normal(size=(3, 2))
    got_lo, got_hi = hull.ranges(B, lo, hi, xl, xh, C)
    for k, c in enumerate(C):
        top, bottom = _exact_max(c, B, lo, hi, xl, xh), -_exact_max(-c, B, lo, hi, xl, xh)
        assert Fraction(got_hi[k]) >= top and Fraction(got_lo[k]) <= bottom
        assert got_hi[k] - float(top) <= 1e-6 and float(bottom) - got_lo[k] <= 1e-6


def test_multipliers_found_on_one_set_prove_a_bound_on_another_with_no_lp():
    # hull.proven: the multipliers of one set bound any set with the same rows and columns; on a wider set
    # the bound still holds (a point of the wider set's optimum never exceeds it), on a narrower one too.
    rng = np.random.default_rng(3)
    B = rng.normal(size=(30, 3))
    x0 = rng.normal(size=3)
    lo, hi = B @ x0 - 0.5, B @ x0 + 0.5
    C = np.eye(3)
    *_, lams = hull.ranges(B, lo, hi, x0 - 3, x0 + 3, C, multipliers=True)
    for widen in (0.8, 1.5):
        lo2, hi2 = B @ x0 - 0.5 * widen, B @ x0 + 0.5 * widen
        p_lo, p_hi = hull.proven(B, lo2, hi2, x0 - 3, x0 + 3, C, [lams])
        t_lo, t_hi = hull.ranges(B, lo2, hi2, x0 - 3, x0 + 3, C)
        assert np.all(p_hi >= t_hi - 1e-12) and np.all(p_lo <= t_lo + 1e-12)


def test_many_rows_by_row_generation_give_the_ends_of_all_rows(monkeypatch):
    # Above GENERATE_ABOVE rows the LPs start on the tightest rows and add violated ones: the same optimum as
    # with every row in the model from the start.
    rng = np.random.default_rng(4)
    rows = highs.GENERATE_ABOVE * 3
    B = rng.normal(size=(rows, 4))
    x0 = rng.normal(size=4)
    lo, hi = B @ x0 - rng.uniform(0.5, 2, rows), B @ x0 + rng.uniform(0.5, 2, rows)
    C = rng.normal(size=(4, 4))
    g_lo, g_hi = hull.ranges(B, lo, hi, x0 - 4, x0 + 4, C)
    monkeypatch.setattr(hull, "GENERATE_ABOVE", 10 * rows)
    a_lo, a_hi = hull.ranges(B, lo, hi, x0 - 4, x0 + 4, C)
    np.testing.assert_allclose(g_lo, a_lo, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(g_hi, a_hi, rtol=1e-7, atol=1e-9)
    assert np.all(g_hi - g_lo < 7.9)                          # the rows cut the column box: a real test


def test_an_empty_set_is_said_not_bounded():
    B = np.array([[1.0, 0.0], [1.0, 0.0]])
    with pytest.raises(hull.Empty):
        hull.ranges(B, np.array([0.0, 2.0]), np.array([1.0, 3.0]), -np.ones(2) * 5, np.ones(2) * 5, np.eye(2))


@pytest.mark.parametrize("seed", range(4))
def test_a_limit_stops_the_hull_only_when_an_end_is_proven_past_it(seed):
    # `beyond` lets the premise box's hull stop at its first end past the box (norm_information): with limits a
    # millionth beyond every end nothing stops and every end is the one without limits, bit for bit; with one limit
    # a millionth inside its end, Beyond. Red if the stop fired on an end within its limit (the box would be
    # rejected that the full hull accepts) or the ends solved were changed by the check.
    B, x0, lo, hi = _polytope(np.random.default_rng(seed), 30, 5)
    C = np.eye(5)
    plain = hull.ranges(B, lo, hi, x0 - 5, x0 + 5, C, multipliers=True)
    width = plain[1] - plain[0]
    within = (plain[0] - 1e-6 * width, plain[1] + 1e-6 * width)
    got = hull.ranges(B, lo, hi, x0 - 5, x0 + 5, C, multipliers=True, beyond=within)
    assert np.array_equal(got[0], plain[0]) and np.array_equal(got[1], plain[1])
    assert all(np.array_equal(a.rows, b.rows) and np.array_equal(a.values, b.values)
               for p, q in zip(got[2], plain[2]) for a, b in zip(p, q))
    k = seed % 5
    for side in (0, 1):
        limits = [within[0].copy(), within[1].copy()]
        limits[side][k] = plain[side][k] + (1e-6 if side == 0 else -1e-6) * width[k]
        with pytest.raises(hull.Beyond):
            hull.ranges(B, lo, hi, x0 - 5, x0 + 5, C, beyond=limits)


def test_the_shared_small_lp_solver_gives_each_lp_what_a_fresh_highs_gives_bit_for_bit():
    # highs.small passes each LP into this thread's one HiGHS, cleared of the last: a hull, a minimax fit and the
    # l1 estimators, in turn and of different sizes, give the solutions a new HiGHS per LP gives, bit for bit, and
    # another thread has its own instance. Red if the last model's rows, basis or options (the hull's primal
    # simplex) carried over into the next.
    import threading
    import highspy
    rng = np.random.default_rng(7)
    B = rng.normal(size=(30, 4))
    lo, hi = B @ np.ones(4) - 1, B @ np.ones(4) + 1

    def fresh(cost, M, row_lo, row_hi, col_lo, col_hi, strategy):
        h = highs.new(presolve=False)
        h.setOptionValue("simplex_strategy", strategy)
        lp = highspy.HighsLp()
        lp.num_col_, lp.num_row_ = M.shape[1], M.shape[0]
        lp.col_cost_, lp.col_lower_, lp.col_upper_ = cost, col_lo, col_hi
        lp.row_lower_, lp.row_upper_ = row_lo, row_hi
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = np.arange(0, M.size + 1, M.shape[0], dtype=np.int32)
        lp.a_matrix_.index_ = np.tile(np.arange(M.shape[0], dtype=np.int32), M.shape[1])
        lp.a_matrix_.value_ = np.ascontiguousarray(M.T).ravel()
        h.passModel(lp)
        highs.solve(h)
        sol = h.getSolution()
        return np.array(sol.col_value), np.array(sol.row_dual)

    def matrix(M):
        return (np.arange(0, M.size + 1, M.shape[0], dtype=np.int32),
                np.tile(np.arange(M.shape[0], dtype=np.int32), M.shape[1]), np.ascontiguousarray(M.T).ravel())

    def shared(cost, M, row_lo, row_hi, col_lo, col_hi, strategy):
        h = highs.small(cost, col_lo, col_hi, row_lo, row_hi, *matrix(M), strategy)
        highs.solve(h)
        sol = h.getSolution()
        return np.array(sol.col_value), np.array(sol.row_dual)

    lps = [(rng.normal(size=4), B, lo, hi, np.full(4, -5.0), np.full(4, 5.0), 4),
           (rng.normal(size=2), B[:7, :2], lo[:7], hi[:7], np.full(2, -3.0), np.full(2, 3.0), 1),
           (rng.normal(size=4), B, lo, hi, np.full(4, -5.0), np.full(4, 5.0), 1)]
    want = [fresh(*lp) for lp in lps]
    for lp, w in zip(lps * 2, want * 2):
        got = shared(*lp)
        assert np.array_equal(got[0], w[0]) and np.array_equal(got[1], w[1])
    cost, M, row_lo, row_hi, col_lo, col_hi, strategy = lps[1]
    other = []
    worker = threading.Thread(target=lambda: other.append(highs.small(cost, col_lo, col_hi, row_lo, row_hi,
                                                                      *matrix(M), strategy)))
    worker.start()
    worker.join()
    assert other[0] is not highs.small(cost, col_lo, col_hi, row_lo, row_hi, *matrix(M), strategy)


def test_each_ends_multipliers_are_kept_by_their_support_and_prove_what_the_dense_ones_prove():
    # 3,000 readings of 5 unknowns (the row generation of `ranges` at work): each end's proof keeps at most one
    # multiplier per column (an LP optimum's basis), not one per reading; the same multipliers written out densely
    # prove the same end (within the rounding allowance, which counts the rows read). Red when the multipliers
    # are kept dense (3,000 per end) or an end is proven from rows it does not read.
    B, x0, lo, hi = _polytope(np.random.default_rng(4), 3000, 5)
    C = np.eye(5)
    out_lo, out_hi, lams = hull.ranges(B, lo, hi, x0 - 5, x0 + 5, C, multipliers=True)
    for k, (a, b) in enumerate(lams):
        assert isinstance(a, hull.Multipliers) and len(a.rows) <= 5 and len(b.rows) <= 5
        dense = np.zeros(len(B))
        dense[b.rows] = b.values
        sparse_end, dense_end = (hull.upper(C[k], B, lo, hi, x0 - 5, x0 + 5, m) for m in (b, dense))
        assert sparse_end <= out_hi[k] * (1 + 1e-12) + 1e-12 and abs(sparse_end - dense_end) <= 1e-9 * abs(dense_end)
    assert np.all(out_hi - out_lo < 2.0)                # the readings prove far more than the box of +-5


def test_the_row_generation_measured_block_by_block_adds_the_rows_it_would_add_at_once(monkeypatch):
    # hull._worst_rows measures the violations VIOLATION_BLOCK rows at a time, so that the row generation holds a
    # block's array, not every reading's times every end's (1e5 positions: estimate's peak 617 -> 362 MiB): in
    # blocks of 97 rows the ends and their multipliers are those of one block holding every row, bit for bit
    # (red when a block's best rows are not merged with the earlier blocks').
    B, x0, lo, hi = _polytope(np.random.default_rng(9), 4000, 4)
    C = np.random.default_rng(10).normal(size=(3, 4))
    monkeypatch.setattr(hull, "VIOLATION_BLOCK", 1 << 20)
    whole = hull.ranges(B, lo, hi, x0 - 5, x0 + 5, C, multipliers=True)
    monkeypatch.setattr(hull, "VIOLATION_BLOCK", 97)
    blocks = hull.ranges(B, lo, hi, x0 - 5, x0 + 5, C, multipliers=True)
    assert np.array_equal(whole[0], blocks[0]) and np.array_equal(whole[1], blocks[1])
    assert all(np.array_equal(a.rows, b.rows) and np.array_equal(a.values, b.values)
               for p, q in zip(whole[2], blocks[2]) for a, b in zip(p, q))


@pytest.mark.parametrize("seed", range(4))
def test_the_row_generation_measures_only_rows_that_can_be_violated_and_misses_none(seed):
    # hull._worst_rows measures violations only on the rows whose slack at the points' mean is below |b_k| rho
    # (rho: the points' largest distance from their mean): at 1e6 positions the later rounds' points lie within
    # 1e-3 of each other in a box of width 2, and 12.6 s of the 1e6-position estimate went to measuring every row.
    # Against every row measured at every point (the worst per_end per point above the tolerance, S left out): the
    # same rows, half of them along a point's offset from the mean with their slack just inside or outside the cut
    # (every violated row kept, so the cut alone decides). Red when rho is the mean distance, not the largest, or
    # the cut taken at 0.999 |b_k| rho.
    rng = np.random.default_rng(seed)
    rows, cols, ends, per_end = 3000, 5, 8, 3000       # every violated row kept: the cut alone decides
    m = rng.uniform(-0.5, 0.5, cols)
    X = m[:, None] + rng.normal(scale=10.0 ** rng.uniform(-4, -1), size=(cols, ends))
    X -= X.mean(axis=1)[:, None] - m[:, None]
    D = X - m[:, None]
    j = rng.integers(0, ends, rows)                   # half the rows along a point's offset, the farthest's among them
    j[::7] = np.argmax(np.linalg.norm(D, axis=0))
    Bs = np.where(rng.random((rows, 1)) < 0.5, (D[:, j] / np.linalg.norm(D[:, j], axis=0)).T,
                  rng.normal(size=(rows, cols))) * rng.uniform(0.1, 3, (rows, 1))
    rho = np.linalg.norm(D, axis=0).max()
    c, norms = Bs @ m, np.linalg.norm(Bs, axis=1)
    reach = norms * rho * rng.choice([0.3, 0.999, 1.001, 3.0], rows)     # each row's slack at m, about the cut
    lo_s, hi_s = c - np.where(rng.random(rows) < 0.2, reach, 10.0), c + np.where(rng.random(rows) < 0.8, reach, 10.0)
    S = np.sort(rng.choice(rows, 50, replace=False))
    got = hull._worst_rows(Bs, X, lo_s, hi_s, S, per_end, norms)
    V = hull._violation(Bs, X, lo_s, hi_s)
    V[S] = -np.inf
    want = set()
    for j in range(ends):
        top = np.argsort(-V[:, j])[:per_end]
        want |= set(top[V[top, j] > hull.TOLERANCE].tolist())
    assert sorted(want) == got.tolist() and 0 < len(want) < rows - 50


@pytest.mark.parametrize("seed", range(3))
def test_objectives_that_are_multiples_of_one_share_its_lps_and_each_end_stays_above_the_exact_optimum(seed):
    # An effect's term on one axis at every interval is t_k e_j: objectives multiples of one another. Those equal in
    # floats once scaled to largest entry 1 (t e_j always; c times a power of 2) cost one LP pair: 4 LPs for these 6
    # rows, sign flips among them. Each end is proven by its own multipliers (the shared ones times t): above the
    # exact optimum in rationals, and what the row gives alone. Red when every row is solved (12 LPs) or when a
    # flipped row takes the other end's multipliers (a wrong bound).
    rng = np.random.default_rng(seed)
    B, x0, lo, hi = _polytope(rng, 12, 2)
    xl, xh = x0 - 5, x0 + 5
    c = rng.normal(size=2)
    C = np.array([c, -2.0 * c, 0.25 * c, [c[0], 0.0], [-7e-3, 0.0], [5.0, 0.0]])
    solved = []
    inner = highs.solve

    def counted(h, *a, **k):
        solved.append(1)
        return inner(h, *a, **k)
    highs.solve = counted
    try:
        got_lo, got_hi = hull.ranges(B, lo, hi, xl, xh, C)
    finally:
        highs.solve = inner
    assert len(solved) == 4                               # c's pair and [c_1, 0]'s
    for k, row in enumerate(C):
        top, bottom = _exact_max(row, B, lo, hi, xl, xh), -_exact_max(-row, B, lo, hi, xl, xh)
        assert Fraction(got_hi[k]) >= top and Fraction(got_lo[k]) <= bottom
        alone_lo, alone_hi = hull.ranges(B, lo, hi, xl, xh, row[None])
        assert abs(got_hi[k] - alone_hi[0]) <= 1e-9 * (1 + abs(alone_hi[0]))
        assert abs(got_lo[k] - alone_lo[0]) <= 1e-9 * (1 + abs(alone_lo[0]))
