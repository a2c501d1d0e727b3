"""The hull of an information set: each linear function's least and largest value over a polytope.

    X = {x : row_lo <= B x <= row_hi,  col_lo <= x <= col_hi},

by HiGHS (one model, the objectives in turn from the last basis) and proven by weak duality: for any
row multipliers lambda and mu = c - B^T lambda, every x in X has

    c^T x = lambda^T B x + mu^T x <= sum_i max(lambda_i lo_i, lambda_i hi_i) + sum_j max(mu_j xl_j, mu_j xh_j),

whatever the solver's accuracy (a poor lambda only gives a wider bound; lambda = 0 gives the column
box itself). The float rounding of mu and of the sums is covered outward (`upper`), so each end is a
proof, not a solver's report. Every column bound must be finite: it is what the rounding of mu is
multiplied by.
"""
from typing import NamedTuple

import numpy as np

from . import highs

EPS = np.finfo(float).eps


class Empty(Exception):
    """HiGHS finds X empty (to its tolerances): no x meets every constraint."""


class Beyond(Exception):
    """An end of the hull is proven past the limit the caller gave (`ranges(..., beyond=...)`): the caller rejects
    such a hull whatever its other ends, so they are not solved."""


class Multipliers(NamedTuple):
    """Row multipliers by their support: `values` at the rows `rows` (shape (..., len(rows))), 0 at every other
    row. An LP's optimum has at most as many nonzero multipliers as columns, so a proof of one end keeps those
    only: a constant size per end, not one number per reading."""

    rows: np.ndarray
    values: np.ndarray


NONE = Multipliers(np.zeros(0, dtype=np.intp), np.zeros(0))      # lambda = 0: the column box


def sparse(lam):
    """Multipliers of a dense vector, or a stack of them (one a row): the rows where any is nonzero."""
    L = np.asarray(lam, float)
    rows = np.flatnonzero(np.any(np.atleast_2d(L) != 0, axis=0))
    return Multipliers(rows, L[..., rows])


def distinct(x):
    """The distinct values of x, increasing: np.unique without its import of numpy.ma (8 ms, a twentieth of a small
    log's calibrate-norm)."""
    x = np.sort(np.asarray(x).ravel())
    return x[np.r_[True, x[1:] != x[:-1]]] if len(x) else x


def stacked(lams):
    """One Multipliers holding a list of them (one vector each) as a stack over the union of their rows."""
    rows = distinct(np.concatenate([m.rows for m in lams])) if lams else NONE.rows
    values = np.zeros((len(lams), len(rows)))
    for i, m in enumerate(lams):
        values[i, np.searchsorted(rows, m.rows)] = m.values
    return Multipliers(rows, values)


def upper(c, B, row_lo, row_hi, col_lo, col_hi, lam):
    """A proven upper bound of c^T x over X from the multipliers lam (Multipliers, or a dense vector; a multiplier
    on a side that is infinite is dropped: it would bound nothing; rows without a multiplier cost nothing, and only
    the rows with one are read). c and lam may be stacks, one objective and its multipliers a row: then an array of
    bounds, one a row. Multipliers whose rows are a stack too (one set of rows per objective, padded with zero
    multipliers: support.py, many proofs at once) read each objective's own rows."""
    m = lam if isinstance(lam, Multipliers) else sparse(lam)
    B, row_lo, row_hi = B[m.rows], np.asarray(row_lo)[m.rows], np.asarray(row_hi)[m.rows]
    C, L = np.atleast_2d(c), np.atleast_2d(m.values)
    lo_ok, hi_ok = np.isfinite(row_lo), np.isfinite(row_hi)
    if not (lo_ok.all() and hi_ok.all()):              # (all finite: nothing to drop)
        L = np.where((L > 0) & ~hi_ok | (L < 0) & ~lo_ok, 0.0, L)
    n = B.shape[-2] + 2                                 # terms of each entry of L B (the rows read)
    if B.ndim == 3:                                     # each objective's own rows
        LB, size = np.einsum("kr,krp->kp", L, B), np.einsum("kr,krp->kp", np.abs(L), np.abs(B))
    else:
        LB, size = L @ B, np.abs(L) @ np.abs(B)
    mu = C - LB
    slack = 1.01 * n * EPS * (np.abs(C) + size)        # |mu_true - mu| (rounding of L B)
    rows = L * np.where(L > 0, np.where(hi_ok, row_hi, 0.0), np.where(lo_ok, row_lo, 0.0))   # the same products
    cols = np.maximum(mu * col_lo, mu * col_hi) + slack * np.maximum(np.abs(col_lo), np.abs(col_hi))
    terms = np.hstack([rows, cols])
    out = terms.sum(axis=1) + 1.01 * (terms.shape[1] + 2) * EPS * np.abs(terms).sum(axis=1)
    return float(out[0]) if np.ndim(c) == 1 else out


