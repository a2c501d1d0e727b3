"""The block's calibration from any stand's estimate: Gamma and the biases, each with a guaranteed bound.

A stand identifies the combinations q = R p of (4) of 000, not every physical parameter. The block's
parameters follow from the q's bounds and the premises: every p with |R p - q_hat| <= e and each stand
error, mounting misalignment and Delta_g/g within its a-priori bound. Each block parameter's least and
largest value over that set (two LPs) give its estimate (the midpoint) and a bound (the half-width) that
holds whenever the premises do. A block parameter confounded with a bounded one (a scale factor with
Delta_g, a misalignment with the mounting theta where the stand cannot tell them apart) carries that
bound, and says so; one the set leaves unbounded is not separated by this stand.
"""
import numpy as np

from ..errors import DataError, LPFailed
from ..solve import highs

BLOCK = [f"Gamma{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)] + [f"bias{i}" for i in (1, 2, 3)]


def calibration(mod, q, e, premises):
    """{Gamma (3x3), Gamma_bound, bias (3, over g), bias_bound, confounded {parameter: [(name, bound, source)]}}
    of the block from q_hat = q and its guaranteed errors e (arrays over Q_NAMES)."""
    names = list(mod.PARAMETER_NAMES)
    if not all(n in names for n in BLOCK):
        raise DataError(f"model {mod.__name__}: no block parameters Gamma11..Gamma33, bias1..bias3")
    M = np.asarray(mod.PHYSICAL_TO_Q, float)
    lo_rows, hi_rows = q - e, q + e
    kinds, b = premises.kinds, premises.bounds
    bounded = np.array([k in ("stand", "gravity", "mounting", "effect") and np.isfinite(x) for k, x in zip(kinds, b)])
    col_lo = np.where(bounded, -b, -highs.INF)
    col_hi = np.where(bounded, b, highs.INF)
    value, half, confounded = {}, {}, {}
    for name in BLOCK:
        k = names.index(name)
        ends, active = [], set()
        for sign in (1.0, -1.0):
            c = np.zeros(len(names))
            c[k] = sign
            try:
                x, _, _ = highs.minimize(c, M, lo_rows, hi_rows, col_lo, col_hi, f"range of {name}")
            except LPFailed as err:
                if "nfeasible" in str(err):
                    raise DataError("no unit within the a-priori bounds has q within the guaranteed errors: the "
                                    "data contradict a premise (a stand error or the mounting beyond its stated "
                                    "bound?): no calibration of the block") from None
                raise DataError(f"this stand does not separate the block's {name} (its range over the premises "
                                "is unbounded): no calibration of the block from it") from None
            ends.append(x[k])
            active |= {j for j in np.flatnonzero(bounded) if b[j] > 0 and abs(x[j]) >= b[j] * (1 - 1e-9)}
        lo_k, hi_k = ends
        value[name], half[name] = 0.5 * (lo_k + hi_k), 0.5 * (hi_k - lo_k) * (1 + 1e-9) + 1e-15
        # the bounded parameters the range reaches the bounds of: the block parameter carries theirs
        partners = {j for nu in np.flatnonzero(M[:, k]) for j in np.flatnonzero(M[nu]) if bounded[j]} & active
        confounded[name] = [(names[j], float(b[j]), premises.sources[j]) for j in sorted(partners)]
    G = np.array([[value[f"Gamma{i}{j}"] for j in (1, 2, 3)] for i in (1, 2, 3)])
    GB = np.array([[half[f"Gamma{i}{j}"] for j in (1, 2, 3)] for i in (1, 2, 3)])
    return {"Gamma": G, "Gamma_bound": GB, "bias": np.array([value[f"bias{i}"] for i in (1, 2, 3)]),
            "bias_bound": np.array([half[f"bias{i}"] for i in (1, 2, 3)]), "confounded": confounded}
