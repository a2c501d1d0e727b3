"""Calibration of a real accelerometer log through the norm relation (2.2) of 001.

The still intervals give mean raw vectors r_k. The calibration a = M (r - b) (M lower-triangular,
m/s^2 per raw unit) is found by iterating on the exact |f|: calibrate with the current M, b, form
sigma_k and n_k, fit the small corrections q by the Chebyshev (minimax) fit of (2.2) in the
guaranteed sense, fold them into M, b, and repeat until the corrections vanish. The guaranteed error
of each parameter on the directions actually present is the LP (3.1)-(3.2) on those directions with
each interval's own noise bound: --delta-sigma, or the noise rule from the data (never the fit's own
residual, which would make the bounds circular), plus the proven remainder (2.3) around the fit.
"""
import functools

import numpy as np

from ..errors import DataError, opt
from ..io.recordings import median, raw_unit
from ..solve import highs, lp, taylor
from . import norm_information, norm_noise
from .norm_noise import noise_axes, noise_rule, noise_rule_name
from .guarantee import SIGMA_WIDER

MAX_ITER = 60
#: The largest correction one step of the fit may make (a scale of 50 %, half a radian): a larger one is
#: a fit running away on orientations that do not hold the parameters apart, stopped and said.
MAX_STEP = 0.5
#: A still interval's direction within this angle (degrees) of a sensor axis is taken as the axis when
#: asking what the orientations identify (six faces held by hand are axes to within it).
ON_AXIS_DEG = 1.0
#: Still intervals whose directions lie within this angle (degrees) hold one orientation.
SAME_ORIENTATION_DEG = 5.0


def chebyshev_fit(Hk, s):
    """min over q of max_k |s_k - Hk[:, k] . q| (HiGHS): q and the minimax residual."""
    q, t, _ = highs.chebyshev_fit(Hk, s)
    return q, t


def initial_map(raw, g):
    """Identity for logs already near g in m/s^2; else an axis-aligned ellipsoid fit."""
    if raw_unit(raw, g) == "m/s^2":
        return np.eye(3), np.zeros(3), "log in m/s^2: starting from the identity"
    mu, scale = raw.mean(axis=0), raw.std(axis=0).max()
    x = (raw - mu) / scale                                   # centred and scaled for conditioning
    X = np.column_stack([x**2, x])
    p, *_ = np.linalg.lstsq(X, np.ones(len(raw)), rcond=None)
    if np.any(p[:3] <= 0):
        raise DataError("the still intervals do not span an ellipsoid; cannot start the fit", param="log")
    c = -p[3:] / (2 * p[:3])
    R2 = 1 + np.sum(p[:3] * c**2)
    axes = scale * np.sqrt(R2 / p[:3])
    return np.diag(g / axes), mu + scale * c, "raw units: starting from an axis-aligned ellipsoid fit"


def pendulosity(mod, n, delta):
    """D(n) of (1.3) over g: delta_l n_idx(l) n_l, for directions n (3, K)."""
    return np.array([delta[k] * n[mod.AXES[k] - 1] * n[k] for k in range(3)])


def calibrated(mod, raw, M, b, delta, g):
    """The readings calibrated by M, b and the nonlinearity delta, over g: shape (K, 3)."""
    f = (raw - b) @ M.T / g                                  # (K, 3), units of g
    n = f.T / np.linalg.norm(f, axis=1)
    return (f.T - pendulosity(mod, n, delta)).T


def sigma_and_n(f):
    """sigma of (2.2) of 001 and the direction n of each calibrated reading f (K, 3) in units of g."""
    r2 = np.sum(f**2, axis=1)
    return (r2 - 1) / (2 * r2), (f / np.sqrt(r2)[:, None]).T


def fold(M, b, delta, q, g):
    """The calibration corrected by q of (2.2) (lower-triangular scale and misalignment, bias over g,
    and nonlinearity when q has 12 entries)."""
    A = norm_information.lower(q)
    return (np.linalg.solve(np.eye(3) + A, M), b + np.linalg.solve(M, g * q[6:9]),
            delta + q[9:12] if len(q) == 12 else delta)


