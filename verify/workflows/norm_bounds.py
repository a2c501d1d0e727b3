"""The bounds of a norm calibration of 001: the parameters of (1.3) the correction q of (2.2) moves (`fold`,
`parameters`, `parameter_map`), their guaranteed errors over the information set, the a-priori ones of the LP
estimator (3.1)-(3.2) on the orientations present, the optimal plan's, and the orientations worth adding."""
import functools

import numpy as np

from ..defaults import SIGMA_WIDER
from ..io.recordings import median
from ..solve import lp, taylor
from . import norm_information


def fold(M, b, delta, q, g):
    """The calibration corrected by q of (2.2) (lower-triangular scale and misalignment, bias over g,
    and nonlinearity when q has 12 entries)."""
    A = norm_information.lower(q)
    return (np.linalg.solve(np.eye(3) + A, M), b + np.linalg.solve(M, g * q[6:9]),
            delta + q[9:12] if len(q) == 12 else delta)

def guaranteed(mod, n, params, noise, cap=None):
    """Guaranteed error of each parameter on the present directions, and the unidentifiable ones:
    the LP min sum_k noise_k |Phi_k| subject to A Phi = e_nu (noise: each direction's bound, units of g),
    solved as the plain LP (7)-(8) on the columns a_k / noise_k."""
    return estimator(mod, n, params, noise, cap)[1:]


def estimator(mod, n, params, noise, cap=None):
    """The optimal guaranteed estimator on the present directions: weights Phi (K x params) on the norm
    residuals, the guaranteed errors, and the unidentifiable parameters (then Phi and errors are None). With
    `cap` (params, inf where none), the a-priori bounds of q: each a measurement of that q, 0 (the fit holds it
    there) within cap, beside the directions (its weight in Phi is left out: it multiplies a residual of 0)."""
    return lp_estimator(mod.H(n)[:params], noise, cap)


def lp_estimator(A, noise, cap=None):
    """`estimator` on the columns A (parameters x intervals) of any design (H of (2.2), or the information set's
    with the bias columns over |F| and the effects' beside)."""
    w = np.broadcast_to(noise, A.shape[1])
    K = A.shape[1]
    if cap is not None:
        held = np.flatnonzero(np.isfinite(cap))
        A, w = np.hstack([A, np.eye(A.shape[0])[:, held]]), np.r_[w, cap[held]]
    missing = lp.unidentifiable(A)
    if missing:
        return None, None, missing
    Phi, err = lp.primal(A / w)
    return (Phi / w[:, None])[:K], err, []


GAIN = 1.25   # orientations are suggested only when they shrink some bound by at least this factor


def directions_to_add(mod, n, params, noise, err, within_deg=10.0, cap=None):
    """Optimal-plan directions farther than within_deg from every direction present, when adding them
    (each held as well as the log's typical interval: the median noise bound) shrinks some bound by GAIN
    or more: (directions with the angle to the nearest present one, the largest factor and the q it is
    for). Otherwise ([], factor, q)."""
    plan = mod.PLAN[:18] if params == 9 else mod.PLAN
    ang = np.degrees(np.arccos(np.clip(plan @ n, -1, 1))).min(axis=1)
    far = [(p, float(a)) for p, a in zip(plan, ang) if a > within_deg]
    if not far:
        return [], 1.0, None
    n_all = np.column_stack([n, np.array([p for p, _ in far]).T])
    err_all = guaranteed(mod, n_all, params, np.r_[noise, np.full(len(far), median(noise))], cap)[0]
    factor = err / err_all
    k = int(np.argmax(factor))
    found = [(p.tolist(), a) for p, a in far] if factor[k] >= GAIN else []
    return found, float(factor[k]), PARAM_LABELS[k]


def parameters(M_total, b, g):
    """Model parameters of (1.3) relative to the raw axes for a log in m/s^2: lambda, misalignments, eps."""
    P = np.linalg.inv(M_total)
    return np.array([P[0, 0] - 1, P[1, 1] - 1, P[2, 2] - 1, P[1, 0], P[2, 0], P[2, 1], *(b / g)])


