"""Optimal plans on a finite grid of positions, found exactly (section 4 of 000), for any stand.

The dual lambda = e_nu / L is optimal on the continuum whenever L = max |H_nu| equals the proven
bound H_SUP of the entry (checked here). By complementary slackness every optimal estimator of q_nu
then uses only measurements where |H^(p)_nu| = L, with the sign of H^(p)_nu; any nonnegative
solution of (8) among them is optimal. So a plan P is optimal for q_nu iff e_nu lies in the cone of
those signed measurement vectors on P, and the minimal such P (the "necessary sets" of Table 1) are
exactly the linearly independent candidate sets that represent e_nu with positive weights
(Caratheodory). On grids where H is integer each minimal set is confirmed in rational arithmetic.
A plan is optimal for all parameters iff it contains a minimal set of each: evaluated for every
subset of a small grid with bit masks (exact count), or on a larger one by a mixed-integer program
(HiGHS) re-solved with each plan cut off (every plan of the minimal size, each confirmed exactly).
Grids where H is not integer (15-, 30-, 45-degree steps, wedges) are exact in Q(sqrt2, sqrt3)
(field.py).
"""
from dataclasses import dataclass
from typing import NamedTuple
from fractions import Fraction
from itertools import combinations, product
from math import comb

import numpy as np


from ..errors import NotExact
from ..models import H_at, layout
from . import field
from .exact import dual_lower_bound, exact_columns

QUARTER_DEG = tuple((a, b) for a in (0, 90, 180, 270) for b in (0, 90, 180, 270))
BITMASK_LIMIT = 20


def grid(mod):
    """Positions to search: detents, or quarter turns inside each angle's range; every mounting.

    Returns (angles in degrees, shape (S, n_angles); mounting index, shape (S,))."""
    names, mounts = layout(mod)
    ranges = mod.ANGLE_RANGES_DEG
    detents = mod.ANGLE_DETENTS_DEG
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


def dual_on_grid(cols, nu, enumerate_sets=True):
    """An optimal dual vector of (9)-(10) for q_nu on the grid (rational when it can be made so),
    and the minimal optimal sets it gives (None when too many to enumerate).

    First lambda = e_nu / max|H_nu| (the Chebyshev polynomial with y = 0); if the grid has no
    estimator reaching its value, the LP's own dual, rationalised and checked exactly on the grid."""
    S, _, m = cols.shape
    if _algebraic(cols):
        entries = [abs(field.QF.of(v)) for v in cols[:, :, nu].ravel()]
        fmax = max(float(v) for v in entries)
        top = max(v for v in entries if float(v) > fmax - 1e-9)              # exact comparisons decide
        lam = [top.inverse() if i == nu else field.QF() for i in range(m)]
    elif cols.dtype.kind == "f":                       # positions off every exact grid: floating point
        top = float(np.abs(cols[:, :, nu]).max())
        lam = [1 / top if i == nu else 0.0 for i in range(m)]
    else:
        top = int(np.abs(cols[:, :, nu]).max())
        lam = [Fraction(int(i == nu), top) for i in range(m)]
    from . import lp
    A = _float(cols).reshape(S * 3, m).T
    sets = _minimal(cols, nu, lam) if enumerate_sets else None
    if sets:
        return lam, sets
    if sets is None:                       # not enumerated: lambda = e_nu / L if the LP reaches 1 / L there
        _, value = lp.primal(A, np.eye(m)[nu])
        if abs(value[0] - 1 / float(top)) <= 1e-9 * value[0]:
            return lam, None
    L, _ = lp.dual(A, np.eye(m)[nu])
    if _algebraic(cols):
        lam = _exact_dual(cols, L[:, 0]) or _slackness_dual(cols, nu, A, L[:, 0])
        if lam is not None:
            return lam, _minimal(cols, nu, lam) if enumerate_sets else None
    if cols.dtype.kind == "i":
        lam = [Fraction(v).limit_denominator(1000) for v in L[:, 0]]
        ok = all(abs(sum(y * int(h) for y, h in zip(lam, col))) <= 1 for col in A.T.astype(int))
        lam = lam if ok else _slackness_dual(cols, nu, A, L[:, 0])
        if lam is not None:
            lam = [Fraction(v.c[0]) if isinstance(v, field.QF) else v for v in lam]
            return lam, _minimal(cols, nu, lam) if enumerate_sets else None
    lam = [float(v) for v in L[:, 0]]                  # the LP's own dual, not made exact: flagged inexact
    return lam, _minimal(cols, nu, lam) if enumerate_sets else None


