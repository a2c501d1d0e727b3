"""Estimate q with guaranteed error bounds from readings at any set of positions ((6)-(8) of 000)."""
import numpy as np

from . import lp
from .data import DataError


def describe(mod, nus):
    return ", ".join(f"{mod.Q_NAMES[nu]} = {mod.Q_DEFINITIONS[nu]}" for nu in nus)


def estimate(mod, positions, sigma, g):
    """q, guaranteed errors sigma * sum |Phi| (the LP on exactly these positions), and residuals.

    The bound holds for |rho| <= sigma in (5); the linearisation remainder of (1) -> (2) is second
    order in the errors and is not included.
    """
    if sigma <= 0:
        raise DataError(f"--sigma must be positive (got {sigma:g})")
    alpha, beta = positions.radians
    z = mod.residual(alpha, beta, positions.f.T, g).T                  # (N, 3)
    A = lp.measurement_matrix(mod.H, np.column_stack([alpha, beta]))
    missing = lp.unidentifiable(A)
    if missing:
        raise DataError(f"{positions.path}: the {len(set(zip(positions.alpha_deg, positions.beta_deg)))} "
                        f"distinct positions cannot identify {describe(mod, missing)}; "
                        "add positions (see `garant plan`)")
    Phi, err = lp.primal(A)
    q = Phi.T @ z.reshape(-1)
    resid = z - np.einsum("pns,n->sp", mod.H(alpha, beta), q)
    distinct = len(set(zip(np.round(positions.alpha_deg, 6), np.round(positions.beta_deg, 6))))
    return {
        "model": mod.__name__.rsplit(".", 1)[-1],
        "g": g, "sigma": sigma, "positions": len(alpha), "distinct_positions": distinct,
        "q": dict(zip(mod.Q_NAMES, q.tolist())),
        "guaranteed_error": dict(zip(mod.Q_NAMES, (sigma * err).tolist())),
        "definitions": dict(zip(mod.Q_NAMES, mod.Q_DEFINITIONS)),
        "units": dict(zip(mod.Q_NAMES, mod.Q_UNITS)),
        "residual": resid.tolist(),
        "residual_max": float(np.abs(resid).max()),
    }
