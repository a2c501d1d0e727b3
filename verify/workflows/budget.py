"""What a calibration guarantees downstream: the worst-case error of a corrected specific force over every
direction at 1 g, the static tilt error, the velocity and position error that error builds up in free
integration, and the per-axis bias and scale bounds a filter takes, each over the information set the readings
prove; for a calibration made elsewhere (imu_tk, imucal), judged against the set of the log it was made from.

A still unit with its vertical along the unit vector n (body axes) reads the true specific force g n. For every
unit of the set (a norm set: the fit M_fit, b_fit corrected by q, (2.2) of 001; a stand's: the block's Gamma and
biases, (28)-(29) of 000) a calibration (M_p, b_p) corrects that reading to a = g n + e with, exactly,

    norm:  e = M_p (b_fit - b_p) + (K - E) g n + K (lower(q) g n + g q_eps),   K = M_p M_fit^-1,
    stand: e = M ((Gamma - G) g n + g (beta - beta_m)) + (M (E + G) - E) g n,

affine in the set's unknowns z. So each figure at one n is an LP pair over the set (solve/hull.py, over the rows
that can bind, each end proven by duality). Over every n: the directions of a cube-sphere grid (every unit vector
within a chord of sqrt(2) / N_SIDE of one) and, between them, for |e| and each axis's error the convexity of an
error affine in n (`_sups`: their largest at the grid, plus a second-order stretch), for the parts along and across
n what e can move between a grid direction and any other (|de_k / dn_j| <= g times the bound of the error's slope
over the set, `_filter`). The error of g (|g_t/g - 1| <= u) adds u g |n_k| (the true specific force is g_t n, along
n).

- specific force: |e| <= the smallest of the norm of the three axes' bounds, that of the bounds along n and across
  it, and the bound over a net of directions (`_net`);
- tilt (the angle between the true and the estimated vertical: pitch errs by at most it, roll by at most it over
  cos(pitch)): atan(|e_perp| / (g (1 - u) - |e_par|)), |e_perp| <= sec(pi / 16) times the largest of 16 directions
  across n;
- velocity and position over a horizon T of free integration with the attitude held: |e| T and |e| T^2 / 2, a bound
  of the integrated calibration error alone (not a navigation solution: no attitude, gyroscope or noise error).
"""
import numpy as np

from ..errors import DataError
from ..solve import hull, support
from . import sample_set
from .peer_files import garant_frame, peer
from .norm_information import lower
from .attitudes import grid, stretch

#: Cube-sphere cells per face side of the attitudes: every unit vector within sqrt(2) / N_SIDE (chord) of one.
N_SIDE = 24
HORIZONS_S = (1, 10, 60)
EPS = np.finfo(float).eps
PERP = 16                                                # directions across n: |e_perp| <= sec(pi/16) times their max
MG = 1e3 / 9.80665                                       # mg per m/s^2 (standard gravity)


class Model:
    """The error of a calibration over a set: e(n) = d0 + D(n) + C(n) z, z in the set (`st`, the calibration
    file's information_set: rows, box, shift, estimate); `affine`: D and C affine in n, so e is at each z (not so
    with the effects' basis Phi(n))."""

    def __init__(self, st, build, d0, g, u, rest=None, affine=True):
        self.st, self.build, self.d0, self.g, self.u = st, build, np.asarray(d0, float), g, u
        self.rest = rest            # (R, r): a part of e outside the set's LP, |r_k(n)| <= g (R |n|)_k + r_k
        self.affine = affine        # `_sups`: the figures between grid attitudes by convexity

    def ranges(self, n, W):
        """(lo, hi) (N, R) of w^T e(n) for each n (rows of n) and each row w of W (R, 3) or each (N, R, 3): each end an
        LP over the set's rows that can bind (support.essential, once a set) proven by its own multipliers
        (hull.ranges), the LPs row w by row w over the attitudes, each from the last one's basis (neighbouring
        objectives: 1.6x faster than attitude by attitude on a three-axis file)."""
        d, C = self.build(n)                                       # (3, N), (3, N, P)
        W = np.broadcast_to(W, (len(n),) + np.shape(W)[-2:])
        obj = np.einsum("nrk,knp->rnp", W, C).reshape(-1, C.shape[2])
        off = np.einsum("nrk,kn->rn", W, d + self.d0[:, None]).ravel()
        st = self.st
        box = np.asarray(st["box_lo"], float), np.asarray(st["box_hi"], float)
        if "_essential" not in st:
            rows, s, b = (np.asarray(st[k], float) for k in ("rows", "centre", "bound"))
            keep, lo, hi = support.essential(rows, s - b, s + b, *box)
            st["_essential"] = rows[keep], lo, hi
        lo, hi = hull.ranges(*st["_essential"], *box, obj, sweep=True)
        reach = np.abs(obj) @ np.asarray(st["shift"], float)
        pad = 4 * (obj.shape[1] + 4) * np.finfo(float).eps * (np.abs(lo) + np.abs(hi) + np.abs(off))
        return tuple((x + off + sign * (reach + pad)).reshape(-1, len(n)).T for x, sign in ((lo, -1.0), (hi, 1.0)))


