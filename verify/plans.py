"""Optimal plans on a finite grid of positions, found exactly (section 4 of 000).

The dual lambda = e_nu / L is optimal on the continuum whenever L = max |H_nu| (checked by
`continuum_dual_bound`). By complementary slackness every optimal estimator of q_nu then uses only
measurements where |H^(p)_nu| = L, with the sign of H^(p)_nu; any nonnegative solution of (8) among
them is optimal. So a plan P is optimal for q_nu iff e_nu lies in the cone of those signed
measurement vectors on P, and the minimal such P (the "necessary sets" of Table 1) are exactly the
linearly independent candidate sets that represent e_nu with positive weights (Caratheodory). On
the quarter-turn grid the vectors are integer, so each minimal set is confirmed in rational
arithmetic. A plan is optimal for all parameters iff it contains a minimal set of each.
"""
from dataclasses import dataclass
from fractions import Fraction
from itertools import combinations

import numpy as np

QUARTER_DEG = tuple((a, b) for a in (0, 90, 180, 270) for b in (0, 90, 180, 270))


def integer_columns(H, positions_deg):
    """H^(p) at grid positions (degrees) as exact integers, shape (S, 3, m); fails if not integer."""
    P = np.deg2rad(np.asarray(positions_deg, float))
    Hs = np.moveaxis(H(P[:, 0], P[:, 1]), -1, 0)       # (S, 3, m)
    rounded = np.rint(Hs)
    if np.abs(Hs - rounded).max() > 1e-12:
        raise ValueError("H is not integer on these positions; exact plan search needs a grid where it is")
    return rounded.astype(np.int64)


def solve_exact(columns, b):
    """Rational x with columns^T x = b for linearly independent integer columns, else None."""
    k = len(columns)
    rows = [[Fraction(int(c[i])) for c in columns] + [Fraction(int(b[i]))] for i in range(len(b))]
    r = 0
    for c in range(k):
        p = next((i for i in range(r, len(rows)) if rows[i][c] != 0), None)
        if p is None:
            return None
        rows[r], rows[p] = rows[p], rows[r]
        rows[r] = [v / rows[r][c] for v in rows[r]]
        for i in range(len(rows)):
            if i != r and rows[i][c] != 0:
                f = rows[i][c]
                rows[i] = [a - f * bb for a, bb in zip(rows[i], rows[r])]
        r += 1
    if any(rows[i][k] != 0 for i in range(r, len(rows))):
        return None
    return [rows[i][k] for i in range(k)]


@dataclass(frozen=True)
class MinimalSet:
    """A minimal optimal set of positions for one q_nu, with its exact estimator."""

    positions: tuple[int, ...]          # indices into the grid
    weights: tuple[tuple[int, int, Fraction], ...]   # (position index, component 0-2, weight)


def minimal_sets(cols, nu):
    """All minimal optimal position sets of q_nu on the grid (cols: integer (S, 3, m))."""
    S, _, m = cols.shape
    top = np.abs(cols[:, :, nu]).max()
    cand = [(s, p) for s in range(S) for p in range(3) if abs(cols[s, p, nu]) == top]
    if len({s for s, _ in cand}) != len(cand):
        raise ValueError("two candidate measurements at one position: use measurement-level search")
    vec = np.array([cols[s, p] * np.sign(cols[s, p, nu]) for s, p in cand], float)   # (C, m)
    e = np.eye(m)[nu] * top
    rank = np.linalg.matrix_rank(vec)
    found = []
    for k in range(1, rank + 1):
        idx = np.array(list(combinations(range(len(cand)), k)))
        if not len(idx):
            break
        B = vec[idx]                                          # (N, k, m)
        G = B @ B.transpose(0, 2, 1)
        ok = np.abs(np.linalg.det(G)) > 0.5                   # integer Gram: det >= 1 if independent
        if not ok.any():
            continue
        x = np.linalg.solve(G[ok], (B[ok] @ e)[..., None])[..., 0]
        resid = np.abs(np.einsum("nk,nkm->nm", x, B[ok]) - e).max(axis=1)
        for row in idx[ok][(resid < 1e-9) & (x.min(axis=1) > 1e-9)]:
            exact = solve_exact([vec[i] for i in row], e)
            if exact is None or min(exact) <= 0:
                raise AssertionError("float and rational arithmetic disagree on a minimal set")
            weights = tuple((cand[i][0], cand[i][1], w * int(np.sign(cols[cand[i]][nu])))
                            for i, w in zip(row, exact))
            found.append(MinimalSet(tuple(sorted(cand[i][0] for i in row)), weights))
    return found


def masks(sets):
    return np.array([sum(1 << s for s in ms.positions) for ms in sets], dtype=np.int64)


def optimal_subsets(cols):
    """Boolean over all 2^S subsets (bit s = grid position s): optimal for every parameter."""
    S, _, m = cols.shape
    subsets = np.arange(1 << S, dtype=np.int64)
    ok = np.ones(1 << S, bool)
    per_nu = [minimal_sets(cols, nu) for nu in range(m)]
    for sets in per_nu:
        has = np.zeros(1 << S, bool)
        for mk in masks(sets):
            has |= (subsets & mk) == mk
        ok &= has
    return ok, per_nu


def popcount(x):
    return np.array([bin(int(v)).count("1") for v in x]) if len(x) else np.array([], int)


@dataclass(frozen=True)
class PlanSearch:
    grid_deg: tuple
    min_positions: int
    optimal_plans: tuple[tuple[int, ...], ...]   # all optimal plans of min_positions (grid indices)
    minimal: tuple                              # per nu: list of MinimalSet

    def plan_deg(self, plan):
        return [self.grid_deg[s] for s in plan]

    def is_optimal_for(self, nu, positions):
        """Whether a plan (grid indices) contains a minimal optimal set of q_nu."""
        return any(set(ms.positions) <= set(positions) for ms in self.minimal[nu])


def search(H, grid_deg=QUARTER_DEG):
    """Minimal number of positions optimal for all q, and every such plan on the grid."""
    cols = integer_columns(H, grid_deg)
    ok, per_nu = optimal_subsets(cols)
    good = np.flatnonzero(ok)
    if not len(good):
        raise ValueError("no plan on this grid is optimal for every parameter")
    sizes = popcount(good)
    n = int(sizes.min())
    plans = tuple(tuple(s for s in range(len(grid_deg)) if (int(v) >> s) & 1) for v in good[sizes == n])
    return PlanSearch(tuple(grid_deg), n, plans, tuple(per_nu))

