"""Calibration over temperature: each q a polynomial in T, one guaranteed bound over the whole range.

The thermal model (derive/effects.py `thermal`) gives every block parameter p (Gamma_ij, bias_i) the
coefficients p_Tk of (T - T0)^k, k = 1..degree. Each q then has a polynomial

    q(T) = psi(tau)^T q_ext,   psi(tau) = e_q + sum_k tau^k x_k,   tau = T - T0,

with x_k the combination of the extended q that is q's block part with every p replaced by p_Tk (found
from PHYSICAL_TO_Q, checked exactly). Its error over the information set Q of the estimate, for every
T in [Tmin, Tmax] at once, is bounded by the Bernstein form: on [a, b], psi(tau) lies in the convex hull
of its Bernstein control points beta_i, and q -> max over Q of beta^T (q - q_hat) is convex, so

    sup over tau in [a, b] of max over Q |psi(tau)^T (q - q_hat)|  <=  max_i of the ends of beta_i over Q,

each end an LP proven by duality (solve/hull.py through InformationSet.ranges). No T is sampled.
"""
from math import comb

import numpy as np

from ..errors import DataError, opt

PIECES = 8          # the range cut into this many pieces, each bounded by its own control points
ROUND_C = 0.5       # temperatures within this of each other (C) count as one chamber temperature


def temperatures(positions, path):
    """The temp_c column of the positions (C), or DataError naming it."""
    T = positions.extra.get("temp_c")
    if T is None:
        raise DataError(f"{path}: {opt('temperature')} needs a temp_c column (degrees C) in the positions file")
    T = np.asarray(T, float)
    if not np.all(np.isfinite(T)) or np.abs(T).max() > 200:
        raise DataError(f"{path}: temp_c must be finite temperatures within +-200 C", param="data")
    return T


def plateaus(T):
    """The distinct chamber temperatures (C): values within ROUND_C of each other taken as one."""
    out = []
    for t in np.sort(T):
        if not out or t - out[-1][-1] > ROUND_C:
            out.append([t])
        else:
            out[-1].append(t)
    return np.array([np.mean(g) for g in out])


CHAMBER_POSITIONS = 3   # a chamber temperature holds at least this many positions (a drifting room holds one each)


def chamber_levels(positions):
    """The chamber temperatures of a positions file (C): plateaus holding CHAMBER_POSITIONS or more positions;
    empty without a temp_c column."""
    T = positions.extra.get("temp_c")
    if T is None:
        return []
    T = np.asarray(T, float)
    return [t for t in plateaus(T) if np.count_nonzero(np.abs(T - t) <= ROUND_C) >= CHAMBER_POSITIONS]


def degree_needed(levels, estimate):
    """The least degree D (1 to 3, at most the chamber temperatures less one) whose thermal model the data
    are consistent with (`estimate(D)` a result of estimate --thermal-degree D), and each degree tried:
    {"tried": [(D, consistent)], "needed": D or None}."""
    tried = []
    for degree in range(1, min(3, len(levels) - 1) + 1):
        try:
            ok = bool(estimate(degree)["consistent"])
        except DataError as e:                    # the degree not identified: said, and the next one tried
            tried.append({"degree": degree, "consistent": None, "why": str(e)})
            continue
        tried.append({"degree": degree, "consistent": ok})
        if ok:
            return {"tried": tried, "needed": degree}
    return {"tried": tried, "needed": None}


def reference(T, degree, path):
    """T0 (the middle of the range, whole degrees C); DataError when the temperatures cannot identify the
    degree (fewer distinct ones than degree + 1)."""
    levels = plateaus(T)
    if len(levels) < degree + 1:
        raise DataError(f"{path}: {len(levels)} distinct temperature(s) ({', '.join(f'{t:g}' for t in levels)} C) "
                        f"cannot identify a polynomial of degree {degree} in T (it needs {degree + 1}); measure at "
                        f"{degree + 1 - len(levels)} more temperature(s) or lower {opt('temperature')}")
    return int(round(0.5 * (T.min() + T.max())))


