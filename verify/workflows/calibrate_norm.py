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
from ..solve import highs, lp
from . import norm_information, norm_noise
from .norm_noise import noise_axes, noise_rule, noise_rule_name
from .norm_bounds import PARAM_LABELS, bounds, fold, guaranteed, information, parameter_map
from .norm_problem import NormVerdict

MAX_ITER = 60
#: The largest correction one step of the fit may make (a scale of 50 %, half a radian): a larger one is
#: a fit running away on orientations that do not hold the parameters apart, stopped and said.
MAX_STEP = 0.5
#: A still interval's direction within this angle (degrees) of a sensor axis is taken as the axis when
#: asking what the orientations identify (six faces held by hand are axes to within it).
ON_AXIS_DEG = 1.0
#: The misalignment premise (--bound) is for six faces: every still interval's direction within this angle (degrees)
#: of a sensor axis. The misalignments' first-order term at each interval's own direction is carried in the set (its
#: column of (2.2) of 001, the premise holding it), so the angle is no soundness limit: beyond it the orientations are
#: no longer faces, and whether they identify the misalignments is their own question (calibrate-norm without
#: --bound answers it).
FACE_TOLERANCE_DEG = 10.0
#: Still intervals whose directions lie within this angle (degrees) hold one orientation.
SAME_ORIENTATION_DEG = 5.0


def chebyshev_fit(Hk, s):
    """min over q of max_k |s_k - Hk[:, k] . q| (HiGHS): q and the minimax residual."""
    q, t, _ = highs.chebyshev_fit(Hk, s)
    return q, t


def initial_map(raw, g, si):
    """Identity for logs already in m/s^2 (`si`); else an axis-aligned ellipsoid fit."""
    if si:
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


def fit(p, ext=None, start=None, weights=None, free=None):
    """Iterate the norm relation of the problem `p` (norm_problem.NormProblem) to convergence: M, b, delta (12
    params), residuals, iterations. With catalogue effects (`ext`, norm_effects.Extension) their parameters
    ext.theta are fitted beside, the term evaluated at the direction p of M (raw - b) and taken out of the reading;
    then p is in the result. `start`: (M, b, note) to start from (default `initial_map`); `weights`: each interval's
    bound, the fit then minimax in their units (the question the premises ask: each interval within its own
    bound); `free`: the corrections fitted (default all; the rest stay 0: misalignments the orientations cannot
    identify, bounded by a premise)."""
    params = p.params
    M, b, note = initial_map(p.raw, p.g, p.si) if start is None else start
    delta = np.zeros(3)
    for it in range(1, MAX_ITER + 1):
        s, n, _ = _state(p, M, b, delta, ext)
        A = p.mod.H(n)[:params] if ext is None else np.vstack([p.mod.H(n)[:params], ext.columns(n)])
        solve = chebyshev_fit if weights is None else lambda H, y: weighted_fit(H, y, weights)
        if free is not None:
            q = np.zeros(A.shape[0])
            q[free] = solve(A[free], s)[0]
        else:
            q = solve(A, s)[0]
        if not np.all(np.isfinite(q)) or np.abs(q[:params]).max() > MAX_STEP:
            k = int(np.nanargmax(np.where(np.isfinite(q), np.abs(q), np.inf)))
            raise Diverged(f"the norm fit diverges at step {it} (a correction of {q[k]:+.3g} to "
                           f"{(PARAM_LABELS[:params] + tuple(ext.labels if ext else ()))[k]})")
        if ext is not None and weights is not None:     # halved while the worst residual grows
            q = _damped(p, M, b, delta, ext, weights, q, float(np.max(np.abs(s) / weights)))
        M, b, delta = fold(M, b, delta, q[:params], p.g)
        if ext is not None:
            ext.theta = ext.theta + q[params:]
        if np.abs(q[:params]).max() < 1e-12 and np.all(np.abs(q[params:]) * np.abs(A[params:]).max(axis=1) < 1e-12):
            break
    s, n, d = _state(p, M, b, delta, ext)
    return dict(M=M, b=b, delta=delta, sigma=s, n=n, iterations=it, note=note, p=d)


#: Halvings of a step of the fit with effects at most (the last one is taken: 2^-40 of a step is no step).
HALVINGS = 40


