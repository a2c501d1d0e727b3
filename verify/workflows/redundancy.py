"""Limiting accuracy of a redundant measuring complex (003): r instruments, q process parameters,
N instants, additive systematic errors C, noise B = sigma^2 I.

- (3) maximum-likelihood estimate from the constraint residuals V = D G C + D Xi;
- (4) covariance of the joint estimate, B_C = [G^T B^-1 G - G^T B^-1 P (P^T B^-1 P)^-1 P^T B^-1 G]^-1;
- trace(B_C^-1) = N (r - q) / sigma^2 for every geometry (5), so by the AM-HM inequality the trace of
  B_C is smallest, r^2 sigma^2 / (N (r - q)), when all its eigenvalues are equal: each variance is then
  sigma^2/N * r/(r - q) (6); and no variance is ever below sigma^2/N, the reference accuracy (7).
"""
import numpy as np
import sympy as sp


def covariance_4(P_blocks, sigma2):
    """(4) with G = stacked identities and B = sigma^2 I; works on numpy or sympy blocks (r x q each)."""
    exact = isinstance(P_blocks[0], sp.MatrixBase)
    r = P_blocks[0].shape[0]
    eye = sp.eye(r) if exact else np.eye(r)
    info = eye * len(P_blocks)
    for P in P_blocks:
        Qi = P * (P.T * P).inv() * P.T if exact else P @ np.linalg.solve(P.T @ P, P.T)
        info = info - Qi
    return (info.inv() * sigma2) if exact else np.linalg.inv(info) * sigma2


def ml_estimate_3(D_blocks, v_blocks, sigma2):
    """(3): C^ = [sum D_i^T (D_i B D_i^T)^-1 D_i]^-1 sum D_i^T (D_i B D_i^T)^-1 v_i, and its covariance."""
    r = D_blocks[0].shape[1]
    A, b = np.zeros((r, r)), np.zeros(r)
    for D, v in zip(D_blocks, v_blocks):
        W = np.linalg.inv(sigma2 * D @ D.T)
        A += D.T @ W @ D
        b += D.T @ W @ v
    cov = np.linalg.inv(A)
    return cov @ b, cov


def random_rational_geometry(r, q, N, rng):
    """N random full-rank r x q blocks with small integer entries (exact arithmetic)."""
    out = []
    while len(out) < N:
        P = sp.Matrix(rng.integers(-3, 4, size=(r, q)).tolist())
        if P.rank() == q:
            out.append(P)
    return out


def balanced_geometry(r, q):
    """Blocks whose projections sum to a multiple of E: every q-subset of coordinate axes once."""
    from itertools import combinations
    blocks = []
    for cols in combinations(range(r), q):
        P = sp.zeros(r, q)
        for j, c in enumerate(cols):
            P[c, j] = 1
        blocks.append(P)
    return blocks


# --- two complexes for Monte Carlo -------------------------------------------------------------

def example2_trajectory(N):
    """003 Example 2: a point seen through x, R, alpha; process parameters (R, alpha); r = 3, q = 2."""
    t = np.linspace(0, 2 * np.pi, N, endpoint=False)
    R, alpha = 10 + 3 * np.sin(2 * t), 0.3 + 1.2 * np.sin(t)
    return np.column_stack([R * np.cos(alpha), R, alpha])


def example2_blocks(f):
    """D_i = dV/df for V = x - R cos(alpha), and P_i = df/d(R, alpha), at the true values."""
    x, R, a = f.T
    D = [np.array([[1.0, -np.cos(ai), Ri * np.sin(ai)]]) for Ri, ai in zip(R, a)]
    P = [np.array([[np.cos(ai), -Ri * np.sin(ai)], [1.0, 0.0], [0.0, 1.0]]) for Ri, ai in zip(R, a)]
    return D, P


def trilateration(N):
    """Ranges from three fixed beacons to a moving point in the plane: r = 3, q = 2 (position).

    The geometry P_i (unit vectors from the beacons) changes as the point moves, so all three range
    biases are estimable; a rigid geometry that only turns would leave them unidentifiable.
    """
    t = np.linspace(0, 2 * np.pi, N, endpoint=False)
    beacons = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])
    p = np.column_stack([4 + 3 * np.cos(t), 4 + 2 * np.sin(2 * t)])
    f0 = np.linalg.norm(p[:, None, :] - beacons[None], axis=2)              # (N, 3)
    P = [(pi - beacons) / fi[:, None] for pi, fi in zip(p, f0)]
    D = [np.linalg.svd(Pi)[0][:, 2:].T for Pi in P]
    return f0, D, P


def monte_carlo(D, truth_f, c, sigma, runs, rng, residual):
    """Sample covariance of the ML estimate (3) over `runs` noisy realisations.

    (3) is linear in the residuals, C^ = sum_i K_i v_i with fixed gains K_i, so all runs are
    computed at once; residual(f) maps readings (runs, N, r) to residuals (runs, N, k).
    """
    cov = ml_estimate_3(D, [np.zeros(Di.shape[0]) for Di in D], sigma**2)[1]
    K = np.stack([cov @ Di.T @ np.linalg.inv(sigma**2 * Di @ Di.T) for Di in D])      # (N, r, k)
    f = truth_f + c + rng.normal(0, sigma, (runs,) + truth_f.shape)
    est = np.einsum("irk,nik->nr", K, residual(f))
    return np.cov(est.T)


def chi2_interval(dof, p=0.999):
    """Two-sided interval for chi^2_dof / dof (Wilson-Hilferty approximation), probability p."""
    z = {0.99: 2.5758, 0.999: 3.2905}[p]
    k = 2 / (9 * dof)
    return (1 - k - z * np.sqrt(k)) ** 3, (1 - k + z * np.sqrt(k)) ** 3
