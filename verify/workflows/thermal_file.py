"""The temperature part of a stand calibration file: Gamma(T) and the biases over T, bounded piece by piece.

The file corrects a sample taken at T by a = (E + Gamma_hat(T))^-1 (f - b_hat(T)), with Gamma_hat and b_hat
polynomials in tau = T - t0. Each of their errors is bounded over the information set of the estimate (the
q that fit every reading, guarantee.InformationSet) and over each piece of the range at once, not as the
bound at t0 plus that of the drift.

In the frame the data define (`lower`, two-axis, the convention of `--gamma`): the stand proves the matrix
M(T) = Q (E + G(q(T))) Q^T = s (E + Gamma(T)) R of the unit in mounting Q (s = 1 - Delta_g/g, R the
mounting's rotation, (26)-(29) of 000). With M(t0) = L0 R0 (a lower-triangular L0 with a positive diagonal
and a rotation R0: LQ, unique), the unit's frame is the one R0 turns the stand's into, and there

    E + Gamma'(T) = M(T) R0^T / s = L0 / s + Delta(T) W,   Delta(T) = M(T) - M(t0),   W = R0^T / s,

so no mounting premise enters Gamma' (the constant file's frame, mounting.exact_gamma). The file holds
Gamma_hat(T) = Gamma'_hat(t0) + Delta_hat(T) W_hat, and for every entry

    Gamma'(T) - Gamma_hat(T) = l^T (x - x_hat) + rho + (Delta(T) - Delta_hat(T)) W_hat + Delta(T) (W - W_hat)
                               + (f(x_hat) - Gamma'_hat(t0)),

x = (G(q(t0)), s), f(x) = L0 / s - E, l its gradient at x_hat, rho the mean-value remainder (the gradient
enclosed over the box of x in interval arithmetic, solve/interval.py). The first and third terms are one
linear function of q, psi(tau)^T (q - q_hat), whose sup over the set and a piece is the largest end of its
Bernstein control points (thermal.py); the others are bounded in interval arithmetic over the box.
Elsewhere (`block`): the block's Gamma at t0 over the information set (workflows/block.py) plus the drift
of each entry over the piece, both over the set.
"""
import numpy as np

from ..errors import DataError
from ..io.calibration import BLOCK_NAMES
from ..solve import interval
from . import mounting, sample_set, thermal

PAD = 1 + 1e-12
EPS = np.finfo(float).eps


def pieces(lo, hi):
    """The cut temperatures (C) of the range's pieces: thermal.PIECES equal ones."""
    return np.linspace(lo, hi, thermal.PIECES + 1)


def _series(mod, degree):
    """(nq, degree + 1, nq): for every q its coefficient vectors x_k (q(T) = sum tau^k x_k^T q); a q without a
    block part does not move with T (x_0 = e_q)."""
    nq = len(mod.Q_NAMES)
    polys = thermal.polynomials(mod, degree)
    S = np.zeros((nq, degree + 1, nq))
    for nu, name in enumerate(mod.Q_NAMES):
        S[nu] = np.array(polys[name]) if name in polys else np.vstack([np.eye(nq)[nu], np.zeros((degree, nq))])
    return S


def _worst(info, q_hat, rows, cuts):
    """rows: (n, degree + 1, nq) polynomials psi(tau) = sum tau^k rows[:, k]. Per piece of `cuts` (relative to
    t0) and row, the proven sup of |psi(tau)^T (q - q_hat)| over the set and the piece: the largest end of its
    Bernstein control points. Returns (pieces, n)."""
    n, d1, _ = rows.shape
    C = np.vstack([thermal.bernstein(list(r), a, b) for a, b in zip(cuts[:-1], cuts[1:]) for r in rows])
    return thermal.controls(info, q_hat, C)[3].reshape(len(cuts) - 1, n, d1).max(axis=2)


def _control_mag(coef, cuts):
    """(pieces, ...) the largest |p(tau)| over each piece of a polynomial with (degree + 1, ...) coefficients:
    the largest magnitude of its Bernstein control points."""
    coef = np.asarray(coef, float)
    flat = coef.reshape(len(coef), -1)
    out = [np.abs(thermal.bernstein(list(flat), a, b)).max(axis=0) for a, b in zip(cuts[:-1], cuts[1:])]
    return np.array(out).reshape((len(cuts) - 1,) + coef.shape[1:]) * PAD