PARAM_LABELS = ("lambda1", "lambda2", "lambda3", "alpha", "beta", "gamma", "eps1/g", "eps2/g", "eps3/g",
                "delta1*g", "delta2*g", "delta3*g")
#: A log in raw counts, relative to its raw axes: P = M^-1 in counts per g (the sensitivities S11-S33 on the
#: diagonal, the cross-sensitivities S21, S31, S32 below) and the biases b1-b3 in counts.
COUNT_LABELS = ("S11", "S22", "S33", "S21", "S31", "S32", "b1", "b2", "b3")

def information(mod, res, params, bound, cap=None):
    """(lo, hi) of the corrections q of (2.2) around the fit over the information set: every q with
    |sigma_k - H(n_k)^T q| <= bound_k (each interval's noise plus the remainder the verdict proves) for every
    interval; LPs, each end proven by duality (solve/hull.py), within the LP estimator's interval (which
    holds the set, and is the column box the proofs need)."""
    from ..solve import hull
    A = mod.H(res["n"])[:params]
    s = res["sigma"]
    Phi, e, _ = estimator(mod, res["n"], params, bound, cap)
    centre = Phi.T @ s
    box = (centre - e * (1 + 1e-9) - 1e-15, centre + e * (1 + 1e-9) + 1e-15)
    if cap is not None:                          # the premise itself: |q| <= cap
        box = (np.maximum(box[0], -cap), np.minimum(box[1], cap))
    try:
        lo, hi = hull.ranges(A.T, s - bound, s + bound, *box, np.eye(params))
    except hull.Empty:                           # the verdict found a fit: empty only to HiGHS's tolerance
        return box
    return np.maximum(lo, box[0]), np.minimum(hi, box[1])


@functools.lru_cache(maxsize=None)
def plan_bounds(mod, params):
    """The guaranteed errors of the optimal plan's estimator (noise 1 per direction): one LP per model."""
    plan = mod.PLAN[:18] if params == 9 else mod.PLAN
    best = lp.primal(mod.H(plan.T)[:params])[1]
    best.flags.writeable = False                        # shared by every call
    return best