def fit(mod, raw, g, params=9, ext=None, start=None, weights=None, free=None):
    """Iterate the norm relation to convergence: M, b, delta (12 params), residuals, iterations. With catalogue
    effects (`ext`, norm_effects.Extension) their parameters ext.theta are fitted beside, the term evaluated at
    the direction p of M (raw - b) and taken out of the reading; then p is in the result. `start`: (M, b, note)
    to start from (default `initial_map`); `weights`: each interval's noise bound, the fit then minimax in their
    units (many parameters on few intervals: the plain fit would follow the noisiest); `free`: the corrections
    fitted (default all; the rest stay 0: misalignments the orientations cannot identify, bounded by a premise)."""
    M, b, note = initial_map(raw, g) if start is None else start
    delta = np.zeros(3)
    for it in range(1, MAX_ITER + 1):
        s, n, p = _state(mod, raw, M, b, delta, g, ext)
        A = mod.H(n)[:params] if ext is None else np.vstack([mod.H(n)[:params], ext.columns(n)])
        if free is not None:
            q = np.zeros(A.shape[0])
            q[free] = chebyshev_fit(A[free], s)[0]
        else:
            q, _ = chebyshev_fit(A, s) if weights is None else weighted_fit(A, s, weights)
        if not np.all(np.isfinite(q)) or np.abs(q[:params]).max() > MAX_STEP:
            k = int(np.nanargmax(np.where(np.isfinite(q), np.abs(q), np.inf)))
            raise Diverged(f"the norm fit diverges at step {it} (a correction of {q[k]:+.3g} to "
                           f"{(PARAM_LABELS[:params] + tuple(ext.labels if ext else ()))[k]})")
        if ext is not None and weights is not None:     # halved while the worst residual grows
            q = _damped(mod, raw, M, b, delta, g, ext, weights, q, float(np.max(np.abs(s) / weights)))
        M, b, delta = fold(M, b, delta, q[:params], g)
        if ext is not None:
            ext.theta = ext.theta + q[params:]
        if np.abs(q[:params]).max() < 1e-12 and np.all(np.abs(q[params:]) * np.abs(A[params:]).max(axis=1) < 1e-12):
            break
    s, n, p = _state(mod, raw, M, b, delta, g, ext)
    return dict(M=M, b=b, delta=delta, sigma=s, n=n, iterations=it, note=note, p=p)


#: Halvings of a step of the fit with effects at most (the last one is taken: 2^-40 of a step is no step).
HALVINGS = 40


def _damped(mod, raw, M, b, delta, g, ext, weights, q, worst):
    """The step q of the fit with effects, halved until the worst residual in units of `weights` does not grow
    (a Chebyshev step on nearly dependent columns may overshoot far beyond where the linearisation holds)."""
    theta = ext.theta
    for _ in range(HALVINGS):
        M2, b2, d2 = fold(M, b, delta, q[:9], g)
        ext.theta = theta + q[9:]
        s2 = _state(mod, raw, M2, b2, d2, g, ext)[0]
        ext.theta = theta
        if np.max(np.abs(s2) / weights) <= worst * (1 + 1e-12):
            return q
        q = q / 2
    return q


def _state(mod, raw, M, b, delta, g, ext):
    """sigma and n of (2.2) for the calibration M, b, delta and the effects' term, and the direction p the term is
    evaluated at (fixed in `ext` with n): the fixed point p = n of the reading with the term taken out, so that
    the truth's direction m, near n, is near p too (norm_effects.FIXED_POINT)."""
    F = calibrated(mod, raw, M, b, delta, g)
    p = F.T / np.linalg.norm(F, axis=1)
    if ext is not None:
        F, p = ext.fixed_point(F)
    s, n = sigma_and_n(F)
    if ext is not None:
        ext.at(p, n)
    return s, n, p


class Diverged(DataError):
    """A norm fit that runs away (a step beyond MAX_STEP): the orientations do not hold the parameters apart."""


