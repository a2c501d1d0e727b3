"""The least and largest value of many linear functions over one polytope: a corrected sample's error over the
information set of its calibration, one function per sample and axis.

    X = {x : row_lo <= B x <= row_hi,  col_lo <= x <= col_hi}.

Each end is proven as hull.py proves one (weak duality, `hull.upper`: any multipliers give a bound, whatever
the solver's accuracy), so no sample needs an LP of its own to be sound. To be sharp without one LP a sample,
the samples' functions are gathered into cells of nearby directions; one LP per cell (its first sample), and
every sample of the cell proven from that LP's multipliers twice: as they are, and re-solved for the sample's
own c on the same active rows and columns (the optimal basis: exact wherever it stays optimal, which it does
for every c of its normal cone). Each sample's LP point gives a value the end cannot be below (to HiGHS's
tolerance); a sample whose proven end is farther than GAP of its width from that value starts a cell of its own
in the next, finer round, within a budget of LPs counted, not timed; past it, a cell is proven by the multipliers
of the nearest cell solved (sound, less sharp).
"""
import functools

import numpy as np

from . import hull

#: The first round's cells: unit directions of c rounded to this step per coordinate; each round halves it.
STEP = 0.5
ROUNDS = 8
#: A sample is settled when its proven end is within GAP of its width (the end less c^T x0) of the LP's value.
GAP = 0.05
#: LPs (cells, each an LP pair) at most for one set (`Solved`): for a whole log, whatever its length.
BUDGET = 4000


class Solved:
    """The LPs solved for one set, by cell: each round's cell (its rounded direction) -> (the indices of the proofs
    of its least and largest end in `proofs` (`_bases`), the LP's points), and the LPs spent against the budget.
    One for the pieces of a log (`ranges(..., solved=...)`): a cell solved for one piece proves the next's
    samples."""

    def __init__(self, budget=BUDGET):
        self.cells, self.budget, self.spent = {}, budget, 0
        self.units, self.pairs = [], []         # every cell's unit c and its pair of proofs, for those past the budget
        self.proofs = []                        # (rows, multipliers, K or None) of each end solved


