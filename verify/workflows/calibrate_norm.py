"""Calibration of a real accelerometer log through the norm relation (2.2) of 001.

The still intervals give mean raw vectors r_k. The calibration a = M (r - b) (M lower-triangular,
m/s^2 per raw unit) is found by iterating on the exact |f|: calibrate with the current M, b, form
sigma_k and n_k, fit the small corrections q by the Chebyshev (minimax) fit of (2.2) in the
guaranteed sense, fold them into M, b, and repeat until the corrections vanish. The guaranteed error
of each parameter on the directions actually present is the LP (3.1)-(3.2) on those directions with
each interval's own noise bound: --delta-sigma, or the noise rule from the data (never the fit's own
residual, which would make the bounds circular), plus the proven remainder (2.3) around the fit.
"""
import numpy as np

from ..errors import DataError, opt
from ..io.recordings import raw_unit
from ..solve import highs, lp
from . import norm_information, norm_noise
from .norm_noise import noise_axes, noise_rule, noise_rule_name
from .norm_bounds import PARAM_LABELS, bounds, fold, guaranteed, information, parameter_map

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


def linearisation_remainder(mod, e, params):
    """The proven bound (2.3) of 001 for errors within e around the fit (units as PARAM_LABELS):
    second order; the noise itself is delta_sigma_max, not counted twice (df = 0); g is taken as exact."""
    return float(mod.remainder_bound(k_max=e[:3].max(), v_max=e[3:6].max(), eps_max=e[6:9].max(),
                                     delta_max=e[9:12].max() if params == 12 else 0.0, df_max=0.0, dg_max=0.0))


def weighted_fit(Hk, s, bounds):
    """min over q of max_k |s_k - Hk[:, k] . q| / bounds_k (HiGHS): the fit in units of each noise bound."""
    q, t, _ = highs.chebyshev_fit(Hk, s, weights=bounds)
    return q, t