def _damped(p, M, b, delta, ext, weights, q, worst):
    """The step q of the fit with effects, halved until the worst residual in units of `weights` does not grow
    (a Chebyshev step on nearly dependent columns may overshoot far beyond where the linearisation holds)."""
    theta = ext.theta
    for _ in range(HALVINGS):
        M2, b2, d2 = fold(M, b, delta, q[:9], p.g)
        ext.theta = theta + q[9:]
        s2 = _state(p, M2, b2, d2, ext)[0]
        ext.theta = theta
        if np.max(np.abs(s2) / weights) <= worst * (1 + 1e-12):
            return q
        q = q / 2
    return q


def _state(p, M, b, delta, ext):
    """sigma and n of (2.2) for the calibration M, b, delta and the effects' term, and the direction d the term is
    evaluated at (fixed in `ext` with n): the fixed point d = n of the reading with the term taken out, so that
    the truth's direction m, near n, is near d too (norm_effects.FIXED_POINT)."""
    F = calibrated(p.mod, p.raw, M, b, delta, p.g)
    d = F.T / np.linalg.norm(F, axis=1)
    if ext is not None:
        F, d = ext.fixed_point(F)
    s, n = sigma_and_n(F)
    if ext is not None:
        ext.at(d, n)
    return s, n, d


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


def _identifiable(p, n, within_deg=ON_AXIS_DEG, cause="", premise=None):
    """Before the fit: the parameters the orientations present identify, structurally: each direction
    within `within_deg` of a sensor axis taken as that axis (six faces, each axis up and down, are axes
    to within a degree), an exact rank test of (2.2) of 001 on them. The parameters they cannot identify
    are named with the orientations to add, and nothing is fitted (a fit on them runs away). After a fit
    that ran away (`cause`), the same statement with the orientations' own distance from the axes. With a
    `premise` ({misalignment: its bound, rad}) that bounds each misalignment they cannot identify (six faces
    along the axes: the misalignments enter (2.2) of 001 only at second order there), the scale factors and
    biases are calibrated: returns the indices the premise bounds; a premise these orientations do not need is
    refused."""
    mod, stills, params, path = p.mod, p.stills, p.params, p.path
    axes = np.vstack([np.eye(3), -np.eye(3)])
    snapped = np.array([axes[np.argmax(axes @ d)] if np.degrees(np.arccos(np.clip((axes @ d).max(), -1, 1)))
                        <= within_deg else d for d in n.T]).T
    unseen = lp.unidentifiable(mod.H(snapped)[:params])
    if premise and not cause:
        if not unseen:
            raise DataError(f"{path}: {opt('bound')} {', '.join(premise)}: these orientations identify the "
                            "misalignments; a bound on them is taken only where they cannot (each orientation along "
                            "an axis)", param="bound")
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


def run(p, diagnose=False):
    """The whole calibration of the problem `p` (norm_problem.NormProblem): the dictionary the CLI prints and
    writes; with `diagnose`, also the effect catalogue tested from the same verdict (diagnose_norm).

    The noise bound delta_sigma_max is --delta-sigma when given, else the noise rule from the data (never the
    fit's own residual). The verdict first, the question the premises ask: does some correction of the exact
    relation, with its proven remainder (2.3), meet every interval's own bound? The fit is minimax in units of each
    interval's bound and the verdict its worst interval over that bound (within 1: consistent); if not, no bound is
    given. With catalogue effects (`p.ext`) the relation carries their columns and each interval's remainder their
    rest (norm_effects), and every bound is over the information set of that extended relation. `p.premise`
    ({misalignment: bound, rad}, --bound): where the orientations cannot identify the misalignments (each along an
    axis), the scale factors and biases are fitted and the misalignments held within it (`_identifiable`)."""
    _enough(p)
    M0, b0, _ = initial_map(p.raw, p.g, p.si)
    before, n0 = sigma_and_n(calibrated(p.mod, p.raw, M0, b0, np.zeros(3), p.g))
    held = _held(p, n0)
    res = _first_fit(p, n0, held)
    v = verdict(p, res, held) if p.ext is None else _verdict_effects(p, res)
    out = _output(p, v, before)
    if v.consistent:
        out.update(bounds(p, v))
    else:
        out["disagreements"] = [int(k) + 1 for k in np.flatnonzero(np.abs(v.res["sigma"]) > v.bnd)]
    if diagnose:
        out["diagnosis"] = _diagnosis(p, v if p.ext is None else verdict(p.base(), _first_fit(p.base(), n0, None),
                                                                            None))
    return out


