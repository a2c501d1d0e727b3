"""The information set of the norm relation (2.2) of 001 around a fit, with each still interval's own remainder.

The sphere-wide bound (2.3) of 001 holds for any direction; a log's intervals each have their own reading |F_k|,
noise and (with catalogue effects, workflows/norm_effects.py) effect terms, and the remainder of each is bounded
from a box of the truth's correction to the fit (`remainder_per_interval`). The box is a premise, stated; the set
contracts from it (`exact_information`).
"""
from typing import NamedTuple, Optional

import numpy as np

from ..solve import hull


def premise_box(premise):
    """The premise the remainder of each interval is proven from, in words (empty where (2.3) is used): its box X of
    the truth's correction and, with effects, its bound V of their term (`Premise`)."""
    if premise is None:
        return ""
    X, V = premise.X, premise.V
    return ("; the truth's correction to this fit is within " + ", ".join(
        f"{x.max():.2g} ({name})" for name, x in (("scale", X[:3]), ("misalignment, rad", X[3:6]), ("bias over g",
                                                                                                    X[6:9])))
        + ("" if V is None else f", its effects' term within {V.max():.2g} (units of g, per interval and axis)")
        + f" (the box each interval's remainder is proven from, at most {PREMISE_FACTORS[0]:g}x the information set's "
        "own box)")


def lower(q):
    """The lower-triangular 3 x 3 of the scale and misalignment entries of q (or of their bounds) in (2.2) of 001:
    [[q0, 0, 0], [q3, q1, 0], [q4, q5, q2]]."""
    return np.array([[q[0], 0, 0], [q[3], q[1], 0], [q[4], q[5], q[2]]])


STEPS = 12                                            # boxes at most, each way
#: The premise box tried, in multiples of the set's own box (the widest that contracts is taken).
PREMISE_FACTORS = (64.0, 32.0, 16.0, 8.0, 4.0, 2.0, 1.5, 1.25)


def remainder_per_interval(F, A_box, e_box, nu, extra=None):
    """What is left of the remainder of (2.2) per interval once q absorbs its part in the span of H', in the
    units of sigma, and the bound of that absorbed shift per q. With B = (E + A)^-1, d = eps/g + u (u the noise of
    the calibrated mean, |u| <= nu) and y = F - d, the truth has |B y| = 1, and B = E - A + A^2 B gives exactly
        c - c(0) + F^T (A F + d) = |d + A F|^2 / 2 + (F - d - A F)^T (A d + A^2 B y) + |A d + A^2 B y|^2 / 2 = R,
        sigma_k = H'(n_k)^T q + n_k^T u / |F_k| - R_k / |F_k|^2,
    H' being H of (2.2) with the bias columns over |F_k|. R's second-order part without u,
    |e|^2/2 + |A F|^2/2 + e^T A F + F^T A e + F^T A^2 F, is over |F|^2 a quadratic form in n plus a linear one over
    |F| (n^T n = 1 carries the constant): H'^T s for a shift s of q that the set absorbs, |s| bounded from the box
    (`shift`); left are the terms in u, |u|^2/2 + e^T u + u^T A F + F^T A u, the third order,
        F^T A^2 (B y - F) - (d + A F)^T (A d + A^2 B y) + |A d + A^2 B y|^2 / 2,   B y - F = -B (A F + d),
    and |e|^2/2 (1/|F|^2 - 1), bounded with a = |A|_F (>= the spectral norm), |A F| <= | |A| |F| |,
    |B| <= 1/(1 - a). F (K, 3): the readings calibrated by the fit, units of g; A_box (3, 3) and e_box (3)
    bound |A| and |eps/g| entrywise. With catalogue effects, `extra` = (v, rho) per interval: d holds the effect's
    part v beside u (|v| <= v_k; its first order n^T v / |F| is the effect's column but for rho, |rho| <= rho_k,
    which stays here), so u's terms are bounded with nu + v. Returns (left per interval (K,), shift bound per
    q (9,))."""
    a = float(np.linalg.norm(A_box))
    if a >= 0.5:
        return np.full(len(F), np.inf), np.full(9, np.inf)
    b = 1.0 / (1.0 - a)
    f = np.linalg.norm(F, axis=1)
    aF = np.linalg.norm(np.abs(F) @ A_box.T, axis=1)
    aFt = np.linalg.norm(np.abs(F) @ A_box, axis=1)
    e = float(np.linalg.norm(e_box))
    rho = 0.0
    if extra is not None:
        v, rho = extra
        nu = nu + v
    d = e + nu
    in_u = 0.5 * nu ** 2 + e * nu + nu * (aF + aFt)
    tail = a * d + a * a * b * (f + d)
    third = a * a * b * f * (aF + d) + (d + aF) * tail + 0.5 * tail ** 2
    left = (in_u + third) / f ** 2 + 0.5 * e * e * np.abs(1.0 / f ** 2 - 1.0) + rho / f
    P = 0.5 * A_box.T @ A_box + A_box @ A_box                 # |n^T (A^T A / 2 + A^2) n|: coefficients bounded by P
    shift = np.concatenate([np.diag(P) + 0.5 * e * e, [P[0, 1] + P[1, 0], P[0, 2] + P[2, 0], P[1, 2] + P[2, 1]],
                            A_box.T @ e_box + A_box @ e_box])
    return left * (1 + 1e-12) + 1e-16, shift * (1 + 1e-12) + 1e-16


