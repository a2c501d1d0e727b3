"""What makes a bound guaranteed: the data consistent with sigma, and the linearisation remainder in it.

The linear model (2) of 000 is z = H^T q + rho + R(p), with |rho| <= sigma (5) and R the remainder
of (1) -> (2). garant bounds R by a proof (solve/taylor.py: interval Taylor arithmetic on the exact
readings of the generated module) over the parameters the premises allow:

1. a priori: every stand and block error within --prior (biases enter linearly and need no bound);
2. a posteriori: the identifiable combinations within their guaranteed bounds around the estimate,
   the unseparable directions (UNSEPARABLE) within what the prior allows, intersected with 1.
   Each step only shrinks the bound, and each is valid whenever the premises hold.

The part of the curvature that a column of H carries is absorbed by a shift C(p) of q (Remainder):
R = H^T C(p) + R', with both |C(p)| and |R'| proven. The verdict: if the premises hold, q + C(p)
satisfies |z_k - a_k^T (q + C)| <= sigma + R'_k for every k, so min over q' of
max_k (|z_k - a_k^T q'| - R'_k) <= sigma. When that minimax exceeds sigma, the data refute sigma (or
the prior, or the model): a proof. Otherwise each q is bounded by sum_k |W_k| (sigma + R'_k) + |C(p)|:
a linear part sigma sum |W| and a remainder part. The exact-model minimax fit (unseparable
directions at 0, the stated representative) is reported as the fit quality.
"""
from dataclasses import dataclass

import numpy as np

from ..solve import highs, taylor

PRIOR_DEFAULT = 1e-3       # rad and dimensionless: the size of every stand and block error


@dataclass
class Verdict:
    consistent: bool
    sigma: float
    sigma_min_supported: float       # smallest sigma the data support (sigma itself when consistent)
    minimax_less_remainder: float    # min_q max_k |z_k - a_k^T q| - R_k
    minimax_linear: float            # min_q max_k |z_k - a_k^T q|
    exact_fit: np.ndarray            # q of the exact-model minimax fit
    minimax_exact: float             # its residual: the fit quality
    remainder: np.ndarray            # R_k, proven, per residual component (N*3,)
    disagree: np.ndarray             # indices k where |z_k - a_k^T q*| - R_k > sigma
    residual: np.ndarray             # z - A^T q* at that minimax fit (N*3,)
    error_linear: np.ndarray = None  # sigma sum |W| per q
    error_remainder: np.ndarray = None   # sum |W_k| R'_k + |C(p)| per q
    q_shift: np.ndarray = None           # the bound of |C(p)|: curvature absorbed by q

    @property
    def guaranteed_error(self):
        return self.error_linear + self.error_remainder


def linear_parameters(mod):
    """Parameters that enter the readings affinely with a constant coefficient: the biases."""
    return np.array([n.startswith("bias") for n in mod.PARAMETER_NAMES])


def coordinates(mod):
    """p = L v with v = (q, t): q the identifiable combinations (p = R+ q), t the coordinates along
    orthonormal unseparable directions N. Combinations that are biases (entering linearly) are left
    out: they do not enter the remainder. Returns (L, index of each q in v or -1, N)."""
    R = np.asarray(mod.PHYSICAL_TO_Q, float)
    lin = linear_parameters(mod)
    Rp = np.linalg.pinv(R)
    keep = [nu for nu in range(R.shape[0]) if np.abs(R[nu, ~lin]).max() > 0]
    U = np.asarray(mod.UNSEPARABLE, float)
    N = np.linalg.qr(U.T)[0].T if U.size else np.zeros((0, R.shape[1]))
    L = np.hstack([Rp[:, keep], N.T])
    L[lin] = 0.0
    return L, keep, N


def box(mod, prior, q=None, e=None):
    """Bounds of v = (q, t): q within [q - e, q + e] (or what the prior allows when no estimate is
    given), t within what |p_k| <= prior allows; every bound also within what the prior allows."""
    R = np.asarray(mod.PHYSICAL_TO_Q, float)
    lin = linear_parameters(mod)
    L, keep, N = coordinates(mod)
    q_prior = np.abs(R[keep][:, ~lin]).sum(axis=1) * prior
    t_prior = np.abs(N[:, ~lin]).sum(axis=1) * prior
    lo, hi = -q_prior, q_prior
    if q is not None:
        lo, hi = np.maximum(lo, q[keep] - e[keep]), np.minimum(hi, q[keep] + e[keep])
        lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
    return L, np.r_[lo, -t_prior], np.r_[hi, t_prior]


