"""The hull of an information set: each linear function's least and largest value over a polytope

    X = {x : row_lo <= B x <= row_hi,  col_lo <= x <= col_hi},

by HiGHS (one model, the objectives in turn from the last basis) and proven by weak duality: for any
row multipliers lambda and mu = c - B^T lambda, every x in X has

    c^T x = lambda^T B x + mu^T x <= sum_i max(lambda_i lo_i, lambda_i hi_i) + sum_j max(mu_j xl_j, mu_j xh_j),

whatever the solver's accuracy (a poor lambda only gives a wider bound; lambda = 0 gives the column
box itself). The float rounding of mu and of the sums is covered outward (`upper`), so each end is a
proof, not a solver's report. Every column bound must be finite: it is what the rounding of mu is
multiplied by.
"""
import highspy
import numpy as np

from . import highs

EPS = np.finfo(float).eps


class Empty(Exception):
    """HiGHS finds X empty (to its tolerances): no x meets every constraint."""


def upper(c, B, row_lo, row_hi, col_lo, col_hi, lam):
    """A proven upper bound of c^T x over X from the multipliers lam (a multiplier on a side that is
    infinite is dropped: it would bound nothing)."""
    lam = np.where((lam > 0) & ~np.isfinite(row_hi) | (lam < 0) & ~np.isfinite(row_lo), 0.0, lam)
    n = B.shape[0] + 2
    mu = c - B.T @ lam
    slack = 1.01 * n * EPS * (np.abs(c) + np.abs(B).T @ np.abs(lam))          # |mu_true - mu| (rounding of B^T lam)
    with np.errstate(invalid="ignore"):
        rows = np.where(lam > 0, lam * row_hi, np.where(lam < 0, lam * row_lo, 0.0))
    cols = np.maximum(mu * col_lo, mu * col_hi) + slack * np.maximum(np.abs(col_lo), np.abs(col_hi))
    terms = np.r_[rows, cols]
    total = terms.sum()
    return float(total + 1.01 * (len(terms) + 2) * EPS * np.abs(terms).sum())


def ranges(B, row_lo, row_hi, col_lo, col_hi, C, points=False, multipliers=False):
    """(lo, hi): the least and largest value over X of c^T x for each row c of C, each end proven
    (`upper`); with `points`, also the solver's x at each end ((x_min, x_max) per row; None where it
    gave none); with `multipliers`, the lambda that proves each end ((for -c, for c) per row), which
    prove a bound on any other set with the same B and columns (`upper`). HiGHS solves on X shifted to the centre of its column box and scaled to rows and columns
    of width 2 (its tolerances are absolute); the multipliers it returns are mapped back and proven on X."""
    B = np.asarray(B, float)
    C = np.atleast_2d(np.asarray(C, float))
    row_lo, row_hi = np.asarray(row_lo, float), np.asarray(row_hi, float)
    col_lo, col_hi = np.asarray(col_lo, float), np.asarray(col_hi, float)
    if not (np.all(np.isfinite(col_lo)) and np.all(np.isfinite(col_hi))):
        raise ValueError("hull.ranges: every column needs a finite bound")
    rows, cols = B.shape
    xc, dc = 0.5 * (col_lo + col_hi), np.maximum(0.5 * (col_hi - col_lo), 1e-300)
    both = np.isfinite(row_lo) & np.isfinite(row_hi)
    r = np.maximum(np.where(both, 0.5 * (row_hi - row_lo), 0.0), np.abs(B) @ dc)   # rows of width <= 2, entries <= 1
    r = np.where(r > 0, r, 1.0)
    Bs = B * dc / r[:, None]
    shift = B @ xc
    lo_s, hi_s = (row_lo - shift) / r, (row_hi - shift) / r
    h = _model(Bs, np.where(np.isfinite(lo_s), lo_s, -highs.INF), np.where(np.isfinite(hi_s), hi_s, highs.INF))
    idx = np.arange(cols, dtype=np.int32)
    out_lo, out_hi, pts, lams = np.empty(len(C)), np.empty(len(C)), [], []
    for k, c in enumerate(C):
        ends, xs, used = [], [], []
        for sign in (1.0, -1.0):                  # max of sign c^T x: HiGHS minimises -sign c
            h.changeColsCost(cols, idx, -sign * c * dc)
            h.run()
            status = h.getModelStatus()
            if status not in (highspy.HighsModelStatus.kOptimal, highspy.HighsModelStatus.kInfeasible):
                h.clearSolver()                   # a warm start that stalls: once more from scratch
                h.run()
                status = h.getModelStatus()
            cands = [np.zeros(rows)]              # lambda = 0: the column box, always valid
            if status == highspy.HighsModelStatus.kOptimal:
                sol = h.getSolution()
                cands.append(-np.array(sol.row_dual) / r)
                xs.append(xc + dc * np.array(sol.col_value))
            elif status == highspy.HighsModelStatus.kInfeasible:
                raise Empty()
            else:                                 # stalled: the box stands
                xs.append(None)
            bounds = [upper(sign * c, B, row_lo, row_hi, col_lo, col_hi, lam) for lam in cands]
            ends.append(min(bounds))
            used.append(cands[int(np.argmin(bounds))])
        out_hi[k], out_lo[k] = ends[0], -ends[1]
        pts.append((xs[1], xs[0]))
        lams.append((used[1], used[0]))
    return (out_lo, out_hi) + ((pts,) if points else ()) + ((lams,) if multipliers else ())


def _model(B, row_lo, row_hi):
    """A HiGHS model of the scaled rows, the columns in their scaled box [-1, 1], no objective yet."""
    rows, cols = B.shape
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = cols, rows
    lp.col_cost_ = np.zeros(cols)
    lp.col_lower_, lp.col_upper_ = -np.ones(cols), np.ones(cols)
    lp.row_lower_, lp.row_upper_ = row_lo, row_hi
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.start_ = np.arange(0, rows * cols + 1, rows, dtype=np.int32)
    lp.a_matrix_.index_ = np.tile(np.arange(rows, dtype=np.int32), cols)
    lp.a_matrix_.value_ = np.ascontiguousarray(B.T).ravel()
    h = highs.new(presolve=False)
    h.passModel(lp)
    return h