GENERATE_ABOVE = highs.GENERATE_ABOVE     # rows: above this, the LPs start on the tightest rows and add violated ones
TOLERANCE = 1e-9                          # a row violated by less (relative to its width) counts as met
#: HiGHS's simplex for the hull: primal (4), as a new objective leaves the last basis feasible (a thermal estimate
#: about 1.5x faster than with its dual simplex (1), python -m verify.bench).
SIMPLEX = 4


def ranges(B, row_lo, row_hi, col_lo, col_hi, C, points=False, multipliers=False, start=(), beyond=None, sweep=False):
    """(lo, hi): the least and largest value over X of c^T x for each row c of C, each end proven
    (`upper`); with `points`, also the solver's x at each end ((x_min, x_max) per row; None where it
    gave none); with `multipliers`, the lambda that proves each end (Multipliers (for -c, for c) per row), which
    prove a bound on any other set with the same B and columns (`upper`). HiGHS solves on X shifted to
    the centre of its column box and scaled to columns and rows of width 2 (its tolerances are absolute);
    the multipliers it returns are mapped back and proven on X. Many rows: the LPs are solved on the rows
    tightest at the box's centre (and `start`: rows known to bind, e.g. a previous set's), and rows an
    optimum violates are added until none is (the optimum over them is then the optimum over all; any
    subset's multipliers prove a bound on X, which lies inside the subset's polytope). `beyond` = (lo, hi) per
    row of C: Beyond as soon as an end is proven past them (below lo, above hi, by more than the proofs' rounding),
    the rest unsolved; an end within them is what it would be without. `sweep`: the ends solved every maximum,
    then every minimum in reverse, each LP warm-started from its neighbour's basis (for many objectives that change
    little from row to row: half the simplex iterations of alternating max and min); else each row's two ends in
    turn. Rows of C that are multiples of one another share one LP pair (`_alike`); each end is still proven by
    its own multipliers (the shared ones times the multiple)."""
    B = np.asarray(B, float)
    C = np.atleast_2d(np.asarray(C, float))
    row_lo, row_hi = np.asarray(row_lo, float), np.asarray(row_hi, float)
    col_lo, col_hi = np.asarray(col_lo, float), np.asarray(col_hi, float)
    if not (np.all(np.isfinite(col_lo)) and np.all(np.isfinite(col_hi))):
        raise ValueError("hull.ranges: every column needs a finite bound")
    rows, cols = B.shape
    xc, dc = 0.5 * (col_lo + col_hi), np.maximum(0.5 * (col_hi - col_lo), 1e-300)
    both = np.isfinite(row_lo) & np.isfinite(row_hi)
    r = np.where(both, 0.5 * (row_hi - row_lo), 0.0)
    if not (r > 0).all():                          # rows of width 2 (one-sided: entries at most 1)
        r = np.where(r > 0, r, np.abs(B) @ dc)
    r = np.where(r > 0, r, 1.0)
    Bs = np.multiply(B, dc)                        # scaled in place: one copy of B, not two
    Bs /= r[:, None]
    shift = B @ xc
    lo_s = np.where(np.isfinite(row_lo), (row_lo - shift) / r, -highs.INF)
    hi_s = np.where(np.isfinite(row_hi), (row_hi - shift) / r, highs.INF)
    if rows <= GENERATE_ABOVE:
        S = np.arange(rows)
    else:                                          # the rows closest to binding at the centre first
        S = np.union1d(np.argpartition(np.minimum(-lo_s, hi_s), GENERATE_ABOVE // 6)[:GENERATE_ABOVE // 6],
                       np.asarray(start, int))
    h = _model(Bs[S], lo_s[S], hi_s[S])
    Cs = C * dc
    unit = np.abs(Cs).max(axis=1)                  # each objective handed over at unit size: HiGHS's optimality
    unit = np.where(unit > 0, unit, 1.0)           # tolerances are absolute (its duals are scaled back below)
    Cs = Cs / unit[:, None]
    rep, flip = _alike(Cs) if beyond is None else (np.arange(len(C)), np.ones(len(C)))
    own = [k for k in range(len(C)) if rep[k] == k]   # the rows solved; a multiple of one shares its LPs
    ends = ([(k, 1.0) for k in own] + [(k, -1.0) for k in reversed(own)] if sweep else
            [(k, sign) for k in own for sign in (1.0, -1.0)])
    found = {}                                     # (k, sign) -> (row duals over S as it then was, x), or None
    norms = None                                   # each scaled row's 2-norm, once rows are generated
    todo = ends
    for _ in range(100):
        for k, sign in todo:
            found[k, sign] = _solve(h, -sign * Cs[k])
            if beyond is not None and len(S) == rows:           # this end's bound as below: the last LP solved it
                _past(C[k] * sign, B, row_lo, row_hi, col_lo, col_hi, _multipliers(found[k, sign], S, unit[k], r),
                      beyond[1][k] if sign > 0 else -beyond[0][k])
        if len(S) == rows:
            break
        pts_ = {e: v[1] for e, v in found.items() if v is not None}
        if not pts_:
            break
        keys = list(pts_)
        X = np.array([pts_[e] for e in keys]).T
        per_end = max(1, GENERATE_ABOVE // 9 // X.shape[1])    # each violated end's worst rows
        if norms is None:
            norms = np.sqrt(np.einsum("ij,ij->i", Bs, Bs))
        new = _worst_rows(Bs, X, lo_s, hi_s, S, per_end, norms)
        if not len(new):
            break
        _add_rows(h, Bs[new], lo_s[new], hi_s[new])
        S = np.r_[S, new]                          # in the model's row order
        V = _violation(Bs[new], X, lo_s[new], hi_s[new])
        todo = [e for e, col in zip(keys, V.T) if col.max() > TOLERANCE] + [e for e in ends if found[e] is None]
    K = len(C)
    for k in np.flatnonzero(rep != np.arange(K)):     # c_k = t c_rep: max c_k is max (or min) c_rep, its x the same,
        for sign in (1.0, -1.0):                       # its lambda that one's times |t| (unit[k] below)
            found[k, sign] = found[rep[k], sign * flip[k]]
    signs = np.array([1.0, -1.0])
    objectives = (signs[None, :, None] * C[:, None, :]).reshape(2 * K, -1)     # (k, +), (k, -), ...
    lam = [_multipliers(found[k, sign], S, unit[k], r) for k in range(K) for sign in signs]
    # lambda = 0 (the column box) is always valid: each end the better of the two proofs
    box = upper(objectives, B, row_lo, row_hi, col_lo, col_hi, Multipliers(NONE.rows, np.zeros((2 * K, 0))))
    solved = upper(objectives, B, row_lo, row_hi, col_lo, col_hi, stacked(lam))
    use = solved <= box
    best = np.where(use, solved, box).reshape(K, 2)
    out_hi, out_lo = best[:, 0], -best[:, 1]
    used = [m if u else NONE for m, u in zip(lam, use)]
    pts = [tuple(None if found[k, sign] is None else xc + dc * found[k, sign][1] for sign in (-1.0, 1.0))
           for k in range(K)]
    lams = [(used[2 * k + 1], used[2 * k]) for k in range(K)]
    return (out_lo, out_hi) + ((pts,) if points else ()) + ((lams,) if multipliers else ())


def _alike(Cs):
    """(rep, flip) for objectives Cs (one a row, each scaled to largest |entry| 1): rep[k] the first row equal to
    row k times flip[k] (+1 or -1), exactly in floats; k itself when none comes before. Objectives that are multiples
    of one another (an effect's term on one axis at every interval, t_k e_j) then cost one LP pair, not one each."""
    K = len(Cs)
    lead = Cs[np.arange(K), np.argmax(np.abs(Cs), axis=1)] if K else np.zeros(0)
    sign = np.where(lead < 0, -1.0, 1.0)
    first, rep = {}, np.arange(K)
    for k, row in enumerate(Cs * sign[:, None] + 0.0):            # + 0.0: -0.0 and 0.0 alike
        rep[k] = first.setdefault(row.tobytes(), k)
    return rep, sign * sign[rep]


def _violation(Bs, X, lo_s, hi_s):
    """By how much each row (of Bs) is violated at each point (column of X): max(lo - B x, B x - hi)."""
    BX = Bs @ X
    V = lo_s[:, None] - BX
    np.subtract(BX, hi_s[:, None], out=BX)
    return np.maximum(V, BX, out=V)


#: Rows whose violation is measured at once: the row generation's memory is a block's, not every reading's.
VIOLATION_BLOCK = 1 << 15


def _worst_rows(Bs, X, lo_s, hi_s, S, per_end, norms):
    """The rows outside S violated by more than TOLERANCE at some point (column of X), at most `per_end` of the
    worst per point, sorted; measured block by block of rows (the same rows as over all at once), and only on the
    rows that can be: |b_k^T (x - m)| <= |b_k| rho for every point x within rho of their mean m, so a row whose
    slack at m exceeds that (with a margin for rounding) holds at every point (the optimal points of a set much
    smaller than its column box lie close together: one product over every row instead of one per point)."""
    rows, ends = Bs.shape[0], X.shape[1]
    m = X.mean(axis=1)
    rho = np.sqrt(((X - m[:, None]) ** 2).sum(axis=0)).max()
    c = Bs @ m
    worst = np.maximum(lo_s - c, c - hi_s) + norms * rho
    may = np.flatnonzero(worst + 1e-12 * (1 + np.abs(c) + norms * rho) > TOLERANCE)
    in_S = np.zeros(rows, bool)
    in_S[S] = True
    may = may[~in_S[may]]
    best_v, best_i = np.full((0, ends), -np.inf), np.zeros((0, ends), np.intp)
    for start in range(0, len(may), VIOLATION_BLOCK):
        block = may[start:start + VIOLATION_BLOCK]
        V = _violation(Bs[block], X, lo_s[block], hi_s[block])
        hit = np.flatnonzero((V > TOLERANCE).any(axis=1))     # only these can be kept
        if not len(hit):
            continue
        vals = np.vstack([best_v, V[hit]])
        idx = np.vstack([best_i, np.broadcast_to(block[hit][:, None], (len(hit), ends))])
        if len(vals) > per_end:
            top = np.argpartition(-vals, per_end - 1, axis=0)[:per_end]
            vals, idx = np.take_along_axis(vals, top, axis=0), np.take_along_axis(idx, top, axis=0)
        best_v, best_i = vals, idx
    return np.unique(best_i[best_v > TOLERANCE])


def _multipliers(got, S, unit, r):
    """The multipliers of one end on the unscaled rows, from the row duals HiGHS gave over the rows S of the
    model as it then was (0 on the rest; none where it gave none)."""
    if got is None:
        return NONE
    y = got[0]
    rows = S[:len(y)]
    keep = y != 0
    return Multipliers(rows[keep], -y[keep] * unit / r[rows[keep]])


def _past(c, B, row_lo, row_hi, col_lo, col_hi, lam, limit):
    """Beyond when the end max c^T x, proven as `ranges` proves it (the better of the multipliers lam and none),
    is above `limit` by more than 1e-9 of either (a bound within that margin is left to the caller's own test,
    unchanged)."""
    end = min(upper(c, B, row_lo, row_hi, col_lo, col_hi, NONE), upper(c, B, row_lo, row_hi, col_lo, col_hi, lam))
    if end - limit > 1e-9 * max(abs(end), abs(limit)):
        raise Beyond()


def proven(B, row_lo, row_hi, col_lo, col_hi, C, proofs):
    """(lo, hi) of c^T x over X for each row c of C from multipliers found before, with no LP: `proofs` is a
    list of what `ranges(..., multipliers=True)` returned for the same B and C (on other row and column
    bounds); each end is the least `upper` over them and lambda = 0 (the column box)."""
    C = np.atleast_2d(np.asarray(C, float))
    K = len(C)
    lams = [m for p in [[(NONE, NONE)] * K] + list(proofs) for pair in p for m in pair]     # (proof, k, min/max)
    objectives = np.stack([-C, C], axis=1).reshape(2 * K, -1)                # (k, min), (k, max), ...
    n = len(lams) // (2 * K)
    ends = upper(np.tile(objectives, (n, 1)), B, row_lo, row_hi, col_lo, col_hi, stacked(lams)).reshape(
        n, K, 2).min(axis=0)
    return -ends[:, 0], ends[:, 1]


def _solve(h, cost):
    """(row duals, x) of the model h minimising cost^T x from its last basis; None where HiGHS gives no
    optimum (Empty when it finds the set empty)."""
    cols = len(cost)
    h.changeColsCost(cols, np.arange(cols, dtype=np.int32), cost)
    status = highs.solve(h, settled=(highs.OPTIMAL, highs.INFEASIBLE))      # warm from the last basis
    if status == highs.INFEASIBLE:
        raise Empty()
    if status != highs.OPTIMAL:
        return None                               # stalled: the box stands
    sol = h.getSolution()
    return np.array(sol.row_dual), np.array(sol.col_value)


def _add_rows(h, B, lo, hi):
    """Append dense rows to the model."""
    rows, cols = B.shape
    h.addRows(rows, lo, hi, rows * cols, np.arange(0, rows * cols, cols, dtype=np.int32),
              np.tile(np.arange(cols, dtype=np.int32), rows), np.ascontiguousarray(B).ravel())


def _model(B, row_lo, row_hi):
    """The thread's HiGHS for small LPs (highs.small) holding the scaled rows, the columns in their scaled box
    [-1, 1], no objective yet."""
    rows, cols = B.shape
    return highs.small(np.zeros(cols), -np.ones(cols), np.ones(cols), row_lo, row_hi,
                       np.arange(0, rows * cols + 1, rows, dtype=np.int32),
                       np.tile(np.arange(rows, dtype=np.int32), cols), np.ascontiguousarray(B.T).ravel(), SIMPLEX)
