"""A corrected sample's error bounded over the information set of its calibration, not through the box of it.

A norm calibration's file M, b is the fit corrected by the set's midpoint q_m (norm_bounds.fold); the truth is
the fit corrected by some q of the set. With N = (E + lower(q_m))^-1 = M M_fit^-1, dq = q - q_m and the true
specific force a_t of a sample the file corrects to a, exactly

    e = a - a_t = N (lower(dq) a_t + g dq_eps) [+ g Phi(p) dtheta, the effects' part],

linear in dq. With a_t = a - e, each component is c_k(a)^T dq - (N lower(dq) e)_k, and |N lower(dq)| <= B (the
file's bound_matrix), so |e| <= (I - B)^-1 w with w_k the largest |c_k(a)^T dq| over the set: an LP per sample
and axis (solve/support.py: proven by duality, one LP per cell of nearby samples). The box bound B |a| + eps
is the same w taken over the set's box instead of the set; the smaller of the two is printed. Where g is
uncertain (|Delta_g/g| <= u) the truth is a_t / (1 + d), |d| <= u: w becomes (1 + u) w + u |a| under the
file's B (which holds u already).

The file carries the set as the LPs that made the calibration bound it (`entry`): each interval's row of the
linearised relation (2.2) of 001 with its noise bound and proven remainder, the column box, the shift the
remainder's part adds (q = x + s, |s| <= shift) and q_m.
"""
import numpy as np

from ..solve import support
from .norm_information import lower

#: The largest set (rows x columns) a calibration file carries: beyond it, the rows that can bind (`binding`), or
#: where those are still more, the box bound alone.
MAX_ENTRIES = 24_000
#: The most rows a file's set holds (its schema's limit).
MAX_ROWS = 4000


def binding(rows, lo, hi, box_lo, box_hi, width=None):
    """The indices of the rows of {x : lo <= rows x <= hi, box_lo <= x <= box_hi} a file carries (`width` numbers
    each, default a row's): every row where they fit MAX_ENTRIES; else those that can bind, or None where still too
    many. A row whose range over the box
    (its centre's value +- |row| times the half-widths, with the rounding outward) lies strictly inside its bounds,
    or whose proven ends over the set of the rows left do (support.essential: that set holds the set), is strictly
    met at every point of the set; the set without all such rows is the set (a point beyond it would join the set
    by a segment leaving it where a dropped row is met with equality)."""
    rows = np.asarray(rows, float)
    width = rows.shape[1] if width is None else width
    if len(rows) * width <= MAX_ENTRIES:
        return np.arange(len(rows))
    c, r = 0.5 * (box_lo + box_hi), 0.5 * (box_hi - box_lo)
    mid, (reach, size) = rows @ c, _abs_products(rows, r, np.abs(c))
    pad = 8 * (rows.shape[1] + 2) * EPS * (size + reach + np.abs(lo) + np.abs(hi))
    may = np.flatnonzero((mid - reach - pad <= lo) | (mid + reach + pad >= hi))
    if len(may) * width > 4 * MAX_ENTRIES:
        return None
    if len(may) * width > MAX_ENTRIES or len(may) > MAX_ROWS:      # the LPs only where the box leaves many
        may = may[support.essential(rows[may], lo[may], hi[may], box_lo, box_hi)[0]]
    return may if may.size * width <= MAX_ENTRIES and len(may) <= MAX_ROWS else None


def _abs_products(rows, *vectors):
    """|rows| v for each v, a block of rows at a time (|rows| of 3e6 readings would be a copy of them)."""
    out = [np.empty(len(rows)) for _ in vectors]
    for b in range(0, len(rows), 1 << 16):
        block = np.abs(rows[b:b + (1 << 16)])
        for o, v in zip(out, vectors):
            o[b:b + len(block)] = block @ v
    return out


def entry(A, s, bound, lo, hi, shift, q_m, u=0.0):
    """The calibration file's `information_set` of a norm calibration: the set {x : |s_k - A_k^T x| <= bound_k,
    lo - shift <= x <= hi + shift} + {|s| <= shift} of the corrections q (A: parameters x intervals), its
    midpoint q_m, the bound u of |Delta_g/g|; the rows that can bind where all are too many for a file
    (`binding`), None where those are too."""
    shift = np.broadcast_to(np.asarray(shift, float), lo.shape)
    s, bound = np.asarray(s, float), np.asarray(bound, float)
    keep = binding(A.T, s - bound, s + bound, lo - shift, hi + shift)
    if keep is None:
        return None
    return {"rows": A.T[keep].tolist(), "centre": s[keep].tolist(), "bound": bound[keep].tolist(),
            "box_lo": (lo - shift).tolist(), "box_hi": (hi + shift).tolist(), "shift": shift.tolist(),
            "estimate": np.asarray(q_m, float).tolist(), "g_uncertainty": float(u)}