def fit(cal):
    """(M_fit, b_fit) of a norm file: the fit its set's q correct, the midpoint q_m taken back out of M and b
    (norm_bounds.fold: M = (E + lower(q_m))^-1 M_fit, b = b_fit + M_fit^-1 g q_m,eps)."""
    q_m, g = np.asarray(cal["information_set"]["estimate"], float), cal["g"]
    M_fit = (np.eye(3) + lower(q_m)) @ np.asarray(cal["M"], float)
    return M_fit, np.asarray(cal["b"], float) - np.linalg.solve(M_fit, g * q_m[6:9])


def norm_model(cal, M_p=None, b_p=None, phi=None):
    """The Model of the calibration (M_p, b_p) (default the file's own) over a norm file's set (`fit`); with
    catalogue effects, `phi(n)` (J, 3, N) their basis at the attitudes n (a temperature's, or a control point's of
    their polynomial in T): the linear part of e, g Phi(n) (theta - theta_m), in the set's columns after the 9
    (theta_m, the file's)."""
    st, g = cal["information_set"], cal["g"]
    if len(st["estimate"]) != 9 and phi is None:
        raise DataError("budget: a norm calibration with catalogue effects is budgeted by `effect_figures`",
                        param="calibration")
    M_fit, b_fit = fit(cal)
    M_p, b_p = (np.asarray(cal["M"], float), np.asarray(cal["b"], float)) if M_p is None else (
        np.asarray(M_p, float), np.asarray(b_p, float))
    K = M_p @ np.linalg.inv(M_fit)
    theta = np.asarray((cal.get("effects") or {}).get("theta", []), float)

    def build(n):
        a = g * np.asarray(n, float).T                              # (3, N)
        if phi is None:
            return (K - np.eye(3)) @ a, sample_set.objectives(st, a, g, N=K)
        f = phi(n)
        return (K - np.eye(3)) @ a - g * np.einsum("j,jkn->kn", theta, f), sample_set.objectives(st, a, g, f, N=K)
    return Model(st, build, M_p @ (b_fit - b_p), g, float(st["g_uncertainty"]), affine=phi is None)


def stand_model(cal):
    """The Model of a stand file over its block's set (block_columns: Gamma11..Gamma33, bias1..bias3 over g), or a
    two-axis file's over its q (Gamma_rows: `lower_model`)."""
    st, g, M = cal["information_set"], cal["g"], np.asarray(cal["M"], float)
    if "Gamma_rows" in st:
        return lower_model(cal)
    z_m = np.asarray(st["estimate"], float)
    G = z_m[np.asarray(st["block_columns"], int)[:9]].reshape(3, 3)
    left = M @ (np.eye(3) + G) - np.eye(3)

    def build(n):
        a = g * np.asarray(n, float).T
        C = sample_set.objectives(st, a, g, M=M)
        return left @ a - np.einsum("knp,p->kn", C, z_m), C
    return Model(st, build, np.zeros(3), g, float(st["g_uncertainty"]))


def lower_model(cal):
    """The Model of a constant two-axis file over its q (sample_set.lower_bound): e = M (dGamma g n + dbias) +
    (M (E + G) - E) g n with dGamma = Gamma_rows^T dq + r, dbias = bias_rows^T dq + r_b; the rest r, r_b outward
    (|M| rest_Gamma, |M| rest_bias), the rounding of M as an inverse with it; the error of g (s, within 1 +- u) as
    the Model's u: the data fix the reading of g n, so g_t n differs from it along n only."""
    st, g, M = cal["information_set"], cal["g"], np.asarray(cal["M"], float)
    G = np.linalg.inv(M) - np.eye(3)
    R, Rb = np.asarray(st["Gamma_rows"], float)[0], np.asarray(st["bias_rows"], float)[0]
    q_m = np.asarray(st["estimate"], float)
    left = M @ (np.eye(3) + G) - np.eye(3)
    slack = 8 * np.finfo(float).eps * (np.abs(M) @ (1 + np.abs(G)))
    rest = (np.abs(M) @ np.asarray(st["rest_Gamma"], float)[0] + slack, np.abs(M) @ np.asarray(st["rest_bias"]))

    def build(n):
        a = g * np.asarray(n, float).T                                  # (3, N)
        C = np.einsum("ka,nap->knp", M, np.einsum("abp,bn->nap", R, a) + Rb[None])
        return left @ a - np.einsum("knp,p->kn", C, q_m), C
    return Model(st, build, np.zeros(3), g, float(st["g_uncertainty"]), rest)


def figures(model, progress=None):
    """The budget of one Model: the worst-case errors over every attitude (the module's docstring). At each
    attitude of the grid: each axis's error, the error along n and its largest across n (PERP directions); |e| is
    the smaller of the axes' norm, that of the parts along and across n, and, at the attitudes where it could be the
    largest, the bound over a net of directions (`_net`)."""
    return _finish(*_outward(model, progress), model.g)


