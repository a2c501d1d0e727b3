"""Optimal plans on a finite grid of positions, found exactly (section 4 of 000), for any stand.

The dual lambda = e_nu / L is optimal on the continuum whenever L = max |H_nu| equals the proven
bound H_SUP of the entry (checked here). By complementary slackness every optimal estimator of q_nu
then uses only measurements where |H^(p)_nu| = L, with the sign of H^(p)_nu; any nonnegative
solution of (8) among them is optimal. So a plan P is optimal for q_nu iff e_nu lies in the cone of
those signed measurement vectors on P, and the minimal such P (the "necessary sets" of Table 1) are
exactly the linearly independent candidate sets that represent e_nu with positive weights
(Caratheodory). On grids where H is integer each minimal set is confirmed in rational arithmetic.
A plan is optimal for all parameters iff it contains a minimal set of each: evaluated for every
subset of a small grid with bit masks (exact count), or as a mixed-integer program (HiGHS) on a
larger one (the minimal size and one plan).
"""
from dataclasses import dataclass
from fractions import Fraction
from itertools import combinations, product
from math import comb

import numpy as np

from garant.derive.estimators import solve_exact

from ..models import layout
from .exact import dual_lower_bound, integer_columns

QUARTER_DEG = tuple((a, b) for a in (0, 90, 180, 270) for b in (0, 90, 180, 270))
BITMASK_LIMIT = 20


def grid(mod):
    """Positions to search: detents, or quarter turns inside each angle's range; every mounting.

    Returns (angles in degrees, shape (S, n_angles); mounting index, shape (S,))."""
    names, mounts = layout(mod)
    ranges = getattr(mod, "ANGLE_RANGES_DEG", ((0, 360),) * len(names))
    detents = getattr(mod, "ANGLE_DETENTS_DEG", ((),) * len(names))
    values = []
    for (lo, hi), det in zip(ranges, detents):
        vals = det or tuple(v for v in (0, 90, 180, 270) if lo <= v <= hi or lo <= v + 360 <= hi)
        values.append(vals)
    pts = [(a, k) for k in range(len(mounts)) for a in product(*values)]
    return np.array([a for a, _ in pts], float), np.array([k for _, k in pts], int)


@dataclass(frozen=True)
class MinimalSet:
    """A minimal optimal set of positions for one q_nu, with its exact estimator."""

    positions: tuple[int, ...]          # indices into the grid
    weights: tuple[tuple[int, int, Fraction], ...]   # (position index, component 0-2, weight)


def dual_on_grid(cols, nu):
    """An optimal dual vector of (9)-(10) for q_nu on the grid (rational when it can be made so),
    and the minimal optimal sets it gives (None when too many to enumerate).

    First lambda = e_nu / max|H_nu| (the Chebyshev polynomial with y = 0); if the grid has no
    estimator reaching its value, the LP's own dual, rationalised and checked exactly on the grid."""
    S, _, m = cols.shape
    top = int(np.abs(cols[:, :, nu]).max())
    lam = [Fraction(int(i == nu), top) for i in range(m)]
    sets = _minimal(cols, nu, lam)
    if sets:
        return lam, sets
    from . import lp
    A = cols.reshape(S * 3, m).T.astype(float)
    L, _ = lp.dual(A, np.eye(m)[nu])
    lam = [Fraction(v).limit_denominator(1000) for v in L[:, 0]]
    ok = all(abs(sum(l * int(h) for l, h in zip(lam, col))) <= 1 for col in A.T.astype(int))
    lam = lam if ok else [float(v) for v in L[:, 0]]
    return lam, _minimal(cols, nu, lam)


ENUMERATION_LIMIT = 200_000


def touching(cols, lam):
    """Measurements (s, p) where |H^T lambda| = 1, and the sign there."""
    S = cols.shape[0]
    exact = all(isinstance(v, Fraction) for v in lam)
    cand, signs = [], []
    for s in range(S):
        for p in range(3):
            v = sum(l * int(h) for l, h in zip(lam, cols[s, p])) if exact else float(np.dot(lam, cols[s, p]))
            if (abs(v) == 1) if exact else abs(abs(v) - 1) < 1e-9:
                cand.append((s, p))
                signs.append(1 if v > 0 else -1)
    return cand, signs


def _minimal(cols, nu, lam):
    """Minimal position sets of q_nu among the measurements where |H^T lambda| = 1 (with its sign);
    None if there are too many candidate subsets to enumerate."""
    S, _, m = cols.shape
    exact = all(isinstance(v, Fraction) for v in lam)
    cand, signs = touching(cols, lam)
    if not cand:
        return []
    vec = np.array([cols[s, p] * g for (s, p), g in zip(cand, signs)], float)      # (C, m)
    den = int(np.lcm.reduce([v.denominator for v in lam])) if exact else 1
    e = np.eye(m)[nu] * den
    rank = np.linalg.matrix_rank(vec)
    if sum(comb(len(cand), k) for k in range(1, rank + 1)) > ENUMERATION_LIMIT:
        return None
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
            if exact:
                w = solve_exact([vec[i] for i in row], e.astype(int))
                if w is None or min(w) <= 0:
                    raise AssertionError("float and rational arithmetic disagree on a minimal set")
                w = [v / den for v in w]
            else:
                w = list(np.linalg.lstsq(vec[list(row)].T, np.eye(m)[nu], rcond=None)[0])
            weights = tuple((cand[i][0], cand[i][1], wi * signs[i]) for i, wi in zip(row, w))
            found.append(MinimalSet(tuple(sorted({cand[i][0] for i in row})), weights))
    # Two measurements can share a position: keep the minimal position sets only.
    sets = {ms.positions for ms in found}
    keep = {p for p in sets if not any(set(o) < set(p) for o in sets)}
    out, seen = [], set()
    for ms in found:
        if ms.positions in keep and ms.positions not in seen:
            seen.add(ms.positions)
            out.append(ms)
    return out