def orientations(n, within_deg=SAME_ORIENTATION_DEG):
    """The distinct orientations among directions n (3, K): a representative of each group of directions
    within `within_deg` of it (greedy, in order)."""
    reps = []
    for d in n.T:
        if all(np.degrees(np.arccos(np.clip(d @ r, -1, 1))) > within_deg for r in reps):
            reps.append(d)
    return np.array(reps)


def _identifiable(mod, stills, n, params, path, within_deg=ON_AXIS_DEG, cause="", premise=None):
    """Before the fit: the parameters the orientations present identify, structurally: each direction
    within `within_deg` of a sensor axis taken as that axis (six faces, each axis up and down, are axes
    to within a degree), an exact rank test of (2.2) of 001 on them. The parameters they cannot identify
    are named with the orientations to add, and nothing is fitted (a fit on them runs away). After a fit
    that ran away (`cause`), the same statement with the orientations' own distance from the axes. With a
    `premise` ({misalignment: its bound, rad}) that bounds each misalignment they cannot identify (six faces
    along the axes: the misalignments enter (2.2) of 001 only at second order there), the scale factors and
    biases are calibrated: returns the indices the premise bounds; a premise these orientations do not need is
    refused."""
    axes = np.vstack([np.eye(3), -np.eye(3)])
    snapped = np.array([axes[np.argmax(axes @ d)] if np.degrees(np.arccos(np.clip((axes @ d).max(), -1, 1)))
                        <= within_deg else d for d in n.T]).T
    unseen = lp.unidentifiable(mod.H(snapped)[:params])
    if premise and not cause:
        if not unseen:
            raise DataError(f"{path}: --bound {', '.join(premise)}: these orientations identify the misalignments; "
                            "a bound on them is taken only where they cannot (each orientation along an axis)",
                            param="bound")
        if set(unseen) <= {3, 4, 5} and all(PARAM_LABELS[k] in premise for k in unseen):
            return list(unseen)
    if not unseen:
        if cause:
            raise DataError(f"{path}: {cause}; record orientations between the axes (garant plan --model norm)",
                            param="log")
        return
    distinct = orientations(n)
    on_axes = all(np.abs(d).max() > np.cos(np.radians(within_deg)) for d in distinct)
    seen = [PARAM_LABELS[k] for k in range(params) if k not in unseen]
    add = [p for p in (mod.PLAN[:18] if params == 9 else mod.PLAN)
           if np.degrees(np.arccos(np.clip(distinct @ p, -1, 1))).min() > 10.0][:6]
    raise DataError(f"{path}: " + (f"{cause}: " if cause else "") + f"{len(stills)} still intervals in "
                    f"{len(distinct)} distinct orientation(s)"
                    + (f", each along an axis (within {within_deg:.2g} degree)" if on_axes else "")
                    + ": they cannot identify " + ", ".join(PARAM_LABELS[k] for k in unseen)
                    + (" (a misalignment enters the norm only at second order when every orientation lies along an "
                       "axis)" if on_axes and any(3 <= k < 6 for k in unseen) else "")
                    + (f"; they would identify {', '.join(seen)}" if seen else "")
                    + (f" (state bounds on {', '.join(PARAM_LABELS[k] for k in unseen)}, e.g. --bound "
                       f"{PARAM_LABELS[unseen[0]]}=1e-3 in rad, to calibrate them with those as a premise)"
                       if set(unseen) <= {3, 4, 5} else "")
                    + "; add orientations such as "
                    + ", ".join("(" + ", ".join(f"{v:+.3f}" for v in p) + ")" for p in add)
                    + " (garant plan --model norm lists them all)", param="log")


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
    A = mod.H(n)[:params]
    w = np.broadcast_to(noise, A.shape[1])
    if cap is not None:
        held = np.flatnonzero(np.isfinite(cap))
        A, w = np.hstack([A, np.eye(params)[:, held]]), np.r_[w, cap[held]]
    missing = lp.unidentifiable(A)
    if missing:
        return None, None, missing
    Phi, err = lp.primal(A / w)
    return (Phi / w[:, None])[:len(n.T)], err, []


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