class Remainder:
    """The proven remainder at a set of positions, with the curvature the combinations absorb.

    Part of the second-order term is a function of the parameters times a column of H (e.g. along the
    unseparable direction Gamma_ii = Delta_g the readings move by Gamma_ii Delta_g u_i, which is q's own
    column): a q shifted by C(p) = 1/2 v^T C v absorbs it exactly. C is fitted once, by least squares
    over (at most FIT_ROWS of) the positions, to the Hessian at 0 (any C is valid: it only moves
    curvature between the two bounds); then for every v in a box
        z_exact = H^T (q + C(p)) + R',  |R'_k| <= 1/2 sum |v_k| |v_j| sup |Hess_kj - (H^T C)_kj|,
    |C(p)_nu| <= 1/2 sum |C_nu,kj| |v_k| |v_j|: both proven (the Hessian enclosed by interval Taylor
    arithmetic, at every position or, for readings that are trigonometric polynomials in the angles,
    interpolated exactly from nodes (taylor.Interpolation); float rounding covered by margins).
    Hessians are symmetric: they are held as packed upper triangles."""

    FIT_ROWS = 256
    BLOCK = 2048             # positions per block of the bound: memory stays linear and small
    DIRECT_ROWS = 256        # up to this many positions, each is enclosed on its own: the tightest bound

    def __init__(self, mod, positions, A, boxes=()):
        self.mod, self.A = mod, A
        self.angles = [np.atleast_1d(np.asarray(a, float)) for a in positions.radians]
        self.mounts = positions.mounts
        self.extra = [np.asarray(positions.extra[str(v)], float) for v in getattr(mod, "VARIABLES", ())]
        self.L = coordinates(mod)[0]
        n, nv = len(self.angles[0]), self.L.shape[1]
        self.P = nv * (nv + 1) // 2
        self.interp = (taylor.Interpolation(mod.TRIG_DEGREE)
                       if taylor.Interpolation.usable(mod, self.angles, self.extra) else None)
        self._nodes = {}
        self.prepare([(np.zeros(nv), np.zeros(nv)), *boxes])
        fit_rows = highs.spread(n, self.FIT_ROWS)
        mid, _ = self._enclosure(np.zeros(nv), np.zeros(nv), fit_rows, direct=self.interp is None)
        self.C = np.linalg.lstsq(A[:, _columns(fit_rows)].T, mid.reshape(len(fit_rows) * 3, -1), rcond=None)[0]

    def prepare(self, boxes):
        """Enclose the Hessian at the nodes for several boxes (lo, hi) in one evaluation (interpolation
        only; the boxes a computation will need, known in advance)."""
        if not self.interpolates():
            return
        for k in ([None] if self.mounts is None else np.unique(self.mounts)):
            todo = [b for b in boxes if ((tuple(b[0]), tuple(b[1])), k) not in self._nodes]
            for b, nodes in zip(todo, self.interp.at_nodes(self.mod, self.L, todo, k) if todo else ()):
                self._nodes[(tuple(b[0]), tuple(b[1])), k] = nodes

    def _enclosure(self, lo, hi, rows, direct):
        """(midpoints, radii) of the packed Hessian enclosure at the given positions: (rows, 3, P),
        position by position (`direct`) or interpolated from the nodes."""
        mounts = None if self.mounts is None else self.mounts[rows]
        if direct:
            H_lo, H_hi = taylor.packed_hessian(self.mod, [a[rows] for a in self.angles], self.L, lo, hi, mounts,
                                               [v[rows] for v in self.extra])
            return taylor.midrad(H_lo, H_hi)
        W = self.interp.weights([a[rows] for a in self.angles])
        key = (tuple(lo), tuple(hi))
        mid, rad = np.empty((len(rows), 3 * self.P)), np.empty((len(rows), 3 * self.P))
        for k in ([None] if mounts is None else np.unique(mounts)):
            if (key, k) not in self._nodes:
                self._nodes[key, k] = self.interp.at_nodes(self.mod, self.L, [(lo, hi)], k)[0]
            sel = slice(None) if k is None else mounts == k
            mid[sel], rad[sel] = self.interp.enclose(W[sel], *self._nodes[key, k])
        return mid.reshape(len(rows), 3, -1), rad.reshape(len(rows), 3, -1)

    def shift(self, v):
        """C(p) = 1/2 v^T C_nu v for each q_nu (C held packed)."""
        k, j = taylor.triangle(len(v))
        return self.C @ (np.where(k == j, 0.5, 1.0) * v[k] * v[j])

    def interpolates(self, rows=None):
        """Whether the bound at these positions (default all) is interpolated rather than made position
        by position: only for many positions (it is faster, and up to about twice as wide)."""
        count = len(self.angles[0]) if rows is None else len(rows)
        return self.interp is not None and count > self.DIRECT_ROWS

    def __call__(self, lo, hi, rows=None, direct=None):
        """(bound of |R'| per residual component (3 per position of `rows`, default all), bound of
        |C(p)| per q (m,)) over the box; position by position or interpolated as `interpolates` says,
        unless `direct` says."""
        direct = not self.interpolates(rows) if direct is None or self.interp is None else direct
        rows = np.arange(len(self.angles[0])) if rows is None else np.asarray(rows)
        w = taylor.pair_weights(np.maximum(-np.minimum(lo, 0.0), np.maximum(hi, 0.0)))
        rb = np.empty((len(rows), 3))
        for b in range(0, len(rows), self.BLOCK):
            block = rows[b:b + self.BLOCK]
            mid, rad = self._enclosure(lo, hi, block, direct)
            fit = (self.A[:, _columns(block)].T @ self.C).reshape(mid.shape)
            margin = taylor.SUM_ERROR * (1 + np.abs(fit) + np.abs(mid))
            rb[b:b + self.BLOCK] = (np.abs(mid - fit) + rad + margin) @ w
        cb = np.abs(self.C) @ w
        return rb.reshape(-1) * (1 + taylor.SUM_ERROR), cb * (1 + taylor.SUM_ERROR)