def ranges(B, row_lo, row_hi, col_lo, col_hi, C, x0, solved=None, seen_too=False):
    """(lo, hi), each (N,): proven ends of c^T x over X for each row c of C (N, P), sharp to about GAP of
    the width about x0 (a point of X, e.g. the estimate) for every sample the budget of LPs reaches, and
    proven for every sample whatever the budget (lambda = 0, the column box, at worst). `solved`: the cells
    solved before on the same set (Solved), used and added to. `seen_too`: also (lo_seen, hi_seen), the values at
    the LP points found (the ends lie beyond them, to HiGHS's tolerance: a guide to what is worth more LPs, no
    proof; -inf and inf where none)."""
    solved = Solved() if solved is None else solved
    C = np.asarray(C, float)
    N = len(C)
    none = hull.Multipliers(hull.NONE.rows, np.zeros((N, 0)))
    best = np.stack([hull.upper(-C, B, row_lo, row_hi, col_lo, col_hi, none),      # max -c^T x, max c^T x
                     hull.upper(C, B, row_lo, row_hi, col_lo, col_hi, none)])
    seen = np.full((2, N), -np.inf)                       # values at LP points: the ends are not below them
    centre = np.asarray(C @ np.asarray(x0, float))
    centre = np.stack([-centre, centre])
    size = np.linalg.norm(C, axis=1)
    todo = np.flatnonzero(size > 0)
    step = STEP
    for r in range(ROUNDS):
        if not len(todo):
            break
        # a cell is its rounded direction, named by a fixed 64-bit hash of it (two cells that share a name are
        # one: a proof holds for any c, so that costs sharpness at most, never soundness)
        rounded = np.round(C[todo] / size[todo, None] / step).astype(np.int64)
        keys, first, cell = np.unique(rounded @ _hash()[:C.shape[1]], return_index=True, return_inverse=True)
        cell = cell.ravel()
        names = [(r, int(k)) for k in keys]
        new = [j for j, name in enumerate(names) if name not in solved.cells]
        room = max(solved.budget - solved.spent, 0)
        if len(new) > room:                  # the new cells of the widest gaps, then the fullest, to the budget
            gap, count = np.zeros(len(keys)), np.bincount(cell, minlength=len(keys))
            np.maximum.at(gap, cell, (best - seen)[:, todo].max(axis=0))
            new = sorted(sorted(new, key=lambda j: (-gap[j], -count[j], j))[:room])
        if new:
            solved.spent += len(new)
            try:
                _, _, pts, lams = hull.ranges(B, row_lo, row_hi, col_lo, col_hi, C[todo[first[new]]], points=True,
                                              multipliers=True, sweep=True)
            except hull.Empty:
                break
            cs = C[todo[first[new]]]
            solved.proofs += _bases(B, [(sign * c, lam[end]) for c, lam in zip(cs, lams)
                                        for end, sign in ((0, -1.0), (1, 1.0))])
            for k, (j, p_, c) in enumerate(zip(new, pts, cs)):
                pair = (len(solved.proofs) - 2 * (len(new) - k), len(solved.proofs) - 2 * (len(new) - k) + 1)
                solved.cells[names[j]] = pair, p_
                solved.units.append(c / np.linalg.norm(c))
                solved.pairs.append(pair)
        X = []
        pair_of = np.full((len(names), 2), -1)               # each cell's proofs: its own, or the nearest's
        for j, name in enumerate(names):
            got = solved.cells.get(name)
            if got is not None:
                pair_of[j] = got[0]
                X += [x for x in got[1] if x is not None]
        unsolved = np.flatnonzero(pair_of[:, 0] < 0)
        if len(unsolved) and solved.units:   # past the budget: the proofs of the nearest cell solved (any round)
            pair_of[unsolved] = _nearest(C[todo[first[unsolved]]], solved)
        members = np.flatnonzero(pair_of[cell, 0] >= 0)
        for end, sign in ((0, -1.0), (1, 1.0)):
            proven = _proven(sign * C[todo[members]], B, row_lo, row_hi, col_lo, col_hi, solved.proofs,
                             pair_of[cell[members], end])
            best[end, todo[members]] = np.minimum(best[end, todo[members]], proven)
        X = np.array(X).reshape(-1, C.shape[1])
        for k in range(0, len(X), POINTS_AT_ONCE):    # every sample left at every point of the cells used
            V = C[todo] @ X[k:k + POINTS_AT_ONCE].T
            seen[0, todo] = np.maximum(seen[0, todo], (-V).max(axis=1))
            seen[1, todo] = np.maximum(seen[1, todo], V.max(axis=1))
        width = np.maximum(best - centre, 0.0)
        todo = todo[(best - np.maximum(seen, centre) > GAP * width)[:, todo].any(axis=0)]
        step /= 2
    return (-best[0], best[1]) + ((-seen[0], seen[1]) if seen_too else ())


def essential(B, row_lo, row_hi, col_lo, col_hi):
    """(rows, lo, hi): the rows of X that can bind, each side that cannot made infinite. A side whose proven end
    over X lies strictly inside it binds nowhere on X, and X without it is X: a point beyond it would join X by a
    segment that crosses it inside X. So LPs over what is kept are smaller and their optima and proofs are those
    of X. An information set's rows are mostly such (on a two-axis file 41 of 96 rows, on a three-axis file 136 of
    192 bind on neither side)."""
    B = np.asarray(B, float)
    row_lo, row_hi = np.asarray(row_lo, float), np.asarray(row_hi, float)
    lo, hi = hull.ranges(B, row_lo, row_hi, col_lo, col_hi, B, sweep=True)
    lo_free, hi_free = lo > row_lo, hi < row_hi
    keep = np.flatnonzero(~(lo_free & hi_free))
    return keep, np.where(lo_free, -np.inf, row_lo)[keep], np.where(hi_free, np.inf, row_hi)[keep]