def bounds(p, v):
    """For data consistent with the noise bound (the problem `p`, norm_problem.NormProblem, and its verdict `v`,
    norm_problem.NormVerdict): the estimate (the midpoint of the information set v.info, (lo, hi) of q, folded into
    the fit v.res), its parameters with guaranteed errors over the same set (each a linear function of q: an LP
    pair, proven), the a-priori ones of the LP estimator (noise + remainder v.rb per interval; v.err the linear
    part), those of the optimal plan, and the orientations worth adding. With catalogue effects, v.exact = (A,
    bound, shift, ext): the set is q = w + s, |s| <= shift, every w with |sigma - A^T w| <= bound
    (norm_information.exact_information), and the effects' parameters are bounded over it too."""
    mod, res, g, params, si = p.mod, v.res, p.g, p.params, p.si
    noise, rb, dsig, err, info, exact, cap = v.noise, v.rb, v.dsig, v.err, v.info, v.exact, v.cap
    from ..solve import hull
    best = plan_bounds(mod, params)
    s = res["sigma"]
    if exact is None:
        A, bnd, shift, ext = mod.H(res["n"])[:params], noise + rb, 0.0, None
        Phi, bound, _ = lp_estimator(A, bnd, cap)
        scale, rest = 1.0, rb
    else:                                                # q = w + s: each interval's own remainder, the shift s
        A, bnd, shift, ext = exact
        Phi, bound, _ = lp_estimator(A, bnd, None if cap is None else np.r_[cap, np.full(len(A) - len(cap), np.inf)])
        bound = bound + shift                              # the estimator's error of w, and q = w + s
        scale = np.sqrt(1.0 - 2.0 * s)                     # noise / |F|: the units of sigma
        rest = bnd - noise * scale
    lo, hi = info
    dq, half = taylor.midrad(lo, hi)
    M, b, delta = fold(res["M"], res["b"], res["delta"], dq[:params], g)
    # relative to the raw axes; a log in counts in counts per g (its sensitivities P g) and counts (biases): the
    # same parameters of M / g and b g, whose map from q is as exactly linear (fold)
    unit = 1.0 if si else 1.0 / g
    pars = parameters(M * unit, b / unit, g).tolist() + delta.tolist()[: params - 9]
    extra = A.shape[0] - params                          # the effects' parameters: no printed parameter moves with them
    J = np.hstack([parameter_map(res["M"] * unit, params), np.zeros((params, extra))])
    p_lo, p_hi = hull.ranges(A.T, s - bnd, s + bnd, lo - shift, hi + shift, J)
    reach = np.abs(J) @ np.broadcast_to(shift, lo.shape)          # the absorbed shift s of q, |s| <= shift
    p_lo, p_hi = p_lo - reach, p_hi + reach
    p_half = np.minimum(np.maximum(p_hi - J @ dq, J @ dq - p_lo) * (1 + taylor.SUM_ERROR),
                        parameter_bounds(res["M"] * unit, half[:params]))
    p_wider = _wider(p, v, A, Phi, SIGMA_WIDER * noise * scale + rest, shift, J if si else np.hstack(
        [np.eye(params), np.zeros((params, extra))]), dq, unit)
    q = pars if si else None
    counts = None if si else {"sensitivity": dict(zip(COUNT_LABELS, (np.array(pars[:9]) + [1, 1, 1, 0, 0, 0, 0, 0, 0])
                                                        .tolist())),
                              "error": dict(zip(COUNT_LABELS, p_half[:9].tolist()))}
    effects = {}
    if ext is not None:
        effects["effects"] = ext.effects_out(lo[params:], hi[params:], bound[params:])
        if getattr(ext, "thermal_range", None) is not None:
            from . import norm_thermal
            effects["thermal"] = norm_thermal.block(ext, A, s, bnd, lo, hi, np.broadcast_to(shift, lo.shape),
                                                    res["M"], res["b"], g, dq, parameter_map(res["M"], 9))
            effects["definitions"] = dict(norm_thermal.DEFINITIONS)
        half, bound, err = half[:params], bound[:params], err[:params]
    found, factor, which = directions_to_add(mod, res["n"], params, noise, err, cap=cap)
    if params in (9, 12):                                 # what apply bounds each sample's error over
        from . import sample_set
        order = np.arange(len(lo)) if ext is None else _applied_first(ext)
        effects["_information_set"] = sample_set.entry(A[order], s, bnd, lo[order], hi[order],
                                                       np.broadcast_to(shift, lo.shape)[order], dq[order])
    return {
        "matrix": M.tolist(), "bias": b.tolist(), "nonlinearity_delta_g": delta.tolist() if params == 12 else None,
        "matrix_fit": res["M"].tolist(),
        "parameters": None if q is None else dict(zip(PARAM_LABELS, q)),
        # the printed parameters' bounds over the information set (relative to the raw axes, affine in q); for
        # a log in raw units, those of (1.3)'s parameters of the calibrated block, as q itself
        "guaranteed_error": dict(zip(PARAM_LABELS, (p_half if si else half).tolist())),
        "guaranteed_error_a_priori": dict(zip(PARAM_LABELS, (parameter_bounds(res["M"], bound) if si
                                                             else bound).tolist())),
        "guaranteed_error_linear": dict(zip(PARAM_LABELS, (parameter_bounds(res["M"], err) if si else err).tolist())),
        "guaranteed_error_optimal_plan": dict(zip(PARAM_LABELS, (parameter_bounds(res["M"], best * dsig) if si
                                                                 else best * dsig).tolist())),
        "guaranteed_error_q": dict(zip(PARAM_LABELS, half.tolist())),
        "sigma_wider": SIGMA_WIDER,
        "guaranteed_error_sigma_wider": dict(zip(PARAM_LABELS, p_wider.tolist())),
        "guaranteed_error_q_a_priori": dict(zip(PARAM_LABELS, bound.tolist())),
        "directions_to_add": [{"n": d, "nearest_present_deg": a} for d, a in found],
        "directions_gain": {"factor": factor, "parameter": which, "threshold": GAIN},
        "raw_axes_counts": counts,
        **effects,
    }


