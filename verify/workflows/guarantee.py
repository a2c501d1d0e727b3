"""What makes a bound guaranteed: the data consistent with sigma, and the linearisation remainder in it.

The readings are linearised where the unit is, not at zero errors: at the exact-model fit p0 (a MEMS
unit's scale errors of 2e-2 would otherwise put H off by 2 % and q by 2e-3). In coordinates
v = (q, t), p = L v, with q the identifiable combinations (4) of 000 and t the parameters with the
smallest a-priori bounds that complete them (the directions no plan separates, `coordinates`):

    z(p) = z(p0) + A^T dq + J_t t + R,     dq = q - q0, t within its a-priori bounds,

R the second-order remainder around the centre, proven by interval Taylor arithmetic
(solve/taylor.py) over a box of v. The box is the a-priori one first (`premises.py`: the stand's
errors from its description, Delta_g/g from the uncertainty of g, wide defaults for the block), then
a posteriori: dq within the guaranteed errors of the estimate, each box valid whenever the premises
hold, each inside the last; the block's errors only start this iteration.

What moves the readings along a column of A is absorbed by q: the first-order t term as G t
(J_t = A^T G + its residual) and the curvature as C(dv) = 1/2 dv^T C dv, so
    z - z(p0) = A^T (dq + G t + C(dv)) + rho + r,   |r_k| <= R'_k + |J_t - A^T G|_k t_max,
both parts proven. The verdict: if the premises hold, some q' fits every reading within sigma + |r_k|;
when none does (a minimax LP), the data refute sigma, or a premise: a proof. Otherwise each q is
bounded by a linear part sigma sum |W| and a remainder part: what is left after absorption (per
reading, or for the functional W_nu r directly, whichever is smaller), the absorbed curvature |C|, and
the unseparable part |W A^T G| t_max: q's definition is linear, the unit's invariance is not, so a q
is known only up to the a-priori bounds of t times the size of the errors.
"""
from dataclasses import dataclass, field

import numpy as np

from ..defaults import SIGMA_WIDER
from ..solve import highs, hull, taylor
from . import subdivide
from .premises import Premises
from .remainder import EPS, ROUNDING, Remainder, _columns, _extra, linear_parameters



class Weights:
    """An estimator W (m x 3N, q = q0 + W y) with its part on the readings it weighs: `Wc` on the columns `cols`, 0
    on the rest. An optimal estimator of (7)-(8) of 000 weighs a few positions, so |W| and the bounds made of it
    cost theirs, not every reading's (|W| made at each use was a copy of all of W). W's own products (W y, W A^T)
    stay over every reading: their rounding is what the bounds' rounding terms measure, unchanged."""

    def __init__(self, W):
        m = W.shape[0]
        self.W = W
        self.support = np.flatnonzero((W != 0).reshape(m, -1, 3).any(axis=(0, 2)))     # positions
        self.cols = _columns(self.support)
        self.Wc = W[:, self.cols]
        self.abs = np.abs(self.Wc)

    def absolute(self, x):
        """|W| x."""
        return self.abs @ x[self.cols]


def coordinates(mod, bounds):
    """p = L v with v = (q, t): q = PHYSICAL_TO_Q p, and t the physical parameters (indices T) with the
    smallest a-priori bounds that make the map invertible, so that the directions no data can see are
    bounded by the premises. Also `keep`: the q that are not biases (the others do not enter the
    remainder). Returns (L, keep, T)."""
    R = np.asarray(mod.PHYSICAL_TO_Q, float)
    m, n = R.shape
    lin = linear_parameters(mod)
    rows, T = R, []
    for k in np.argsort(np.where(lin, np.inf, bounds), kind="stable"):
        if len(T) == n - m:
            break
        trial = np.vstack([rows, np.eye(n)[k]])
        if np.linalg.matrix_rank(trial) > len(rows):
            rows, T = trial, T + [int(k)]
    L = np.linalg.inv(rows)
    keep = [nu for nu in range(m) if np.abs(R[nu, ~lin]).max() > 0]
    return L, keep, T