def _outward(model, progress=None):
    """(sup, filt) of one Model (`_sups`, `_filter`) with its rest added outward at every attitude: |r(n)| <= g R |n|
    + r, |n| = 1."""
    filt = _filter(model)
    sup = _sups(model, filt, 0.0, progress)
    if model.rest is not None:
        R, r = model.rest
        r_axis, r_norm = model.g * np.linalg.norm(R, axis=1) + r, model.g * np.linalg.norm(R, 2) + np.linalg.norm(r)
        e = sup["e"] + r_norm
        sup = dict(sup, per_axis=sup["per_axis"] + r_axis, e=e, perp=sup["perp"] + r_norm,
                   par=min(sup["par"] + r_norm, e))
        filt = {"bias_bound_mps2": (np.asarray(filt["bias_bound_mps2"]) + r).tolist(),
                "slope_bound": (np.asarray(filt["slope_bound"]) + R).tolist()}
    return sup, filt


def lower_thermal_figures(cal, progress=None):
    """The budget of a two-axis file over temperature (the frame the data define: sample_set.lower_bound) over every
    attitude and every temperature of its calibrated range [a, b].

    With t_c the range's middle and M_c = M(t_c), a still unit at n reads, at every T of the range, e = M(T) X +
    left(T) g n, X = dGamma(T) g n + dbias(T) (the unit read at s = 1; the error of g apart, the Model's u; M(T) the
    file's (E + Gamma_hat(T))^-1 as apply computes it, left its rounding), and M(T) X = M_c X + (M(T) - M_c) X:
    - M_c X's part linear in q is a polynomial in tau = T - t0 with coefficients M_c (Gamma_rows_k g n +
      bias_rows_k): over the range it lies in the hull of its Bernstein control points (thermal.bernstein), each
      a Model of LPs over the set; its rest M_c (r g n + r_b) outward (the file's rest_Gamma, rest_bias);
    - |M(T) - M_c| <= (I - K)^-1 K |M_c|, K = |M_c| D, D the largest |Gamma_hat(T) - Gamma_hat(t_c)| over the range
      (the file's polynomial's control points), times |X| <= bound_Gamma g |n| + bound_bias (the file's box bounds,
      their largest over its pieces), outward.
    The figures are the largest over the control points' Models."""
    from ..io.calibration import thermal_gamma
    from .thermal import bernstein
    st, th, g = cal["information_set"], cal["thermal"], cal["g"]
    lo, hi = (float(x) for x in th["range_c"])
    a, b = lo - th["t0_c"], hi - th["t0_c"]
    G_c = thermal_gamma(cal, [(lo + hi) / 2])[0][0]
    M_c = np.linalg.inv(np.eye(3) + G_c)
    absM = np.abs(M_c)
    drift = bernstein([np.linalg.inv(cal["M"]) - np.eye(3) - G_c, *th["Gamma"]], a, b)
    K = absM @ np.abs(drift).max(axis=0)
    if K.sum(axis=1).max() >= 0.5:
        raise DataError("budget: the calibration's drift over its range is too large to bound its inverse",
                        param="calibration")
    dM = np.linalg.solve(np.eye(3) - K, K @ absM) * (1 + 1e-12)
    G_top = np.abs(G_c) + np.abs(drift).max(axis=0)
    R_slope = (absM @ np.asarray(st["rest_Gamma"], float).max(axis=0) + dM @ np.asarray(th["bound_Gamma"]).max(axis=0)
               + 16 * EPS * ((absM + dM) @ (1 + G_top)))
    r_bias = absM @ np.asarray(st["rest_bias"], float) + dM @ np.asarray(th["bound_bias"]).max(axis=0)
    q_m = np.asarray(st["estimate"], float)
    Rc = bernstein(list(np.asarray(st["Gamma_rows"], float)), a, b)           # (D + 1, 3, 3, P) control points
    Rbc = bernstein(list(np.asarray(st["bias_rows"], float)), a, b)

    def model(R, Rb):
        def build(n):
            C = np.einsum("ka,nap->knp", M_c, np.einsum("abp,bn->nap", R, g * np.asarray(n, float).T) + Rb[None])
            return -np.einsum("knp,p->kn", C, q_m), C
        return Model(st, build, np.zeros(3), g, float(st["g_uncertainty"]), (R_slope, r_bias))
    got = []
    for k, (R, Rb) in enumerate(zip(Rc, Rbc)):
        got.append(_outward(model(R, Rb), None if progress is None else
                            lambda d, n, k=k: progress(k * n + d, len(Rc) * n)))
    sups = [x[0] for x in got]
    worst = max(sups, key=lambda x: x["e"])
    e = worst["e"]
    sup = dict(worst, per_axis=np.max([x["per_axis"] for x in sups], axis=0), perp=max(x["perp"] for x in sups),
               par=min(max(x["par"] for x in sups), e))
    filt = {key: np.max([np.asarray(x[1][key]) for x in got], axis=0).tolist()
            for key in ("bias_bound_mps2", "slope_bound")}
    return dict(_finish(sup, filt, g), temperature_range_c=[lo, hi])


