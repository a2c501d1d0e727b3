"""Estimate q, with guaranteed error bounds, from readings at any set of positions ((6)-(8) of 000)."""
import numpy as np

from ..errors import DataError
from ..solve import lp
from . import mounting, nearby

EXACT_DEG = 1e-6   # positions closer than this to the plan count as on it


def describe(mod, nus):
    return ", ".join(f"{mod.Q_NAMES[nu]} = {mod.Q_DEFINITIONS[nu]}" for nu in nus)


def residuals_table_axes(mod, positions, g, Q):
    """z of (1) in block axes, turned to table axes by Q^-1 ((26) of 000): shape (N, 3).

    For a stand with several mountings, z stays in block axes (H already includes each Q)."""
    if positions.mounts is not None:
        return mod.residual(*positions.radians, positions.f.T, g, mount=positions.mounts).T
    z_block = positions.f.T / g - Q @ mod.up_nominal(*positions.radians)
    return (Q.T @ z_block).T


def check_residual_size(z, path, limit=0.5):
    """Readings must be near the model: a residual beyond half of g is a unit or column mistake, not
    a small error the linear model (2) can describe."""
    worst = np.abs(z).max(axis=1)
    if worst.max() > limit:
        k = int(np.argmax(worst))
        raise DataError(f"{path}: position {k + 1} differs from the model by {worst[k]:.3g} g; readings must be "
                        "specific force in m/s^2 (check --g, the units and the column order)")


def choose_estimator(mod, positions, A):
    """Weights (m x 3N) and the method: (23) of 000 near the optimal plan, else the LP (7)-(8)."""
    plan = getattr(mod, "PLAN_DEG", np.zeros((0, 2)))
    match = (nearby.match_plan(positions.alpha_deg, positions.beta_deg, plan)
             if len(plan) and positions.angles_deg.shape[1] == 2 and positions.mounts is None else None)
    if match is not None and match[1] > EXACT_DEG:
        order, miss = match
        cols = np.array([3 * order[s] + p for s in range(len(order)) for p in range(3)])
        Psi = nearby.estimator_23(nearby.plan_estimators(mod), A[:, cols])
        W = np.zeros_like(A)
        W[:, cols] = Psi
        return W, (f"positions within {miss:.3g} deg of the optimal plan but not on it: "
                   "estimator (23) of 000, q* = (D H^T)^-1 D Z")
    Phi, _ = lp.primal(A)
    return Phi.T, "optimal guaranteed estimator on these positions (LP (7)-(8) of 000)"


def estimate(mod, positions, sigma, g, remount=None, mount=None, gamma="lower"):
    """q, guaranteed errors sigma * sum |weights|, residuals, and the block's physical errors.

    The bounds hold for |rho| <= sigma in (5); the second-order remainder of the linearisation
    (1) -> (2) is not included.
    """
    if sigma <= 0:
        raise DataError(f"--sigma must be positive (got {sigma:g})")
    if g <= 0:
        raise DataError(f"--g must be positive (got {g:g} m/s^2)")
    Q = remount.MOUNTS[mount] if mount else np.eye(3)
    angles = positions.radians
    z = residuals_table_axes(mod, positions, g, Q)
    A = lp.measurement_matrix(mod, np.column_stack(angles), positions.mounts)
    keys = [tuple(r) for r in np.round(positions.angles_deg, 6)]
    if positions.mounts is not None:
        keys = [k + (m,) for k, m in zip(keys, positions.mounts)]
    distinct = len(set(keys))
    missing = lp.unidentifiable(A)
    if missing:
        raise DataError(f"{positions.path}: the {distinct} distinct positions cannot identify "
                        f"{describe(mod, missing)}; add positions (see `garant plan`)")
    check_residual_size(z, positions.path)
    W, method = choose_estimator(mod, positions, A)
    q = W @ z.reshape(-1)
    resid = z - (A.T @ q).reshape(-1, 3)
    out = {
        "model": mod.__name__.rsplit(".", 1)[-1], "method": method,
        "g": g, "sigma": sigma, "positions": len(z), "distinct_positions": distinct,
        "q": dict(zip(mod.Q_NAMES, q.tolist())),
        "guaranteed_error": dict(zip(mod.Q_NAMES, (sigma * np.abs(W).sum(axis=1)).tolist())),
        "definitions": dict(zip(mod.Q_NAMES, mod.Q_DEFINITIONS)),
        "units": dict(zip(mod.Q_NAMES, mod.Q_UNITS)),
        "residual": resid.tolist(),
        "residual_max": float(np.abs(resid).max()),
    }
    if remount is not None:
        phys, bound, note = mounting.recover(remount, mount or "+x+y+z", gamma, q, W, sigma, g)
        out.update(mount=mount or "+x+y+z", gamma=gamma, physical=phys, physical_bound=bound,
                   physical_note=note)
    return out