def q_entry(info, q_m):
    """The calibration file's `information_set` of a stand's q (guarantee.InformationSet: q = q0 + w - u,
    |y_k - a_k^T w| <= s_k, w in its proven box, |u| <= shift) in the form `entry` writes: x = q0 + w, so
    |y_k + a_k^T q0 - a_k^T x| <= s_k, each row's bound widened by the rounding of its centre; the estimate q_m.
    Where the rows are too many for a file, the box is the set's hull and the rows those that can bind
    (`binding`); None where those are too."""
    A = np.asarray(info.A, float)
    q0, rows = np.asarray(info.lin.q0, float), A.T
    centre = info.y + rows @ q0
    slack = 4 * (len(q0) + 2) * EPS * (np.abs(info.y) + _abs_products(rows, np.abs(q0))[0] + np.abs(centre))
    bound = (np.asarray(info.s, float) + slack) * (1 + 4 * EPS)
    pad = 4 * EPS * (np.abs(q0) + np.abs(info.w_lo) + np.abs(info.w_hi))
    lo, hi = q0 + info.w_lo - pad, q0 + info.w_hi + pad
    if A.size > MAX_ENTRIES:                     # x = q0 + w lies in the set's hull too (q = x - u, |u| <= shift)
        shift = np.broadcast_to(np.asarray(info.shift, float), q0.shape)
        ql, qh = info.q
        wide = 4 * EPS * (np.abs(ql) + np.abs(qh)) + 1e-300
        lo, hi = np.maximum(lo, ql - shift - wide), np.minimum(hi, qh + shift + wide)
    keep = binding(rows, centre - bound, centre + bound, lo, hi)
    if keep is None:
        return None
    return {"rows": rows[keep], "centre": centre[keep], "bound": bound[keep], "box_lo": lo, "box_hi": hi,
            "shift": np.broadcast_to(np.asarray(info.shift, float), q0.shape).copy(),
            "estimate": np.asarray(q_m, float)}


def objectives(st, a, g, phi=None, M=None, N=None, tau=None):
    """C (3, N, P): row k of sample n, c_k(a_n) with e_k = c_k(a)^T dq + ... (the module's docstring); `phi`
    (J, 3, N), the effects' basis at each sample's direction, for the parameters after the 9; `N` the matrix the
    norm set's rows are read through (default (E + lower(q_m))^-1, the file's own; workflows/budget.py passes a
    peer's). A stand's set (`block_columns`, the columns of Gamma11..Gamma33, bias1..bias3 over g) with the file's
    M: e = M ((Gamma - G) a_t + g (beta - beta_m)) exactly, so c_k reads M_ki a_j at Gamma_ij and M_ki g at bias_i;
    over temperature (`block_powers`, the columns of each power of tau = T - t0; M (N, 3, 3) per sample, `tau` (N,))
    the same times tau^k at the k-th power's columns."""
    q_m = np.asarray(st["estimate"], float)
    P, n = len(q_m), a.shape[1]
    C = np.zeros((3, n, P))
    if "block_columns" in st:
        Mt = np.moveaxis(np.broadcast_to(M, (n, 3, 3)), 0, 1)               # (3, N, 3): Mt[k, n, i] = M_n,ki
        powers = [st["block_columns"], *st.get("block_powers", ())]
        for k, cols in enumerate(np.asarray(powers, int)):
            t = 1.0 if k == 0 else tau ** k
            for i in range(3):
                for j in range(3):
                    C[:, :, cols[3 * i + j]] = Mt[:, :, i] * (a[j] * t)
                C[:, :, cols[9 + i]] = Mt[:, :, i] * (g * t)
        return C
    R = np.zeros((3, n, P))
    for j, cols in enumerate(((0,), (3, 1), (4, 5, 2))):      # lower(dq) a: row j reads a_1..a_(j+1)
        for i, c in enumerate(cols):
            R[j, :, c] = a[i]
        R[j, :, 6 + j] = g
    C = np.einsum("kj,jnp->knp", np.linalg.inv(np.eye(3) + lower(q_m)) if N is None else N, R)
    if phi is not None:
        C[:, :, 9:9 + len(phi)] += g * np.moveaxis(phi, 0, 2)
    return C


