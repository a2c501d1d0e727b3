"""`garant calibrate-norm LOG --thermal-degree D`, D = 1 to 3: a warm-up log's biases, scale factors and
misalignments, each a polynomial in the IMU's temperature T (its temp_c column), with one guaranteed bound over
the logged range, and the files the flight stacks load (io/tcal.py) from it; a still-only warm-up's drift per axis.

The norm relation (2.2) of 001 carries the effects bias_temperature, scale_temperature and
misalignment_temperature (and their terms of degree 2 and 3: derive/effects.py, workflows/norm_effects.py), T
counted from the middle of the range, so every parameter is bounded over the information set of that extended
relation. In the raw readings, with x = T - t_ref and P = M^-1,

    raw = b + g P (a / g + sum_k x^k (T_k + K_k a / g)),   K_k = diag(S_k) + the strictly lower X_k,

so the raw bias over g is beta(T) = b / g + sum_k x^k P T_k and the raw scale and misalignment matrix Gamma(T) =
P (E + sum_k x^k K_k) - E: per axis the polynomials the flight stacks hold (bias_i, Gamma_ii), about t0 (`block`).
"""
import numpy as np

from ..errors import DataError, opt

#: The degrees of --thermal-degree D calibrate-norm fits.
DEGREES = (1, 2, 3)


def names(degree):
    """The effects that carry the polynomials of `degree` (workflows/norm_effects.py, derived in derive/norm.py)."""
    return tuple(f"{kind}_temperature{'' if k == 1 else f'_{k}'}" for kind in ("bias", "scale", "misalignment")
                 for k in range(1, degree + 1))


#: A still interval is cut where the temperature has moved by more than this (C) since the piece began.
SPLIT_C = 1.0


def of_intervals(data, stills):
    """Each still interval's mean temperature (C) and the temperature's rate over it (C/s, a least-squares line
    through its samples): the variables of the temperature effects."""
    temps, rates = [], []
    for st in stills:
        keep = (data.t >= st.start) & (data.t <= st.stop)
        t, T = data.t[keep], data.temp[keep]
        temps.append(float(np.mean(T)))
        rates.append(float(np.polyfit(t - t.mean(), T, 1)[0]) if len(t) > 1 and np.ptp(t) > 0 else 0.0)
    return temps, rates


def sample_range(data, stills):
    """(lowest, highest) temperature of the samples in the still intervals (C): the range a calibration over
    temperature is proven and applied over."""
    keep = np.zeros(len(data.t), bool)
    for st in stills:
        keep |= (data.t >= st.start) & (data.t <= st.stop)
    return float(data.temp[keep].min()), float(data.temp[keep].max())


def check_degree(degree):
    """The degree of --thermal-degree D, or a one-line refusal."""
    if isinstance(degree, bool) or degree not in DEGREES:
        raise DataError(f"{opt('thermal_degree')} {str(degree)[:20]}: give the degree of the polynomials in T, "
                        f"1, 2 or 3",
                        param="thermal_degree")
    return degree


def split(data, stills, min_still):
    """Each still interval cut into pieces over which the temperature moves by at most SPLIT_C (each at least
    min_still s, the last piece joined to the one before when shorter): a warm-up's long still interval becomes
    one interval per temperature step, each at its own mean temperature."""
    from .stills import still_of
    out = []
    for st in stills:
        idx = np.flatnonzero((data.t >= st.start) & (data.t <= st.stop))
        T = data.temp[idx]
        cuts, a = [0], 0
        for k in range(1, len(idx)):
            if abs(T[k] - T[a]) > SPLIT_C and data.t[idx[k]] - data.t[idx[a]] >= min_still:
                cuts.append(k)
                a = k
        if len(cuts) > 1 and data.t[idx[-1]] - data.t[idx[cuts[-1]]] < min_still:
            cuts.pop()
        cuts.append(len(idx))
        out += [still_of(data, idx[i], idx[j - 1] + 1) for i, j in zip(cuts[:-1], cuts[1:])]
    return out


#: The range cut into this many pieces, each bounded by the Bernstein control points of its polynomial.
PIECES = 8