def _sups(model, filt, extra, progress=None):
    """The largest per-axis error, |e|, and parts across and along n over every attitude, each proven: at the grid's
    attitudes by LPs, between them by the slope the set allows (`filt`, from `_filter`) and `extra` (m/s^2 per unit
    of the chord: a slope not in the Model's linear part)."""
    g, u = model.g, model.u
    N, delta = grid(N_SIDE)
    G = g * (np.asarray(filt["slope_bound"]) - u * np.eye(3))    # |de_k / dn_j| <= G_kj over the set
    slack_axis = np.linalg.norm(G, axis=1) * delta + extra * delta     # |n - n'|_2 <= delta
    slack_norm = np.linalg.norm(G, 2) * delta + extra * delta           # |G v| <= |G|_2 |v| (G >= 0)
    U = _refine(model, N, progress)
    axes, along = U[:, :3], U[:, -1]
    across = U[:, 3:-1].max(axis=1) / np.cos(np.pi / PERP)
    # the error of g, d g n with |d| <= u, moves a still unit's reading along n only: |e| <= |(e_perp, e_par + u g)|;
    # between attitudes it moves by at most u g |n - n'| (per axis and in norm)
    here = _net(model, N, np.minimum(np.linalg.norm(axes + u * g * np.abs(N), axis=1), np.hypot(across, along + u * g)),
                U)
    axes = axes + u * g * np.abs(N)
    if model.affine:
        # e(n) = e(0) + L n at each unit of the set and each error of g, so |e_k(n)| and |e(n)| are convex in n at
        # each, and at most their largest at a grid triangle's corners over its hull. Every unit vector is t m with
        # m in a triangle's hull and 1 <= t <= stretch(N_SIDE), and e(t m) = e(m) + (t - 1) L m with |L_kj| <= g
        # times the slope bound S (`_filter`, the error of g on its diagonal) and |m| <= 1: no slope by the chord
        S = g * np.asarray(filt["slope_bound"], float)
        t = stretch(N_SIDE) - 1
        per_axis = (axes.max(axis=0) + t * np.linalg.norm(S, axis=1)) * (1 + 4 * EPS)
        e_sup = (float(here.max()) + t * np.linalg.norm(S, 2)) * (1 + 4 * EPS)
    else:
        per_axis = axes.max(axis=0) + slack_axis + u * g * delta
        e_sup = float(here.max()) + slack_norm + u * g * delta
    return {"per_axis": per_axis, "e": e_sup,
            # |n n^T - n' n'^T|_2 = sin of their angle, times |e(n)| <= here(n) (the error of g lies along n'); and
            # n'^T e(n') - n^T e(n) = (n' - n)^T e(n) + n'^T (e(n') - e(n)). Each part is at most |e|
            "perp": min(float((across + here * delta).max()) + slack_norm, e_sup),
            "par": min(float((along + here * delta).max()) + slack_norm, e_sup), "u": u,
            "worst": N[int(np.argmax(here))], "attitudes": len(N), "delta": delta}


#: |e| at an attitude over nets of directions: cube-sphere grids with these many cells per face side (5: every unit
#: vector within 16.3 degrees of one), each at the attitudes whose bound could be the largest, at most NET_AT of them
#: a net (counted).
NET_SIDES = (5,)
NET_AT = 512


def _net(model, N, here, U):
    """`here` (N,), each attitude's bound of |e| from the axes and the parts along and across n (U, `_refine`), made
    the smaller of it and the bound over a net of directions w (|e| <= max_w w^T e / cos(theta), theta the net's
    covering angle; `_net_at`), at the attitudes in order of their bound until the largest found is at least every
    bound not yet refined (or NET_AT of them); with several nets, each after the last."""
    for side in NET_SIDES:
        W, chord = grid(side)
        W = W[W @ np.array([1.0, 0.5 ** 0.5, 3.0 ** -0.5]) > 0]         # one of each +-w pair (the net is symmetric)
        sec = 1.0 / np.cos(2 * np.arcsin(chord / 2))
        out, best = here.copy(), -np.inf
        order = np.argsort(-here, kind="stable")[:NET_AT]
        for k in range(0, len(order), 32):
            idx = order[k:k + 32]
            if here[idx[0]] <= best:
                break                                   # every attitude left is bounded by one refined
            idx = np.sort(idx)                          # in the grid's order: neighbouring LPs
            out[idx] = np.minimum(here[idx], _net_at(model, N[idx], U[idx], W) * sec * (1 + 1e-12))
            best = max(best, float(out[idx].max()))
        here = out
    return here


#: Directions of the net solved at a time at each attitude (`_net_at`).
PICK = 4


