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

#: The largest set (rows x columns) a calibration file carries: beyond it the file keeps the box bound alone.
MAX_ENTRIES = 24_000


def entry(A, s, bound, lo, hi, shift, q_m, u=0.0):
    """The calibration file's `information_set` of a norm calibration: the set {x : |s_k - A_k^T x| <= bound_k,
    lo - shift <= x <= hi + shift} + {|s| <= shift} of the corrections q (A: parameters x intervals), its
    midpoint q_m, the bound u of |Delta_g/g|; None where it is too large for a file (MAX_ENTRIES)."""
    if A.size > MAX_ENTRIES:
        return None
    shift = np.broadcast_to(np.asarray(shift, float), lo.shape)
    return {"rows": A.T.tolist(), "centre": np.asarray(s, float).tolist(), "bound": np.asarray(bound, float).tolist(),
            "box_lo": (lo - shift).tolist(), "box_hi": (hi + shift).tolist(), "shift": shift.tolist(),
            "estimate": np.asarray(q_m, float).tolist(), "g_uncertainty": float(u)}


def objectives(st, a, g, phi=None, M=None, N=None):
    """C (3, N, P): row k of sample n, c_k(a_n) with e_k = c_k(a)^T dq + ... (the module's docstring); `phi`
    (J, 3, N), the effects' basis at each sample's direction, for the parameters after the 9; `N` the matrix the
    norm set's rows are read through (default (E + lower(q_m))^-1, the file's own; workflows/budget.py passes a
    peer's). A stand's set (`block_columns`, the columns of Gamma11..Gamma33, bias1..bias3 over g) with the file's
    M: e = M ((Gamma - G) a_t + g (beta - beta_m)) exactly, so c_k reads M_ki a_j at Gamma_ij and M_ki g at bias_i."""
    q_m = np.asarray(st["estimate"], float)
    P, n = len(q_m), a.shape[1]
    C = np.zeros((3, n, P))
    if "block_columns" in st:
        cols = np.asarray(st["block_columns"], int)
        for i in range(3):
            for j in range(3):
                C[:, :, cols[3 * i + j]] = M[:, i, None] * a[j]
            C[:, :, cols[9 + i]] = M[:, i, None] * g
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


def linear_sup(st, a, g, phi=None, M=None):
    """w (3, N): the largest |c_k(a)^T dq| over the set at each corrected sample a (3, N) (`objectives`, with the
    effects' basis `phi` or a stand file's M), proven (each end by duality, the rounding of c^T q_m and of the
    difference covered outward); the LPs solved kept with the set for the next piece of the same log
    (solve/support.py Solved)."""
    rows, s, bound = (np.asarray(st[k], float) for k in ("rows", "centre", "bound"))
    lo, hi, shift, q_m = (np.asarray(st[k], float) for k in ("box_lo", "box_hi", "shift", "estimate"))
    solved = st.setdefault("_solved", support.Solved())
    n = a.shape[1]
    w = np.empty((3, n))
    for i in range(0, n, SAMPLES_AT_ONCE):             # the work's memory is a block's, not the log's
        part = slice(i, i + SAMPLES_AT_ONCE)
        C = objectives(st, a[:, part], g, None if phi is None else phi[:, :, part], M)
        flat = C.reshape(-1, len(q_m))
        e_lo, e_hi = support.ranges(rows, s - bound, s + bound, lo, hi, flat, q_m, solved)
        mid = flat @ q_m
        rounding = 4 * (len(q_m) + 2) * EPS * (np.abs(e_lo) + np.abs(e_hi) + np.abs(flat) @ np.abs(q_m))
        w[:, part] = (np.maximum(e_hi - mid, mid - e_lo) + np.abs(flat) @ shift + rounding).reshape(3, -1)
    return w


#: Samples whose errors are bounded at once (3 rows each).
SAMPLES_AT_ONCE = 4096


def bound(cal, a):
    """The per-sample bound (3, N) over the set of a file without effects, at its corrected samples a (3, N):
    (I - B)^-1 v, B the file's bound_matrix. A norm file: v = (1 + u) w + u |a|. A stand file, whose Gamma is
    relative to g where it absorbs Delta_g (io/calibration.py `through_M`: the truth's specific force is a_t / c,
    |1/c - 1| <= u' = u / (1 - u)): v = w + u B |a| + u' |a| + (1 + u') |M (E + G) - E| |a|, the last the rounding
    of M as an inverse (G the estimate's Gamma)."""
    st, B, g = cal["information_set"], cal["bound_matrix"], cal["g"]
    u = float(st["g_uncertainty"])
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


def apply(cal, raw, frame="garant"):
    """io/calibration.py `apply` with each sample's bound the smaller of the box's and the set's (a file with an
    `information_set` and no effects); in the frame asked for."""
    from ..io import calibration as cal_io
    a, box = cal_io.apply(cal, raw)
    if "information_set" in cal:
        box = np.minimum(box, bound(cal, a.T).T)
    if frame == "imu_tk":
        R = cal_io.imu_tk_form(cal)[2]
        a, box = a @ R.T, (box @ np.abs(R).T) * (1 + 1e-12)
    return a, box