@dataclass
class Linearisation:
    """The exact model linearised at its minimax fit (the centre: q0, t = 0)."""

    mod: object
    positions: object
    premises: Premises
    L: np.ndarray          # p = L v, v = (q, t): n x n
    keep: list             # q that are not biases
    T: list                # indices of the physical parameters t
    q0: np.ndarray         # the centre
    z0: np.ndarray         # z_exact at the centre (3N,)
    A: np.ndarray          # dz/dq at the centre: the relinearised H, m x 3N
    Jt: np.ndarray         # dz/dt at the centre, 3N x len(T)
    minimax_exact: float   # the exact model's minimax residual at the centre: the fit quality

    @property
    def t_bound(self):
        """The a-priori bounds of the parameters no plan separates (t)."""
        return self.premises.bounds[self.T]

    @property
    def stated_bounds(self):
        """Each physical parameter's a-priori bound as stated (an absorbed one's own, from the split; a bias,
        which needs no bound, 0): what a unit within the premises has."""
        b = np.where(linear_parameters(self.mod), 0.0, self.premises.bounds)
        for name, (bound, _) in self.premises.split.items():
            b[self.premises.names.index(name)] = bound
        return b

    @property
    def q_prior(self):
        """What the a-priori bounds of the parameters that enter nonlinearly allow for each q, the absorbed
        parameters' own bounds included (a bias counts 0; a q of biases alone is not in the remainder's box)."""
        return np.abs(np.asarray(self.mod.PHYSICAL_TO_Q, float)) @ self.stated_bounds


    @property
    def q_box(self):
        """(lo, hi) of each q that the premises allow: +-q_prior, unbounded for a q that holds a bias."""
        biases = np.asarray(self.mod.PHYSICAL_TO_Q, float)[:, linear_parameters(self.mod)].any(axis=1)
        qp = np.where(biases, np.inf, self.q_prior * (1 + 1e-12))
        return -qp, qp


def _z_exact(mod, positions, p, g):
    kw = {"mount": positions.mounts} if positions.mounts is not None else {}
    f = mod.readings(*positions.radians, p, g, *_extra(mod, positions), **kw)
    return mod.residual(*positions.radians, f, g, **kw).T.reshape(-1)


def exact_fit(mod, positions, z, A, g, Lq, iterations=8):
    """Minimax fit of the exact model with t = 0 (p = Lq q): successive Chebyshev fits of the exact
    residual with the linear A, a contraction when the errors are small. (q, its minimax residual)."""
    q, best, _ = highs.chebyshev_fit(A, z)
    for _ in range(iterations):
        dq, t, _ = highs.chebyshev_fit(A, z - _z_exact(mod, positions, Lq @ q, g))
        if t >= best * (1 - 1e-9):
            break
        q, best = q + dq, t
    return q, float(np.abs(z - _z_exact(mod, positions, Lq @ q, g)).max())


def linearise(mod, positions, z, A, premises, at_zero=False):
    """The Linearisation of the model at the exact-model fit of the residuals z (A: H at zero errors),
    or, `at_zero`, at zero errors (the linear model (2) of 000 itself: z0 = 0 and A)."""
    L, keep, T = coordinates(mod, premises.bounds)
    m = A.shape[0]
    if at_zero:
        q0, fit = np.zeros(m), float(np.abs(z - highs.chebyshev_fit(A, z)[2]).max())
    else:
        q0, fit = exact_fit(mod, positions, z, A, premises.g, L[:, :m])
    return at(Linearisation(mod, positions, premises, L, keep, T, q0, None, None, None, fit), q0)


def at(lin, q0):
    """The Linearisation `lin` moved to the centre q0 (t = 0): z_exact and its Jacobian there (the fit quality
    kept: it is the data's, not the centre's)."""
    mod, positions, m = lin.mod, lin.positions, len(q0)
    value, J = taylor.jacobian(mod, positions.radians, lin.L, lin.L[:, :m] @ q0, positions.mounts,
                               _extra(mod, positions))
    kw = {"mount": positions.mounts} if positions.mounts is not None else {}
    z0 = (value - mod.up_nominal(*positions.radians, **kw).T).reshape(-1)
    K = J.shape[0] * 3
    return Linearisation(mod, positions, lin.premises, lin.L, lin.keep, lin.T, np.asarray(q0, float), z0,
                         J[:, :, :m].reshape(K, m).T, J[:, :, m:].reshape(K, -1), lin.minimax_exact)