def design(mod, res, ext=None):
    """(A, |F|): the columns of the information set of (2.2) around the fit `res` (H' of `remainder_per_interval`,
    the bias columns over |F_k|, and with catalogue effects theirs, n . phi_j(p) / |F_k|) and each interval's |F_k|
    (sigma = (|F|^2 - 1) / (2 |F|^2))."""
    s, n = res["sigma"], res["n"]
    f = 1.0 / np.sqrt(1.0 - 2.0 * s)
    A = mod.H(n)[:9].copy()
    A[6:9] /= f
    if ext is not None:
        A = np.vstack([A, ext.columns(n) / f])
    return A, f


def exact_information(mod, res, noise, nu, ext=None, start=None, cap=None):
    """The information set of the 9 corrections q of (2.2) around the fit with each interval's own remainder
    (`remainder_per_interval`) instead of the sphere-wide (2.3): q = w + s, every w with |sigma_k - H'_k^T w| <=
    noise_k / |F_k| + left_k(box), |s| <= shift(box). The remainder needs a box to start from, so it is a premise,
    stated: the truth's correction to this fit is within X, the widest of PREMISE_FACTORS times the set's own box
    (the smallest box the remainder is consistent with) from which the set contracts (its hull lies in X). From
    X each box is the set's hull (LPs, each end proven by duality) within the last, and the remainder is
    bounded on it again, while it shrinks: each holds the truth when X does. With catalogue effects (`ext`,
    norm_effects.Extension) q holds their parameters' corrections after the 9, their columns beside H'. Returns
    ((lo, hi) of q, what is left of the remainder per interval, X, the shift bound), or None when no premise box
    contracts. `start`: each interval's bound of the first set, whose hull sets the scale of the box to start from
    (default noise / |F|: the linear set; a set that is empty without a remainder needs one). `cap`: a stated
    a-priori bound of q (inf where none; calibrate_norm.misalignment_cap), held in every set."""
    s, n = res["sigma"], res["n"]
    A, f = design(mod, res, ext)
    F = (n * f).T
    base = noise / f
    cap = np.full(A.shape[0], np.inf) if cap is None else np.r_[cap, np.full(A.shape[0] - len(cap), np.inf)]

    def step(reach, X=None, proofs=None, within=False, V=None):
        """(lo, hi) of q, the remainder left, the multipliers proving them, the shift and the bound of the effects'
        term over the set (None without effects), on the box |q| <= reach (and X), or None; with `proofs`
        (multipliers of earlier sets), bounded from them alone, no LP. `within`: None as soon as an LP proves some
        |q| past X, or the effects' term past V (the premise is then rejected whatever the other ends). `V` (3, K):
        a bound of the effects' term |Phi(p) theta'| the truth meets (a premise's, or an earlier set's); with
        effects each set is solved REFINE times, its term bounded over the last pass's set (`effect_reach`)."""
        A_box = lower(reach)
        v_set, passes = V, REFINE if ext is not None and proofs is None else 1
        for k in range(passes):
            extra = None if ext is None else ext.extra(reach[9:], A_box, reach[6:9], nu, v_set)
            left, shift = remainder_per_interval(F, A_box, reach[6:9], nu, extra)
            shift = np.concatenate([shift, np.zeros(len(reach) - 9)])
            if not (np.all(np.isfinite(left)) and np.all(np.isfinite(shift))):
                return None
            box = None if X is None and not np.isfinite(cap).any() else np.minimum(1.0 if X is None else X, cap) + shift
            try:
                lo, hi, lams = _hull(A, s, base + left, box, proofs,
                                     (shift - X, X - shift) if within and k == passes - 1 else None)
            except hull.Beyond:
                return None
            if ext is not None and proofs is None:       # the effects' term over this set: the next pass's bound
                reach_v = effect_reach(A, s, base + left, box, ext)
                v_set = reach_v if v_set is None or reach_v is None else np.minimum(v_set, reach_v)
        if within and V is not None and v_set is not None and np.any(v_set > V):
            return None
        return lo - shift, hi + shift, left, lams, shift, v_set

    start_bound = base if start is None else start
    lo, hi, lams = _hull(A, s, start_bound, np.minimum(1.0, cap))    # the box's scale
    own, proofs = np.maximum(np.abs(lo), np.abs(hi)), [lams]
    v_own = None if ext is None else effect_reach(A, s, start_bound, np.minimum(1.0, cap), ext)
    for _ in range(STEPS):                                   # the smallest self-consistent box, from the linear set up
        for by in (proofs, None):                            # by the multipliers solved, then by LPs
            got = step(own, None, by, V=v_own)
            if got is None:
                return None
            grown = np.maximum(np.abs(got[0]), np.abs(got[1]))
            v_grown = v_own if got[5] is None or v_own is None else np.maximum(v_own, got[5])
            if np.all(grown <= own * 1.1):                    # it only sets the premise's scale
                break
        else:
            own, v_own = grown, v_grown
            proofs.append(got[3])
            continue
        break
    for factor in PREMISE_FACTORS:                           # each box tried by those multipliers, then by LPs
        X, V = factor * own, None if v_own is None else factor * v_own
        got = next((got for by in (proofs, None) for got in [step(X, X, by, within=True, V=V)]
                    if got is not None and np.all(np.maximum(np.abs(got[0]), np.abs(got[1])) <= X)), None)
        if got is not None:
            break
    else:
        return None
    lo, hi, left = np.maximum(got[0], -np.minimum(X, cap)), np.minimum(got[1], np.minimum(X, cap)), got[2]
    v_now = V if got[5] is None else got[5]
    proofs += [got[3]] if got[3] is not None else []
    # from the premise down: each box proven, inside the last; first by the multipliers of the two sets solved
    # (no LP: the sets between differ in their bounds only), then by LPs until no bound moves by much
    for by in (proofs, None):
        for _ in range(STEPS):
            got = step(np.maximum(np.abs(lo), np.abs(hi)), X, by, V=v_now)
            lo2, hi2 = np.maximum(lo, got[0]), np.minimum(hi, got[1])
            shrunk = np.all(hi2 - lo2 >= 0.95 * (hi - lo))
            lo, hi, left = lo2, hi2, np.minimum(left, got[2])
            v_now = v_now if got[5] is None else got[5]
            if shrunk:                                       # a smaller box would move no bound by much
                break
    return (lo, hi), left, Premise(X, V), got[4]