def _slackness_dual(cols, nu, A, lam_float):
    """An exact dual by complementary slackness: the measurements the float dual touches
    (|h^T lambda| = 1) are active, so h_k^T lambda = sign_k there; m independent ones among them give
    lambda exactly (rationals or Q(sqrt2, sqrt3)), then checked feasible exactly. None if they do not
    determine it."""
    S, _, m = cols.shape
    colsf = _float(cols)
    v = colsf @ lam_float                                           # (S, 3)
    active = sorted(zip(*np.nonzero(np.abs(np.abs(v) - 1) < 1e-7)), key=lambda sp_: -abs(v[sp_]))
    chosen, rows = [], []
    for s_, p in active:
        trial = rows + [colsf[s_, p]]
        if np.linalg.matrix_rank(np.array(trial)) == len(trial):
            chosen.append((s_, p))
            rows = trial
        if len(rows) == m:
            break
    zeros = []                         # a basic solution may hold components at zero: those are active too
    for i in np.argsort(np.abs(lam_float)):
        if len(rows) == m or abs(lam_float[i]) > 1e-12:
            break
        trial = rows + [np.eye(m)[i]]
        if np.linalg.matrix_rank(np.array(trial)) == len(trial):
            zeros.append(int(i))
            rows = trial
    if len(rows) < m:
        return None
    # solve sum_i lambda_i (column i of the active rows) = signs (0 for the components held at zero)
    columns = [[field.QF.of(cols[s_, p][i] if _algebraic(cols) else int(cols[s_, p][i])) for s_, p in chosen]
               + [field.QF(int(i == z)) for z in zeros] for i in range(m)]
    signs = [1 if v[s_, p] > 0 else -1 for s_, p in chosen] + [0] * len(zeros)
    lam = field.combination(columns, signs)
    if lam is None or abs(float(lam[nu]) - lam_float[nu]) > 1e-6:
        return None
    return _exact_dual(cols, lam, exact=lam)


def _exact_dual(cols, lam, exact=None):
    """The LP's float dual made exact in Q(sqrt2, sqrt3) and checked feasible exactly (|H^T lambda| <= 1
    at every measurement of the grid), or None."""
    import sympy as sp
    if exact is None:
        try:
            exact = [field.from_sympy(sp.nsimplify(float(v), [sp.sqrt(2), sp.sqrt(3)], tolerance=1e-10))
                     if abs(v) > 1e-12 else field.QF() for v in lam]
        except ValueError:
            return None
    nz = [i for i, v in enumerate(exact) if not v.is_zero()]
    colsf, lamf = _float(cols), np.array([float(v) for v in exact])
    near = np.abs(colsf @ lamf) > 1 - 1e-6                  # only these can reach 1: decided exactly
    if np.any(np.abs(colsf @ lamf) > 1 + 1e-6):
        return None
    for s, p in zip(*np.nonzero(near)):
        h = cols[s, p] if _algebraic(cols) else [int(x) for x in cols[s, p]]
        if abs(sum((exact[i] * h[i] for i in nz), field.QF())) > 1:
            return None
    return exact


ENUMERATION_LIMIT = 200_000


def _algebraic(cols):
    return cols.dtype == object


_FLOATS = {}


def _float(cols):
    """cols as floats (the screen before exact checks); the last few conversions of exact arrays kept."""
    if not _algebraic(cols):
        return cols.astype(float)
    hit = _FLOATS.get(id(cols))
    if hit is not None and hit[0] is cols:
        return hit[1]
    if len(_FLOATS) > 8:
        _FLOATS.clear()
    out = np.vectorize(float, otypes=[float])(cols)
    _FLOATS[id(cols)] = (cols, out)
    return out


def is_exact(lam):
    """Whether every entry is exact (a Fraction or a QF), not a float."""
    return all(isinstance(v, (Fraction, field.QF)) for v in lam)