def box(lin, q=None, e=None):
    """Bounds (lo, hi) of v = (q kept, t): q within what the premises allow, and within [q - e, q + e]
    when an estimate is given; t within its a-priori bounds."""
    qp = lin.q_prior[lin.keep]
    lo, hi = -qp, qp
    if q is not None:
        lo, hi = np.maximum(lo, q[lin.keep] - e[lin.keep]), np.minimum(hi, q[lin.keep] + e[lin.keep])
        lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
    return np.r_[lo, -lin.t_bound], np.r_[hi, lin.t_bound]


class Unbounded(Exception):
    """A target of InformationSet.physical whose range over the premises is unbounded: its index among the
    targets is `args[0]` (the stand does not separate it)."""


class InformationSet:
    """What the readings prove: every q whose linearised readings fit each reading within its bound,
        Q = {q = q0 + w - u : |y_k - a_k^T w| <= s_k for every k, |u| <= shift},
    s_k = sigma + the proven remainder left at reading k, u what q absorbs (the curvature C(dv) and the
    first-order t term G t, bounded per q). Any function of q is bounded over Q by LPs whose ends are
    proven by weak duality (solve/hull.py); w lies in a box the estimator W proves (|w - W y| <=
    |W| s + |W A^T - I| |w|), which the proofs multiply their rounding by. Adding readings adds rows:
    Q can only shrink."""

    def __init__(self, lin, y, s, shift, W, start=()):
        """The set of the readings y within s (per reading) and what q absorbs (`shift`), within the premises:
        each q in the box they allow (`Linearisation.q_box`: a premise the bounds print, so it cuts them),
        where that box meets the estimator's (else a premise is refuted, and the estimator's box alone is
        kept: the caller says so)."""
        self.lin, self.A, self.y, self.s, self.shift = lin, lin.A, y, s, shift
        self.start = start                      # rows that bound a previous set's hull: where this one starts
        m = self.A.shape[0]
        Ac = self.A[:, W.cols]                  # W: Weights, on the readings it weighs
        Wy = W.W @ y
        E = np.abs(W.W @ self.A.T - np.eye(m)) + taylor.SUM_ERROR * (W.abs @ np.abs(Ac.T))
        e = W.absolute(s) + taylor.SUM_ERROR * W.absolute(np.abs(y))
        e_max = (e.max() + (E @ np.abs(Wy)).max()) / max(1 - E.sum(axis=1).max(), 1e-3)
        e = (e + E @ (np.abs(Wy) + e_max)) * (1 + 1e-9) + 1e-300
        self.w_lo, self.w_hi = Wy - e, Wy + e
        # q = q0 + w - u, |u| <= shift: the premises' box of q is one of w, widened by shift and rounding
        q_lo, q_hi = lin.q_box
        pad = shift + taylor.SUM_ERROR * (np.abs(lin.q0) + np.where(np.isfinite(q_hi), q_hi, 0.0)) + 1e-300
        w_lo, w_hi = np.maximum(self.w_lo, q_lo - lin.q0 - pad), np.minimum(self.w_hi, q_hi - lin.q0 + pad)
        if np.all(w_lo <= w_hi):
            self.w_lo, self.w_hi = w_lo, w_hi
        self._reach = W.abs.sum(axis=1) / max(1 - E.sum(axis=1).max(), 1e-3) * (1 + 1e-9)   # w's box per unit of s
        self._q = None

    def ranges(self, C, keep=False):
        """(lo, hi) of each c^T q (rows of C) over Q, proven; `keep`: the multipliers that prove them are
        kept (for `widened`). A row that is a multiple of one e_nu is that q's range, scaled (no LP)."""
        C = np.atleast_2d(np.asarray(C, float))
        single = (np.count_nonzero(C, axis=1) == 1) if self._q is not None and not keep else np.zeros(len(C), bool)
        if single.any():
            lo, hi = np.empty(len(C)), np.empty(len(C))
            nu = np.argmax(C[single] != 0, axis=1)
            a = C[single, nu]
            ql, qh = self._q
            lo[single] = np.minimum(a * ql[nu], a * qh[nu])
            hi[single] = np.maximum(a * ql[nu], a * qh[nu])
            pad = 4 * EPS * (np.abs(lo[single]) + np.abs(hi[single]))
            lo[single], hi[single] = lo[single] - pad, hi[single] + pad
            if (~single).any():
                lo[~single], hi[~single] = self.ranges(C[~single])
            return lo, hi
        try:
            lo, hi, lams = hull.ranges(self.A.T, self.y - self.s, self.y + self.s, self.w_lo, self.w_hi, C,
                                       multipliers=True, start=self.start)
        except hull.Empty:                       # the verdict found a fit: empty only to HiGHS's tolerance
            none = hull.NONE
            lams = [(none, none)] * len(C)
            lo = np.array([-hull.upper(-c, self.A.T, self.y - self.s, self.y + self.s, self.w_lo, self.w_hi, none)
                           for c in C])
            hi = np.array([hull.upper(c, self.A.T, self.y - self.s, self.y + self.s, self.w_lo, self.w_hi, none)
                           for c in C])
        if keep:
            self._lams = (C, lams)
        return self._shifted(C, lo, hi)

    def widened(self, extra):
        """(lo, hi) of each q over the set with every reading's bound s + extra: the multipliers that proved
        `q` prove these too (weak duality holds for any lambda): at most the wider set's own hull."""
        C, lams = self._lams
        rows_lo, rows_hi = self.y - self.s - extra, self.y + self.s + extra
        w_lo, w_hi = self.w_lo - self._reach * extra, self.w_hi + self._reach * extra
        lo = np.array([-hull.upper(-c, self.A.T, rows_lo, rows_hi, w_lo, w_hi, a) for c, (a, _) in zip(C, lams)])
        hi = np.array([hull.upper(c, self.A.T, rows_lo, rows_hi, w_lo, w_hi, b) for c, (_, b) in zip(C, lams)])
        return self._shifted(C, lo, hi)

    def _shifted(self, C, lo, hi):
        """c^T q = c^T (q0 + w - u): the ranges of c^T w moved by c^T q0 and widened by |c|^T shift."""
        c0 = C @ self.lin.q0
        pad = np.abs(C) @ self.shift + taylor.SUM_ERROR * (np.abs(C) @ np.abs(self.lin.q0) + np.abs(c0)) + 4 * EPS * (
            np.abs(lo) + np.abs(hi))
        return c0 + lo - pad, c0 + hi + pad

    @property
    def binding(self):
        """The readings whose multipliers prove q's ranges (after `q`)."""
        return np.unique(np.concatenate([m.rows[m.values != 0] for pair in self._lams[1] for m in pair]))

    @property
    def q(self):
        """(lo, hi) of each q over Q."""
        if self._q is None:
            self._q = self.ranges(np.eye(self.A.shape[0]), keep=True)
        return self._q

    def physical(self, R, col_lo, col_hi, targets):
        """(lo, hi, points) of each physical parameter p_j (j in targets) over {p : R p in Q, col_lo <= p <=
        col_hi}: one LP pair each in (p, u) over `physical_set`. points: the p at each end (min, max), for what
        the range reaches. hull.Empty when no such p exists."""
        n = np.shape(R)[1]
        B, row_lo, row_hi, lo, hi = self.physical_set(R, col_lo, col_hi, targets)
        C = np.zeros((len(targets), B.shape[1]))
        C[np.arange(len(targets)), np.asarray(targets)] = 1.0
        out_lo, out_hi, pts = hull.ranges(B, row_lo, row_hi, lo, hi, C, points=True)
        return out_lo, out_hi, [tuple(None if x is None else x[:n] for x in ends) for ends in pts]

    def physical_set(self, R, col_lo, col_hi, targets=(), rows=None):
        """The set {p : R p in Q, col_lo <= p <= col_hi} as an LP's rows and columns (B, row_lo, row_hi, lo, hi) in
        (p, u): w = R p - q0 + u with |u| <= shift, rows A^T w within y +- s (only the readings `rows`, when given:
        those that can bind). Unbounded columns (inf) are first enclosed through a row of R whose other entries are
        bounded (q_nu over Q); a target that no row encloses is not separated (Unbounded names it)."""
        R = np.asarray(R, float)
        m, n = R.shape
        lo, hi = np.array(col_lo, float), np.array(col_hi, float)
        ql, qh = self.q
        for _ in range(n):
            free = ~(np.isfinite(lo) & np.isfinite(hi))
            if not free.any():
                break
            for j in np.flatnonzero(free):
                for nu in np.flatnonzero(R[:, j]):
                    others = np.flatnonzero(R[nu]) != j
                    ks = np.flatnonzero(R[nu])[others]
                    if not (np.all(np.isfinite(lo[ks])) and np.all(np.isfinite(hi[ks]))):
                        continue
                    reach = np.abs(R[nu, ks]) @ np.maximum(np.abs(lo[ks]), np.abs(hi[ks]))
                    a, b = (ql[nu] - reach) / R[nu, j], (qh[nu] + reach) / R[nu, j]
                    a, b = min(a, b), max(a, b)
                    pad = 8 * EPS * (abs(a) + abs(b)) + 1e-300
                    lo[j], hi[j] = max(lo[j], a - pad), min(hi[j], b + pad)
            if np.array_equal(free, ~(np.isfinite(lo) & np.isfinite(hi))):
                break
        free = ~(np.isfinite(lo) & np.isfinite(hi))
        if free[list(targets)].any():
            raise Unbounded(int(np.flatnonzero(free[list(targets)])[0]))
        # a column no row encloses is never a target (refused above); it gets the box |p| <= 1, a premise that
        # binds nothing on the built-in stands (every parameter is bounded or enclosed there)
        lo, hi = np.where(free, -1.0, lo), np.where(free, 1.0, hi)
        # w = R p - q0 + u, |u| <= shift: the rows A^T (R p + u) within y + A^T q0 +- s (its rounding in s)
        pick = slice(None) if rows is None else np.asarray(rows)
        At, y, s = self.A.T[pick], self.y[pick], self.s[pick]
        base = At @ self.lin.q0
        s = s + taylor.SUM_ERROR * (np.abs(At) @ np.abs(self.lin.q0) + np.abs(base))
        return (np.hstack([At @ R, At]), y + base - s, y + base + s, np.r_[lo, -self.shift], np.r_[hi, self.shift])