def block(ext, A, s, bnd, lo, hi, shift, M_fit, b_fit, g, dq, J):
    """The thermal result (the shape of estimate --thermal-degree's, which io/tcal.py writes the flight stacks'
    files from): per axis the raw bias over g and the scale Gamma_ii as polynomials about t0 with one bound over
    the logged range, over the information set (A, s, bnd: |s - A^T w| <= bnd, q = w + s', |s'| <= shift, q
    within lo, hi; dq the set's midpoint, where the estimate is). M_fit, b_fit: the fit (m/s^2 per raw unit); J:
    how the printed lambda_i (P_ii - 1) and eps_i/g (b_i/g) move with q (norm_bounds.parameter_map).

    With x = T - ref (the effects' reference temperature, ext.temp_ref), beta_i(T) = b_i/g + sum_k x^k (P (E +
    A(q)) T_k)_i and Gamma_ii(T) = (P (E + A(q)))_ii (1 + sum_k x^k S_k,i) - 1. Their parts linear in q are
    polynomials in x with rows of q as coefficients; on each of PIECES pieces of the range the largest |L(x) (q -
    q_hat)| over the set is at most the largest over the Bernstein control points of L (workflows/thermal.py
    `bernstein`: L(x) is their convex combination), each an LP pair proven by duality. The parts bilinear in q
    (P's correction times an effect's) are bounded from the set's
    box, at q and at q_hat."""
    from ..solve import hull
    from .norm_information import lower
    from .thermal import bernstein
    t_lo, t_hi = ext.thermal_range
    t0, ref = round(0.5 * (t_lo + t_hi), 1), ext.temp_ref       # the effects' temperature counts from ref
    D = max(int(x.rsplit("_", 1)[1]) if x[-1].isdigit() else 1 for x in ext.names)
    P = np.linalg.inv(M_fit)
    Q = A.shape[0]
    k_T = [[9 + ext.labels.index(f"T{'' if k == 1 else k}_{i + 1}") for i in range(3)] for k in range(1, D + 1)]
    # K_k = diag(S_k) + X_k (strictly lower): the scale and misalignment terms of degree k, index in q per entry
    k_K = [{(i, i): 9 + ext.labels.index(f"S{'' if k == 1 else k}_{i + 1}") for i in range(3)}
           | {(i, j): 9 + ext.labels.index(f"X{'' if k == 1 else k}_{i + 1}{j + 1}") for i, j in LOWER}
           for k in range(1, D + 1)]
    th = np.r_[np.zeros(9), ext.theta]
    dA = np.zeros((6, 3, 3))                      # d A / d q_k, A = [[q0, 0, 0], [q3, q1, 0], [q4, q5, q2]]
    for k, (i, j) in enumerate(((0, 0), (1, 1), (2, 2), (1, 0), (2, 0), (2, 1))):
        dA[k, i, j] = 1.0
    cells = [(i, i) for i in range(3)] + list(LOWER)          # Gamma_11, 22, 33, 21, 31, 32
    rows = [np.zeros((9, Q)) for _ in range(D + 1)]   # L(x) = sum_k x^k rows[k]: beta_1..3, then the cells
    rows[0][:3, :9], rows[0][3:6, :9], rows[0][6:, :9] = J[6:9], J[0:3], J[3:6]
    for k in range(1, D + 1):
        t_k = th[k_T[k - 1]]
        K = np.zeros((3, 3))
        for (i, j), n in k_K[k - 1].items():
            K[i, j] = th[n]
        for i in range(3):
            rows[k][i, :6] = np.einsum("j,kjl,l->k", P[i], dA, t_k)
            rows[k][i, k_T[k - 1]] = P[i]
        for r, (i, j) in enumerate(cells):        # (P (E + A) K)_ij: through A with K, through K with P
            rows[k][3 + r, :6] = np.einsum("l,klm,m->k", P[i], dA, K[:, j])
            for (row, col), n in k_K[k - 1].items():
                if col == j:
                    rows[k][3 + r, n] = P[i, row]
    cuts = np.linspace(t_lo - ref, t_hi - ref, PIECES + 1)
    C = np.vstack([np.vstack(bernstein(rows, a, b)) for a, b in zip(cuts[:-1], cuts[1:])])
    U, back = np.unique(C, axis=0, return_inverse=True)
    p_lo, p_hi = hull.ranges(A.T, s - bnd, s + bnd, lo - shift, hi + shift, U)
    reach, mid = np.abs(U) @ shift, U @ dq
    half = np.maximum(p_hi + reach - mid, mid - p_lo + reach)[np.ravel(back)].reshape(-1, 9).max(axis=0)
    box = np.maximum(np.abs(lo), np.abs(hi))
    PA = np.abs(P) @ np.abs(lower(box))          # |P A(q)| entrywise, from the set's box
    x_max = max(abs(t_lo - ref), abs(t_hi - ref))
    second = np.zeros(9)                          # the bilinear parts, x^k P A(q) T'_k and x^k P A(q) K'_k
    for k in range(1, D + 1):
        K_box = np.zeros((3, 3))
        for (i, j), n in k_K[k - 1].items():
            K_box[i, j] = box[n]
        PAK = PA @ K_box
        second += x_max ** k * np.r_[PA @ box[k_T[k - 1]], [PAK[i, j] for i, j in cells]]
    bound = (half + 2 * second) * (1 + 1e-9)
    beta, gam = _polynomials(P, dq, th, k_T, k_K, b_fit / g)
    return _result(D, t0, (t_lo, t_hi), _about(beta, t0 - ref), _about(gam, t0 - ref), bound, cells)