def _nearest(reps, solved):
    """(n, 2): the proofs (least end, largest end) for cells past the budget, each that of the cell solved whose c
    is nearest in direction to the cell's first c (`reps`), the pair swapped where the nearest is -c."""
    near = (reps / np.linalg.norm(reps, axis=1)[:, None]) @ np.asarray(solved.units).T
    pick = np.argmax(np.abs(near), axis=1)
    pairs = np.asarray(solved.pairs)[pick]
    flip = near[np.arange(len(reps)), pick] < 0
    return np.where(flip[:, None], pairs[:, ::-1], pairs)


#: LP points whose values at every sample are taken at once (the memory of that step: samples x this).
POINTS_AT_ONCE = 16
@functools.cache
def _hash():
    """Odd 64-bit multipliers of a cell's rounded coordinates (wrapping sums): its name. Made at first use: numpy.random
    is 9 ms of a small log's calibrate-norm, which never names a cell."""
    return np.random.default_rng(20261129).integers(1, 2 ** 62, 256, dtype=np.int64) * 2 + 1


def _bases(B, ends):
    """[(lam, K)] of each end (c, lam): the multipliers lam of the LP for c and the map K (rows of lam x columns)
    from any c' to the multipliers on the same rows that meet c' with the same columns at a bound (least squares on
    that basis: exact where the basis is square and regular); K None where lam has no rows. The bases of one shape
    are inverted at once (by QR; the pseudo-inverse where one has a lower rank)."""
    out, groups = [None] * len(ends), {}
    for i, (c, lam) in enumerate(ends):
        if not len(lam.rows):
            out[i] = lam, None
            continue
        Br = B[lam.rows]
        mu = c - Br.T @ lam.values
        cols = np.flatnonzero(np.abs(mu) > 1e-12 * (np.abs(c) + np.abs(Br.T) @ np.abs(lam.values)))
        basis = np.hstack([Br.T, np.eye(B.shape[1])[:, cols]])
        groups.setdefault(basis.shape, []).append((i, basis))
    for (rows, cols), got in groups.items():
        stack = np.stack([b for _, b in got])
        try:                                    # full column rank: A = QR, A^+ = R^-1 Q^T (a square one: A^-1)
            Q, R = np.linalg.qr(stack)
            inverse = np.linalg.solve(R, np.swapaxes(Q, 1, 2))
            if not np.isfinite(inverse).all():
                raise np.linalg.LinAlgError
        except np.linalg.LinAlgError:           # one of lower rank in the stack: the pseudo-inverse for all
            inverse = np.linalg.pinv(stack)
        for (i, _), K in zip(got, inverse):
            lam = ends[i][1]
            out[i] = lam, K[:len(lam.rows)]
    return out


#: Objectives proven at once by `_proven` (its memory: this x the rows read x the columns).
PROVEN_AT_ONCE = 2048


def _proven(C, B, row_lo, row_hi, col_lo, col_hi, proofs, which):
    """The proven ends max c_s^T x of the rows c_s of C, each from its proof proofs[which[s]] (`_bases`): its
    multipliers as they are, and re-solved for c_s on its basis; the better of the two. One `hull.upper` for many
    proofs at once: each objective's multipliers on its proof's rows, padded with zero multipliers (which read
    nothing)."""
    out = np.empty(len(C))
    ids, inverse = np.unique(which, return_inverse=True)
    R = max((len(proofs[i][0].rows) for i in ids), default=0)
    rows, lam, K = np.zeros((len(ids), R), np.intp), np.zeros((len(ids), R)), np.zeros((len(ids), R, B.shape[1]))
    for t, i in enumerate(ids):
        m, k = proofs[i]
        rows[t, :len(m.rows)], lam[t, :len(m.rows)] = m.rows, m.values
        if k is not None:
            K[t, :len(m.rows)] = k
    plain = np.array([proofs[i][1] is None for i in ids], bool)   # no basis: the multipliers as they are, twice
    for a in range(0, len(C), PROVEN_AT_ONCE):
        part = slice(a, a + PROVEN_AT_ONCE)
        c, t = C[part], inverse.ravel()[part]
        resolved = np.where(plain[t][:, None], lam[t], np.einsum("mrp,mp->mr", K[t], c))
        out[part] = np.minimum(*(hull.upper(c, B, row_lo, row_hi, col_lo, col_hi, hull.Multipliers(rows[t], L))
                                 for L in (lam[t], resolved)))
    return out

