"""Guaranteed estimation on the continuum by the exchange (cutting-plane) method on the dual (9)-(10).

Start from a few positions; solve the dual LP there (all targets at once); find, for each target, the
position of the whole box of angles where |H^(p)(x)^T lambda| is largest (a scan of the box, then a
local pattern search from the best points); add every position where it exceeds 1; repeat until no
constraint is violated. The primal on the final positions then gives the optimal estimators, and the
value equals the dual value (the optimum on the continuum, up to the search's tolerance; the
certificates of `certificate.py` prove it).
"""
from dataclasses import dataclass

import numpy as np

from . import lp
@dataclass
class Solution:
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


def _refine(H, x, lam_col, step, lo, hi):
    """Local pattern search for a larger |H^T lambda| from x."""
    best = _violation(H, x[None], lam_col[:, None])[0, 0]
    n = len(x)
    for _ in range(400):
        if step < 1e-9:
            break
        moves = np.concatenate([np.eye(n), -np.eye(n)]) * step
        cand = np.clip(x + moves, lo, hi)
        vals = _violation(H, cand, lam_col[:, None])[:, 0]
        k = int(np.argmax(vals))
        if vals[k] > best + 1e-12:
            x, best = cand[k], vals[k]
        else:
            step /= 2
    return x, best


def solve(H, n_angles, targets, start=None, scan_deg=15.0, tol=1e-6, max_iter=60, top=12):
    """Exchange method on [0, 2 pi)^n_angles for the targets (columns of `targets`, m x T)."""
    lo, hi = np.zeros(n_angles), np.full(n_angles, 2 * np.pi)
    g = np.deg2rad(np.arange(0, 360, scan_deg))
    scan = np.array(np.meshgrid(*[g] * n_angles, indexing="ij")).reshape(n_angles, -1).T
    if start is None:                                   # quarter turns: identify every q of the stands here
        q = np.deg2rad([0, 90, 180, 270])
        start = np.array(np.meshgrid(*[q] * n_angles, indexing="ij")).reshape(n_angles, -1).T
    X = np.asarray(start, float)
    for it in range(1, max_iter + 1):
        A = lp.measurement_matrix(H, X)
        lam, _ = lp.sparse_dual(A, targets)
        viol = _violation(H, scan, lam)                                  # (K, T)
        new = []
        for t in range(lam.shape[1]):
            # refine from every scan point that is nearly active (up to `top` of them): a peak
            # between scan points can exceed 1 even where the scan shows less
            near = [k for k in np.argsort(viol[:, t])[::-1][:top] if viol[k, t] > 0.9]
            for k in near:
                x, v = _refine(H, scan[k], lam[:, t], np.deg2rad(scan_deg) / 2, lo, hi)
                if v > 1 + tol and not any(np.allclose(x, y, atol=1e-6) for y in [*new, *X]):
                    new.append(x)
        if not new:
            break
        X = np.vstack([X, np.array(new)])
    Phi, values = lp.primal(lp.measurement_matrix(H, X), targets)
    return Solution(values, lam, X, Phi, it)