def _net_at(model, n, U, W):
    """(N,): at each attitude n the largest over the net's directions w (K, 3) of a bound of |w^T e| + u g |w^T n|
    (the error of g along n). Each starts as a bound that costs no LP, from the attitude's rows U: |w^T e| <= sum_k
    |w_k| |e_k|, and <= |w^T n| |e_par| + |P_n w| |e_perp|; LPs then go to the directions of the largest, PICK at
    a time, until at every attitude the largest an LP proved is at least every bound left (it is then the largest
    of all)."""
    ug = model.u * model.g
    wn = np.abs(n @ W.T)                                                    # (N, K)
    across = U[:, 3:-1].max(axis=1) / np.cos(np.pi / PERP)
    val = np.minimum(U[:, :3] @ np.abs(W).T, wn * U[:, -1:] + np.sqrt(np.maximum(1 - wn ** 2, 0.0)) * across[:, None])
    val += ug * wn
    solved = np.zeros(val.shape, bool)
    while True:
        left = np.where(solved, -np.inf, val)
        todo = np.flatnonzero(left.max(axis=1) > np.where(solved, val, -np.inf).max(axis=1))
        if not len(todo):
            return val.max(axis=1)
        pick = np.argsort(-left[todo], axis=1, kind="stable")[:, :PICK]
        i, j = np.repeat(todo, pick.shape[1]), pick.ravel()
        keep = ~solved[i, j]
        i, j = i[keep], j[keep]
        turn = np.lexsort((i, j))                                           # direction by direction: neighbouring LPs
        i, j = i[turn], j[turn]
        lo, hi = model.ranges(n[i], W[j][:, None, :])
        val[i, j] = np.minimum(val[i, j], np.maximum(hi[:, 0], -lo[:, 0]) + ug * wn[i, j])
        solved[i, j] = True


def _finish(sup, filt, g):
    """The printed figures from the largest values `_sups` proves (tilt from the parts across and along n)."""
    e_sup, perp_sup, par_sup = sup["e"], sup["perp"], sup["par"]
    g_low = g * (1 - sup["u"])                 # the true g n, whose tilt the error across n sets against it
    if par_sup >= g_low:
        raise DataError("budget: the error bound reaches g: no tilt is bounded", param="calibration")
    tilt = float(np.arctan(perp_sup / (g_low - par_sup)))
    return {
        "specific_force_error_mps2": e_sup, "specific_force_error_mg": e_sup * MG,
        "per_axis_error_mps2": np.asarray(sup["per_axis"]).tolist(),
        "tilt_error_rad": tilt, "tilt_error_deg": float(np.degrees(tilt)),
        "velocity_error_mps": {str(T): e_sup * T for T in HORIZONS_S},
        "position_error_m": {str(T): e_sup * T * T / 2 for T in HORIZONS_S},
        **filt,
        "attitudes": int(sup["attitudes"]), "grid_chord": float(sup["delta"]),
        "worst_attitude": np.asarray(sup["worst"]).tolist(),
    }