def _weighted_minimax(A, z, rb):
    """min over q of max_k (|z_k - a_k^T q| - rb_k): (value, q, residual)."""
    q, t, r = highs.chebyshev_fit(A, z, slack=rb, what="minimax fit with remainder")
    return t, q, r


@dataclass
class Verdict:
    """Whether the data are consistent with sigma and, with an estimator, the guaranteed errors and their parts."""

    consistent: bool
    sigma: float
    sigma_min_supported: float       # smallest sigma the data support, to SIGMA_TOLERANCE (sigma when consistent)
    minimax_less_remainder: float    # min_q max_k |y_k - a_k^T q| - r_k
    minimax_linear: float            # min_q max_k |y_k - a_k^T q| (relinearised)
    minimax_exact: float             # the exact model's minimax residual at the centre: the fit quality
    remainder: np.ndarray            # |r_k|, proven, per residual component (N*3,): left after absorption
    disagree: np.ndarray             # indices k where |y_k - a_k^T q*| - r_k > sigma
    residual: np.ndarray             # y - A^T q* at that minimax fit (N*3,)
    error_linear: np.ndarray = None      # sigma sum |W| per q
    error_remainder: np.ndarray = None   # the rest: left after absorption, absorbed, unseparable, rounding
    parts: dict = field(default_factory=dict)   # the remainder part's terms, per q
    q_shift: np.ndarray = None           # per q: the part not carried by W's readings (absorbed, unseparable)
    box: tuple = None                    # (lo, hi) of v = (kept q, t): the last box the truth is proven in
    info: "InformationSet" = None        # the information set: what these readings prove (with an estimator)
    interval: tuple = None               # (lo, hi) per q printed: the information set's hull within the a-priori bound
    interval_wider: tuple = None         # the same had sigma been SIGMA_WIDER times larger (the remainder as for sigma)
    split_refuted: bool = False          # every piece of the split premise box refuted (subdivide.py)

    @property
    def guaranteed_error(self):
        """Linear part plus proven remainder part, per q."""
        return self.error_linear + self.error_remainder


