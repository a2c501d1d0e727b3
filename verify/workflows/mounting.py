"""The block in any mounting Q: exact simulation, and recovery of its physical errors with bounds."""
import numpy as np

from ..solve import taylor

PHYSICAL_KEYS = ("kappa", "dalpha_plus_astar", "epsilon")


def mounted_readings(mod, remount, alpha, beta, stand, Gamma, bias, theta_k, mount, g):
    """Exact readings (3, ...) in m/s^2 of a block mounted by Q with errors given in block axes.

    stand: the base model's stand parameters except theta (dict name -> value); Gamma (3x3) and
    bias (3, over g) in block axes; theta_k (3, rad) the mounting misalignment in block axes.
    The block's readings are Q times those of the base model with Gamma' = Q^-1 Gamma Q,
    Delta_f0' = Q^-1 Delta_f0 and theta' = Q^-1 theta^k ((26)-(27) of 000), exactly.
    """
    Q = remount.MOUNTS[mount]
    values = dict(stand)
    Gt, bt, tt = Q.T @ np.asarray(Gamma) @ Q, Q.T @ np.asarray(bias), Q.T @ np.asarray(theta_k)
    for i in range(3):
        values[f"bias{i + 1}"] = bt[i]
        for j in range(3):
            values[f"Gamma{i + 1}{j + 1}"] = Gt[i, j]
    values.update(dict(zip(("theta1", "theta2", "theta3"), tt)))
    physical = [values.get(n, 0.0) for n in mod.PARAMETER_NAMES]
    return np.einsum("ij,j...->i...", Q, mod.readings(alpha, beta, physical, g))


def recover(remount, mount, gamma, info, g, q_shift=0.0, neglected=None, q_box=None):
    """Physical errors in block axes, each K_row q bounded over the information set `info`
    (guarantee.InformationSet: an LP pair each, proven); q_shift bounds a further shift of q (the gap of
    the literal q, `literal_gap`); biases are returned in m/s^2. `neglected` {name: bound}: the a-priori
    bounds of what (29) of 000 leaves out, Delta_g/g (on the diagonal of Gamma) and Delta_beta (in the
    theta_k of the axis along the table's), added to those bounds: a premise, printed with them. Returns
    (values, bounds, note, the part of each bound the premises alone set: no readings reduce it)."""
    K = remount.recovery_matrix(mount, gamma)
    nq = info.A.shape[0]
    if nq > K.shape[1]:                          # a thermal extension: its first q are the base model's, at t0
        K = np.hstack([K, np.zeros((len(K), nq - K.shape[1]))])
    names = list(remount.OUTPUTS)
    exact = gamma == "lower" and q_box is not None
    rows = [k for k, n in enumerate(names) if not (exact and n.startswith("Gamma"))]
    lo, hi = np.zeros(len(K)), np.zeros(len(K))
    lo[rows], hi[rows] = info.ranges(K[rows])
    value, half = taylor.midrad(lo, hi)
    neglected = neglected or {}
    dg, db = neglected.get("Delta_g", 0.0), neglected.get("Delta_beta", 0.0)
    premised = (np.abs(K) @ np.broadcast_to(q_shift, K.shape[1]) + np.abs(remount.neglected(mount, 1.0, 0.0,
                                                                                            gamma)) * dg
                + np.abs(remount.neglected(mount, 0.0, 1.0, gamma)) * db)
    bound = (half + premised) * (1 + 1e-15)
    if exact:                                    # Gamma exactly (LQ), not through the linear split and its gap
        G, GB, GP = exact_gamma(remount, mount, *q_box, dg)
        for i in range(3):
            for j in range(3):
                k = names.index(f"Gamma{i + 1}{j + 1}")
                value[k], bound[k], premised[k] = G[i, j], GB[i, j], GP[i, j]
    note = ("(29) of 000 leaves out Delta_g/g and Delta_beta (not identifiable on this stand): the bounds include "
            f"what their a-priori bounds move the outputs by, |Delta_g/g| <= {dg:g} and |Delta_beta| <= {db:g}")
    return _by_kind(remount, value, g), _by_kind(remount, bound, g, 1 + 1e-15), note, _by_kind(remount, premised, g)


def _by_kind(remount, x, g, up=1.0):
    """Outputs in the order of OUTPUTS as {kappa, dalpha_plus_astar, epsilon, bias (m/s^2), Gamma, theta_k}."""
    names = list(remount.OUTPUTS)
    out = {key: float(x[names.index(key)]) for key in PHYSICAL_KEYS}
    out["bias"] = (g * x[[names.index(f"bias{i}") for i in (1, 2, 3)]] * up).tolist()
    out["Gamma"] = x[[names.index(f"Gamma{i}{j}") for i in (1, 2, 3) for j in (1, 2, 3)]].reshape(3, 3).tolist()
    out["theta_k"] = x[[names.index(f"theta_k{i}") for i in (1, 2, 3)]].tolist()
    return out