def effect_figures(cal, progress=None):
    """The budget of a norm file with catalogue effects (--thermal-degree, --effect) over every attitude and every
    temperature of its calibrated range.

    With u = M (raw - b) and u_t the true unit's, u - u_t = N (lower(dq) u_t + g dq_eps) exactly, and the model
    (a = u - g Phi(p) theta, p = u / |u|) gives for a still unit at n (u_t = g n + g Phi(p_t) theta_t, p_t its
    direction)

        e = [N (lower(dq) g n + g dq_eps) + g Phi(n) (theta_t - theta)]                      (linear in the set)
            + g N lower(dq) Phi(p_t) theta_t + g (Phi(p_t) - Phi(n)) theta_t + g (Phi(n) - Phi(p)) theta.

    The linear part's figures are LPs as a constant file's, at each control point of Phi's polynomial in T (its
    Bernstein coefficients over pieces of the range, whose hull holds every value between: exact at the range's
    ends for degree 1); the rest, outward: |N lower(dq)| <= B (bound_matrix), |Phi(m) theta - Phi(m') theta| <=
    l |m - m'| (l the effects' Lipschitz bound at |theta| + bound), |p_t - n| <= 2 s / (1 - 2 l) and |p - n| <= 2
    (|e| / g + s) / (1 - 2 l) with s the largest |Phi(n)| (|theta| + bound), |e| closed on itself."""
    from .. import models
    from .norm_effects import lipschitz
    from .thermal import bernstein
    mod = models.load("norm")
    st, g, eff = cal["information_set"], cal["g"], cal["effects"]
    names, theta, h = eff["names"], np.asarray(eff["theta"], float), np.asarray(eff["bound"], float)
    shift = 20.0 - float(eff.get("temp_ref_c", 20.0))          # the basis reads T - 20: counted from temp_ref_c
    thermal = [x for x in names if "temp_c" in mod.EFFECT_VARIABLES[x]]
    if any(mod.EFFECT_VARIABLES[x] and x not in thermal for x in names):
        raise DataError("budget: an effect of time or of the temperature's rate is not budgeted", param="calibration")
    degree = max((int(x.rsplit("_", 1)[1]) if x[-1].isdigit() else 1 for x in thermal), default=0)
    lo, hi = eff["temp_range_c"] if thermal else (20.0 - shift, 20.0 - shift)
    pieces = np.linspace(lo, hi, (1 if degree <= 1 else EFFECT_PIECES) + 1)
    # on a piece of width w, Phi's values at degree + 1 equispaced temperatures give its coefficients in T - a
    # (Vandermonde) and those its Bernstein control points (thermal.bernstein): weights from values to controls
    tau = np.linspace(0.0, 1.0, degree + 1)
    inverse = np.linalg.inv(np.vander(tau, degree + 1, increasing=True))

    def basis(n, T):
        p = np.asarray(n, float).T
        return np.concatenate([mod.effect_basis(x, p, 0.0, np.full(p.shape[1], T + shift)) for x in names]
                              + [np.zeros((0, 3, p.shape[1]))])     # (a session-only effect's columns: none)
    controls = [(np.linspace(a, b, degree + 1), w) for a, b in zip(pieces[:-1], pieces[1:])
                for w in bernstein([inverse[k] / (b - a or 1.0) ** k for k in range(degree + 1)], 0.0, b - a)]
    reach = max(float(np.abs(w).sum()) for _, w in controls)     # a control point's slope in n, over a value's
    phis = [lambda n, T=T, w=w: sum(wi * basis(n, Ti) for wi, Ti in zip(w, T)) for T, w in controls]
    jac = np.concatenate([mod.effect_jacobian_bound(x, 0.0, np.array([lo, hi]) + shift) for x in names]
                         + [np.zeros((0, 3, 3, 2))])
    ell = float(lipschitz(jac, np.abs(theta) + h).max())         # of Phi(m) theta_t in m, theta_t in the box
    J = len(theta)                                              # (the set's columns past them: not applied)
    box = np.maximum(np.abs(np.asarray(st["box_lo"], float)[9:9 + J] - theta),
                     np.abs(np.asarray(st["box_hi"], float)[9:9 + J] - theta))
    extra = g * float(lipschitz(jac, box).max()) * reach         # g Phi(n) (theta_t - theta) between attitudes
    filt = _filter(norm_model(cal, phi=lambda n: np.zeros((len(theta), 3, len(n)))))
    sups = []
    for k, phi in enumerate(phis):
        sups.append(_sups(norm_model(cal, phi=phi), filt, extra,
                          None if progress is None else lambda d, n, k=k: progress(k * n + d, len(phis) * n)))
    N, delta = grid(N_SIDE)
    size = np.abs(theta) + h
    top = np.max([np.abs(phi(N)) for phi in phis], axis=0)       # each entry of Phi(n, T) within its control points'
    s_max = float(np.linalg.norm(np.einsum("j,jkn->kn", size, top), axis=0).max()) + ell * delta   # (between n's)
    r0, kappa = _rest(s_max, ell, np.asarray(cal["bound_matrix"], float), g)
    worst = max(sups, key=lambda x: x["e"])
    e_sup = (worst["e"] + float(np.linalg.norm(r0))) / (1 - np.sqrt(3) * kappa)
    r_axis = r0 + kappa * e_sup
    r_norm = float(np.linalg.norm(r0)) + np.sqrt(3) * kappa * e_sup
    sup = {"per_axis": np.max([x["per_axis"] for x in sups], axis=0) + r_axis, "e": e_sup * (1 + 1e-12),
           "perp": max(x["perp"] for x in sups) + r_norm, "par": min(max(x["par"] for x in sups) + r_norm, e_sup),
           "worst": worst["worst"], "attitudes": worst["attitudes"], "delta": worst["delta"], "u": worst["u"]}
    # a filter's model, |e_k| <= bias_k + sum_j slope_kj |a_j|: the effects' linear part (g Phi(n) (theta_t -
    # theta), per axis over every attitude and temperature) and the remainder as bias
    linear = g * np.einsum("j,jkn->kn", box, top).max(axis=1) + extra * delta
    out = _finish(sup, dict(filt, bias_bound_mps2=(np.asarray(filt["bias_bound_mps2"]) + linear + r_axis).tolist()),
                  g)
    return dict(out, temperature_range_c=[float(lo), float(hi)] if thermal else None)


def _rest(s_max, ell, B, g):
    """(r0, kappa): the second-order rest of an effects file's error per axis is at most r0 + kappa |e| (the
    docstring of `effect_figures`: g B 1 s / (1 - 2 l) + 4 g l s / (1 - 2 l), kappa = 2 l / (1 - 2 l))."""
    if 2 * ell >= 0.25:
        raise DataError("budget: the effects are too large for their remainder to close (Lipschitz bound "
                        f"{ell:.3g} >= 1/8)", param="calibration")
    return (g * s_max / (1 - 2 * ell) * B.sum(axis=1) + 4 * g * ell * s_max / (1 - 2 * ell),
            2 * ell / (1 - 2 * ell))