LOWER = [(0, 0), (1, 0), (2, 0), (1, 1), (2, 1), (2, 2)]


def _lower(mod, remount, mount, info, q_hat, interval_q, degree, u, g, G0, b0):
    """The parts of the error of a two-axis file in the frame the data define (module docstring), as polynomials
    in tau of degree `degree` (0: a constant file): rows (3, 3, D + 1, nq), each entry of Gamma' - Gamma_hat's part
    linear in q; fixed (3, 3), the bound of its rest at t0 (rho and the offset of G0 from the split at q_hat), and
    at_s1 the same for the unit read at s = 1 (Gamma'' = L0 - E: the readings over s, the error of g apart);
    Dl (3, 3, D + 1, nq) the drift Delta(T); W_hat, W_err; brows (3, D + 1, nq) the biases' rows (over g);
    bias_hat (D + 1, 3) m/s^2 and b_off (3), the offset of b0 from it. G0 (3 x 3) and b0 (3, m/s^2): the file's
    Gamma and biases at t0 (the constant calibration's, `from_stand`); interval_q the box of q holding the set; u
    the bound of |Delta_g/g| (s within 1 +- u)."""
    Q = np.asarray(remount.MOUNTS[mount], float)
    idx = np.asarray(remount.G_INDEX)
    S = _series(mod, degree)                                           # (nq, D + 1, nq)
    # Delta(T) in block axes: (Q G_drift Q^T)_ab, coefficient vectors (3, 3, D + 1, nq), k = 0 part zero
    Gs = S[idx]                                                        # (3, 3, D + 1, nq): G(q(T)), stand axes
    Dl = np.einsum("ai,bj,ijkn->abkn", Q, Q, Gs)
    Dl[:, :, 0] = 0.0
    # f and W at the estimate, and their gradients over the box (G's 9 entries and s)
    g_hat = q_hat[idx]
    lo, hi = interval_q
    lo_g, hi_g = np.minimum(lo[idx], g_hat), np.maximum(hi[idx], g_hat)
    c = [*g_hat.ravel(), 1.0]
    point = interval.box_variables([np.atleast_1d(x) for x in c], [np.atleast_1d(x) for x in c])
    box = interval.box_variables([np.atleast_1d(x) for x in [*lo_g.ravel(), 1 - u]],
                                 [np.atleast_1d(x) for x in [*hi_g.ravel(), 1 + u]])
    split = lambda x: mounting.lq([x[0:3], x[3:6], x[6:9]], x[9], Q)            # noqa: E731
    f_pt, W_pt = split(point)
    f_box, W_box = split(box)
    W_hat = np.array([[float(np.mean([w.v.lo[0], w.v.hi[0]])) for w in row] for row in W_pt])
    W_err = np.array([[max(w.v.hi[0] - W_hat[a, b], W_hat[a, b] - w.v.lo[0]) for b, w in enumerate(row)]
                      for a, row in enumerate(W_box)])
    radius = np.append(np.maximum(hi_g - g_hat, g_hat - lo_g).ravel(), u)
    # the linear function of q of each entry of Gamma': l^T G(q(t0)) (lower entries) + (Delta(T) W_hat)_ab
    rows = np.einsum("amkn,mb->abkn", Dl, W_hat)
    offset, rho, by_s = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
    for (a, b), fp, fb in zip(LOWER, f_pt, f_box):
        ell = np.array([(d.lo[0] + d.hi[0]) / 2 for d in fp.d])
        rows[a, b, 0] = np.einsum("ij,ijn->n", ell[:9].reshape(3, 3), S[idx, 0])
        spread = np.array([max(d.hi[0] - e, e - d.lo[0]) for d, e in zip(fb.d, ell)])
        rho[a, b] = spread[:9] @ radius[:9]
        by_s[a, b] = max(abs(fb.d[9].lo[0]), abs(fb.d[9].hi[0])) * u     # s enters only here: |df/ds| u
        offset[a, b] = max(fp.v.hi[0] - G0[a][b], G0[a][b] - fp.v.lo[0])
    # the biases in block axes: K's bias rows of the remount formulas, each q its polynomial
    nq = len(q_hat)
    K = np.zeros((len(remount.OUTPUTS), nq))
    K[:, :remount.recovery_matrix(mount).shape[1]] = remount.recovery_matrix(mount)
    rb = [list(remount.OUTPUTS).index(f"bias{i}") for i in (1, 2, 3)]
    brows = np.einsum("rn,nkm->rkm", K[rb], S)
    bias_hat = np.einsum("rkm,m->kr", brows, q_hat) * g
    return {"rows": rows, "fixed": offset + rho + by_s, "at_s1": offset + rho, "Dl": Dl, "W_hat": W_hat,
            "W_err": W_err, "brows": brows, "bias_hat": bias_hat, "b_off": np.abs(bias_hat[0] - np.asarray(b0, float))}