def _enough(p):
    """Refuse a log with fewer still intervals than the calibration has parameters plus three, and effects on a
    model or noise bound they do not take."""
    if p.ext is not None and (p.params != 9 or not (not p.stated or p.si)):
        raise DataError(f"{p.path}: {opt('effects')} takes the 9-parameter model (cross_coupling holds the "
                        f"nonlinearity of {opt('params')} 12 as a case) and, on a log in counts, the noise rule (no "
                        f"{opt('delta_sigma')})", param="effects")
    need = p.params + 3 + (len(p.ext.labels) if p.ext else 0)
    if len(p.stills) < need:
        what = f" with {p.ext.option}" if p.ext else ""
        raise DataError(f"{p.path}: found only {len(p.stills)} still interval(s); a {p.params}-parameter "
                        f"calibration{what} needs at least {need}: record {need - len(p.stills)} more orientation(s) "
                        f"(garant plan --model norm lists them; shuffled on a warm-up), each held still for at least "
                        f"{opt('min_still')} s")


def _off_axis(n):
    """The largest angle (degrees) of the directions n (3, K) from their nearest sensor axis."""
    return float(np.degrees(np.arccos(np.clip(np.abs(n).max(axis=0), -1, 1))).max())


def _held(p, n0):
    """Before the fit, from the directions n0 of the first map: the q the misalignment premise holds (or None), after
    checking that the orientations identify the rest and the effects."""
    if p.premise:
        if p.ext is not None:
            raise DataError(f"{p.path}: {opt('bound')} (the misalignments of six faces) and {opt('effects')} are "
                            f"not taken together",
                            param="bound")
        off = _off_axis(n0)
        if off > FACE_TOLERANCE_DEG:
            raise DataError(f"{p.path}: {opt('bound')} (the misalignments of six faces) takes orientations within "
                            f"{FACE_TOLERANCE_DEG:g} degrees of the sensor axes; these lie up to {off:.1f} degrees "
                            f"off: drop {opt('bound')} (calibrate-norm then says whether they identify the "
                            "misalignments, and which orientations to add), or record each face flat", param="bound")
        return _identifiable(p, n0, max(off * 1.01, ON_AXIS_DEG), premise=p.premise)
    _identifiable(p, n0)
    if p.ext is not None:
        p.ext.at(n0, n0)
        missing = p.ext.identifiable(p.mod.H(n0)[:p.params])
        if missing:
            raise DataError(f"{p.path}: beside scale, misalignment and bias these orientations cannot identify "
                            f"{', '.join(missing)} of {p.ext.option} (--diagnose lists the effects "
                            "they cannot tell apart): add fewer effects, or orientations", param="log")
    return None


def _free(p, held):
    """The corrections the fit moves: all but those a premise holds at 0."""
    return None if held is None else [k for k in range(p.params) if k not in held]


def _first_fit(p, n0, held):
    """The fit of the base model (each interval weighted alike), or the one line of what the orientations, as they
    lie, cannot hold apart when it runs away."""
    try:
        return fit(p, free=_free(p, held))
    except Diverged as e:
        _identifiable(p, n0, max(_off_axis(n0) * 1.01, ON_AXIS_DEG), str(e))


def _noise(p, res):
    """At the fit `res`: each interval's noise rule, its noise bound as the bound uses it (units of g), the bound of
    its calibrated mean's error (nu, the remainder's), delta_sigma_max and its source."""
    rule = noise_rule(p.stills, res["M"], res["n"], p.g, p.quantum)
    dsig = float(rule.max()) if not p.stated else p.delta_sigma
    source = "--delta-sigma" if p.stated else noise_rule_name(p.stills, p.quantum)
    if not p.stated:
        noise = np.minimum(rule, dsig)
    elif p.si:      # a raw error of norm D g moves the calibrated reading along n by at most |M^T n| D g
        noise = dsig * np.linalg.norm(res["M"].T @ res["n"], axis=0) * (1 + 1e-12)
    else:
        noise = np.full(len(p.stills), dsig)
    nu = (np.linalg.norm(np.abs(res["M"]) @ noise_axes(p.stills, p.quantum).T, axis=0) / p.g if not p.stated
          else np.full(len(p.stills), np.linalg.norm(res["M"], 2) * dsig))
    return rule, noise, nu, dsig, source