def linear_sup(st, a, g, phi=None, M=None, tau=None):
    """w (3, N): the largest |c_k(a)^T dq| over the set at each corrected sample a (3, N) (`objectives`, with the
    effects' basis `phi` or a stand file's M), proven (`sup`); the LPs solved kept with the set for the next piece
    of the same log (solve/support.py Solved)."""
    n = a.shape[1]
    w = np.empty((3, n))
    for i in range(0, n, SAMPLES_AT_ONCE):             # the work's memory is a block's, not the log's
        part = slice(i, i + SAMPLES_AT_ONCE)
        C = objectives(st, a[:, part], g, None if phi is None else phi[:, :, part],
                       M[part] if M is not None and np.ndim(M) == 3 else M, tau=None if tau is None else tau[part])
        w[:, part] = sup(st, C.reshape(-1, C.shape[-1])).reshape(3, -1)
    return w


def sup(st, flat):
    """The largest |c^T dq| over the set for each row c of `flat`, dq = q - estimate, proven: each end by duality
    (solve/support.py, the LPs kept with the set in `_solved`), the rounding of c^T q_m and of the difference
    covered outward, the shift q absorbs added as |c|^T shift."""
    rows, s, bound = (np.asarray(st[k], float) for k in ("rows", "centre", "bound"))
    lo, hi, shift, q_m = (np.asarray(st[k], float) for k in ("box_lo", "box_hi", "shift", "estimate"))
    solved = st.setdefault("_solved", support.Solved())
    e_lo, e_hi = support.ranges(rows, s - bound, s + bound, lo, hi, flat, q_m, solved)
    mid = flat @ q_m
    rounding = 4 * (len(q_m) + 2) * EPS * (np.abs(e_lo) + np.abs(e_hi) + np.abs(flat) @ np.abs(q_m))
    return np.maximum(e_hi - mid, mid - e_lo) + np.abs(flat) @ shift + rounding


#: Samples whose errors are bounded at once (3 rows each).
SAMPLES_AT_ONCE = 4096


def bound(cal, a, linear=None):
    """The per-sample bound (3, N) over the set of a file without effects, at its corrected samples a (3, N):
    (I - B)^-1 v, B the file's bound_matrix. A norm file: v = (1 + u) w + u |a| (of the 12-parameter model:
    `nonlinear`, with its linear correction `linear` = M (raw - b)). A stand file, whose Gamma is
    relative to g where it absorbs Delta_g (io/calibration.py `through_M`: the truth's specific force is a_t / c,
    |1/c - 1| <= u' = u / (1 - u)): v = w + u B |a| + u' |a| + (1 + u') |M (E + G) - E| |a|, the last the rounding
    of M as an inverse (G the estimate's Gamma)."""
    st, B, g = cal["information_set"], cal["bound_matrix"], cal["g"]
    u = float(st["g_uncertainty"])
    if twelve(cal):
        return nonlinear(cal, a, linear)
    w = linear_sup(st, a, g, M=cal["M"])
    if "block_columns" in st:
        M = cal["M"]
        G = np.asarray(st["estimate"], float)[np.asarray(st["block_columns"][:9], int)].reshape(3, 3)
        left = np.abs(M @ (np.eye(3) + G) - np.eye(3)) + 8 * EPS * (np.abs(M) @ (1 + np.abs(G)))
        up = u / (1 - u)
        v = w + u * (B @ np.abs(a)) + up * np.abs(a) + (1 + up) * (left @ np.abs(a))
    else:
        v = (1 + u) * w + u * np.abs(a)
    return np.linalg.solve(np.eye(3) - B, v) * (1 + 1e-12)


EPS = np.finfo(float).eps


def twelve(cal):
    """Whether the file is a 12-parameter norm calibration's: its set's columns 10-12 the nonlinearity delta (a file
    with effects holds theirs there)."""
    return cal["kind"] == "norm" and "effects" not in cal and len(cal["information_set"]["estimate"]) == 12