def _with_rows(info, q_hat, parts, g, u, rest_Gamma):
    """The file's information_set (sample_set.q_entry) with the error's rows (`Gamma_rows` (D + 1, 3, 3, nq),
    `bias_rows` (D + 1, 3, nq) in m/s^2), the bounds of its rest at s = 1 (`rest_Gamma` per piece, `rest_bias`) and
    u, the bound of |s - 1| (`g_uncertainty`: the error of g, apart), for apply's bound over the set
    (sample_set.lower_bound); None where the set is too large for a file."""
    st = sample_set.q_entry(info, q_hat)
    if st is not None:
        st.update(Gamma_rows=np.moveaxis(parts["rows"], 2, 0), bias_rows=g * np.moveaxis(parts["brows"], 1, 0),
                  rest_Gamma=rest_Gamma * PAD, rest_bias=parts["b_off"] * PAD, g_uncertainty=float(u))
    return st


def lower_set(mod, remount, mount, info, q_hat, interval_q, u, g, G0, b0):
    """The information_set of a constant two-axis file in the frame the data define (`_lower` at degree 0)."""
    parts = _lower(mod, remount, mount, info, q_hat, interval_q, 0, u, g, G0, b0)
    return _with_rows(info, q_hat, parts, g, u, parts["at_s1"][None])


def symmetric_set(remount, mount, info, q_hat, u, g, G0, b0, premised):
    """The information_set of a constant two-axis file with --gamma symmetric: each entry of Gamma and each bias
    is linear in q by the remount formulas ((28)-(29) of 000, K's rows), within what the premises alone set
    (`premised`, mounting.recover's: the split's gap and Delta_beta; its Delta_g/g part, E Delta_g/g of (29), taken
    out: the error of g is apart, |s - 1| <= u, as in `lower_set`) and the file's offset from K q_hat (G0, b0 in
    m/s^2: the file's own, the midpoints of the ranges)."""
    nq, names = len(q_hat), list(remount.OUTPUTS)
    K = np.zeros((len(names), nq))
    K[:, :remount.recovery_matrix(mount, "symmetric").shape[1]] = remount.recovery_matrix(mount, "symmetric")
    gi = [names.index(f"Gamma{i}{j}") for i in (1, 2, 3) for j in (1, 2, 3)]
    rows = K[gi].reshape(3, 3, 1, nq)
    brows = K[[names.index(f"bias{i}") for i in (1, 2, 3)]][:, None]
    G0, b0 = np.asarray(G0, float), np.asarray(b0, float)
    P_G, P_b = np.asarray(premised["Gamma"], float), np.asarray(premised["bias"], float)
    by_g = np.abs(remount.neglected(mount, 1.0, 0.0, "symmetric"))[gi].reshape(3, 3) * u
    at_hat, b_hat = rows[:, :, 0] @ q_hat, g * (brows[:, 0] @ q_hat)
    rounding = 8 * (nq + 2) * EPS * (np.abs(rows[:, :, 0]) @ np.abs(q_hat) + np.abs(G0) + P_G + by_g)
    rest_G = np.abs(at_hat - G0) + np.maximum(P_G - by_g, 0.0) + rounding
    b_off = (np.abs(b_hat - b0) + P_b + 8 * (nq + 2) * EPS * (g * np.abs(brows[:, 0]) @ np.abs(q_hat) + np.abs(b0)
                                                              + P_b))
    return _with_rows(info, q_hat, {"rows": rows, "brows": brows, "b_off": b_off}, g, u, rest_G[None])