SIGMA_TOLERANCE = 0.01     # relative: the smallest supported sigma is bracketed this closely
#: No further a posteriori box once each q's remainder part that the box sets (left after absorption,
#: absorbed) is within this fraction of its linear part: a smaller box lowers no bound by more.
BOX_GAIN = 0.001
#: No further box of the information set once what the box sets (the remainder left at each reading, through
#: the estimator's weights, and the absorbed curvature) is within this fraction of each q's half-width (at 0.01 a
#: single-axis stand's bounds grew by up to 9e-4 of themselves when readings were added; at 0.001, 5e-5:
#: tests/workflows/test_single_axis_prior.py).
INFO_GAIN = 0.001


def verdict(lin, z, sigma, W=None, steps=8, sharper=None, progress=None):
    """The consistency verdict on the residuals z and, with an estimator W (m x 3N, q = q0 + W (z - z0)),
    the guaranteed errors with the proven remainder. `sharper` (3N, units of g): how much below the noise
    bound each residual is known (repeated readings joined by their intersection, estimate.sharper); a
    noise bound s then bounds residual k by s - sharper_k (none below what the repeats themselves allow).
    A premise box too wide to contract from is split (subdivide.py): when every piece is refuted, so is sigma
    (or a premise). `progress(text)`, when given, hears of the split."""
    rem = Remainder(lin, boxes=[box(lin)])
    y = z - lin.z0
    sharp = np.zeros(len(y)) if sharper is None else np.asarray(sharper, float)
    m = lin.A.shape[0]
    if W is not None:
        W = Weights(W)
        support, cols = W.support, W.cols
        Ac = lin.A[:, cols]
        WA = W.W @ lin.A.T
        E = np.abs(WA - np.eye(m)) + taylor.SUM_ERROR * (W.abs @ np.abs(Ac.T))
        unseparable = np.abs(WA @ rem.G) @ lin.t_bound * (1 + taylor.SUM_ERROR)
        unseparable_q = np.abs(rem.G) @ lin.t_bound * (1 + taylor.SUM_ERROR)
        dq = W.W @ y

    def errors(s, rb, cb, functional):
        """Per q: (linear part, remainder part, its terms, the part beyond W's readings)."""
        left = np.minimum(W.absolute(rb), functional) if functional is not None else W.absolute(rb)
        absorbed = np.abs(WA) @ cb
        beyond = absorbed + unseparable
        linear = W.abs @ (s - sharp[cols])
        r = linear + left + beyond
        # W A^T = I only to rounding: |(W A^T - I) dq_true| with |dq_true| <= |dq| + e, e <= r + E (|dq| + e)
        norm = E.sum(axis=1).max()
        e_max = (r.max() + (E @ np.abs(dq)).max()) / max(1 - norm, 1e-3)
        rounding = E @ (np.abs(dq) + e_max)
        parts = {"left_after_absorption": left, "absorbed_into_q": absorbed, "unseparable": unseparable,
                 "rounding": rounding}
        return linear, left + beyond + rounding, parts, beyond + rounding

    def proven(s):
        """(r per reading, C bound, the errors) when the noise bound is s: over the a-priori box; with an
        estimator, then over a posteriori boxes (each valid if the premises hold, each inside the
        last), the intermediate ones at the estimator's positions only, the last at every position."""
        lo, hi = box(lin)
        if W is None:
            rb, cb = rem(lo, hi)
            return rb + rem.t_residual, cb, None
        one_by_one = not rem.interpolates()
        rb = np.zeros(len(y))
        rb[cols], cb = rem(lo, hi, support, one_by_one)

        def contract(lo, hi, cb):
            """The a posteriori boxes from [lo, hi] (rb in place); and, when they stop with a q whose estimator
            interval, its remainder part the larger, spans the box (the box then proves nothing of it), the
            estimator's box of every q (lo, hi) (else None)."""
            for step in range(steps):
                lin_e, rem_e, parts, _ = errors(s, rb + rem.t_residual, cb, None)
                if np.all(parts["left_after_absorption"] + parts["absorbed_into_q"] <= BOX_GAIN * lin_e):
                    break                            # a smaller box would lower no bound by BOX_GAIN
                lo2, hi2 = box(lin, lin.q0 + dq, lin_e + rem_e)
                lo2, hi2 = np.maximum(lo2, lo), np.minimum(hi2, hi)
                nq = len(lin.keep)                  # t keeps its a-priori bounds: only q's boxes shrink
                shrink = np.min((hi2 - lo2)[:nq] / np.maximum(hi - lo, 1e-300)[:nq], initial=1.0)
                lo, hi = lo2, hi2
                rb_s, cb_s = rem(lo, hi, support, one_by_one)
                rb[cols], cb = np.minimum(rb[cols], rb_s), np.minimum(cb, cb_s)
                if shrink > 0.9:                     # no box shrank by a tenth: the next would gain little
                    kept, half = lin.keep, 0.5 * (hi - lo)[:nq]
                    spans = ((lin_e + rem_e)[kept] >= half) & (rem_e > lin_e)[kept]
                    stuck = (lin.q0 + dq - lin_e - rem_e, lin.q0 + dq + lin_e + rem_e) if spans.any() else None
                    return lo, hi, cb, stuck
            return lo, hi, cb, None
        lo, hi, cb, stuck = contract(lo, hi, cb)
        if stuck is not None:                        # the premise box too wide to contract from: split it
            q_lo, q_hi = lin.q_box
            q_lo, q_hi = np.maximum(stuck[0], q_lo), np.minimum(stuck[1], q_hi)
            q_lo[lin.keep], q_hi[lin.keep] = lo[:len(lin.keep)], hi[:len(lin.keep)]
            found = subdivide.proven_box(lin, z, s - sharp, (q_lo, q_hi), at, progress)
            split_refuted[0] = found is None         # no q of the box fits within s: s, or a premise, refuted
            if found is not None:                    # with the centre: the remainder is proven about it
                centre = np.r_[lin.q0[lin.keep], np.zeros(len(lin.T))]
                lo, hi = np.minimum(found[0], centre), np.maximum(found[1], centre)
                rb_s, cb_s = rem(lo, hi, support, one_by_one)
                rb[cols], cb = np.minimum(rb[cols], rb_s), np.minimum(cb, cb_s)
                lo, hi, cb, _ = contract(lo, hi, cb)
        rb_all, cb_all = rem(lo, hi)
        rb_all[cols] = np.minimum(rb_all[cols], rb[cols])
        if rem.interpolates():
            rb_all[cols] = np.minimum(rb_all[cols], rem(lo, hi, support, direct=True)[0])
        cb = np.minimum(cb, cb_all)
        functional = None
        if len(support) <= rem.DIRECT_ROWS:         # the functional W_nu r at once: R' and the t residual
            Jt = lin.Jt[cols]
            t_res = np.abs(W.Wc @ (Jt - Ac.T @ rem.G)) @ lin.t_bound
            t_res += taylor.SUM_ERROR * (W.abs @ (np.abs(Jt) + np.abs(Ac.T) @ np.abs(rem.G))) @ lin.t_bound
            functional = rem.functional(W.W, lo, hi, support) + t_res + W.abs.sum(axis=1) * ROUNDING
        errs = errors(s, rb_all + rem.t_residual, cb, functional)
        # what these readings prove: the information set, its box contracting the remainder in turn
        info = InformationSet(lin, y, s - sharp + rb_all + rem.t_residual, cb * (1 + taylor.SUM_ERROR) + unseparable_q,
                              W)
        for _ in range(steps):
            ql, qh = info.q
            half = 0.5 * (qh - ql)
            if np.all(W.absolute(rb_all) + cb <= INFO_GAIN * half):
                break                                # a smaller box would lower no bound by INFO_GAIN
            lo2, hi2 = box(lin, 0.5 * (ql + qh), half)
            lo2, hi2 = np.maximum(lo2, lo), np.minimum(hi2, hi)
            nq = len(lin.keep)
            if np.min((hi2 - lo2)[:nq] / np.maximum(hi - lo, 1e-300)[:nq], initial=1.0) > 0.9:
                break
            lo, hi = lo2, hi2
            rb_n, cb_n = rem(lo, hi)
            rb_all, cb = np.minimum(rb_all, rb_n), np.minimum(cb, cb_n)
            info = InformationSet(lin, y, s - sharp + rb_all + rem.t_residual,
                                  cb * (1 + taylor.SUM_ERROR) + unseparable_q, W, info.binding)
        return rb_all + rem.t_residual, cb, (errs, (lo, hi), info)

    def slack(s):
        """Each residual's slack at s (its remainder less what the repeats sharpen), or None where the split of
        the premise box refutes s."""
        split_refuted[0] = False
        rb = proven(s)[0]
        return None if split_refuted[0] else rb - sharp
    split_refuted = [False]
    rb, cb, out = proven(sigma)
    by_split = split_refuted[0]
    errs, last_box, info = out if out is not None else (None, None, None)
    # the slack of each residual is its remainder less what the repeats sharpen: |r_k| <= s - sharper_k + rb_k
    t, _, r = _weighted_minimax(lin.A, y, rb - sharp)
    t_lin = highs.chebyshev_fit(lin.A, y)[1]
    floor = float(sharp.max(initial=0.0))      # below it the repeats alone refute the noise bound
    consistent = bool(t <= sigma) and floor <= sigma and not by_split
    supported = sigma if consistent else _smallest_sigma(
        lin.A, y, sigma, max(t_lin + floor, floor), slack, t_lin / (1 + SIGMA_TOLERANCE / 2) if by_split else float(t),
        floor)
    v = Verdict(consistent=consistent, sigma=sigma, sigma_min_supported=supported,
                minimax_less_remainder=float(t), minimax_linear=t_lin, minimax_exact=lin.minimax_exact,
                remainder=rb, disagree=np.flatnonzero(np.abs(r) - rb + sharp > sigma * (1 + 1e-9)), residual=r,
                split_refuted=by_split)
    if W is not None:
        v.error_linear, v.error_remainder, v.parts, v.q_shift = errs
        v.box, v.info = last_box, info
        q_apriori = lin.q0 + dq
        v.interval = _printed(q_apriori, v.guaranteed_error, info.q, lin.q_box)
        if consistent:                               # a sensitivity: sigma larger, the remainder as proven for sigma
            wider = info.widened((SIGMA_WIDER - 1) * sigma)
            more = (SIGMA_WIDER - 1) * sigma * W.abs.sum(axis=1)
            v.interval_wider = _printed(q_apriori, v.guaranteed_error + more, wider, lin.q_box)
    return v


