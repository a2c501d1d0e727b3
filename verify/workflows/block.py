"""The block's calibration from any stand's estimate: Gamma and the biases, each with a guaranteed bound.

A stand identifies the combinations q = R p of (4) of 000, not every physical parameter. The block's
parameters are bounded over the information set: every p whose q = R p fits every reading within
sigma plus the proven remainder (guarantee.InformationSet), each stand error, mounting misalignment
and Delta_g/g within its a-priori bound. Each block parameter's least and largest value over that set
(two LPs, each end proven by duality) give its estimate (the midpoint) and a bound (the half-width)
that holds whenever the premises do. A block parameter confounded with a bounded one (a scale factor
with Delta_g, a misalignment with the mounting theta where the stand cannot tell them apart) carries
that bound, and says so; one the set leaves unbounded is not separated by this stand.
"""
import numpy as np

from ..errors import DataError
from ..io.calibration import BLOCK_NAMES
from ..solve import hull, taylor
from .guarantee import Unbounded

BLOCK = BLOCK_NAMES                     # Gamma11..Gamma33, bias1..bias3


def calibration(mod, info, premises):
    """{Gamma (3x3), Gamma_bound, bias (3, over g), bias_bound, confounded {parameter: [(name, bound, source)]}}
    of the block over the information set `info` (guarantee.InformationSet)."""
    names = list(mod.PARAMETER_NAMES)
    if not all(n in names for n in BLOCK):
        raise DataError(f"model {mod.__name__}: no block parameters Gamma11..Gamma33, bias1..bias3", param="model")
    M = np.asarray(mod.PHYSICAL_TO_Q, float)
    kinds, b = premises.kinds, premises.bounds
    bounded = np.array([k in ("stand", "gravity", "mounting", "effect") and np.isfinite(x) for k, x in zip(kinds, b)])
    targets = [names.index(n) for n in BLOCK]
    ql, qh = info.q
    if np.any(ql > qh):
        raise DataError(_CONTRADICT, param="bound")
    try:
        lo, hi, points = info.physical(M, np.where(bounded, -b, -np.inf), np.where(bounded, b, np.inf), targets)
    except hull.Empty:
        raise DataError(_CONTRADICT, param="bound") from None
    except Unbounded as err:
        raise DataError(f"this stand does not separate the block's {BLOCK[err.args[0]]} (its range over the "
                        "premises is unbounded): no calibration of the block from it", param="bound") from None
    if np.any(lo > hi):
        raise DataError(_CONTRADICT, param="bound")
    value, half, confounded = {}, {}, {}
    for name, k, lo_k, hi_k, ends in zip(BLOCK, targets, lo, hi, points):
        value[name], half[name] = (float(x) for x in taylor.midrad(lo_k, hi_k))
        active = {j for x in ends if x is not None for j in np.flatnonzero(bounded)
                  if b[j] > 0 and abs(x[j]) >= b[j] * (1 - 1e-9)}
        # the bounded parameters the range reaches the bounds of: the block parameter carries theirs
        partners = {j for nu in np.flatnonzero(M[:, k]) for j in np.flatnonzero(M[nu]) if bounded[j]} & active
        confounded[name] = [(names[j], float(b[j]), premises.sources[j]) for j in sorted(partners)]
    G = np.array([[value[f"Gamma{i}{j}"] for j in (1, 2, 3)] for i in (1, 2, 3)])
    GB = np.array([[half[f"Gamma{i}{j}"] for j in (1, 2, 3)] for i in (1, 2, 3)])
    return {"Gamma": G, "Gamma_bound": GB, "bias": np.array([value[f"bias{i}"] for i in (1, 2, 3)]),
            "bias_bound": np.array([half[f"bias{i}"] for i in (1, 2, 3)]), "confounded": confounded,
            "_set": _information_set(info, M, np.where(bounded, -b, -np.inf), np.where(bounded, b, np.inf), targets,
                                     [value[n] for n in BLOCK])}


def _information_set(info, R, col_lo, col_hi, targets, mid):
    """The calibration file's information_set of the block (workflows/sample_set.py): the LP of the physical
    parameters' set (guarantee.InformationSet.physical_set) in (p, u), its estimate the block's midpoints at
    `targets` (the box's elsewhere: no sample's error reads them), or None where it is too large for a file."""
    from . import sample_set
    rows = None
    if info.A.shape[1] * (R.shape[1] + R.shape[0]) > sample_set.MAX_ENTRIES:
        # only the readings that can bind: each row reads p through w = R p - q0 + u, which lies in the set of q's
        # hull (q = q0 + w - u, |u| <= shift): screened there (sample_set.binding), a file's width per row
        ql, qh = info.q
        q0, shift = np.asarray(info.lin.q0, float), np.broadcast_to(np.asarray(info.shift, float), ql.shape)
        wide = 4 * EPS * (np.abs(ql) + np.abs(qh) + np.abs(q0)) + 1e-300
        rows = sample_set.binding(info.A.T, info.y - info.s, info.y + info.s, ql - q0 - shift - wide,
                                  qh - q0 + shift + wide, width=R.shape[1] + R.shape[0])
        if rows is None:
            return None
    B, row_lo, row_hi, lo, hi = info.physical_set(R, col_lo, col_hi, targets, rows)
    centre = 0.5 * (row_lo + row_hi)
    bound = 0.5 * (row_hi - row_lo) * (1 + 4 * EPS) + 4 * EPS * np.abs(centre)    # holds [row_lo, row_hi] rounded
    estimate = 0.5 * (lo + hi)
    estimate[list(targets)] = mid
    return {"rows": B, "centre": centre, "bound": bound, "box_lo": lo, "box_hi": hi, "shift": np.zeros(len(lo)),
            "estimate": estimate, "block_columns": list(map(int, targets))}


EPS = np.finfo(float).eps


_CONTRADICT = ("no unit within the a-priori bounds has q within the guaranteed errors: the data contradict a premise "
               "(a stand error or the mounting beyond its stated bound: compare each q printed with the bounds of "
               "its parameters, and state a wider one with --bound NAME=VALUE): no calibration of the block")