def lower_section(mod, remount, mount, info, q_hat, interval_q, T, t0, degree, u, g, G0, b0):
    """The thermal section of a two-axis calibration in the frame the data define (module docstring, `_lower`),
    with its information set (`_set`)."""
    parts = _lower(mod, remount, mount, info, q_hat, interval_q, degree, u, g, G0, b0)
    rows, Dl, brows, nq = parts["rows"], parts["Dl"], parts["brows"], len(q_hat)
    cuts = pieces(*(np.array([T.min(), T.max()]) - t0))
    linear = _worst(info, q_hat, rows.reshape(9, degree + 1, nq), cuts).reshape(-1, 3, 3)
    # |Delta(T)| over each piece: the estimate's largest value there plus the drift's bound over the set
    drift_hat = np.einsum("abkn,n->kab", Dl, q_hat)
    drift_mag = _control_mag(drift_hat, cuts) + _worst(info, q_hat, Dl.reshape(9, degree + 1, nq),
                                                       cuts).reshape(-1, 3, 3)
    turn = np.einsum("pam,mb->pab", drift_mag, parts["W_err"])
    bound_G = (linear + parts["fixed"][None] + turn) * PAD
    bound_b = (g * _worst(info, q_hat, brows, cuts) + parts["b_off"][None]) * PAD
    return {"frame": "lower", "pieces_c": (cuts + t0).tolist(),
            "Gamma": np.einsum("kam,mb->kab", drift_hat, parts["W_hat"])[1:].tolist(),
            "bias": parts["bias_hat"][1:].tolist(), "bound_Gamma": bound_G.tolist(), "bound_bias": bound_b.tolist(),
            "_set": _with_rows(info, q_hat, parts, g, u, parts["at_s1"][None] + turn)}


def block_section(mod, info, q_hat, T, t0, degree, g, block, u):
    """The thermal section in the block's own axes (a stand without the remount formulas): Gamma and the
    biases at t0 from the block's calibration over the set (`block`, workflows/block.py), each entry's drift
    from the q that holds that block parameter alone; per piece, the bound at t0 plus that of the drift over
    the set and the piece. u: the bound of |Delta_g/g| where Gamma is relative to the g given."""
    R = np.asarray(mod.PHYSICAL_TO_Q, float)
    names = list(mod.PARAMETER_NAMES)
    cols = [names.index(n) for n in BLOCK_NAMES]
    owner = {}
    for nu in range(len(mod.Q_NAMES)):
        used = [k for k in cols if R[nu, k] != 0]
        if len(used) == 1 and R[nu, used[0]] == 1:
            owner.setdefault(names[used[0]], nu)
    missing = [n for n in BLOCK_NAMES if n not in owner]
    if missing:
        raise DataError(f"--save with --thermal-degree: this stand's q do not hold {', '.join(missing)} alone; the "
                        "calibration's temperature polynomial needs each block parameter", param="save")
    S = _series(mod, degree)
    rows = np.array([S[owner[n]] for n in BLOCK_NAMES])
    rows[:, 0] = 0.0                                                  # the drift: q(T) - q(t0)
    cuts = pieces(*(np.array([T.min(), T.max()]) - t0))
    drift = _worst(info, q_hat, rows, cuts)                          # (pieces, 12)
    coef = np.einsum("pkn,n->kp", rows, q_hat)                        # (D + 1, 12)
    out = {"frame": "block", "pieces_c": (cuts + t0).tolist(),
            "Gamma": coef[1:, :9].reshape(-1, 3, 3).tolist(), "bias": (g * coef[1:, 9:]).tolist(),
            "bound_Gamma": ((np.asarray(block["Gamma_bound"])[None] + drift[:, :9].reshape(-1, 3, 3)) * PAD).tolist(),
            "bound_bias": (g * (np.asarray(block["bias_bound"])[None] + drift[:, 9:]) * PAD).tolist(),
            "g_uncertainty": u}
    st = block.get("_set")
    powers = [[names.index(f"{n}_T{k}") if f"{n}_T{k}" in names else -1 for n in BLOCK_NAMES]
              for k in range(1, degree + 1)]
    if st is not None and min(map(min, powers)) >= 0:
        # the block's set is over every parameter of the thermal model: each power's columns beside the block's, at
        # the file's polynomial (the q that hold them alone, q_hat's series)
        estimate = np.array(st["estimate"], float)
        for k, cols in enumerate(powers, start=1):
            estimate[cols] = coef[k]
        out["_set"] = dict(st, estimate=estimate, block_powers=powers, g_uncertainty=float(u))
    return out