def nonlinear(cal, a, linear):
    """`bound` of a 12-parameter norm file (the nonlinearity delta of (1.3) of 001 as q_10..q_12): the file corrects
    a' = M (raw - b) to a = a' - g delta o P(n'), P_l(n) = n_ax(l) n_l (its pendulosity axes), n' = a' / |a'|; the
    truth a_t = a'_t - g delta_t o P(n'_t), delta_t = delta + dq_d. Exactly
        e = a - a_t = c(a')^T dq + g dq_d o P(n') - N lower(dq) e' - g delta_t o (P(n') - P(n'_t)),
    e' = a' - a'_t the linear part's error (the module's docstring, at a'), so with W the largest |c_k(a')^T dq +
    g P_k(n') dq_d,k| over the set (the 12 columns: `sup`) and E' = (I - B)^-1 w' the bound of |e'| (w' = W + g
    |P(n')| r_d >= |c_k(a')^T dq|, r_d the set's reach in delta), |P_k(n') - P_k(n'_t)| <= 2 |n' - n'_t| <= 4 |e'| /
    |a'|: |e| <= W + B E' + g (|delta| + r_d) 4 |E'| / |a'|. The error of g (|d| <= u) scales the truth: a -
    a_t / (1 + d) adds u' (|a| + |e|), u' = u / (1 - u)."""
    st, B, g = cal["information_set"], cal["bound_matrix"], cal["g"]
    u = float(st["g_uncertainty"])
    q_m = np.asarray(st["estimate"], float)
    r_d = (np.maximum(np.asarray(st["box_hi"]) - q_m, q_m - np.asarray(st["box_lo"])) + np.asarray(st["shift"]))[9:]
    norm = np.sqrt((linear * linear).sum(axis=0))
    P = linear[np.asarray(cal["pendulosity_axes"], int) - 1] * linear / np.maximum(norm, 1e-300) ** 2
    phi = np.zeros((3, 3, linear.shape[1]))
    phi[[0, 1, 2], [0, 1, 2]] = P
    W = linear_sup(st, linear, g, phi)
    E1 = np.linalg.solve(np.eye(3) - B, W + g * r_d[:, None] * np.abs(P))
    e = W + B @ E1 + (g * (np.abs(np.asarray(cal["delta"], float)) + r_d))[:, None] * (
        4 * np.sqrt((E1 * E1).sum(axis=0)) / np.maximum(norm, 1e-300))
    up = u / (1 - u)
    return ((1 + up) * e + up * np.abs(a)) * (1 + 1e-12)


def lower_bound(cal, a, T=None):
    """The per-sample bound (3, N) over the set of a two-axis stand file in the frame the data define (constant, or
    over temperature with T (N,) in C: workflows/thermal_file.py `_lower`), at its corrected samples a (3, N). Each
    entry of Gamma(T) - Gamma_hat(T) is psi_ij(tau)^T dq + r_ij, |r_ij| <= rest_Gamma of the piece, and each bias
    error g psi_i(tau)^T dq + r_i, |r_i| <= rest_bias (the set's `Gamma_rows`, `bias_rows`: coefficients of tau^k,
    tau = T - t0; one power and one piece for a constant file), each for the unit read at s = 1: the readings are
    f = (E + Gamma'') a_t / s + bias with E + Gamma'' = L0 (T) and |s - 1| <= u (`g_uncertainty`). With M = (E +
    Gamma_hat(T))^-1 and a_s = a_t / s = a - e_s, exactly
        e_s = c(a, tau)^T dq + M r a + M r_b + (M (E + Gamma_hat) - E) a - (M dGamma + M (E + Gamma_hat) - E) e_s,
    c_k = sum_i M_ki (sum_j a_j psi_ij(tau) + g psi_i(tau)), so |e_s| <= (I - B)^-1 (w + |M| rest_Gamma |a| +
    |M| rest_bias + left |a|), B the (piece's) bound matrix (io/calibration.py through_M: its bounds hold s = 1), w
    the largest |c_k^T dq| over the set (`sup`), left the rounding of M as an inverse; and a - a_t = e_s + a_t (1/s -
    1), |1/s - 1| <= u' = u / (1 - u), |a_t| <= |a| + |e|: |e| <= (|e_s| + u' |a|) / (1 - u')."""
    from ..io import calibration as cal_io
    st, n = cal["information_set"], a.shape[1]
    if T is None:
        G = np.broadcast_to(np.linalg.inv(cal["M"]) - np.eye(3), (n, 3, 3))
        M, B = np.broadcast_to(cal["M"], (n, 3, 3)), np.broadcast_to(cal["bound_matrix"], (n, 3, 3))
        piece, tau = np.zeros(n, int), np.zeros(n)
    else:
        th = cal["thermal"]
        G, _, piece = cal_io.thermal_gamma(cal, T)
        M, B, _ = cal_io.through_M(G, th["bound_Gamma"][piece], th["bound_bias"][piece])
        tau = np.asarray(T, float) - th["t0_c"]
    absM = np.abs(M)
    left = np.abs(M @ (np.eye(3) + G) - np.eye(3)) + 8 * EPS * (absM @ (1 + np.abs(G)))
    R, Rb = np.asarray(st["Gamma_rows"], float), np.asarray(st["bias_rows"], float)    # (D+1, 3, 3, P), (D+1, 3, P)
    q_m = np.asarray(st["estimate"], float)
    reach = np.maximum(np.asarray(st["box_hi"]) - q_m, q_m - np.asarray(st["box_lo"])) + np.asarray(st["shift"])
    w = np.empty((3, n))
    for i in range(0, n, SAMPLES_AT_ONCE):
        part = slice(i, i + SAMPLES_AT_ONCE)
        pw = tau[part, None] ** np.arange(len(R))                                   # (n, D + 1)
        inner = np.einsum("nabp,bn->nap", np.einsum("nk,kabp->nabp", pw, R), a[:, part]) + np.einsum(
            "nk,kap->nap", pw, Rb)
        flat = np.einsum("nka,nap->knp", M[part], inner).reshape(-1, len(q_m))
        size = np.einsum("nka,nap->knp", absM[part], np.einsum("nabp,bn->nap", np.einsum(
            "nk,kabp->nabp", np.abs(pw), np.abs(R)), np.abs(a[:, part])) + np.einsum(
            "nk,kap->nap", np.abs(pw), np.abs(Rb)))
        rounding = 16 * (len(R) + 8) * EPS * (size.reshape(-1, len(q_m)) @ reach)
        w[:, part] = (sup(st, flat) + rounding).reshape(3, -1)
    rest = (np.einsum("nka,nab,bn->kn", absM, np.asarray(st["rest_Gamma"], float)[piece], np.abs(a))
            + np.einsum("nka,a->kn", absM, np.asarray(st["rest_bias"], float))
            + np.einsum("nka,an->kn", left, np.abs(a)))
    e_s = np.linalg.solve(np.eye(3)[None] - B, (w + rest).T[..., None])[..., 0].T
    up = float(st["g_uncertainty"]) / (1 - float(st["g_uncertainty"]))
    return (e_s + up * np.abs(a)) / (1 - up) * (1 + 1e-12)