def touching(cols, lam):
    """Measurements (s, p) where |H^T lambda| = 1, and the sign there (exactly when lambda is exact)."""
    exact = is_exact(lam)
    colsf, lamf = _float(cols), np.array([float(v) for v in lam])
    near = np.abs(np.abs(colsf @ lamf) - 1) < 1e-7                       # (S, 3): the float screen
    cand, signs = [], []
    for s, p in zip(*np.nonzero(near)):
        if exact:
            h = cols[s, p]
            v = sum((y * (h_ if isinstance(h_, field.QF) else int(h_)) for y, h_ in zip(lam, h) if y != 0),
                    Fraction(0))
            if abs(v) != 1:
                continue
            sign = 1 if v > 0 else -1
        else:
            sign = 1 if colsf[s, p] @ lamf > 0 else -1
        cand.append((int(s), int(p)))
        signs.append(sign)
    return cand, signs


def _minimal(cols, nu, lam, first=False):
    """Minimal position sets of q_nu among the measurements where |H^T lambda| = 1 (with its sign);
    None if there are too many candidate subsets to enumerate."""
    S, _, m = cols.shape
    exact = is_exact(lam)
    algebraic = _algebraic(cols)
    cand, signs = touching(cols, lam)
    if not cand:
        return []
    colsf = _float(cols)
    vec = np.array([colsf[s, p] * g for (s, p), g in zip(cand, signs)], float)      # (C, m)
    den = int(np.lcm.reduce([v.denominator for v in lam])) if exact and not algebraic else 1
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
        ok = (np.abs(np.linalg.det(G)) > 0.5 if not algebraic     # integer Gram: det >= 1 if independent
              else np.linalg.matrix_rank(B) == k)
        if not ok.any():
            continue
        x = np.linalg.solve(G[ok], (B[ok] @ e)[..., None])[..., 0]
        resid = np.abs(np.einsum("nk,nkm->nm", x, B[ok]) - e).max(axis=1)
        for row in idx[ok][(resid < 1e-9) & (x.min(axis=1) > 1e-9)]:
            if exact and algebraic:                            # confirmed in Q(sqrt2, sqrt3)
                w = field.combination([[h * signs[i] for h in cols[cand[i]]] for i in row],
                                [int(j == nu) for j in range(m)])
                if w is None or min(x.sign() for x in w) <= 0:
                    raise AssertionError("float and exact arithmetic disagree on a minimal set")
            elif exact:
                from garant.derive.linear import solve_exact
                w = solve_exact([vec[i] for i in row], e.astype(int))
                if w is None or min(w) <= 0:
                    raise AssertionError("float and rational arithmetic disagree on a minimal set")
                w = [v / den for v in w]
            else:
                w = list(np.linalg.lstsq(vec[list(row)].T, np.eye(m)[nu], rcond=None)[0])
            weights = tuple((cand[i][0], cand[i][1], wi * signs[i]) for i, wi in zip(row, w))
            found.append(MinimalSet(tuple(sorted({cand[i][0] for i in row})), weights))
            if first:
                return found
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
    """The number of set bits of each integer (positions in a plan bitmask)."""
    return np.array([bin(int(v)).count("1") for v in x]) if len(x) else np.array([], int)


@dataclass(frozen=True)
class PlanSearch:
    """The result of a plan search: the grid, each q's optimal error and the minimal optimal plans."""

    angles_deg: np.ndarray                      # (S, n_angles) grid
    mounts: np.ndarray                          # (S,) mounting index
    min_positions: int
    optimal_plans: tuple[tuple[int, ...], ...]   # optimal plans of min_positions (grid indices)
    exhaustive: bool                            # all such plans (bit masks), or one (MILP)
    minimal: tuple                              # per nu: list of MinimalSet
    errors: tuple                               # per nu: optimal guaranteed error (units of sigma)
    proven: tuple                               # per nu: the error holds on the whole continuum
    duals: tuple = ()                           # per nu: the dual vector lambda (exact when it could be)
    method: str = ""                            # how the plans were counted
    floor: int | None = None                    # None: min_positions proven; else a proven lower bound
    clock: bool = False                         # a safety time limit, not the work budget, stopped the search

    def plan_deg(self, plan):
        """The angles in degrees of the positions of a plan (indices into the grid)."""
        return [tuple(float(v) for v in self.angles_deg[s]) for s in plan]

    def is_optimal_for(self, nu, positions):
        """Whether a plan (grid indices) contains a minimal optimal set of q_nu."""
        return any(set(ms.positions) <= set(positions) for ms in self.minimal[nu] or ())

    def exact_errors(self):
        """The optimal errors as exact numbers (text), where the duals are exact."""
        return [str(lam[nu].sympy() if isinstance(lam[nu], field.QF) else lam[nu]) if is_exact(lam) else None
                for nu, lam in enumerate(self.duals)]

    @property
    def grid_deg(self):
        """Every grid position's angles, degrees."""
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