def _linear_errors(p, res, noise, cap):
    """The LP estimator's errors of q (noise only) on the fit's directions, or the one line of what the orientations
    cannot identify."""
    err, missing = guaranteed(p.mod, res["n"], p.params, noise, cap)
    if missing:
        raise DataError(f"{p.path}: the {len(p.stills)} orientations cannot identify "
                        f"{', '.join(p.mod.Q_NAMES[k] for k in missing)}; add orientations", param="log")
    return err


def _at(p, res, held):
    """The noise bounds, premise cap, linear errors and sphere-wide remainder (2.3) at the fit `res`: a NormVerdict
    not yet judged."""
    rule, noise, nu, dsig, source = _noise(p, res)
    cap = None if held is None else misalignment_cap(res["M"], p.params, p.premise, held, p.si)
    err = _linear_errors(p, res, noise, cap)
    rb = linearisation_remainder(p.mod, err, p.params)
    rb = linearisation_remainder(p.mod, guaranteed(p.mod, res["n"], p.params, noise + rb, cap)[0], p.params)
    return NormVerdict(res, rule, noise, nu, dsig, source, err, rb, noise + rb, cap=cap, held=held)


def verdict(p, res, held=None):
    """The verdict of the base model (no effects) from its first fit `res`: the fit again, minimax in units of
    each interval's own bound (noise plus the proven remainder (2.3)), and its worst interval over that bound; for
    consistent data the information set, with each interval's own remainder where it can be proven from a premise
    box (norm_information.exact_information), the worst interval then over that sharper bound."""
    v = _at(p, res, held)
    try:                                      # each interval in units of its own bound, as the premises ask
        v = _at(p, fit(p, start=(res["M"], res["b"], res["note"]), weights=v.bnd, free=_free(p, held)), held)
    except Diverged:                          # the first fit stays; the verdict below is the same question at it
        pass
    H = p.mod.H(v.res["n"])[:p.params]
    v.worst = (weighted_fit(H, v.res["sigma"], v.bnd)[1] if v.cap is None
               else held_fit(H, v.res["sigma"], v.bnd, v.cap))
    if v.consistent and p.params == 9 and (not p.stated or p.si):
        found = norm_information.exact_information(p.mod, v.res, v.noise, v.nu, cap=v.cap)
        if found is not None:             # the set q = w + s, |s| <= shift: the remainder's part q absorbs
            info, rb_k, box, shift = found
            A, f = norm_information.design(p.mod, v.res)
            bnd = v.noise / f + rb_k      # each interval's own remainder: the verdict's number from the sharper set
            worst = weighted_fit(A, v.res["sigma"], bnd)[1] if v.cap is None else held_fit(A, v.res["sigma"], bnd,
                                                                                             v.cap)
            if worst <= 1:                # else its premise box is refuted: the sphere-wide set (2.3) stands
                v.info, v.box, v.rb, v.bnd, v.worst = info, box, float(rb_k.max()), bnd, worst
                v.exact = (A, bnd, shift, None)
    if v.consistent and v.info is None:
        v.info = information(p.mod, v.res, p.params, v.noise + v.rb, v.cap)
    return v


def _verdict_effects(p, res):
    """The verdict with catalogue effects: from the base model's fit `res`, the extended fit in units of each
    interval's noise bound, its remainder per interval proven from a premise box (norm_information), and whether
    some correction within it meets every interval's bound."""
    ext = p.ext
    rule0 = noise_rule(p.stills, res["M"], res["n"], p.g, p.quantum)
    worst0 = weighted_fit(p.mod.H(res["n"])[:p.params], res["sigma"], rule0)[1]
    res = fit(p, ext, (res["M"], res["b"], res["note"]), rule0 if not p.stated else np.full(len(p.stills),
                                                                                             p.delta_sigma))
    rule, noise, nu, dsig, source = _noise(p, res)
    _linear_errors(p, res, noise, None)
    try:
        worst, A, bnd, err = ext.verdict(res, noise, nu)
    except DataError as e:
        raise DataError(str(e) + _confounded(p, res["n"]), param=e.param) from None
    base = noise * np.sqrt(1.0 - 2.0 * res["sigma"])             # noise / |F|, the units of sigma
    v = NormVerdict(res, rule, noise, nu, dsig, source, err, float((bnd - base).max()), bnd, worst)
    if v.consistent:
        found = norm_information.exact_information(p.mod, res, noise, nu, ext, bnd)
        if found is None:
            raise DataError(_unproven(p, err) + _confounded(p, res["n"]), param="effects")
        v.info, rb_k, v.box, shift = found
        v.rb, v.bnd = float(rb_k.max()), base + rb_k
        v.exact = (A, v.bnd, shift, ext)
        # each contraction's set holds the truth when the premise box does; their common part is empty when
        # no correction within it meets every interval's bound: the data refute the extended relation there
        v.worst = weighted_fit(A, res["sigma"], v.bnd)[1]
    v.discrepancy = [float(worst0), float(weighted_fit(np.vstack([p.mod.H(res["n"])[:p.params], ext.columns(res["n"])]),
                                                       res["sigma"], rule)[1])]
    return v


