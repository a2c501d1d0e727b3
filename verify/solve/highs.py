"""Linear programs passed to HiGHS directly (highspy): the hot paths, where cvxpy's modelling layer
costs more than the solve (python -m verify.bench measures both).

    minimise c^T x  subject to  row_lo <= M x <= row_hi,  col_lo <= x <= col_hi,

with M dense (rows x cols), handed over column-wise. The small LPs (hulls, minimax fits, l1 estimators) share one
quiet solver per thread (`small`), each LP passed into it afresh; the plan search has its own. The banner HiGHS
prints on its first construction is kept off standard output.
"""
import os
import threading

import highspy
import numpy as np

from ..errors import DataError, LPFailed
from ..defaults import COUNT_NODES, SEARCH_NODES

INF = highspy.kHighsInf
_quiet = False


def new(presolve=True):
    """A HiGHS instance that prints nothing, on one thread. The LPs here are small and dense: presolve finds nothing
    to remove and costs more than the solve (python -m verify.bench), so LP callers turn it off."""
    global _quiet
    if not _quiet:
        fd = os.dup(1)
        try:
            with open(os.devnull, "w") as null:
                os.dup2(null.fileno(), 1)
                h = highspy.Highs()
        finally:
            os.dup2(fd, 1)
            os.close(fd)
        _quiet = True
    else:
        h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("threads", 1)          # its thread pool costs 0.25 ms a run on LPs this small (3.5x),
    if not presolve:                        # and one thread gives the same answer on any machine
        h.setOptionValue("presolve", "off")
    return h


_small = threading.local()


def small(cost, col_lo, col_hi, row_lo, row_hi, start, index, value, strategy=1):
    """The thread's HiGHS for small LPs (no presolve, `strategy` its simplex_strategy), holding the LP
    min cost^T x, row_lo <= M x <= row_hi, col_lo <= x <= col_hi, M column-wise (column j's entries are
    value[start[j]:start[j+1]] in the rows index[start[j]:start[j+1]]), and nothing of the last: a HiGHS built
    per LP (`new` and a HighsLp passed) costs about as much as solving one of these LPs, for the same solutions bit
    for bit (tests/solve/test_hull.py; python -m verify.bench.outputs). The instance is shared: done with one LP
    before the next."""
    h = getattr(_small, "h", None)
    if h is None:
        h = _small.h = new(presolve=False)
    else:
        h.clearModel()
    h.setOptionValue("simplex_strategy", strategy)
    cols = len(cost)
    h.passModel(cols, len(row_lo), len(index), 1, 1, 0.0, cost, col_lo, col_hi, row_lo, row_hi, start[:cols], index,
                value, np.zeros(cols, dtype=np.int32))   # 1, 1: column-wise, minimise
    return h


OPTIMAL, INFEASIBLE = highspy.HighsModelStatus.kOptimal, highspy.HighsModelStatus.kInfeasible


def solve(h, settled=None, presolve=False):
    """Run h and return its model status: the one HiGHS call of the package, with both retries it needs.
    Once more after resetting HiGHS's global thread scheduler when another HiGHS of this process (the caller's
    own, cvxpy's) started it with more threads than the one asked for here: HiGHS then refuses to run (an error,
    model status Not Set) rather than change the count. And, given `settled` (the statuses a model warm-started
    from the last LP's basis may end in), any other status is a warm start that stalled: once more from scratch
    (with presolve for that run when `presolve`)."""
    status = h.run()
    if status == highspy.HighsStatus.kError and h.getModelStatus() == highspy.HighsModelStatus.kNotset:
        highspy.Highs.resetGlobalScheduler(True)
        h.run()
    if settled is not None and h.getModelStatus() not in settled:
        h.clearSolver()
        if presolve:
            h.setOptionValue("presolve", "on")
        h.run()
        if presolve:
            h.setOptionValue("presolve", "off")
    return h.getModelStatus()


def failed(h, what):
    """LPFailed for `what`, carrying HiGHS's model status (its text, as cvxpy's statuses are)."""
    text = h.modelStatusToString(h.getModelStatus())
    return LPFailed(f"{what}: {text}", text)


def minimize(c, M, row_lo, row_hi, col_lo, col_hi, what):
    """(x, row duals, objective) of the LP above; LPFailed unless optimal."""
    M = np.asarray(M, float)
    rows, cols = M.shape
    h = small(np.asarray(c, float), np.broadcast_to(col_lo, cols).astype(float),
              np.broadcast_to(col_hi, cols).astype(float), np.asarray(row_lo, float), np.asarray(row_hi, float),
              np.arange(0, rows * cols + 1, rows, dtype=np.int32), np.tile(np.arange(rows, dtype=np.int32), cols),
              np.ascontiguousarray(M.T).ravel())
    if solve(h) != OPTIMAL:
        raise failed(h, what)
    sol = h.getSolution()
    return np.array(sol.col_value), np.array(sol.row_dual), h.getInfo().objective_function_value