def _applied_first(ext):
    """The set's columns in the calibration file's order: q's 9, the effects a file applies (in the order named), then
    those it does not (norm_effects.SESSION_ONLY: their columns stay in the set, which is over them too, and no
    sample's error moves with them)."""
    from .norm_effects import SESSION_ONLY
    cols, at = {}, 9
    for x in ext.names:
        cols[x] = list(range(at, at + len(ext.mod.EFFECTS[x])))
        at += len(ext.mod.EFFECTS[x])
    return np.array(list(range(9)) + [c for x in ext.names if x not in SESSION_ONLY for c in cols[x]]
                    + [c for x in ext.names if x in SESSION_ONLY for c in cols[x]])


def _wider(p, v, A, Phi, wider, shift, C, dq, unit):
    """The bounds of the printed parameters (C q: J on a log in m/s^2, q itself in counts) had each interval's noise
    bound been SIGMA_WIDER times larger (`wider`, the remainder as proven): the ranges over that wider set, within
    the LP estimator's box for it (`Phi`, or the premise's estimator with a cap), about the estimate's q `dq`."""
    from ..solve import hull
    s, lo_shape = v.res["sigma"], v.info[0].shape
    centre, e_w = Phi.T @ s, (np.abs(Phi).T @ np.broadcast_to(wider, s.shape)) * (1 + 1e-9) + 1e-15
    if v.cap is not None:                          # the held q's measurements of 0 within cap count too
        Phi_w, e_w, _ = lp_estimator(A, wider, np.r_[v.cap, np.full(len(A) - len(v.cap), np.inf)])
        centre, e_w = Phi_w.T @ s, e_w * (1 + 1e-9) + 1e-15
    try:
        w_lo, w_hi = hull.ranges(A.T, s - wider, s + wider, centre - e_w, centre + e_w, C)
    except hull.Empty:                           # it holds the set the verdict found a fit in
        w_lo, w_hi = C @ (centre - e_w), C @ (centre + e_w)
    reach = np.abs(C) @ np.broadcast_to(shift, lo_shape)
    w_lo, w_hi, mid = w_lo - reach, w_hi + reach, C @ dq
    return np.minimum(np.maximum(w_hi - mid, mid - w_lo) * (1 + taylor.SUM_ERROR),
                      parameter_bounds(v.res["M"] * unit, e_w[:p.params]) if p.si else e_w[:p.params])


def parameter_map(M_fit, params):
    """J (params x params): the printed parameters' change for a correction q of the fit M_fit, exactly linear
    (P = inv(M) moves by P_fit dA, b/g by P_fit dq_b, delta by dq_delta: `fold`)."""
    P = np.linalg.inv(M_fit)
    J = np.zeros((params, params))
    for j in range(params):
        e = np.zeros(params)
        e[j] = 1.0
        A = norm_information.lower(e)
        PA = P @ A
        J[:, j] = [PA[0, 0], PA[1, 1], PA[2, 2], PA[1, 0], PA[2, 0], PA[2, 1], *(P @ e[6:9]), *e[9:params]]
    return J


def parameter_bounds(M_fit, e):
    """Bounds of the printed parameters from bounds e of q (2.2) around the fit M_fit. The estimate and
    the truth are (I + A) corrections of M_fit (fold), so P = inv(M) moves by P_fit dA and b/g by
    P_fit dq_b, exactly linear: |P_fit| |dA| and |P_fit| |dq_b| bound them (componentwise)."""
    e = np.asarray(e, float)
    Pabs = np.abs(np.linalg.inv(M_fit))
    E = norm_information.lower(e)
    EP = Pabs @ E
    out = np.array([EP[0, 0], EP[1, 1], EP[2, 2], EP[1, 0], EP[2, 0], EP[2, 1], *(Pabs @ e[6:9]), *e[9:]])
    return np.nextafter(out, np.inf)