#: Still intervals per parameter from which simulated warm-ups of realistic size calibrate (degree 2 on 60 intervals,
#: 27 parameters; degree 3 on 100, 36: tests/workflows/test_warm_up.py): what a refusal asks for.
INTERVALS_PER_PARAMETER = 2.5


def _unproven(p, err):
    """The line for data consistent with the extended relation whose remainder no premise box proves: which
    correction the orientations bound too loosely for its second-order terms, and what recording would do."""
    import math
    ext, K, P = p.ext, len(p.stills), len(err)
    labels = list(PARAM_LABELS[:9]) + list(ext.labels)
    k = int(np.argmax(err[:6]))
    need = math.ceil(INTERVALS_PER_PARAMETER * P)
    thermal = ext.option.startswith("--thermal-degree")
    degree = int(ext.option.split()[1]) if thermal else 0
    fewer = (f"--thermal-degree {degree - 1}" if degree > 1 else "a constant calibration (no --thermal-degree)"
             if thermal else "fewer effects")
    return (f"{p.path}: consistent with {ext.option}, but the remainder of the extended relation cannot be proven "
            f"from any box around the fit: on {K} still intervals its {P} parameters are bounded only to "
            f"{err[k]:.1g} ({labels[k]}) and {err[9:].max():.1g} ({labels[9 + int(np.argmax(err[9:]))]}), where the "
            f"second-order terms of (2.2) of 001 exceed the intervals' noise bounds. Record more orientations (about "
            f"{need} still intervals for {P} parameters; each held still, in shuffled order while it warms), or take "
            f"{fewer}: no bound")


#: |correlation| of the intervals' temperature with an axis's share of g above which a refusal says they are
#: confounded (an ordered warm-up: face up while cold, face down while hot).
CONFOUNDED = 0.5


def _confounded(p, n):
    """A sentence for a warm-up whose orientation moved with its temperature (the correlation over the intervals of
    T with n_i or n_i^2 beyond CONFOUNDED): a temperature term and a scale factor or bias are then told apart only
    by how the two differ; the fix in recording. Empty otherwise."""
    if p.temps is None or len(p.temps) < 3 or np.ptp(p.temps) == 0:
        return ""
    T = np.asarray(p.temps, float)
    best = max(((abs(c), c, i, k) for i in range(3) for k, x in ((1, n[i]), (2, n[i] ** 2)) if np.ptp(x) > 0
                for c in [float(np.corrcoef(T, x)[0, 1])]), default=(0.0,))
    if best[0] <= CONFOUNDED:
        return ""
    _, c, i, k = best
    share = f"n{i + 1}" if k == 1 else f"n{i + 1}^2"
    return (f". Orientation and temperature moved together in this log (the intervals' temperature correlates "
            f"{c:+.2f} with {share}, axis {i + 1}'s share of g{'' if k == 1 else ' squared'}): the warm-up cannot "
            "tell a temperature term from a scale factor or bias. Record the orientations in shuffled order, or at "
            "the end, hot, turn it back through every orientation in reverse order (garant simulate --model norm "
            "--ordered --revisit N makes such a log to try)")