def _polynomials(P, dq, th, k_T, k_K, bias):
    """The estimate: the exact polynomials in x = T - ref at the set's midpoint dq, the raw bias over g (`bias` at
    x = 0, then P (E + A(dq)) T_k) and Gamma (P (E + A(dq)) - E, then P (E + A(dq)) K_k), coefficients by degree."""
    from .norm_information import lower
    Pm = P @ (np.eye(3) + lower(dq))
    beta = [bias + P @ dq[6:9]] + [Pm @ (th[t] + dq[t]) for t in k_T]
    gam = [Pm - np.eye(3)]
    for cells in k_K:
        K = np.zeros((3, 3))
        for (i, j), n in cells.items():
            K[i, j] = th[n] + dq[n]
        gam.append(Pm @ K)
    return beta, gam


def _result(D, t0, t_range, beta, gam, bound, cells):
    """The thermal block as estimate --thermal-degree gives it: each bias and Gamma cell's polynomial about t0 (C),
    its one bound over the range and its units."""
    unit = ["1/degC" if k == 1 else f"1/degC^{k}" for k in range(1, D + 1)]
    names = [f"scale{i + 1}" for i in range(3)] + list(MISALIGNMENTS)
    return {"degree": D, "t0_c": t0, "range_c": [float(t_range[0]), float(t_range[1])],
            "q": {**{f"bias{i + 1}": [float(c[i]) for c in beta] for i in range(3)},
                  **{n: [float(c[i, j]) for c in gam] for n, (i, j) in zip(names, cells)}},
            "bound": {**{f"bias{i + 1}": float(bound[i]) for i in range(3)},
                      **{n: float(bound[3 + r]) for r, n in enumerate(names)}},
            "units": {**{f"bias{i + 1}": ["1 (over g)"] + [f"{u} (over g)" for u in unit] for i in range(3)},
                      **{f"scale{i + 1}": ["1"] + unit for i in range(3)},
                      **{n: ["rad"] + [f"rad {u}" for u in unit] for n in MISALIGNMENTS}}}


#: The strictly lower cells of Gamma: the misalignments alpha, beta, gamma of (1.3) of 001.
LOWER = ((1, 0), (2, 0), (2, 1))
MISALIGNMENTS = {"alpha": "Gamma21", "beta": "Gamma31", "gamma": "Gamma32"}


def _about(coeffs, d):
    """The coefficients of p(x) = sum_k coeffs[k] x^k in y = x - d."""
    from math import comb
    return [sum(comb(k, m) * d ** (k - m) * coeffs[k] for k in range(m, len(coeffs))) for m in range(len(coeffs))]


#: What each thermal q is, in the names io/tcal.py looks for (estimate's definitions).
DEFINITIONS = {**{f"bias{i}": f"bias{i}" for i in (1, 2, 3)}, **{f"scale{i}": f"Gamma{i}{i}" for i in (1, 2, 3)},
               **MISALIGNMENTS}


#: Still intervals whose mean readings all lie within this angle (degrees) of the first are one orientation.
ONE_ORIENTATION_DEG = 5.0


def one_orientation(stills):
    """Whether every still interval holds the unit in the same orientation (a still-only warm-up)."""
    m = np.array([st.mean for st in stills])
    m = m / np.linalg.norm(m, axis=1, keepdims=True)
    return bool(np.all(m @ m[0] >= np.cos(np.radians(ONE_ORIENTATION_DEG))))