def block_thermal_bound(cal, a, T):
    """The per-sample bound (3, N) over the set of a stand's file over temperature in the block's axes (the block's
    set with each power's columns, `block_powers`), at its corrected samples a (3, N) and temperatures T (N,): as
    `bound`'s stand file, with each sample's M(T) = (E + Gamma_hat(T))^-1 and the bound matrix B of its piece
    (io/calibration.py thermal_at), w the largest |c_k(a, tau)^T dp| over the set."""
    from ..io import calibration as cal_io
    st, g, th = cal["information_set"], cal["g"], cal["thermal"]
    u = float(st["g_uncertainty"])
    M, _, B, _ = cal_io.thermal_at(cal, T)
    G = cal_io.thermal_gamma(cal, T)[0]
    tau = np.asarray(T, float) - th["t0_c"]
    w = linear_sup(st, a, g, M=M, tau=tau)
    left = np.abs(M @ (np.eye(3) + G) - np.eye(3)) + 8 * EPS * (np.abs(M) @ (1 + np.abs(G)))
    up = u / (1 - u)
    absa = np.abs(a).T[..., None]                                                     # (N, 3, 1)
    v = w.T[..., None] + u * (B @ absa) + up * absa + (1 + up) * (left @ absa)
    return (np.linalg.solve(np.eye(3)[None] - B, v)[..., 0] * (1 + 1e-12)).T


def apply_thermal(cal, raw, T, path="the log"):
    """io/calibration.py `apply_thermal` with each sample's bound the smaller of the piece's box bound and the
    set's (`lower_bound`, or `block_thermal_bound` in the block's axes; a file that carries its set)."""
    from ..io import calibration as cal_io
    a, box = cal_io.apply_thermal(cal, raw, T, path)
    if "information_set" in cal:
        box = np.minimum(box, (block_thermal_bound if "block_columns" in cal["information_set"] else lower_bound)(
            cal, a.T, T).T)
    return a, box


def apply(cal, raw, frame="garant"):
    """io/calibration.py `apply` with each sample's bound the smaller of the box's and the set's (a file with an
    `information_set` and no effects); in the frame asked for."""
    from ..io import calibration as cal_io
    a, box = cal_io.apply(cal, raw)
    if "information_set" in cal:
        st = cal["information_set"]
        box = np.minimum(box, lower_bound(cal, a.T).T if "Gamma_rows" in st else bound(
            cal, a.T, cal["M"] @ (np.asarray(raw, float) - cal["b"]).T).T)
    if frame == "imu_tk":
        R = cal_io.imu_tk_form(cal)[2]
        a, box = a @ R.T, (box @ np.abs(R).T) * (1 + 1e-12)
    return a, box
