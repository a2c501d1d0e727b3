"""Positions that miss their target: the estimator (23) of 000 and its guaranteed error (20)-(24).

D (m x S) holds the optimal estimators of the exact plan, one row per q; the realised plan gives the
measurement matrix A (m x S, columns H at the positions actually set). Then
(23) q* = (D A^T)^-1 D Z is unbiased, (24) Psi~ A^T = E, with guaranteed error sum_k |Psi~_k| per q.
Reusing D itself carries the bias (D A^T - E) q: its guaranteed error is infinite.
"""
import numpy as np

from ..solve import lp
def plan_estimators(mod):
    """D: the generated optimal estimators on PLAN_DEG as an m x 3S matrix, columns ordered (s, p)."""
    return mod.PSI.reshape(len(mod.Q_NAMES), -1)


def realised_matrix(mod, positions_deg):
    """The measurement matrix of the positions actually reached (degrees)."""
    return lp.measurement_matrix(mod.H, np.deg2rad(np.asarray(positions_deg, float)))


def estimator_23(D, A):
    """Psi~ = (D A^T)^-1 D of (23), shape m x S (A: m x S, the realised measurement matrix)."""
    return np.linalg.solve(D @ A.T, D)


def compare(mod, realised_deg):
    """Guaranteed errors (units of sigma) on a realised plan: (23), the LP optimum, and the bias of D."""
    D, A = plan_estimators(mod), realised_matrix(mod, realised_deg)
    Psi = estimator_23(D, A)
    _, best = lp.primal(A)
    return {
        "unbiased_23": float(np.abs(Psi @ A.T - np.eye(len(D))).max()),
        "error_23": np.abs(Psi).sum(axis=1),
        "error_lp": best,
        "bias_of_exact": D @ A.T - np.eye(len(D)),     # q-coefficients of the bias when D is reused
    }


def wrap_deg(x):
    """Angles wrapped into [-180, 180) degrees."""
    return (np.asarray(x, float) + 180.0) % 360.0 - 180.0


def match_plan(alpha_deg, beta_deg, plan_deg, tol_deg=3.0):
    """Order of the data rows that puts them on the plan, if every row is within tol of a distinct
    plan position and all plan positions are present; else None. Returns (order, max miss in deg)."""
    data = np.column_stack([alpha_deg, beta_deg])
    plan = np.asarray(plan_deg, float)
    if len(data) != len(plan):
        return None
    miss = np.abs(wrap_deg(data[:, None, :] - plan[None, :, :])).max(axis=2)   # (N, S)
    order = miss.argmin(axis=0)
    if len(set(order)) != len(plan) or miss[order, range(len(plan))].max() > tol_deg:
        return None
    return order, float(miss[order, range(len(plan))].max())


def sweep(mod, misses_deg, trials=20, seed=0):
    """Max over q of the guaranteed errors of (23) and of the LP, per miss size: (mean, worst) pairs."""
    out = []
    for miss in misses_deg:
        rng = np.random.default_rng([seed,
                                     int(round(1000 * miss))])     # the same draws for a miss, alone or in a sweep
        e23, elp = [], []
        for _ in range(trials):
            P = np.asarray(mod.PLAN_DEG, float) + rng.uniform(-miss, miss, (len(mod.PLAN_DEG), 2))
            r = compare(mod, P)
            e23.append(r["error_23"].max())
            elp.append(r["error_lp"].max())
        out.append((miss, np.mean(e23), np.max(e23), np.mean(elp), np.max(elp)))
    return np.array(out)


if __name__ == "__main__":
    import sys
    import warnings

    from garant.generated import two_axis
    warnings.filterwarnings("ignore", category=RuntimeWarning)
    target = sys.argv[1] if len(sys.argv) > 1 else "docs/img/realised_plan.png"
    from ..io import plots
    rows = sweep(two_axis, np.linspace(0, 5, 11))
    plots.realised_plan(rows, target)
    print(f"wrote {target}")
    print("miss_deg  (23)_mean  (23)_worst  LP_mean  LP_worst")
    for r in rows:
        print("  ".join(f"{v:8.4f}" for v in r))
