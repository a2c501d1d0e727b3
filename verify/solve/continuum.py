"""Guaranteed estimation on the continuum by the exchange (cutting-plane) method on the dual (9)-(10).

Start from a few positions; solve the dual LP there (all targets at once); find, for each target, the
position of the whole box of angles where |H^(p)(x)^T lambda| is largest (a scan of the box, then a
local pattern search from the best points); add every position where it exceeds 1; repeat until no
constraint is violated. The primal on the final positions then gives the optimal estimators, and the
value equals the dual value (the optimum on the continuum, up to the search's tolerance; the
certificates of `proof/check.py` prove it).
"""
from dataclasses import dataclass

import numpy as np

from . import lp
@dataclass
class Solution:
    """The exchange method's result: each q's optimum on the continuum of angles and its positions."""

    values: np.ndarray            # optimal guaranteed error per target (units of sigma)
    lam: np.ndarray               # dual vectors (m x n_targets)
    positions: np.ndarray         # (S, n_angles) radians: the final exchange set
    Phi: np.ndarray               # primal estimators on it (3S x n_targets)
    iterations: int


def _H_rows(H, X):
    """H at positions X (K, n) -> (K, rows, m) (rows: 3, or 3 per mounting)."""
    return np.moveaxis(H(*X.T), -1, 0)


def _violation(H, X, lam):
    """max over components of |H^(p)(x)^T lambda| at positions X (K, n), per target: (K, n_targets)."""
    return np.abs(np.einsum("kpm,mt->kpt", _H_rows(H, X), lam)).max(axis=1)


def _refine(H, X, Lam, step, lo, hi, iterations=400):
    """Local pattern search for a larger |H^T lambda|, from every start at once: X (P, n) starts,
    Lam (m, P) the dual vector of each; each move tries +-step along every angle, and a start whose
    moves all fail halves its step. Returns the final points (P, n) and values (P,)."""
    P, n = X.shape
    moves = np.concatenate([np.eye(n), -np.eye(n)])                      # (2n, n)
    best = np.abs(np.einsum("kpm,mk->kp", _H_rows(H, X), Lam)).max(axis=1)
    steps = np.full(P, float(step))
    for _ in range(iterations):
        live = steps >= 1e-9
        if not live.any():
            break
        idx = np.flatnonzero(live)
        cand = np.clip(X[idx, None, :] + moves[None] * steps[idx, None, None], lo, hi)   # (L, 2n, n)
        rows = _H_rows(H, cand.reshape(-1, n)).reshape(len(idx), 2 * n, -1, Lam.shape[0])
        vals = np.abs(np.einsum("lcpm,ml->lcp", rows, Lam[:, idx])).max(axis=2)          # (L, 2n)
        k = vals.argmax(axis=1)
        top = vals[np.arange(len(idx)), k]
        up = top > best[idx] + 1e-12
        X[idx[up]] = cand[np.flatnonzero(up), k[up]]
        best[idx[up]] = top[up]
        steps[idx[~up]] /= 2
    return X, best


def exchange(H, n_angles, targets, start=None, scan_deg=15.0, tol=1e-6, max_iter=60, top=12, ranges_deg=None):
    """Exchange method on the box of angles (default [0, 2 pi)^n_angles; `ranges_deg` (lo, hi) per
    angle for a stand with limited ranges) for the targets (columns of `targets`, m x T)."""
    ranges = np.array(ranges_deg if ranges_deg is not None else [(0, 360)] * n_angles, float)
    full = ranges[:, 1] - ranges[:, 0] >= 360
    lo, hi = np.deg2rad(ranges[:, 0]), np.deg2rad(np.where(full, ranges[:, 0] + 360, ranges[:, 1]))
    axes = [np.deg2rad(np.arange(a, b + (0 if f else 1e-9), scan_deg)) for (a, b), f in
            zip(np.where(full[:, None], [[r[0], r[0] + 360] for r in ranges], ranges), full)]
    scan = np.array(np.meshgrid(*axes, indexing="ij")).reshape(n_angles, -1).T
    if start is None:                                   # quarter turns: identify every q of the stands here
        quarter = [np.deg2rad([v for v in (0, 90, 180, 270, 360, -90) if a <= v <= b or f][:4] or [a, b])
                   for (a, b), f in zip(ranges, full)]
        start = np.array(np.meshgrid(*quarter, indexing="ij")).reshape(n_angles, -1).T
        if ranges_deg is not None and not full.all():
            start = np.vstack([start, scan])            # a limited range: every scan point to start from
    X = np.asarray(start, float)
    for it in range(1, max_iter + 1):
        A = lp.measurement_matrix(H, X)
        lam, _ = lp.sparse_dual(A, targets)
        viol = _violation(H, scan, lam)                                  # (K, T)
        # refine from every scan point that is nearly active (up to `top` of them per target): a peak
        # between scan points can exceed 1 even where the scan shows less
        pairs = [(k, t) for t in range(lam.shape[1]) for k in np.argsort(viol[:, t])[::-1][:top] if viol[k, t] > 0.9]
        new = []
        if pairs:
            ks, ts = np.array(pairs).T
            xs, vs = _refine(H, scan[ks].copy(), lam[:, ts], np.deg2rad(scan_deg) / 2, lo, hi)
            for x, v in zip(xs, vs):           # new unless within 1e-6 (+1e-5 relative) of a point kept
                known = np.vstack([X, *new]) if new else X
                if v > 1 + tol and not np.any(np.all(np.abs(x - known) <= 1e-6 + 1e-5 * np.abs(known), axis=1)):
                    new.append(x)
        if not new:
            break
        X = np.vstack([X, np.array(new)])
    Phi, values = lp.primal(lp.measurement_matrix(H, X), targets)
    return Solution(values, lam, X, Phi, it)