def minimal_sets(cols, nu, lam=None):
    """All minimal optimal position sets of q_nu on the grid (cols: integer (S, 3, m))."""
    return dual_on_grid(cols, nu)[1] if lam is None else _minimal(cols, nu, lam)


def popcount(x):
    return np.array([bin(int(v)).count("1") for v in x]) if len(x) else np.array([], int)


@dataclass(frozen=True)
class PlanSearch:
    angles_deg: np.ndarray                      # (S, n_angles) grid
    mounts: np.ndarray                          # (S,) mounting index
    min_positions: int
    optimal_plans: tuple[tuple[int, ...], ...]   # optimal plans of min_positions (grid indices)
    exhaustive: bool                            # all such plans (bit masks), or one (MILP)
    minimal: tuple                              # per nu: list of MinimalSet
    errors: tuple                               # per nu: optimal guaranteed error (units of sigma)
    proven: tuple                               # per nu: the error holds on the whole continuum

    def plan_deg(self, plan):
        return [tuple(float(v) for v in self.angles_deg[s]) for s in plan]

    def is_optimal_for(self, nu, positions):
        """Whether a plan (grid indices) contains a minimal optimal set of q_nu."""
        return any(set(ms.positions) <= set(positions) for ms in self.minimal[nu] or ())

    @property
    def grid_deg(self):
        return [tuple(a) for a in self.angles_deg]


def _bitmask_plans(S, per_nu):
    subsets = np.arange(1 << S, dtype=np.int64)
    ok = np.ones(1 << S, bool)
    for sets in per_nu:
        has = np.zeros(1 << S, bool)
        for ms in sets:
            mk = sum(1 << s for s in ms.positions)
            has |= (subsets & mk) == mk
        ok &= has
    good = np.flatnonzero(ok)
    if not len(good):
        return 0, ()
    sizes = popcount(good)
    n = int(sizes.min())
    return n, tuple(tuple(s for s in range(S) if (int(v) >> s) & 1) for v in good[sizes == n])


def _milp_plan(cols, lams):
    """Fewest positions carrying an optimal estimator of every q: a mixed-integer program (HiGHS).

    For each q_nu, weights w >= 0 on the measurements where its dual certificate touches, with
    sum_k w_k sign_k H_k = e_nu (then sum w = lambda_nu, the optimum), and w_k <= lambda_nu x_s."""
    import cvxpy as cp

    from . import lp
    S, _, m = cols.shape
    x = cp.Variable(S, boolean=True)
    cons = []
    for nu, lam in enumerate(lams):
        cand, signs = touching(cols, lam)
        V = np.array([cols[s, p] * g for (s, p), g in zip(cand, signs)], float).T        # (m, C)
        w = cp.Variable(len(cand), nonneg=True)
        sel = np.zeros((len(cand), S))
        sel[range(len(cand)), [s for s, _ in cand]] = 1
        cons += [V @ w == np.eye(m)[nu], w <= float(lam[nu]) * (sel @ x)]
    prob = cp.Problem(cp.Minimize(cp.sum(x)), cons)
    lp.solve(prob, "the plan search (mixed-integer program)")
    plan = tuple(int(s) for s in np.flatnonzero(np.round(x.value) > 0.5))
    return len(plan), (plan,)


def search(mod, angles_deg=None, mounts=None):
    """Optimal guaranteed errors, the minimal number of positions optimal for all q, and the plans."""
    if angles_deg is None:
        angles_deg, mounts = grid(mod)
    mounts = np.zeros(len(angles_deg), int) if mounts is None else np.asarray(mounts)
    cols = integer_columns(mod, angles_deg, mounts)
    m = cols.shape[2]
    lams, per_nu = zip(*[dual_on_grid(cols, nu) for nu in range(m)])
    if any(sets == [] for sets in per_nu):
        bad = ", ".join(f"q{nu + 1}" for nu, sets in enumerate(per_nu) if sets == [])
        raise ValueError(f"the grid has no optimal estimator of {bad} (not identifiable there?)")
    errors = tuple(float(lam[nu]) for nu, lam in enumerate(lams))
    sup = getattr(mod, "H_SUP", None)
    proven = tuple(bool(sup is not None and all(isinstance(v, Fraction) for v in lam)
                        and dual_lower_bound(sup, np.eye(m, dtype=int)[nu], lam) == lam[nu])
                   for nu, lam in enumerate(lams))
    S = len(angles_deg)
    if S <= BITMASK_LIMIT and all(sets is not None for sets in per_nu):
        n, plans = _bitmask_plans(S, per_nu)
        exhaustive = True
    else:
        n, plans = _milp_plan(cols, lams)
        exhaustive = False
    if not plans:
        raise ValueError("no plan on this grid is optimal for every parameter")
    return PlanSearch(np.asarray(angles_deg, float), mounts, n, plans, exhaustive, tuple(per_nu), errors, proven)
