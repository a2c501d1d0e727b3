"""Guaranteed estimation as linear programs on a finite set of measurements, solved by HiGHS.

A is the m x K matrix whose columns are the measurement vectors H^(p)(alpha_s, beta_s). For each
a = e_nu (all nu at once, the problems are separable):
- primal (7)-(8) of 000: min sum |Phi| subject to A Phi = a (Phi: one estimator per column of a);
- dual (9)-(10): max a^T lambda subject to |A^T lambda| <= 1;
- generalised Chebyshev polynomial (11)-(12): L_nu = min over y, y_nu = 1, of max |A^T y|.
Theorem 3: primal = dual = 1 / L_nu. Values are in units of sigma.
"""
import cvxpy as cp
import numpy as np

from ..errors import LPFailed


def _solve(problem, what):
    problem.solve(solver=cp.HIGHS)
    if problem.status != cp.OPTIMAL:
        raise LPFailed(f"{what}: solver status {problem.status}")


def primal(A, targets=None):
    """Optimal estimators Phi (K x n) and their guaranteed errors sum |Phi| (n), for a = targets."""
    m, K = A.shape
    T = np.eye(m) if targets is None else np.asarray(targets, float).reshape(m, -1)
    pos, neg = cp.Variable((K, T.shape[1]), nonneg=True), cp.Variable((K, T.shape[1]), nonneg=True)
    _solve(cp.Problem(cp.Minimize(cp.sum(pos + neg)), [A @ (pos - neg) == T]), "primal (7)-(8)")
    Phi = pos.value - neg.value
    return Phi, np.abs(Phi).sum(axis=0)


def dual(A, targets=None):
    """Optimal dual vectors lambda (m x n) of (9)-(10) and their values a^T lambda (n)."""
    m, K = A.shape
    T = np.eye(m) if targets is None else np.asarray(targets, float).reshape(m, -1)
    Lam = cp.Variable((m, T.shape[1]))
    _solve(cp.Problem(cp.Maximize(cp.sum(cp.multiply(T, Lam))), [cp.abs(A.T @ Lam) <= 1]),
           "dual (9)-(10)")
    return Lam.value, (T * Lam.value).sum(axis=0)


def sparse_dual(A, targets=None, slack=1e-9):
    """Among the optimal duals of (9)-(10), the one of least sum |lambda| (per target): on a finite set
    the optimal dual is rarely unique, and the sparse one is the one that tends to stay feasible
    between the points (the Chebyshev polynomial of fewest terms)."""
    m, K = A.shape
    T = np.eye(m) if targets is None else np.asarray(targets, float).reshape(m, -1)
    _, value = dual(A, T)
    Lam = cp.Variable((m, T.shape[1]))
    cons = [cp.abs(A.T @ Lam) <= 1, cp.sum(cp.multiply(T, Lam), axis=0) >= value - slack * np.maximum(1, value)]
    _solve(cp.Problem(cp.Minimize(cp.sum(cp.abs(Lam))), cons), "sparse dual")
    return Lam.value, value


def chebyshev(A):
    """L_nu and the minimising y (column nu, y_nu = 1) of the Chebyshev polynomial (12)."""
    m, K = A.shape
    Y, t = cp.Variable((m, m)), cp.Variable(m)
    cons = [cp.diag(Y) == 1, cp.abs(A.T @ Y) <= cp.reshape(t, (1, m), order="C")]
    _solve(cp.Problem(cp.Minimize(cp.sum(t)), cons), "Chebyshev polynomial (12)")
    return t.value, Y.value


def measurement_matrix(H, positions, mounts=None):
    """Columns H^(p) at the positions, ordered (s, p); positions in radians, shape (S, n_angles).

    H is a model's H function (or a module, for stands with several mountings: then `mounts`
    gives each position's mounting index)."""
    positions = np.atleast_2d(np.asarray(positions, float))
    if callable(H):
        Hs = H(*[positions[:, i] for i in range(positions.shape[1])])          # (rows, m, S)
    else:
        from ..models import H_at
        Hs = H_at(H, positions, mounts)
    return np.transpose(Hs, (1, 2, 0)).reshape(Hs.shape[1], -1)


def unidentifiable(A, tol=1e-9):
    """Indices nu for which no unbiased estimator exists: e_nu is not in the range of A."""
    if A.size == 0:
        return list(range(A.shape[0]))
    x, *_ = np.linalg.lstsq(A, np.eye(A.shape[0]), rcond=None)
    return [nu for nu in range(A.shape[0]) if np.abs(A @ x[:, nu] - np.eye(A.shape[0])[nu]).max() > tol]