def _printed(q, e, hull, box):
    """(lo, hi) per q: the information set's hull (lo, hi) within the a-priori interval q +- e of the
    estimator and within the box the premises allow q (`Linearisation.q_box`): all three hold. Where the
    first two do not meet, a premise fails, and the a-priori interval is kept; where the box does not meet
    them, the data put q beyond its premises, and their interval is kept (the caller says the premise is
    refuted)."""
    pad = 4 * EPS * (np.abs(q) + e)
    lo, hi = hull
    lo2, hi2 = np.maximum(lo, q - e - pad), np.minimum(hi, q + e + pad)
    bad = lo2 > hi2
    lo2, hi2 = np.where(bad, q - e - pad, lo2), np.where(bad, q + e + pad, hi2)
    lo3, hi3 = np.maximum(lo2, box[0]), np.minimum(hi2, box[1])
    out = lo3 > hi3
    return np.where(out, lo2, lo3), np.where(out, hi2, hi3)


def _smallest_sigma(A, y, refuted, supported, proven, guess=None, floor=0.0):
    """Bisection (in log) between a refuted sigma and one the data support (the linear minimax
    residual, plus `floor`, always is), until the bracket is within SIGMA_TOLERANCE: its upper end. `guess`,
    the fit at the refuted sigma, is tried first with the point SIGMA_TOLERANCE below it: the remainder
    changes little with sigma, so these two usually close the bracket (each end still decided by its own
    proof). `proven(s)`: each residual's slack at s, or None where another proof refutes s; below `floor` the
    repeated readings refute s."""
    lo, hi = refuted, supported

    def fits(s):
        if s < floor:
            return False
        slack = proven(s)
        return slack is not None and _weighted_minimax(A, y, slack)[0] <= s
    if guess is not None and lo < guess < hi:
        if fits(guess):
            hi = guess
            below = guess / (1 + SIGMA_TOLERANCE)
            if lo < below:
                if fits(below):
                    hi = below
                else:
                    lo = below
        else:
            lo = guess
    while hi > lo * (1 + SIGMA_TOLERANCE):
        mid = np.sqrt(lo * hi)
        if fits(mid):
            hi = mid
        else:
            lo = mid
    return float(hi)