GENERATE_ABOVE = 900     # measurements: above this, an LP starts from a spread subset and adds what it violates
TOLERANCE = 1e-9         # relative: a measurement violating by less is within the solver's own tolerance


def spread(K, size):
    """`size` indices spread evenly over range(K), increasing (deduplicated by hand: np.unique loads numpy.ma,
    a tenth of a small estimate's run)."""
    idx = np.linspace(0, K - 1, min(K, size)).round().astype(int)
    return idx[np.r_[True, idx[1:] != idx[:-1]]]


def _generate(K, solve_on, violation, what, start=None):
    """An LP over K measurements solved on a subset S (spread over all, with `start` added), measurements
    that violate its optimum added (the worst first), until none does: then that optimum is the optimum
    over all K (the others' constraints hold at it). A subset too small to be feasible is doubled.
    Returns (S, the optimum)."""
    return _generate_each(K, 1, lambda k, S: solve_on(S), lambda outs: violation(outs[0][1], outs[0][0])[:, None],
                          lambda k: what, start)[0]


def _generate_each(K, n, solve_on, violations, what, start=None):
    """`_generate` for n LPs over the same K measurements at once, each with its own subset: LP k solved on its S
    by solve_on(k, S), then every unfinished LP's violations measured in one pass (`violations` of [(S, optimum)]
    in order: (K, that many)): one read of the measurements per round, not one per LP. Each LP's rounds are those
    it would have alone. Returns [(S, optimum)] per LP."""
    base = spread(K, GENERATE_ABOVE // 3) if start is None else np.union1d(spread(K, GENERATE_ABOVE // 6), start)
    S, out, todo = [base] * n, [None] * n, list(range(n))
    for _ in range(100):
        solved = []
        for k in todo:
            try:
                out[k] = solve_on(k, S[k])
                solved.append(k)
            except LPFailed:
                if len(S[k]) == K:
                    raise
                S[k] = np.union1d(S[k], spread(K, 2 * len(S[k])))
        V = violations([(S[k], out[k]) for k in solved]) if solved else np.zeros((K, 0))
        todo = [k for k in todo if k not in solved]
        for k, v in zip(solved, V.T):
            v[S[k]] = -np.inf
            new = np.flatnonzero(v > 0)
            if not len(new):
                continue
            keep = GENERATE_ABOVE // 9
            if len(new) > keep:
                new = new[np.argpartition(-v[new], keep)[:keep]]
            S[k] = np.union1d(S[k], new)
            todo.append(k)
        if not todo:
            return list(zip(S, out))
        todo.sort()
    raise LPFailed(f"{what(todo[0])}: no convergence adding measurements", "no convergence")


def chebyshev_fit(A, z, weights=None, slack=None, what="minimax fit"):
    """min t over q with |z_k - a_k^T q| <= t w_k + s_k for every k (A: m x K; w = 1, s = 0 unless
    given): (q, t, the residual vector z - A^T q). Plain, it is the minimax (Chebyshev) fit. Many
    measurements: constraint generation (_generate), the same optimum."""
    m, K = A.shape
    w = np.ones(K) if weights is None else np.asarray(weights, float)
    s = np.zeros(K) if slack is None else np.asarray(slack, float)
    c = max(np.abs(z).max(), np.abs(s).max())   # HiGHS's tolerances are absolute: solve with data of size 1
    if c == 0.0:                                  # z = 0 and no slack: q = 0 fits exactly
        return np.zeros(m), 0.0, np.zeros(K)
    if c != 1.0:
        q, t, _ = chebyshev_fit(A, z / c, w, s / c if slack is not None else None, what)
        return q * c, t * c, z - A.T @ (q * c)
    if K <= GENERATE_ABOVE:
        return _chebyshev(A, z, w, s, slack is not None, what)

    def violation(out, S):
        q, t, _ = out
        return (np.abs(z - A.T @ q) - s) / w - t - TOLERANCE * max(abs(t), np.abs(z).max())
    # start where the minimax fit is decided: the largest residuals of the least-squares fit
    r_ls = (np.abs(z - A.T @ np.linalg.lstsq(A.T, z, rcond=None)[0]) - s) / w
    start = np.argpartition(-r_ls, GENERATE_ABOVE // 6)[:GENERATE_ABOVE // 6]
    _, (q, t, _) = _generate(K, lambda S: _chebyshev(A[:, S], z[S], w[S], s[S], slack is not None, what),
                             violation, what, start)
    return q, t, z - A.T @ q


def _chebyshev(A, z, w, s, free, what):
    m, K = A.shape
    M = np.block([[A.T, w[:, None]], [A.T, -w[:, None]]])
    c = np.zeros(m + 1)
    c[-1] = 1.0
    x, _, t = minimize(c, M, np.concatenate([z - s, np.full(K, -INF)]), np.concatenate([np.full(K, INF), z + s]),
                    np.concatenate([np.full(m, -INF), [-INF if free else 0.0]]), INF, what)
    q = x[:m]
    return q, float(t), z - A.T @ q


def l1_estimators(A, targets=None):
    """The primal (7)-(8) of 000 for each target a (columns of `targets`, default every e_nu):
    min sum |Phi| subject to A Phi = a, as u - v with u, v >= 0. One model, the targets solved in turn
    with the previous basis (only the right-hand side changes): (Phi (K x n), sum |Phi| (n,)).
    Many measurements: column generation (_generate) on the duals, |a_k^T lambda| <= 1 for every k."""
    A = np.asarray(A, float)
    m, K = A.shape
    T = np.eye(m) if targets is None else np.asarray(targets, float).reshape(m, -1)
    if K <= GENERATE_ABOVE:
        return _l1(A, T)[:2]
    Phi, err = np.zeros((K, T.shape[1])), np.zeros(T.shape[1])
    found = _generate_each(K, T.shape[1], lambda k, S: _l1(A[:, S], T[:, [k]]),   # each dual has its own peaks
                           lambda outs: _beyond_one(A.T @ np.column_stack([o[2][:, 0] for _, o in outs])),
                           lambda k: f"primal (7)-(8), target {k + 1}")
    for k, (S, (Phi_S, e, _)) in enumerate(found):
        Phi[S, k], err[k] = Phi_S[:, 0], e[0]
    return Phi, err


def _beyond_one(V):
    """|V| - 1 - TOLERANCE, in place (V is a measurement per row: a new array of that size each round was most of
    the column generation's system time)."""
    np.abs(V, out=V)
    V -= 1
    V -= TOLERANCE
    return V


def _l1(A, T):
    """(Phi, sum |Phi|, row duals lambda (m x n)) on the measurements A."""
    m, K = A.shape
    nz = A != 0
    counts = nz.sum(axis=0)
    rows = np.nonzero(nz.T)[1].astype(np.int32)                 # row indices, column by column
    vals = A.T[nz.T]
    h = small(np.ones(2 * K), np.zeros(2 * K), np.full(2 * K, INF), T[:, 0].copy(), T[:, 0].copy(),
              np.concatenate([[0], np.cumsum(np.concatenate([counts, counts]))]).astype(np.int32),
              np.concatenate([rows, rows]), np.concatenate([vals, -vals]))
    idx = np.arange(m, dtype=np.int32)
    Phi, err, Y = np.zeros((K, T.shape[1])), np.zeros(T.shape[1]), np.zeros((m, T.shape[1]))
    for k in range(T.shape[1]):
        if k:
            h.changeRowsBounds(m, idx, T[:, k], T[:, k])
        if solve(h, settled=(OPTIMAL,), presolve=True) != OPTIMAL:     # warm from the last target's basis
            raise failed(h, f"primal (7)-(8), target {k + 1}")
        sol = h.getSolution()
        x = np.array(sol.col_value)
        Phi[:, k] = x[:K] - x[K:]
        err[k] = np.abs(Phi[:, k]).sum()
        Y[:, k] = sol.row_dual
    return Phi, err, Y


def dual(A, targets=None):
    """The dual (9)-(10) of 000 per target a: max a^T lambda subject to |A^T lambda| <= 1 (one ranged
    row per measurement). Returns (Lambda (m x n), values (n,))."""
    A = np.asarray(A, float)
    m, K = A.shape
    T = np.eye(m) if targets is None else np.asarray(targets, float).reshape(m, -1)
    Lam, values = np.zeros((m, T.shape[1])), np.zeros(T.shape[1])
    for k, a in enumerate(T.T):
        Lam[:, k], _, neg = minimize(-a, A.T, -np.ones(K), np.ones(K), -INF, INF, "dual (9)-(10)")
        values[k] = -neg
    return Lam, values


def sparse_dual(A, targets=None, slack=1e-9):
    """Per target a: the optimum of the dual (9)-(10), max a^T lambda with |A^T lambda| <= 1, and among
    its optimal lambdas the one of least sum |lambda| (variables lambda, s with -s <= lambda <= s).
    Returns (Lambda (m x n), values (n,))."""
    A = np.asarray(A, float)
    m, K = A.shape
    T = np.eye(m) if targets is None else np.asarray(targets, float).reshape(m, -1)
    Lam, values = dual(A, T)
    eye = np.eye(m)
    for k, a in enumerate(T.T):
        floor = values[k] - slack * max(1.0, values[k])
        M = np.block([[A.T, np.zeros((K, m))], [a[None], np.zeros((1, m))], [eye, -eye], [-eye, -eye]])
        x, _, _ = minimize(np.r_[np.zeros(m), np.ones(m)], M,
                        np.r_[-np.ones(K), floor, np.full(2 * m, -INF)], np.r_[np.ones(K), INF, np.zeros(2 * m)],
                        np.r_[np.full(m, -INF), np.zeros(m)], INF, "sparse dual")
        Lam[:, k] = x[:m]
    return Lam, values




def covering_plans(S, blocks, limit, seconds=30.0, search_seconds=None, fixed=(), nodes=SEARCH_NODES,
                   count_nodes=COUNT_NODES):
    """Every smallest set of positions x (binary, S) such that, for each block (V (m x C), owner (C,)
    position of each column, cap), some w >= 0 has V w = e and w_k <= cap x_owner(k): a mixed-integer
    program solved (at most `nodes` branch-and-bound nodes), then re-solved with each set found cut off
    (sum over it <= size - 1) and the size fixed, until infeasible, `limit` sets or `count_nodes` nodes in
    all. Returns (size, sets, complete, floor, clock): floor is None when size is proven smallest, else the
    solver's proven lower bound on it (the first solve stopped with a set found but not proven smallest);
    clock is True when a safety time limit (`search_seconds` for the first solve, `seconds` in all) stopped
    the work rather than its node budget: then the result may differ on another machine. The positions
    `fixed` are in every set (those already measured)."""
    import math
    import time
    start = time.perf_counter()
    h = new()
    h.setOptionValue("mip_rel_gap", 0.0)
    h.setOptionValue("mip_max_nodes", int(nodes))
    if search_seconds is not None:
        h.setOptionValue("time_limit", float(search_seconds))
    inf = INF
    lower = np.zeros(S)
    lower[list(fixed)] = 1.0
    h.addVars(S, lower, np.ones(S))
    h.changeColsIntegrality(S, np.arange(S, dtype=np.int32), np.full(S, highspy.HighsVarType.kInteger))
    h.changeColsCost(S, np.arange(S, dtype=np.int32), np.ones(S))
    n = S
    for V, owner, cap, e in blocks:
        m, C = V.shape
        h.addVars(C, np.zeros(C), np.full(C, inf))
        idx = np.arange(n, n + C, dtype=np.int32)
        for i in range(m):
            nz = np.flatnonzero(V[i])
            h.addRow(e[i], e[i], len(nz), idx[nz], V[i, nz])
        for k in range(C):                                   # w_k - cap x_owner <= 0
            h.addRow(-inf, 0.0, 2, np.array([idx[k], owner[k]], dtype=np.int32), np.array([1.0, -cap]))
        n += C
    stopped = (highspy.HighsModelStatus.kTimeLimit, highspy.HighsModelStatus.kSolutionLimit,
               highspy.HighsModelStatus.kIterationLimit)
    found, size, spent = [], None, 0
    while len(found) < limit:
        if found:                                   # the first plan always; the count within what is left
            left = count_nodes - spent
            if left <= 0 or time.perf_counter() - start >= seconds:
                return size, tuple(found), False, None, left > 0
            h.setOptionValue("mip_max_nodes", int(left))
            h.setOptionValue("time_limit", max(seconds - (time.perf_counter() - start), 0.1))
        status = solve(h)
        clock = status == highspy.HighsModelStatus.kTimeLimit
        if found:
            spent += max(h.getInfo().mip_node_count, 1)
            if status in stopped:
                return size, tuple(found), False, None, clock
        elif status in stopped and h.getInfo().primal_solution_status == 2:
            x = np.array(h.getSolution().col_value[:S])              # a plan, not proven the smallest
            plan = tuple(int(v) for v in np.flatnonzero(x > 0.5))
            return len(plan), (plan,), False, math.ceil(h.getInfo().mip_dual_bound - 1e-6), clock
        elif status in stopped:
            which = "--search-seconds" if clock else "--search-nodes"
            raise DataError(f"the plan search found no plan within {which} on {S} candidate positions: raise it, or "
                            "give fewer candidates", param=which.lstrip("-").replace("-", "_"))
        if status != highspy.HighsModelStatus.kOptimal:
            if found:
                return size, tuple(found), True, None, False
            raise failed(h, "the plan search (mixed-integer program)")
        x = np.array(h.getSolution().col_value[:S])
        plan = tuple(int(v) for v in np.flatnonzero(x > 0.5))
        if size is None:
            size = len(plan)
            # at most `size`: it is proven least, so every set found has exactly that size; the inequality solves
            # faster than the equality (`plan two-axis --grid 30`, 64 plans counted: 11 s against 14 s in all)
            h.addRow(-inf, size, S, np.arange(S, dtype=np.int32), np.ones(S))
        found.append(plan)
        h.addRow(-inf, size - 1, size, np.array(plan, dtype=np.int32), np.ones(size))
    return size, tuple(found), False, None, False