def polynomials(mod, degree):
    """{q name: (x_0, ..., x_degree)}: q(T) = sum_k tau^k x_k^T q_ext, for every q of the base model that has a
    block part (x_0 = e_q); the combinations are solved from PHYSICAL_TO_Q and checked to 1e-12."""
    R = np.asarray(mod.PHYSICAL_TO_Q, float)
    names = list(mod.PARAMETER_NAMES)
    thermal = {n for n in names if "_T" in n and n.rsplit("_T", 1)[1].isdigit()}
    out = {}
    for j, qname in enumerate(mod.Q_NAMES):
        used = [names[i] for i in np.flatnonzero(R[j])]
        if any(n in thermal for n in used):
            continue
        block = [n for n in used if f"{n}_T1" in names]
        if not block:
            continue
        xs = [np.eye(len(R))[j]]
        for k in range(1, degree + 1):
            r = np.zeros(len(names))
            for n in block:
                r[names.index(f"{n}_T{k}")] = R[j, names.index(n)]
            x, *_ = np.linalg.lstsq(R.T, r, rcond=None)
            x = np.round(x, 9)
            if np.abs(R.T @ x - r).max() > 1e-12:
                break
            xs.append(x)
        if len(xs) == degree + 1:
            out[qname] = tuple(xs)
    return out


def psi(xs, tau):
    """psi(tau) = sum_k tau^k xs[k]."""
    return sum(tau ** k * x for k, x in enumerate(xs))


def bernstein(xs, a, b):
    """The Bernstein control points (rows) on [a, b] of psi(tau) = sum_k tau^k xs[k]; the first and last are
    psi(a) and psi(b) (so neighbouring pieces share them exactly)."""
    d, h = len(xs) - 1, b - a
    y = [sum(comb(k, m) * a ** (k - m) * h ** m * xs[k] for k in range(m, d + 1)) for m in range(d + 1)]
    pts = np.array([sum(comb(i, m) / comb(d, m) * y[m] for m in range(i + 1)) for i in range(d + 1)])
    pts[0], pts[-1] = psi(xs, a), psi(xs, b)
    return pts


def controls(info, q_hat, C, reach=None):
    """(lo, hi, v, worst) per row c of C (control points): the proven ends of c^T q over the information set
    `info`, v = c^T q_hat and worst = max |c^T (q - q_hat)| over the set, padded by the float rounding of the
    rows (reach: a bound of |q|, default |q_hat|). A row of zeros (psi of the drift at T0) takes no LP, and rows
    shared by neighbouring pieces or chamber points one pair."""
    nonzero = np.flatnonzero(np.abs(C).max(axis=1) > 0)
    U, back = np.unique(C[nonzero], axis=0, return_inverse=True)
    lo, hi = np.zeros(len(C)), np.zeros(len(C))
    lo[nonzero], hi[nonzero] = (x[np.ravel(back)] for x in info.ranges(U))
    v = C @ q_hat
    pad = 1e-12 * (np.abs(C) @ (np.abs(q_hat) if reach is None else reach)) + 1e-300
    return lo, hi, v, np.maximum(hi - v, v - lo) + pad