class Premise(NamedTuple):
    """The premise a per-interval remainder is proven from: X, the box of the truth's correction q to the fit, and
    V (3, K), the bound of the effects' term |Phi(p) theta'| (None without effects)."""

    X: np.ndarray
    V: Optional[np.ndarray] = None


#: Passes of a set with catalogue effects: the effect's term |Phi(p) theta'| bounded over the last pass's set (LPs)
#: rather than from the box of theta' alone (which loses how the parameters of a polynomial in T move together).
REFINE = 3


def effect_reach(A, s, bound, X, ext):
    """(3, K): the largest |Phi(p_k) theta'|_i over the set |s - A^T q| <= bound, |q| <= X (default 1), theta' =
    q[9:], each component of each interval an LP pair proven by duality (solve/hull.py). Each set holds the truth
    when its box does, so the bound holds for the truth's correction too."""
    P, K = ext.phi.shape[0], len(s)
    C = np.zeros((3 * K, A.shape[0]))
    C[:, 9:9 + P] = np.moveaxis(ext.phi, 0, 2).reshape(3 * K, P)        # row i K + k: Phi(p_k)[i, :]
    box = np.ones(A.shape[0]) if X is None else np.asarray(X, float)
    try:
        lo, hi = hull.ranges(A.T, s - bound, s + bound, -box, box, C, sweep=True)   # an axis's rows alike
    except hull.Empty:
        return None
    return np.maximum(np.abs(lo), np.abs(hi)).reshape(3, K)


def _hull(A, s, bound, X=None, proofs=None, beyond=None):
    """(lo, hi) of each q over |s_k - a_k^T q| <= bound_k and |q| <= X (default 1: no correction of a fit is as
    large), proven (solve/hull.py), and the multipliers that prove it; from `proofs` alone when given. `beyond`:
    hull.Beyond as soon as an end is proven past it (hull.ranges)."""
    box = np.ones(A.shape[0]) if X is None else np.asarray(X, float)
    args = (A.T, s - bound, s + bound, -box, box, np.eye(A.shape[0]))
    if proofs is not None:
        return (*hull.proven(*args, proofs), None)
    try:
        return hull.ranges(*args, multipliers=True, beyond=beyond)
    except hull.Empty:
        return -box, box, [(np.zeros(len(s)), np.zeros(len(s)))] * A.shape[0]