def _columns(rows):
    """Columns of A (and components of z) of the given positions: 3 per position."""
    return (3 * np.asarray(rows)[:, None] + np.arange(3)).reshape(-1)


def _weighted_minimax(A, z, rb):
    """min over q of max_k (|z_k - a_k^T q| - rb_k): (value, q, residual)."""
    q, t, r = highs.chebyshev_fit(A, z, slack=rb, what="minimax fit with remainder")
    return t, q, r


def exact_fit(mod, positions, z, A, g, iterations=6):
    """Minimax fit of the exact model, unseparable directions at 0 (p = R+ q): successive Chebyshev fits
    of the exact residual with the linear H, a contraction when the remainder is small."""
    Rp = np.linalg.pinv(np.asarray(mod.PHYSICAL_TO_Q, float))
    kw = {"mount": positions.mounts} if positions.mounts is not None else {}
    extra = [positions.extra[str(v)] for v in getattr(mod, "VARIABLES", ())]

    def model(q):
        f = mod.readings(*positions.radians, Rp @ q, g, *extra, **kw)
        return mod.residual(*positions.radians, f, g, **kw).T.reshape(-1)
    q, best, _ = highs.chebyshev_fit(A, z)
    for _ in range(iterations):
        dq, t, _ = highs.chebyshev_fit(A, z - model(q))
        if t >= best * (1 - 1e-9):
            break
        q, best = q + dq, t
    return q, float(np.abs(z - model(q)).max())


def verdict(mod, positions, z, A, sigma, g, prior=PRIOR_DEFAULT, W=None, steps=2):
    """The consistency verdict and, with an estimator W (m x K), the guaranteed errors with remainder."""
    rem = Remainder(mod, positions, A, boxes=[box(mod, prior)[1:]])
    if W is not None:
        support = np.flatnonzero(np.abs(W).reshape(len(W), -1, 3).max(axis=(0, 2)) > 0)
        cols = _columns(support)

    def proven(s):
        """(R' per residual component, C) bounds when the noise bound is s: over the prior box; with an
        estimator, then over a posteriori boxes (each valid if the premises hold, each inside the last),
        the intermediate ones at the estimator's positions only, the last at every position (and, when
        that one is interpolated, at the estimator's positions on their own too: the guaranteed errors
        depend on those alone, so they keep the tightest bound)."""
        lo, hi = box(mod, prior)[1:]
        if W is None:
            return rem(lo, hi)
        # The intermediate boxes are made as the last one is (one by one, or interpolated): they only
        # size the next box, and interpolating them moves the guaranteed errors by less than 1e-4.
        one_by_one = not rem.interpolates()
        rb_s, cb = rem(lo, hi, support, one_by_one)
        q = W @ z
        for step in range(steps):
            e = np.abs(W[:, cols]) @ (s + rb_s) + cb
            lo, hi = box(mod, prior, q, e)[1:]
            last = step == steps - 1
            rb2, cb2 = rem(lo, hi) if last else rem(lo, hi, support, one_by_one)
            cb = np.minimum(cb, cb2)
            if last:
                rb2[cols] = np.minimum(rb2[cols], rb_s)
                if rem.interpolates():
                    rb2[cols] = np.minimum(rb2[cols], rem(lo, hi, support, direct=True)[0])
                return rb2, cb
            rb_s = np.minimum(rb_s, rb2)
        return rem(lo, hi)[0], cb
    rb, cb = proven(sigma)
    t, _, r = _weighted_minimax(A, z, rb)
    t_lin = highs.chebyshev_fit(A, z)[1]
    q_exact, t_exact = exact_fit(mod, positions, z, A, g)
    consistent = bool(t <= sigma)
    supported = sigma if consistent else _smallest_sigma(A, z, sigma, t_lin, lambda s: proven(s)[0])
    v = Verdict(consistent=consistent, sigma=sigma, sigma_min_supported=supported,
                minimax_less_remainder=float(t), minimax_linear=t_lin, exact_fit=q_exact,
                minimax_exact=t_exact, remainder=rb,
                disagree=np.flatnonzero(np.abs(r) - rb > sigma * (1 + 1e-9)), residual=r)
    if W is not None:
        v.error_linear = sigma * np.abs(W).sum(axis=1)
        v.error_remainder = np.abs(W) @ rb + cb
        v.q_shift = cb
    return v


def _smallest_sigma(A, z, refuted, supported, proven, steps=4):
    """Bisection (in log) between a refuted sigma and one the data support (the linear minimax
    residual always is): the smallest supported sigma found, to within the last bracket."""
    lo, hi = refuted, supported
    for _ in range(steps):
        mid = np.sqrt(lo * hi)
        if _weighted_minimax(A, z, proven(mid))[0] <= mid:
            hi = mid
        else:
            lo = mid
    return float(hi)