def summary(mod, info, q, e, T, degree, t0):
    """The thermal part of an estimate: per q its coefficients (lowest first, per C^k), q(T0) and one
    guaranteed bound over [Tmin, Tmax]; the estimate and bound at each chamber temperature beside it."""
    polys = polynomials(mod, degree)
    lo_t, hi_t = float(T.min()), float(T.max())
    levels = plateaus(T)
    cuts = np.linspace(lo_t - t0, hi_t - t0, PIECES + 1)
    q_hat = np.asarray(q, float)
    reach = np.abs(q_hat) + np.asarray(e, float)
    coef, bound, drift, at = {}, {}, {}, {}
    taus = levels - t0
    stack, parts = [], {}           # every control point and chamber psi of every q, for one batch of LPs

    def add(name, what, pts):
        parts[name, what] = (len(stack), len(pts))
        stack.extend(pts)
    for name, xs in polys.items():
        zero = (0 * xs[0],) + tuple(xs[1:])                     # q(T) - q(T0): what a calibration at T0 adds
        add(name, "range", np.vstack([bernstein(xs, a, b) for a, b in zip(cuts[:-1], cuts[1:])]))
        add(name, "drift", np.vstack([bernstein(zero, a, b) for a, b in zip(cuts[:-1], cuts[1:])]))
        add(name, "at", np.array([psi(xs, t) for t in taus]))
    lo, hi, v, worst = controls(info, q_hat, np.array(stack), reach)

    def over_range(name, what):
        """The proven sup over the range of |psi(tau)^T (q - q_hat)|: the largest at its control points."""
        i, n = parts[name, what]
        return float(worst[i:i + n].max())
    for name, xs in polys.items():
        coef[name] = (np.array(xs) @ q_hat).tolist()
        drift[name] = over_range(name, "drift")
        i, n = parts[name, "at"]
        at[name] = [(float(t), float(x), float(max(h - x, x - lo_) * (1 + 1e-12)))
                    for t, x, lo_, h in zip(levels, v[i:i + n], lo[i:i + n], hi[i:i + n])]
        # each proof holds; the range's is never printed below a chamber temperature's own (their LPs' rounding)
        bound[name] = max(over_range(name, "range"), max(b for _, _, b in at[name]))
    return {
        "t0_c": t0, "degree": degree, "range_c": [lo_t, hi_t], "temperatures_c": levels.tolist(),
        "q": coef, "bound": bound, "bound_drift": drift,
        "units": {name: [mod.Q_UNITS[mod.Q_NAMES.index(name)]] + [f"{mod.Q_UNITS[mod.Q_NAMES.index(name)]}/C^{k}"
                                                                   for k in range(1, degree + 1)] for name in polys},
        "at_temperature": {name: [{"temp_c": t, "q": x, "bound": b} for t, x, b in rows] for name, rows in at.items()},
        "premise": (f"each Gamma_ij and bias_i is a polynomial of degree {degree} in T over [{lo_t:g}, {hi_t:g}] C "
                    f"(T = temp_c); the bound holds at every T of that range, not beyond it"),
    }


def plan(model, temperatures, degree):
    """Which positions at which chamber temperatures identify every coefficient of the thermal model: the
    candidate positions of the stand (detents or quarter turns, every mounting) at each temperature, added
    one temperature at a time, each time the position that raises the rank the most (ties: the first), until
    every q is identified. Returns the plan {temperature: [(angles in degrees, mounting index)]}, the positions
    per temperature it needed, the counting lower bound (3 readings a position: at least q / (3 n) per
    temperature) and the model."""
    from .. import models
    from ..solve import lp, plans
    temps = [float(t) for t in temperatures]
    if len(temps) < degree + 1:
        raise DataError(f"{len(temps)} temperature(s) cannot identify a polynomial of degree {degree} in T (it needs "
                        f"{degree + 1}); give more with {opt('temperatures')} or lower {opt('temperature')}")
    t0 = int(round(0.5 * (min(temps) + max(temps))))
    mod = models.thermal(model, degree, t0)
    P, M = plans.grid(mod)
    nq = len(mod.Q_NAMES)
    blocks = [lp.measurement_matrix(mod, np.deg2rad(P), M, [np.full(len(P), t)]).T.reshape(len(P), 3, nq)
              for t in temps]
    chosen = {j: [] for j in range(len(temps))}
    rows = np.zeros((0, nq))
    scale = max(float(np.abs(b).max()) for b in blocks)
    rank = 0
    while rank < nq:
        moved = False
        for j in range(len(temps)):
            if rank == nq or len(chosen[j]) == len(P):
                continue
            best, best_rank = None, rank
            for i in range(len(P)):
                if i in chosen[j]:
                    continue
                r = np.linalg.matrix_rank(np.vstack([rows, blocks[j][i]]), tol=1e-9 * scale)
                if r > best_rank:
                    best, best_rank = i, r
            if best is not None:
                chosen[j].append(best)
                rows, rank, moved = np.vstack([rows, blocks[j][best]]), best_rank, True
        if not moved:
            break
    A = np.vstack([blocks[j][i] for j in chosen for i in chosen[j]]).T
    missing = lp.unidentifiable(A)
    if missing:
        raise DataError(f"the stand's positions at {len(temps)} temperatures cannot identify "
                        + ", ".join(f"{mod.Q_NAMES[k]} ({mod.Q_DEFINITIONS[k]})" for k in missing[:6]),
                        param="temperatures")
    per = max(len(c) for c in chosen.values())
    lower = -(-nq // (3 * len(temps)))
    out = {t: [(tuple(float(a) for a in P[i]), int(M[i])) for i in sorted(chosen[j])] for j, t in enumerate(temps)}
    return out, per, lower, mod