def exact_gamma(remount, mount, q_lo, q_hi, u):
    """(value, bound, premised) of the block's Gamma (3 x 3, block axes, lower-triangular) over the box of q and
    |Delta_g/g| <= u, without the second-order gap of (29) of 000 taken linearly. The equivalent unit's
    E + Gamma' in block axes, M = Q (E + G(q)) Q^T, is s (E + Gamma) R with s = 1 - Delta_g/g and R a rotation
    (the mounting and Delta_beta): a lower-triangular factor with a positive diagonal times a rotation is
    unique (LQ; L the Cholesky factor of M M^T), so Gamma = L / s - E exactly. Each entry is enclosed in
    interval arithmetic (solve/interval.py: every operation rounded outward) over the box; `premised` is the part
    |Delta_g/g| <= u alone sets, |L| u / (1 - u)."""
    from ..solve import interval
    Q = np.asarray(remount.MOUNTS[mount], float)
    idx = np.asarray(remount.G_INDEX)
    pairs = [(i, j) for i in range(3) for j in range(3)]

    def split(*x):
        return lq([x[0:3], x[3:6], x[6:9]], x[9], Q)[0]

    def enclose(lo, hi):                  # the box is a few sigma wide: the natural enclosure is tight enough
        return split(*(interval.Iv(np.atleast_1d(a), np.atleast_1d(b)) for a, b in zip(lo, hi)))
    g_lo = [q_lo[idx[i, j]] for i, j in pairs]
    g_hi = [q_hi[idx[i, j]] for i, j in pairs]
    whole = enclose(g_lo + [1 - u], g_hi + [1 + u])
    value, bound, premised = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
    for (i, j), w in zip([(0, 0), (1, 0), (2, 0), (1, 1), (2, 1), (2, 2)], whole):
        value[i, j], bound[i, j] = (float(x) for x in taylor.midrad(w.lo[0], w.hi[0]))
        # s alone moves L / s by at most |L| u / (1 - u): what no readings reduce
        premised[i, j] = min(abs(value[i, j] + (i == j)) * u / (1 - u), bound[i, j])
    return value, bound, premised


def lq(G, s, Q):
    """(f, W) of x = (G (3 x 3 of the equivalent unit), s): f = L / s - E (lower entries, row-major 6) and
    W = R^T / s (3 x 3) for Q (E + G) Q^T = L R (LQ); G and s intervals
    (solve/interval.py) or interval.Grad over a box: every operation is theirs, so each result encloses the
    exact one."""
    pairs = [(i, j) for i in range(3) for j in range(3)]
    EG = [[G[i][j] + (1.0 if i == j else 0.0) for j in range(3)] for i in range(3)]
    M = [[sum(EG[i][j] * float(Q[a, i] * Q[b, j]) for i, j in pairs if Q[a, i] and Q[b, j]) for b in range(3)]
         for a in range(3)]
    A = [[M[a][0] * M[b][0] + M[a][1] * M[b][1] + M[a][2] * M[b][2] for b in range(3)] for a in range(3)]
    L11 = A[0][0].sqrt()
    r11 = L11.recip()
    L21, L31 = A[1][0] * r11, A[2][0] * r11
    L22 = (A[1][1] - L21 * L21).sqrt()
    r22 = L22.recip()
    L32 = (A[2][1] - L31 * L21) * r22
    L33 = (A[2][2] - L31 * L31 - L32 * L32).sqrt()
    r33 = L33.recip()
    R0 = [M[0][b] * r11 for b in range(3)]
    R1 = [(M[1][b] - L21 * R0[b]) * r22 for b in range(3)]
    R2 = [(M[2][b] - L31 * R0[b] - L32 * R1[b]) * r33 for b in range(3)]
    r = s.recip()
    f = [L11 * r + (-1.0), L21 * r, L31 * r, L22 * r + (-1.0), L32 * r, L33 * r + (-1.0)]
    W = [[R[a] * r for R in (R0, R1, R2)] for a in range(3)]
    return f, W


def literal_gap(mod, premises, gamma_bound):
    """Bound of |q - q_literal| for each q: q are those of the unit with the model's ABSORBED parameters
    absorbed into Gamma, Gamma' = (1 - Delta_g)(E + Gamma) R - E with R = Q C(theta) Q^T; q_literal are the
    combinations (4) of 000 of the unit itself, on which the split (28)-(29) into Gamma and theta_k is
    linear. Their difference is PHYSICAL_TO_Q on the Gamma entries of the second-order part of Gamma',
        D = Gamma (R - E) + (R - E - Theta) - Delta_g (A R - E),   A = E + Gamma, Theta: R's first order.
    With s = 1 - Delta_g, A = (E + Gamma') R^T / s and s A R = E + Gamma' give
        D = [(2E - R - R^T) + Delta_g (R - E) + Gamma' (E - R^T) - Delta_g (Gamma' + Delta_g E)] / s + (R - E - Theta),
    and with t = |theta1| + |theta2| + |theta3| (R a product of three exponentials of skew generators of
    norm 1) every entry of R - E is within e^t - 1, of R - E - Theta within e^t - 1 - t, of the symmetric
    2E - R - R^T (twice R's second-order part, the first cancels) within 2 (e^t - 1 - t). The bounds of
    theta and u = |Delta_g/g| are those `premises.split` holds: premises of the split alone. gamma_bound:
    entrywise bound of Gamma' (3 x 3)."""
    names, kinds = list(premises.names), dict(zip(premises.names, premises.kinds))
    t = sum(premises.split[n][0] for n in premises.absorbed if kinds[n] in ("mounting", "stand"))
    u = max((premises.split[n][0] for n in premises.absorbed if kinds[n] == "gravity"), default=0.0)
    r1, r2 = np.expm1(t), np.expm1(t) - t
    B = np.asarray(gamma_bound, float)
    D = (2 * r2 + u * r1 + B.sum(axis=1, keepdims=True) * r1 + u * (B + u * np.eye(3))) / (1 - u) + r2
    cols = [names.index(f"Gamma{i}{j}") for i in (1, 2, 3) for j in (1, 2, 3)]
    return np.abs(np.asarray(mod.PHYSICAL_TO_Q, float)[:, cols]) @ D.reshape(-1) * (1 + 1e-12)