PLAN_COUNT_LIMIT = 200


def covering_plans(cols, lams, limit=PLAN_COUNT_LIMIT, seconds=10.0, search_seconds=None, fixed=(), nodes=None,
                   count_nodes=None):
    """The fewest positions carrying an optimal estimator of every q, and every plan of that size: a
    mixed-integer program (HiGHS), re-solved with each plan found cut off until the size grows (or
    `limit` plans), within `nodes` and `count_nodes` (None: highs.SEARCH_NODES, COUNT_NODES). Returns
    (size, plans, complete, floor, clock) as highs.covering_plans.

    For each q_nu, weights w >= 0 on the measurements where its dual certificate touches, with
    sum_k w_k sign_k H_k = e_nu (then sum w = lambda_nu, the optimum), and w_k <= lambda_nu x_s.
    Positions `fixed` are in every plan."""
    from . import highs
    S, _, m = cols.shape
    colsf = _float(cols)
    blocks = []
    for nu, lam in enumerate(lams):
        cand, signs = touching(cols, lam)
        V = np.array([colsf[s, p] * g for (s, p), g in zip(cand, signs)], float).T        # (m, C)
        blocks.append((V, np.array([s for s, _ in cand]), float(lam[nu]), np.eye(m)[nu]))
    return highs.covering_plans(S, blocks, limit, seconds, search_seconds, fixed, nodes or highs.SEARCH_NODES,
                                highs.COUNT_NODES if count_nodes is None else count_nodes)


def estimator_in(cols, nu, lam, touched=None, memo=None):
    """An optimal estimator of q_nu on the positions of cols: a vertex of {w >= 0 : sum_k w_k sign_k
    H_k = e_nu} over the measurements the dual touches (HiGHS), its support solved again exactly
    (rationals or Q(sqrt2, sqrt3)) and found positive when lambda is exact. [(position, component,
    weight)], or None when there is none. `touched`: the (measurements, signs) to use, when already known
    (`touching`); `memo`: a dict keeping each exact solve by its support, for the many plans of one grid."""
    from . import highs
    colsf = _float(cols)
    cand, signs = touching(cols, lam) if touched is None else touched
    if not cand:
        return None
    V = np.array([colsf[s, p] * g for (s, p), g in zip(cand, signs)], float)          # (C, m)
    m = V.shape[1]
    try:
        w, _, _ = highs.minimize(np.zeros(len(cand)), V.T, np.eye(m)[nu], np.eye(m)[nu], 0.0, highs.INF,
                              "an estimator on the plan")
    except Exception:
        return None
    chosen = []
    for k in np.argsort(-w):
        if w[k] > 1e-12 and np.linalg.matrix_rank(V[chosen + [k]]) == len(chosen) + 1:
            chosen.append(int(k))
    if not is_exact(lam):
        return [(cand[k][0], cand[k][1], float(w[k]) * signs[k]) for k in chosen]
    key = (nu, tuple((cand[k], signs[k]) for k in chosen))
    if memo is not None and key in memo:
        x = memo[key]
    else:
        vecs = [[field.QF.of(h if _algebraic(cols) else int(h)) * signs[k] for h in cols[cand[k]]] for k in chosen]
        x = field.combination(vecs, [int(j == nu) for j in range(m)])
        if memo is not None:
            memo[key] = x
    if x is None or any(v.sign() <= 0 for v in x):
        return None
    return [(cand[k][0], cand[k][1], xi * signs[k]) for k, xi in zip(chosen, x)]


def _confirm(cols, lams, plan, touched, memo):
    """Every q_nu has an optimal estimator inside the plan (a plan the solver found), exactly where
    the dual is exact. `touched`: `touching` of each lambda on all of cols; `memo`: the exact solves of the
    plans before. Returns whether every check was exact."""
    inside = set(int(s) for s in plan)
    for nu, lam in enumerate(lams):
        cand, signs = touched[nu]
        keep = [k for k, (s, _) in enumerate(cand) if s in inside]
        if estimator_in(cols, nu, lam, ([cand[k] for k in keep], [signs[k] for k in keep]), memo) is None:
            raise AssertionError(f"a plan found by the solver is not optimal for q{nu + 1}")
    return all(is_exact(lam) for lam in lams)