def run(mod, stills, g, params, path, delta_sigma=None, quantum=0.0, ext=None, premise=None):
    """The whole calibration of a log's still intervals: the dictionary the CLI prints and writes.

    The noise bound delta_sigma_max is --delta-sigma when given, else the noise rule from the data
    (never the fit's own residual). The verdict first: the data are consistent when the minimax
    residual of the exact norm relation is within delta_sigma_max plus the proven remainder (2.3)
    of the linearisation around the fit; if not, no bound is given. With catalogue effects (`ext`,
    norm_effects.Extension) the relation carries their columns and each interval's remainder their rest
    (norm_effects), and every bound is over the information set of that extended relation. `premise`
    ({misalignment: bound, rad}, --bound): where the orientations cannot identify the misalignments (each along
    an axis), the scale factors and biases are fitted and the misalignments held within it (`_identifiable`)."""
    need = params + 3 + (len(ext.labels) if ext else 0)
    if len(stills) < need:
        raise DataError(f"{path}: found only {len(stills)} still interval(s); a {params}-parameter "
                        f"calibration needs at least {need} (record more orientations, each held still for at least "
                        f"{opt('min_still')} s)")
    raw = np.array([s.mean for s in stills])
    M0, b0, _ = initial_map(raw, g)
    before, n0 = sigma_and_n(calibrated(mod, raw, M0, b0, np.zeros(3), g))
    free = held = None
    if premise:
        if ext is not None:
            raise DataError(f"{path}: --bound (the misalignments of six faces) and --effect are not taken together",
                            param="bound")
        off = max(np.degrees(np.arccos(np.clip(np.abs(d).max(), -1, 1))) for d in orientations(n0))
        held = _identifiable(mod, stills, n0, params, path, max(off * 1.01, ON_AXIS_DEG), premise=premise)
        free = [k for k in range(params) if k not in held]
    else:
        _identifiable(mod, stills, n0, params, path)
    if ext is not None:
        ext.at(n0, n0)
        missing = ext.identifiable(mod.H(n0)[:params])
        if missing:
            raise DataError(f"{path}: beside scale, misalignment and bias these orientations cannot identify "
                            f"{', '.join(missing)} of {ext.option} (--diagnose lists the effects "
                            "they cannot tell apart): add fewer effects, or orientations", param="log")
    try:
        res = fit(mod, raw, g, params, free=free)
    except Diverged as e:                      # say what the orientations, as they lie, cannot hold apart
        off = max(np.degrees(np.arccos(np.clip(np.abs(d).max(), -1, 1))) for d in orientations(n0))
        _identifiable(mod, stills, n0, params, path, max(off * 1.01, ON_AXIS_DEG), str(e))
    if ext is not None:     # from the base model's fit, in units of each interval's noise bound
        rule = noise_rule(stills, res["M"], res["n"], g, quantum)
        worst = [weighted_fit(mod.H(res["n"])[:params], res["sigma"], rule)[1]]
        res = fit(mod, raw, g, params, ext, (res["M"], res["b"], res["note"]),
                  rule if delta_sigma is None else np.full(len(stills), delta_sigma))
    fit_residual = float(np.abs(res["sigma"]).max())
    rule = noise_rule(stills, res["M"], res["n"], g, quantum)
    dsig = float(rule.max()) if delta_sigma is None else delta_sigma
    source = "--delta-sigma" if delta_sigma is not None else noise_rule_name(stills, quantum)
    si = raw_unit(raw, g) == "m/s^2"
    if delta_sigma is None:
        noise = np.minimum(rule, dsig)
    elif si:      # a raw error of norm D g moves the calibrated reading along n by at most |M^T n| D g
        noise = dsig * np.linalg.norm(res["M"].T @ res["n"], axis=0) * (1 + 1e-12)
    else:
        noise = np.full(len(stills), dsig)
    cap = None if held is None else misalignment_cap(res["M"], params, premise, held, si)
    err, missing = guaranteed(mod, res["n"], params, noise, cap)
    if missing:
        raise DataError(f"{path}: the {len(stills)} orientations cannot identify "
                        f"{', '.join(mod.Q_NAMES[k] for k in missing)}; add orientations", param="log")
    nu = (np.linalg.norm(np.abs(res["M"]) @ noise_axes(stills, quantum).T, axis=0) / g if delta_sigma is None
          else np.full(len(stills), np.linalg.norm(res["M"], 2) * dsig))
    info = box = exact = None
    if ext is not None:
        if params != 9 or not (delta_sigma is None or si):
            raise DataError(f"{path}: --effect takes the 9-parameter model (cross_coupling holds the nonlinearity of "
                            "--params 12 as a case) and, on a log in counts, the noise rule (no --delta-sigma)",
                            param="effects")
        consistent, A, bnd, err = ext.verdict(res, noise, nu)
        base = noise * np.sqrt(1.0 - 2.0 * res["sigma"])             # noise / |F|, the units of sigma
        rb = float((bnd - base).max())
        if consistent:
            found = norm_information.exact_information(mod, res, noise, nu, ext, bnd)
            if found is None:
                raise DataError(f"{path}: consistent with {ext.option}, but the remainder of the "
                                "extended relation cannot be proven from any box around the fit: no bound",
                                param="effects")
            info, rb_k, box, shift = found
            rb, bnd = float(rb_k.max()), base + rb_k
            exact = (A, bnd, shift, ext)
            # each contraction's set holds the truth when the premise box does; their common part is empty when
            # no correction within it meets every interval's bound: the data refute the extended relation there
            consistent = weighted_fit(A, res["sigma"], bnd)[1] <= 1.0
    else:
        rb = linearisation_remainder(mod, err, params)
        rb = linearisation_remainder(mod, guaranteed(mod, res["n"], params, noise + rb, cap)[0], params)
        bnd = noise + rb
        consistent = bool(np.all(np.abs(res["sigma"]) <= bnd)) if cap is None else held_fit(
            mod.H(res["n"])[:params], res["sigma"], bnd, cap) <= 1.0
    if ext is None and consistent and params == 9 and (delta_sigma is None or si):
        found = norm_information.exact_information(mod, res, noise, nu, cap=cap)
        if found is not None:
            info, rb_k, box, _ = found
            rb = float(rb_k.max())
    if consistent and info is None:
        info = information(mod, res, params, noise + rb, cap)
    out = {
        "log": path, "g": g, "params": params, "intervals": len(stills), "iterations": res["iterations"],
        "start": res["note"], "raw_unit": raw_unit(raw, g), "matrix": res["M"].tolist(), "bias": res["b"].tolist(),
        "nonlinearity_delta_g": res["delta"].tolist() if params == 12 else None,
        "consistent": bool(consistent), "minimax_residual": fit_residual, "delta_sigma_max": dsig,
        "delta_sigma_source": source, "remainder_bound": rb,
        "premises": {"statement": "the bounds hold if " + norm_noise.premise(dsig, source, delta_sigma is not None, si,
                                                                             g)
                     + f"; the gravity is g = {g:g} m/s^2 "
                     "(its error Delta_g/g enters lambda_i* = lambda_i - Delta_g/g, (2.2) of 001; the remainder "
                     + ("takes g as exact" if box is not None else "of (2.3) takes g and delta_f as exact")
                     + "); the orientations are still" + norm_information.premise_box(box)
                     + _misalignment_premise(premise, held), "g": g, "noise_bound": dsig, "noise_source": source},
        "sigma_min_supported": max(fit_residual - rb, 0.0),
        "per_interval": [{"start_s": s.start, "stop_s": s.stop, "raw_mean": s.mean.tolist(),
                          "noise_rule": float(nr), "noise_bound": float(nb),
                          "noise_source": "its noise rule" if delta_sigma is None else source,
                          "residual_before_ms2": float(g * sb),
                          "residual_after_ms2": float(g * sa), "direction": d.tolist()}
                         for s, nr, nb, sb, sa, d in zip(stills, rule, np.broadcast_to(noise, rule.shape), before,
                                                         res["sigma"], res["n"].T)],
    }
    if held is not None:
        out["misalignment_premise"] = {PARAM_LABELS[k]: float(premise[PARAM_LABELS[k]]) for k in held}
    if ext is not None:
        worst.append(weighted_fit(np.vstack([mod.H(res["n"])[:params], ext.columns(res["n"])]), res["sigma"], rule)[1])
        out["model_discrepancy"] = {"max_residual_before": float(worst[0]), "max_residual_after": float(worst[1]),
                                    "units": "each interval's noise rule (first order of (2.2) of 001, no remainder)"}
        out["effect_names"] = list(ext.names)
        out["effect_reference"] = {"time_s": ext.t_ref, "temp_c": ext.temp_ref}
    if not consistent:
        out["disagreements"] = [int(k) + 1 for k in np.flatnonzero(np.abs(res["sigma"]) > bnd)]
        return out
    out.update(bounds(mod, res, raw, g, params, noise, rb, dsig, err, info, exact, cap))
    return out


