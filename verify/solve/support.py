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
    """The LPs solved for one set, by cell: each round's cell (its rounded direction) -> (the proofs of its least
    and largest end (`_basis`), the LP's points), and the LPs spent against the budget. One
    for the pieces of a log (`ranges(..., solved=...)`): a cell solved for one piece proves the next's samples."""

    def __init__(self, budget=BUDGET):
        self.cells, self.budget, self.spent = {}, budget, 0
        self.units, self.proofs = [], []        # every cell's unit c and proofs, for the cells past the budget


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
        keys, first, cell = np.unique(rounded @ _HASH[:C.shape[1]], return_index=True, return_inverse=True)
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
            for j, p_, lam in zip(new, pts, lams):
                c = C[todo[first[j]]]
                solved.cells[names[j]] = (_basis(B, -c, lam[0]), _basis(B, c, lam[1])), p_
                solved.units.append(c / np.linalg.norm(c))
                solved.proofs.append(solved.cells[names[j]][0])
        X = []
        unsolved = [j for j, name in enumerate(names) if name not in solved.cells]
        if unsolved and solved.units:        # past the budget: the proofs of the nearest cell solved (any round)
            _nearest(C, B, row_lo, row_hi, col_lo, col_hi, best, solved, todo, first, cell, unsolved)
        for j, name in enumerate(names):
            got = solved.cells.get(name)
            if got is None:
                continue
            members = todo[cell == j]
            proofs, p_ = got
            for end, sign in ((0, -1.0), (1, 1.0)):
                proven = _proven(sign * C[members], B, row_lo, row_hi, col_lo, col_hi, proofs[end])
                best[end, members] = np.minimum(best[end, members], proven)
            X += [x for x in p_ if x is not None]
        X = np.array(X).reshape(-1, C.shape[1])
        for k in range(0, len(X), POINTS_AT_ONCE):    # every sample left at every point of the cells used
            V = C[todo] @ X[k:k + POINTS_AT_ONCE].T
            seen[0, todo] = np.maximum(seen[0, todo], (-V).max(axis=1))
            seen[1, todo] = np.maximum(seen[1, todo], V.max(axis=1))
        width = np.maximum(best - centre, 0.0)
        todo = todo[(best - np.maximum(seen, centre) > GAP * width)[:, todo].any(axis=0)]
        step /= 2
    return (-best[0], best[1]) + ((-seen[0], seen[1]) if seen_too else ())


def _nearest(C, B, row_lo, row_hi, col_lo, col_hi, best, solved, todo, first, cell, unsolved):
    """The samples of the cells `unsolved` (past the budget) proven by the multipliers of the cell solved whose c
    is nearest in direction (its proofs swapped where the nearest is -c); `best` lowered in place."""
    reps = C[todo[first[unsolved]]]
    near = (reps / np.linalg.norm(reps, axis=1)[:, None]) @ np.asarray(solved.units).T
    pick = np.argmax(np.abs(near), axis=1)
    flip = near[np.arange(len(unsolved)), pick] < 0
    for k, f in set(zip(pick.tolist(), flip.tolist())):
        members = todo[np.isin(cell, np.asarray(unsolved)[(pick == k) & (flip == f)])]
        pair = solved.proofs[k][::-1] if f else solved.proofs[k]
        for end, sign in ((0, -1.0), (1, 1.0)):
            proven = _proven(sign * C[members], B, row_lo, row_hi, col_lo, col_hi, pair[end])
            best[end, members] = np.minimum(best[end, members], proven)


#: LP points whose values at every sample are taken at once (the memory of that step: samples x this).
POINTS_AT_ONCE = 16
#: Odd 64-bit multipliers of a cell's rounded coordinates (wrapping sums): its name.
_HASH = np.random.default_rng(20261129).integers(1, 2 ** 62, 256, dtype=np.int64) * 2 + 1


def _basis(B, c, lam):
    """(lam, K): the multipliers lam of the LP for c and the map K (rows of lam x columns) from any c' to the
    multipliers on the same rows that meet c' with the same columns at a bound (least squares on that basis:
    exact where the basis is square and regular); K None where lam has no rows."""
    if not len(lam.rows):
        return lam, None
    Br = B[lam.rows]
    mu = c - Br.T @ lam.values
    cols = np.flatnonzero(np.abs(mu) > 1e-12 * (np.abs(c) + np.abs(Br.T) @ np.abs(lam.values)))
    basis = np.hstack([Br.T, np.eye(B.shape[1])[:, cols]])
    return lam, np.linalg.pinv(basis)[:len(lam.rows)]


def _proven(C, B, row_lo, row_hi, col_lo, col_hi, proof):
    """The proven ends max c_s^T x of the rows c_s of C from a cell's proof (`_basis`): its multipliers as they
    are, and re-solved for each c_s on its basis; the better of the two (one `hull.upper` for both)."""
    lam, K = proof
    n = len(C)
    if K is None:
        return hull.upper(C, B, row_lo, row_hi, col_lo, col_hi,
                          hull.Multipliers(lam.rows, np.broadcast_to(lam.values, (n, len(lam.rows)))))
    both = hull.upper(np.vstack([C, C]), B, row_lo, row_hi, col_lo, col_hi,
                      hull.Multipliers(lam.rows, np.vstack([np.broadcast_to(lam.values, (n, len(lam.rows))), C @ K.T])))
    return np.minimum(both[:n], both[n:])