#: Pieces of the temperature range the budget of a polynomial of degree 2 or 3 is bounded over (Bernstein).
EFFECT_PIECES = 2


STEP = 256                                              # attitudes at a time (the memory of a step)


def _refine(model, N, progress=None):
    """(N, 3 + PERP / 2 + 1): at each attitude the proven bound of |w^T e| over the set for the axes, the directions
    across n and n itself."""
    nN, R = len(N), 3 + PERP // 2 + 1
    U = np.full((nN, R), np.inf)
    for i in range(0, nN, STEP):
        idx = np.arange(i, min(i + STEP, nN))
        n = N[idx]
        for cols, W in ((slice(0, 3), np.eye(3)), (slice(3, R), _across(n))):
            lo, hi = model.ranges(n, W)
            U[idx, cols] = np.maximum(-lo, hi)
        if progress:
            progress(idx[-1] + 1, nN)
    return U


def _across(n):
    """(N, PERP / 2 + 1, 3): PERP / 2 unit directions across each n, evenly over half a turn (with their opposites
    the PERP directions of the circle), and n itself last."""
    a = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    p1 = np.cross(n, a)
    p1 /= np.linalg.norm(p1, axis=1)[:, None]
    p2 = np.cross(n, p1)
    ang = np.pi * np.arange(PERP // 2) / (PERP // 2)
    W = np.cos(ang)[None, :, None] * p1[:, None] + np.sin(ang)[None, :, None] * p2[:, None]
    return np.concatenate([W, n[:, None]], axis=1)


def _filter(model):
    """The bounds a filter's measurement model takes, over the set: per axis the bias (the error at a = 0, m/s^2)
    and the 3 x 3 bound of the error's slope by the true specific force (dimensionless: scale on the diagonal,
    misalignment and cross-axis off it); the error of g counts in the diagonal (u)."""
    zero = np.zeros((1, 3))
    lo, hi = model.ranges(zero, np.eye(3))
    bias = np.maximum(-lo, hi)[0]
    slope = np.zeros((3, 3))
    for j in range(3):
        e = np.zeros((1, 3))
        e[0, j] = 1.0
        d1, C1 = model.build(e)
        d0, C0 = model.build(zero)
        sub = Model(model.st, lambda n, d1=d1, d0=d0, C1=C1, C0=C0: (d1 - d0, C1 - C0), np.zeros(3), model.g, 0.0)
        lo, hi = sub.ranges(np.zeros((1, 3)), np.eye(3))
        slope[:, j] = np.maximum(-lo, hi)[0] / model.g
    slope += model.u * np.eye(3)
    return {"bias_bound_mps2": bias.tolist(), "slope_bound": slope.tolist()}


def refuted(cal, M_p, b_p):
    """None when the correction (M_p, b_p) (garant's convention) is a unit of the norm set of `cal`, else
    (the interval, its residual over its bound): the interval whose linearised relation (2.2) of 001 it misses by
    the most, with the shift the set allows counted for it."""
    st, g = cal["information_set"], cal["g"]
    M_fit, b_fit = fit(cal)
    Lq = M_fit @ np.linalg.inv(M_p) - np.eye(3)
    q = np.array([Lq[0, 0], Lq[1, 1], Lq[2, 2], Lq[1, 0], Lq[2, 0], Lq[2, 1], *(M_fit @ (b_p - b_fit) / g)])
    rows, s, bound = (np.asarray(st[k], float) for k in ("rows", "centre", "bound"))
    over = (np.abs(s - rows @ q) - np.abs(rows) @ np.asarray(st["shift"], float)) / bound
    k = int(np.argmax(over))
    return None if over[k] <= 1 else (k + 1, float(over[k]))


def _constant(cal, path):
    if "thermal" in cal or (cal.get("effects") or {}).get("names"):
        raise DataError(f"{path}: a calibration over temperature or with catalogue effects is budgeted over its own "
                        "information set only: give it without --log", param="calibration")


def own(cal, path, progress=None):
    """The budget of a garant calibration (the checked dictionary, read from `path`) over its own information set;
    DataError naming what is missing when it carries none or is one budget does not take yet."""
    from ..io import results
    if "thermal" in cal and "information_set" not in cal:
        raise DataError(f"{path}: a stand's calibration over temperature in the block's axes (three-axis, single-axis) "
                        "carries no information_set and is not budgeted; budget the constant calibration of the same "
                        "readings", param="calibration")
    if "information_set" not in cal:
        raise DataError(f"{path}: holds no information_set (a set too large for a file): give --log LOG to judge it "
                        "against a log's own set", param="calibration")
    if "thermal" in cal and "block_columns" in cal["information_set"]:
        raise DataError(f"{path}: a stand's calibration over temperature in the block's axes (three-axis, single-axis) "
                        "is not budgeted yet; budget the constant calibration of the same readings",
                        param="calibration")
    if sample_set.twelve(cal):
        raise DataError(f"{path}: a 12-parameter norm calibration (its nonlinearity delta) is not budgeted yet: give "
                        "--log LOG to judge it against a log's own set, or budget the 9-parameter calibration of the "
                        "same log", param="calibration")
    effects = cal["kind"] == "norm" and len(cal["information_set"]["estimate"]) > 9   # effects (applied or not)
    out = {"calibration": str(path), "calibration_kind": f"garant {cal['kind']}", "calibration_slot": None, "log": None,
           "horizons_s": list(HORIZONS_S), "temperature_range_c": None, "frame_turn_deg": 0.0, "refuted": None,
           "garant": None}
    got = effect_figures(cal, progress) if effects else lower_thermal_figures(cal, progress) if "thermal" in cal \
        else figures(norm_model(cal) if cal["kind"] == "norm" else stand_model(cal), progress)
    out.update(got, g=cal["g"], g_uncertainty=float(cal["information_set"]["g_uncertainty"]),
               premises=cal["premises"])
    return results.Budget(out)


def run(calibration, log=None, log_result=None, progress=None, imu=None):
    """The budget of a calibration file (`garant budget CAL [--log LOG]`): of a garant file over its own set, or,
    with `log` and its calibration `log_result` (calibrate-norm's result), of any calibration (garant's, imu_tk's,
    imucal's, a flight stack's parameter file: the slot of the log's accelerometer, or of `imu`) over the set of
    that log, with garant's calibration of the log beside it."""
    from ..io import calibration as cal_io, results
    path = str(calibration)
    kind, cal, b_p, slot = peer(path, (log_result or {}).get("flight"), imu)
    out = {"calibration": path, "calibration_kind": kind if kind != "garant" else f"garant {cal['kind']}",
           "calibration_slot": slot, "log": None if log is None else str(log), "horizons_s": list(HORIZONS_S),
           "temperature_range_c": None, "frame_turn_deg": 0.0, "refuted": None, "garant": None}
    if kind == "garant":
        if log is None:
            return own(cal, path, progress)
        _constant(cal, path)
        M_p, b_p = cal["M"], cal["b"]
    elif log is None:
        raise DataError(f"{path}: a calibration made by {kind} is judged against the readings: give --log LOG (the "
                        "log it was made from, or any static log of the same unit)", param="log")
    else:
        M_p = cal
    res = log_result
    if not res["consistent"] or "calibration" not in res:
        raise DataError(f"{log}: the log is not consistent with the norm relation under its noise bound (worst "
                        f"interval {res['worst_over_bound']:.3g}x its bound): no set to judge a calibration against",
                        param="log")
    mine = cal_io.checked(res["calibration"], str(log))
    if "information_set" not in mine:
        raise DataError(f"{log}: its calibration carries no information set (too many intervals for a file): no "
                        "budget", param="log")
    L, _, turn = garant_frame(np.asarray(M_p, float))
    ref = refuted(mine, L, np.asarray(b_p, float))
    out.update(figures(norm_model(mine, L, b_p), progress), g=mine["g"], g_uncertainty=float(
        mine["information_set"]["g_uncertainty"]), premises=mine["premises"], frame_turn_deg=turn,
        refuted=None if ref is None else {"interval": ref[0], "times_its_bound": ref[1]},
        garant=figures(norm_model(mine)))
    return results.Budget(out)


def attitude(a, bound):
    """(roll, pitch, roll_bound, pitch_bound), rad, of still samples: a (N, 3) corrected specific force (m/s^2, the
    vertical of a still unit, up), bound (N, 3) its per-sample error bound. roll = atan2(a_y, a_z), pitch =
    atan2(-a_x, hypot(a_y, a_z)) (the usual tilt-sensing convention: level with z up reads 0, 0). The true vertical
    lies within the angle t = asin(|bound| / |a|) of a (every a - e with |e| <= r < |a|: the cone of half-angle
    asin(r / |a|)): pitch, an elevation, errs by at most t; roll, the azimuth about x, by at most
    asin(sin t / cos(pitch)) while that cap misses the x axis, else by anything (pi)."""
    a, bound = np.asarray(a, float), np.asarray(bound, float)
    norm = np.linalg.norm(a, axis=1)
    r = np.linalg.norm(bound, axis=1) * (1 + 1e-12)
    t = np.arcsin(np.clip(r / np.maximum(norm, 1e-300), 0.0, 1.0))
    t = np.where(r < norm, t, np.pi)
    side = np.hypot(a[:, 1], a[:, 2])
    roll, pitch = np.arctan2(a[:, 1], a[:, 2]), np.arctan2(-a[:, 0], side)
    s = np.sin(np.minimum(t, np.pi / 2)) / np.maximum(side / np.maximum(norm, 1e-300), 1e-300)
    roll_bound = np.where((s < 1) & (t < np.pi / 2), np.arcsin(np.clip(s, 0.0, 1.0)), np.pi)
    return roll, pitch, roll_bound * (1 + 1e-12), np.minimum(t, np.pi) * (1 + 1e-12)