def misalignment_cap(M_fit, params, premise, held, si):
    """The bound of each held correction q_k (the fit keeps it 0) from the premise on the printed misalignment:
    on a log in m/s^2 the printed misalignment moves by J_kk q_k alone when the fit's M is diagonal
    (`parameter_map`: P = inv(M) moves by P_fit dA, exactly), so |q_k| <= bound / |J_kk|; on a log in counts
    the printed parameters are q."""
    cap = np.full(params, np.inf)
    J = parameter_map(M_fit, params) if si else np.eye(params)
    for k in held:
        if np.count_nonzero(J[k]) != 1:
            raise DataError("the fit's M is not diagonal: a misalignment premise cannot be carried to q", param="bound")
        cap[k] = premise[PARAM_LABELS[k]] / abs(J[k, k]) * (1 + 1e-12)
    return cap


def held_fit(H, s, bound, cap):
    """The weighted minimax residual (`weighted_fit`) with each held q_k also a measurement of 0 within cap_k:
    within 1 when some correction within the premise meets every interval's bound."""
    held = np.flatnonzero(np.isfinite(cap))
    return weighted_fit(np.hstack([H, np.eye(H.shape[0])[:, held]]), np.r_[s, np.zeros(len(held))],
                        np.r_[bound, cap[held]])[1]


