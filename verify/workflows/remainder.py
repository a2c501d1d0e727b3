"""The proven linearisation remainder of the exact model around its fit (workflows/guarantee.py's R): interval Taylor
arithmetic (solve/taylor.py) over a box of v = (q, t), per reading, with what q absorbs of it (the first-order t
term G t and the curvature C) taken out and proven apart."""
import numpy as np

from ..solve import highs, taylor

EPS = np.finfo(float).eps

ROUNDING = 1e-13           # absolute, on z of size 1: the float value and Jacobian of the exact model at p0


def linear_parameters(mod):
    """Parameters that enter the readings affinely with a constant coefficient: the biases."""
    return np.array([k == "bias" for k in mod.PARAMETER_KINDS])


def _extra(mod, positions):
    return [np.asarray(positions.extra[str(v)], float) for v in mod.VARIABLES]


def _columns(rows):
    """Columns of A (and components of z) of the given positions: 3 per position."""
    return (3 * np.asarray(rows)[:, None] + np.arange(3)).reshape(-1)


class Remainder:
    """The proven remainder around the centre at a set of positions, with what q absorbs.

    C (curvature) and G (the first-order t term) are fitted once, by least squares over (at most
    FIT_ROWS of) the positions, at the centre (any C and G are valid: they only move terms between the
    bounds); then for every v in a box containing the centre c,
        |R_k - (A^T C(v - c))_k| <= 1/2 sum |dv_i| |dv_j| sup |Hess_k,ij - (A^T C)_k,ij|,
    |C(dv)_nu| <= 1/2 sum |C_nu,ij| |dv_i| |dv_j|, the Hessian enclosed by interval Taylor arithmetic
    at every position or, for readings that are trigonometric polynomials in the angles, interpolated
    exactly from nodes (taylor.Interpolation); float rounding covered by margins."""

    FIT_ROWS = 256
    BLOCK = 2048             # positions per block of the bound: memory stays linear and small
    DIRECT_ROWS = 256        # up to this many positions, each is enclosed on its own: the tightest bound

    def __init__(self, lin, boxes=()):
        self.lin, self.mod, self.A = lin, lin.mod, lin.A
        pos = lin.positions
        self.angles = [np.atleast_1d(np.asarray(a, float)) for a in pos.radians]
        self.mounts = pos.mounts
        self.extra = _extra(lin.mod, pos)
        m = lin.A.shape[0]
        cols = list(lin.keep) + list(range(m, lin.L.shape[1]))
        self.Lv = lin.L[:, cols].copy()
        self.Lv[linear_parameters(lin.mod)] = 0.0
        self.centre = np.r_[lin.q0[lin.keep], np.zeros(len(lin.T))]
        n, nv = len(self.angles[0]), len(cols)
        self.P = nv * (nv + 1) // 2
        self.interp = (taylor.Interpolation(self.mod.TRIG_DEGREE)
                       if taylor.Interpolation.usable(self.mod, self.angles, self.extra) else None)
        self._nodes = {}
        self._direct_box, self._direct = None, {}
        self.prepare([(self.centre, self.centre), *boxes])
        fit_rows = highs.spread(n, self.FIT_ROWS)
        mid, _, _ = self._enclosure(self.centre, self.centre, fit_rows, direct=self.interp is None)
        At = lin.A[:, _columns(fit_rows)].T
        self.C = np.linalg.lstsq(At, mid.reshape(len(fit_rows) * 3, -1), rcond=None)[0]
        self.G = np.linalg.lstsq(At, lin.Jt[_columns(fit_rows)], rcond=None)[0] if len(lin.T) else np.zeros((m, 0))
        self.t_residual = np.empty(lin.Jt.shape[0])          # |J_t - A^T G| t_max, per reading
        for b in range(0, len(self.t_residual), 3 * self.BLOCK):            # a block at a time: linear, small
            Jt, At = lin.Jt[b:b + 3 * self.BLOCK], lin.A[:, b:b + 3 * self.BLOCK].T
            t_res = np.abs(Jt - At @ self.G)
            t_res += taylor.SUM_ERROR * (np.abs(Jt) + np.abs(At) @ np.abs(self.G))
            self.t_residual[b:b + 3 * self.BLOCK] = t_res @ lin.t_bound + ROUNDING

    def prepare(self, boxes):
        """Enclose the Hessian at the nodes for several boxes (lo, hi) in one evaluation (interpolation
        only; the boxes a computation will need, known in advance)."""
        if not self.interpolates():
            return
        for k in ([None] if self.mounts is None else np.unique(self.mounts)):
            todo = [b for b in boxes if ((tuple(b[0]), tuple(b[1])), k) not in self._nodes]
            for b, nodes in zip(todo, self.interp.at_nodes(self.mod, self.Lv, todo, k, self.centre) if todo else ()):
                self._nodes[(tuple(b[0]), tuple(b[1])), k] = nodes

    def _enclosure(self, lo, hi, rows, direct):
        """(midpoints, radii) of the packed Hessian enclosure at the given positions: (rows, 3, P),
        position by position (`direct`) or interpolated from the nodes; and the jets' error bounds
        (rows, 3), 0 where the readings are smooth over the box (taylor.Jet2: |x| where x may be 0)."""
        if direct:
            return self._direct_enclosure(lo, hi, rows)
        mounts = None if self.mounts is None else self.mounts[rows]
        W = self.interp.weights([a[rows] for a in self.angles])
        key = (tuple(lo), tuple(hi))
        mid, rad = np.empty((len(rows), 3 * self.P)), np.empty((len(rows), 3 * self.P))
        for k in ([None] if mounts is None else np.unique(mounts)):
            if (key, k) not in self._nodes:
                self._nodes[key, k] = self.interp.at_nodes(self.mod, self.Lv, [(lo, hi)], k, self.centre)[0]
            sel = slice(None) if k is None else mounts == k
            mid[sel], rad[sel] = self.interp.enclose(W[sel], *self._nodes[key, k])
        return mid.reshape(len(rows), 3, -1), rad.reshape(len(rows), 3, -1), np.zeros((len(rows), 3))

    def _direct_enclosure(self, lo, hi, rows):
        """`_enclosure` position by position, reusing what is kept for the last box: it is asked for at
        the estimator's positions, then at all, then for the functional. Up to DIRECT_ROWS positions are
        kept, so memory stays that of one block whatever the number of positions."""
        key, rows = (tuple(lo), tuple(hi)), np.asarray(rows, dtype=int)
        if self._direct_box != key:
            self._direct_box, self._direct = key, {}
        have = np.array([r in self._direct for r in rows.tolist()], dtype=bool)
        mid, rad = np.empty((len(rows), 3, self.P)), np.empty((len(rows), 3, self.P))
        err = np.empty((len(rows), 3))
        todo = rows[~have]
        if len(todo):
            mounts = None if self.mounts is None else self.mounts[todo]
            H_lo, H_hi, err[~have] = taylor.packed_hessian(self.mod, [a[todo] for a in self.angles], self.Lv, lo, hi,
                                                           mounts, [v[todo] for v in self.extra], centre=self.centre)
            mid[~have], rad[~have] = taylor.midrad(H_lo, H_hi)
            if len(self._direct) + len(todo) <= self.DIRECT_ROWS:
                self._direct.update(zip(todo.tolist(), zip(mid[~have], rad[~have], err[~have])))
        for i in np.flatnonzero(have):
            mid[i], rad[i], err[i] = self._direct[int(rows[i])]
        return mid, rad, err

    def shift(self, dv):
        """C(dv) = 1/2 dv^T C_nu dv for each q_nu (C held packed): the curvature q absorbs."""
        k, j = taylor.triangle(len(dv))
        return self.C @ (np.where(k == j, 0.5, 1.0) * dv[k] * dv[j])

    def interpolates(self, rows=None):
        """Whether the bound at these positions (default all) is interpolated rather than made position
        by position: only for many positions (it is faster, and up to about twice as wide)."""
        count = len(self.angles[0]) if rows is None else len(rows)
        return self.interp is not None and count > self.DIRECT_ROWS

    def _weights(self, lo, hi):
        return taylor.pair_weights(np.maximum(self.centre - np.minimum(lo, self.centre),
                                              np.maximum(hi, self.centre) - self.centre))

    def __call__(self, lo, hi, rows=None, direct=None):
        """(bound of |R'| per residual component (3 per position of `rows`, default all), bound of
        |C(dv)| per kept q) over the box; position by position or interpolated as `interpolates` says,
        unless `direct` says."""
        direct = not self.interpolates(rows) if direct is None or self.interp is None else direct
        rows = np.arange(len(self.angles[0])) if rows is None else np.asarray(rows)
        w = self._weights(lo, hi)
        rb = np.empty((len(rows), 3))
        for b in range(0, len(rows), self.BLOCK):
            block = rows[b:b + self.BLOCK]
            mid, rad, err = self._enclosure(lo, hi, block, direct)
            fit = (self.A[:, _columns(block)].T @ self.C).reshape(mid.shape)
            # (|mid - fit| + rad) + SUM_ERROR (1 + |fit| + |mid|), in place: the same operations in the same order
            margin = np.abs(fit)
            margin += 1
            margin += np.abs(mid)
            margin *= taylor.SUM_ERROR
            d = np.subtract(mid, fit, out=fit)
            np.abs(d, out=d)
            d += rad
            d += margin
            rb[b:b + self.BLOCK] = d @ w + err
        cb = np.abs(self.C) @ w
        return rb.reshape(-1) * (1 + taylor.SUM_ERROR), cb * (1 + taylor.SUM_ERROR)

    def functional(self, W, lo, hi, rows):
        """Bound of |W_nu R'| for each estimator row, the functional at once (the curvature of a sum
        cancels where the per-reading bounds add): positions `rows` hold W's support."""
        mid, rad, err = self._enclosure(lo, hi, rows, direct=True)
        cols = _columns(rows)
        fit = (self.A[:, cols].T @ self.C).reshape(mid.shape)
        D = (mid - fit).reshape(len(cols), -1)
        margin = taylor.SUM_ERROR * (1 + np.abs(fit) + np.abs(mid)).reshape(len(cols), -1)
        Wc = W[:, cols]
        return ((np.abs(Wc @ D) + np.abs(Wc) @ (rad.reshape(len(cols), -1) + margin)) @ self._weights(lo, hi)
                + np.abs(Wc) @ err.reshape(-1)) * (1 + taylor.SUM_ERROR)