def columns(mod, angles_deg, mounts):
    """H^(p) at the positions (S, 3, m): exact (solve/exact.py) where the stand allows, else in floating
    point (e.g. exchange positions at 22.5 degrees)."""
    try:
        return exact_columns(mod, angles_deg, mounts)
    except NotExact:
        return np.moveaxis(H_at(mod, np.deg2rad(np.asarray(angles_deg, float)), mounts), -1, 0)


class Optimal(NamedTuple):
    """Each q's optimal guaranteed error on a set of candidates, from its dual there (optimal_errors)."""

    cols: np.ndarray          # H^(p) at the candidates (S, 3, m), exact where the stand allows
    duals: tuple              # per q: the dual vector lambda
    minimal: tuple            # per q: the minimal supports of its optimal estimators (None beyond bit masks)
    errors: tuple             # per q: optimal guaranteed error (units of sigma)
    proven: tuple             # per q: that error holds on the whole continuum


def optimal_errors(mod, angles_deg, mounts):
    """Each q's optimal guaranteed error on the candidates (units of sigma), from its dual on them (Optimal)."""
    cols = columns(mod, angles_deg, mounts)
    m = cols.shape[2]
    small = len(angles_deg) <= BITMASK_LIMIT
    lams, per_nu = zip(*[dual_on_grid(cols, nu, small) for nu in range(m)])
    if any(sets == [] for sets in per_nu):
        bad = ", ".join(f"q{nu + 1}" for nu, sets in enumerate(per_nu) if sets == [])
        raise ValueError(f"the grid has no optimal estimator of {bad} (not identifiable there?)")
    errors = tuple(float(lam[nu]) for nu, lam in enumerate(lams))          # a^T lambda with a = e_nu
    sup = mod.H_SUP
    proven = tuple(bool(sup is not None and all(isinstance(v, Fraction) for v in lam)
                        and dual_lower_bound(sup, np.eye(m, dtype=int)[nu], lam) == lam[nu])
                   for nu, lam in enumerate(lams))
    return Optimal(cols, lams, per_nu, errors, proven)


def search(mod, angles_deg=None, mounts=None, count_limit=PLAN_COUNT_LIMIT, count_seconds=10.0,
           search_seconds=None, search_nodes=None, count_nodes=None, optimal=None):
    """Optimal guaranteed errors, the minimal number of positions optimal for all q, and the plans.

    A mixed-integer search (grids beyond the bit masks) is budgeted by work: `search_nodes` nodes to prove
    the fewest positions (beyond, it keeps the plan it found, with the solver's proven lower bound as
    `floor`) and `count_nodes` to count the plans of that size; `search_seconds` and `count_seconds` are a
    safety stop (`clock` says when one fired). `optimal`: what optimal_errors gave on these candidates."""
    import time
    deadline = None if search_seconds is None else time.perf_counter() + search_seconds
    if angles_deg is None:
        angles_deg, mounts = grid(mod)
    mounts = np.zeros(len(angles_deg), int) if mounts is None else np.asarray(mounts)
    cols, lams, per_nu, errors, proven = optimal or optimal_errors(mod, angles_deg, mounts)
    S = len(angles_deg)
    floor, clock = None, False
    if S <= BITMASK_LIMIT and all(sets is not None for sets in per_nu):
        n, plans = _bitmask_plans(S, per_nu)
        exhaustive, method = True, "every subset of the grid (bit masks)" + (
            ", in floating point (positions off the 15-degree grid)" if cols.dtype.kind == "f" else "")
    else:
        left = None if deadline is None else max(deadline - time.perf_counter(), 0.5)
        n, plans, exhaustive, floor, clock = covering_plans(cols, lams, count_limit, count_seconds, left,
                                                            nodes=search_nodes, count_nodes=count_nodes)
        touched, memo = [touching(cols, lam) for lam in lams], {}
        exact = all([_confirm(cols, lams, plan, touched, memo) for plan in plans])
        method = ("a mixed-integer program, the plan then confirmed " if count_nodes == 0 else
                  "a mixed-integer program re-solved with each plan cut off, each plan then confirmed ") + (
                  "exactly" if exact else "(in floating point where the dual is not exact)")
    if not plans:
        raise ValueError("no plan on this grid is optimal for every parameter")
    return PlanSearch(np.asarray(angles_deg, float), mounts, n, plans, exhaustive, tuple(per_nu), errors, proven,
                      tuple(lams), method, floor, clock)