def _misalignment_premise(premise, held):
    """The misalignment premise in words, or empty."""
    if held is None:
        return ""
    return ("; the misalignments are within " + ", ".join(f"|{PARAM_LABELS[k]}| <= {premise[PARAM_LABELS[k]]:g} rad"
                                                        for k in held)
            + " (--bound, stated: each orientation lies along an axis, where they enter (2.2) of 001 only at second "
              "order, so the data cannot bound them)")


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


def bounds(mod, res, raw, g, params, noise, rb, dsig, err, info, exact=None, cap=None):
    """For data consistent with the noise bound: the estimate (the midpoint of the information set `info`,
    (lo, hi) of q, folded into the fit `res`), its parameters with guaranteed errors over the same set (each a
    linear function of q: an LP pair, proven), the a-priori ones of the LP estimator (noise + remainder rb per
    interval; `err` the linear part), those of the optimal plan, and the orientations worth adding. With catalogue
    effects, `exact` = (A, bound, shift, ext): the set is q = w + s, |s| <= shift, every w with |sigma - A^T w| <=
    bound (norm_information.exact_information), and the effects' parameters are bounded over it too."""
    from ..solve import hull
    best = plan_bounds(mod, params)
    s = res["sigma"]
    if exact is None:
        A, bnd, shift, ext = mod.H(res["n"])[:params], noise + rb, 0.0, None
        Phi, bound, _ = estimator(mod, res["n"], params, noise + rb, cap)
        scale, rest = 1.0, rb
    else:
        A, bnd, shift, ext = exact
        Phi, bound = lp.primal(A / bnd)
        Phi, bound = Phi / bnd[:, None], bound + shift       # the estimator's error of w, and q = w + s
        scale = np.sqrt(1.0 - 2.0 * s)                     # noise / |F|: the units of sigma
        rest = bnd - noise * scale
    lo, hi = info
    dq, half = taylor.midrad(lo, hi)
    M, b, delta = fold(res["M"], res["b"], res["delta"], dq[:params], g)
    si = raw_unit(raw, g) == "m/s^2"
    # relative to the raw axes; a log in counts in counts per g (its sensitivities P g) and counts (biases): the
    # same parameters of M / g and b g, whose map from q is as exactly linear (fold)
    unit = 1.0 if si else 1.0 / g
    p = parameters(M * unit, b / unit, g).tolist() + delta.tolist()[: params - 9]
    extra = A.shape[0] - params                          # the effects' parameters: no printed parameter moves with them
    J = np.hstack([parameter_map(res["M"] * unit, params), np.zeros((params, extra))])
    p_lo, p_hi = hull.ranges(A.T, s - bnd, s + bnd, lo - shift, hi + shift, J)
    reach = np.abs(J) @ np.broadcast_to(shift, lo.shape)          # the absorbed shift s of q, |s| <= shift
    p_lo, p_hi = p_lo - reach, p_hi + reach
    p_half = np.minimum(np.maximum(p_hi - J @ dq, J @ dq - p_lo) * (1 + taylor.SUM_ERROR),
                        parameter_bounds(res["M"] * unit, half[:params]))
    # had each interval's noise bound been SIGMA_WIDER times larger (the remainder as proven): the ranges
    # over that wider set, within the LP estimator's box for it
    wider = SIGMA_WIDER * noise * scale + rest
    centre, e_w = Phi.T @ s, (np.abs(Phi).T @ np.broadcast_to(wider, s.shape)) * (1 + 1e-9) + 1e-15
    if cap is not None:                          # the held q's measurements of 0 within cap count too
        Phi_w, e_w, _ = estimator(mod, res["n"], params, wider, cap)
        centre, e_w = Phi_w.T @ s, e_w * (1 + 1e-9) + 1e-15
    C = J if si else np.hstack([np.eye(params), np.zeros((params, extra))])
    try:
        w_lo, w_hi = hull.ranges(A.T, s - wider, s + wider, centre - e_w, centre + e_w, C)
    except hull.Empty:                           # it holds the set the verdict found a fit in
        w_lo, w_hi = C @ (centre - e_w), C @ (centre + e_w)
    w_lo, w_hi = w_lo - np.abs(C) @ np.broadcast_to(shift, lo.shape), w_hi + np.abs(C) @ np.broadcast_to(shift,
                                                                                                          lo.shape)
    mid = C @ dq
    p_wider = np.minimum(np.maximum(w_hi - mid, mid - w_lo) * (1 + taylor.SUM_ERROR),
                         parameter_bounds(res["M"] * unit, e_w[:params]) if si else e_w[:params])
    q = p if si else None
    counts = None if si else {"sensitivity": dict(zip(COUNT_LABELS, (np.array(p[:9]) + [1, 1, 1, 0, 0, 0, 0, 0, 0])
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


def linearisation_remainder(mod, e, params):
    """The proven bound (2.3) of 001 for errors within e around the fit (units as PARAM_LABELS):
    second order; the noise itself is delta_sigma_max, not counted twice (df = 0); g is taken as exact."""
    return float(mod.remainder_bound(k_max=e[:3].max(), v_max=e[3:6].max(), eps_max=e[6:9].max(),
                                     delta_max=e[9:12].max() if params == 12 else 0.0, df_max=0.0, dg_max=0.0))


def weighted_fit(Hk, s, bounds):
    """min over q of max_k |s_k - Hk[:, k] . q| / bounds_k (HiGHS): the fit in units of each noise bound."""
    q, t, _ = highs.chebyshev_fit(Hk, s, weights=bounds)
    return q, t
