"""Guaranteed estimation as linear programs on a finite set of measurements, solved by HiGHS.

A is the m x K matrix whose columns are the measurement vectors H^(p)(alpha_s, beta_s). For each
a = e_nu (all nu at once, the problems are separable):
- primal (7)-(8) of 000: min sum |Phi| subject to A Phi = a (Phi: one estimator per column of a);
- dual (9)-(10): max a^T lambda subject to |A^T lambda| <= 1;
- generalised Chebyshev polynomial (11)-(12): L_nu = min over y, y_nu = 1, of max |A^T y|.
Theorem 3: primal = dual = 1 / L_nu. Values are in units of sigma. cvxpy is imported only by the
functions that state an LP through it.
"""
import numpy as np

from ..errors import LPFailed
from . import highs


def optimal(problem, what):
    """Solve a cvxpy problem with HiGHS; LPFailed unless optimal."""
    import cvxpy as cp
    highs.new()                                   # the first HiGHS of the process prints a banner: not here
    problem.solve(solver=cp.HIGHS)
    if problem.status != cp.OPTIMAL:
        raise LPFailed(f"{what}: solver status {problem.status}", problem.status)


def primal(A, targets=None):
    """Optimal estimators Phi (K x n) and their guaranteed errors sum |Phi| (n), for a = targets.

    Passed to HiGHS directly (solve/highs.py): the hot path of `estimate`, where cvxpy's
    canonicalisation cost more time and memory than the solve (python -m verify.bench). The dual and
    the Chebyshev polynomial below stay in cvxpy, as the papers state them: an independent route."""
    return highs.l1_estimators(A, targets)


def dual(A, targets=None):
    """Optimal dual vectors lambda (m x n) of (9)-(10) and their values a^T lambda (n), by HiGHS directly
    (one ranged row per measurement); the Chebyshev polynomial (12) below is the cvxpy statement."""
    return highs.dual(A, targets)


def sparse_dual(A, targets=None, slack=1e-9):
    """Among the optimal duals of (9)-(10), the one of least sum |lambda| (per target): on a finite set
    the optimal dual is rarely unique, and the sparse one is the one that tends to stay feasible
    between the points (the Chebyshev polynomial of fewest terms). HiGHS directly: the exchange
    method's hot path."""
    return highs.sparse_dual(A, targets, slack)


def chebyshev(A):
    """L_nu and the minimising y (column nu, y_nu = 1) of the Chebyshev polynomial (12): min over y with
    y_nu = 1 of max_k |a_k^T y|. With y_nu fixed that is the minimax fit of the row a_nu by the other rows
    (y_j = -q_j), solved by HiGHS per nu (highs.chebyshev_fit). cvxpy's statement of (12) as one problem is
    the reference tests/papers/test_stand_000.py compares this with; `garant verify` need not import cvxpy."""
    A = np.asarray(A, float)
    m = A.shape[0]
    L, Y = np.zeros(m), np.zeros((m, m))
    for nu in range(m):
        others = np.arange(m) != nu
        q, L[nu], _ = highs.chebyshev_fit(A[others], A[nu], what="Chebyshev polynomial (12)")
        Y[nu, nu], Y[others, nu] = 1.0, -q
    return L, Y


def measurement_matrix(H, positions, mounts=None, variables=()):
    """Columns H^(p) at the positions, ordered (s, p); positions in radians, shape (S, n_angles).

    H is a model's H function (or a module, for stands with several mountings: then `mounts`
    gives each position's mounting index; `variables`, the values (S,) of the module's VARIABLES)."""
    positions = np.atleast_2d(np.asarray(positions, float))
    if callable(H):
        Hs = H(*[positions[:, i] for i in range(positions.shape[1])])          # (rows, m, S)
    else:
        from ..models import H_at
        Hs = H_at(H, positions, mounts, variables)
    return np.transpose(Hs, (1, 2, 0)).reshape(Hs.shape[1], -1)


def gram_spectrum(A, chunk=100_000):
    """Eigen-decomposition of the m x m Gram matrix A A^T (A: m x K), summed in chunks of columns:
    memory independent of K. range(A) = range(A A^T), and the eigenvectors of its (numerically) zero
    eigenvalues span the combinations no column of A can see."""
    m, K = A.shape
    G = np.zeros((m, m))
    for k in range(0, K, chunk):
        B = A[:, k:k + chunk]
        G += B @ B.T
    return np.linalg.eigh(G)


def blind_directions(A, tol=1e-12):
    """Orthonormal rows spanning {x : A^T x = 0}: eigenvalues of A A^T below tol x the largest (singular
    values below 1e-6 of the largest)."""
    if A.shape[1] == 0:
        return np.eye(A.shape[0])
    w, V = gram_spectrum(A)
    return V[:, w <= tol * max(w.max(), 1e-300)].T


def unidentifiable(A, tol=1e-12):
    """Indices nu for which no unbiased estimator exists: e_nu is not in the range of A (m x K), i.e. it
    has a component along a blind direction."""
    N = blind_directions(A, tol)
    return [nu for nu in range(A.shape[0]) if np.linalg.norm(N[:, nu]) > 1e-6]