def _output(p, v, before):
    """The calibration's dictionary from the verdict `v` (the bounds are added by norm_bounds.bounds)."""
    res, g = v.res, p.g
    A = p.mod.H(res["n"])[:p.params] if v.exact is None else v.exact[0]
    uniform = float(chebyshev_fit(A if v.cap is None else A[_free(p, v.held)], res["sigma"])[1])
    out = {
        "log": p.path, "g": g, "params": p.params, "intervals": len(p.stills), "iterations": res["iterations"],
        "start": res["note"], "raw_unit": p.raw_unit, "matrix": res["M"].tolist(), "bias": res["b"].tolist(),
        "nonlinearity_delta_g": res["delta"].tolist() if p.params == 12 else None,
        "consistent": v.consistent, "worst_over_bound": float(v.worst), "minimax_residual": uniform,
        "delta_sigma_max": v.dsig, "delta_sigma_source": v.source, "remainder_bound": v.rb,
        "premises": {"statement": "the bounds hold if " + norm_noise.premise(v.dsig, v.source, p.stated, p.si, g)
                     + f"; the gravity is g = {g:g} m/s^2 "
                     "(its error Delta_g/g enters lambda_i* = lambda_i - Delta_g/g, (2.2) of 001; the remainder "
                     + ("takes g as exact" if v.box is not None else "of (2.3) takes g and delta_f as exact")
                     + "); the orientations are still" + norm_information.premise_box(v.box)
                     + _misalignment_premise(p.premise, v.held, _off_axis(res["n"])), "g": g, "noise_bound": v.dsig,
                     "noise_source": v.source},
        "sigma_min_supported": max(uniform - v.rb, 0.0),
        "per_interval": [{"start_s": s.start, "stop_s": s.stop, "raw_mean": s.mean.tolist(),
                          "noise_rule": float(nr), "noise_bound": float(nb),
                          "noise_source": "its noise rule" if not p.stated else v.source,
                          "bound": float(b), "residual_before_ms2": float(g * sb),
                          "residual_after_ms2": float(g * sa), "direction": d.tolist()}
                         for s, nr, nb, b, sb, sa, d in zip(p.stills, v.rule, np.broadcast_to(v.noise, v.rule.shape),
                                                            np.broadcast_to(v.bnd, v.rule.shape), before,
                                                            res["sigma"], res["n"].T)],
    }
    if v.held is not None:
        out["misalignment_premise"] = {PARAM_LABELS[k]: float(p.premise[PARAM_LABELS[k]]) for k in v.held}
    if p.ext is not None:
        out["model_discrepancy"] = {"max_residual_before": v.discrepancy[0], "max_residual_after": v.discrepancy[1],
                                    "units": "each interval's noise rule (first order of (2.2) of 001, no remainder)"}
        out["effect_names"] = list(p.ext.names)
        out["effect_reference"] = {"time_s": p.ext.t_ref, "temp_c": p.ext.temp_ref}
    return out


def _diagnosis(p, v):
    """The effect catalogue tested on the base model's verdict `v` (its fit, each interval's bound and its worst
    residual over it: the diagnosis's first line is the verdict), and the set to add checked by the whole
    calibration."""
    from . import diagnose_norm, norm_effects
    d = diagnose_norm.diagnose(p.mod, p.stills, v.res, p.params, v.noise, v.worst, p.temps, p.rates,
                               noise_bound=v.source)
    return diagnose_norm.settle(d, *diagnose_norm.to_add(d, p.mod, lambda names: run(p.with_effects(
        norm_effects.Extension(p.mod, names, p.stills, p.temps, p.path, p.rates)))))


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


def _misalignment_premise(premise, held, off):
    """The misalignment premise in words, or empty; `off`: the orientations' largest angle from an axis (degrees)."""
    if held is None:
        return ""
    return ("; the misalignments are within " + ", ".join(f"|{PARAM_LABELS[k]}| <= {premise[PARAM_LABELS[k]]:g} rad"
                                                        for k in held)
            + f" (--bound, stated: the orientations lie within {off:.2g} degrees of the axes, where the data bound the "
              "misalignments weakly or not at all; their term at each orientation's own direction is carried in every "
              "bound, to first order in the set and the rest in the remainder)")


def linearisation_remainder(mod, e, params):
    """The proven bound (2.3) of 001 for errors within e around the fit (units as PARAM_LABELS):
    second order; the noise itself is delta_sigma_max, not counted twice (df = 0); g is taken as exact."""
    return float(mod.remainder_bound(k_max=e[:3].max(), v_max=e[3:6].max(), eps_max=e[6:9].max(),
                                     delta_max=e[9:12].max() if params == 12 else 0.0, df_max=0.0, dg_max=0.0))


def weighted_fit(Hk, s, bounds):
    """min over q of max_k |s_k - Hk[:, k] . q| / bounds_k (HiGHS): the fit in units of each noise bound."""
    q, t, _ = highs.chebyshev_fit(Hk, s, weights=bounds)
    return q, t
