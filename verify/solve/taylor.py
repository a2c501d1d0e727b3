"""Proven second-order remainders of a generated model, by interval Taylor arithmetic.

A `Jet2` carries a value, its gradient and its Hessian with respect to the variables, every entry an
outward-rounded interval (interval.Iv), vectorised over positions. Evaluating a generated module's
exact `readings` on jets whose values are boxes encloses the Hessian of the readings over the whole
box. With Taylor's theorem (Lagrange form), for every p of a box containing 0:

    |z(p) - z(0) - J p|_i <= 1/2 sum_kj |p_k| |p_j| sup |d2 z_i / dp_k dp_j|,

a proof of the linearisation remainder of (1) -> (2) of 000, position by position. The generated
function is evaluated unchanged: its `np` is replaced, for that call only, by a namespace whose
sin, cos, array and asarray accept jets. For readings that are trigonometric polynomials in the
angles (the module's TRIG_DEGREE), `Interpolation` gives the enclosure at any number of positions
from the enclosures at a few nodes, exactly.

Hand-written for the same reason as interval.py: jets over all positions at once, as numpy arrays
(tests/solve/test_arithmetic.py checks them against exact derivatives in mpmath).
"""
import functools
import types

import numpy as np

from .interval import Iv

CHUNK = 100           # positions per evaluation: a chunk's jets, (nv (nv + 1) / 2, CHUNK) intervals, stay in cache


@functools.lru_cache(maxsize=None)
def triangle(n):
    """Index pairs (k, j), k <= j, of the packed upper triangle of a symmetric n x n matrix."""
    return np.triu_indices(n)


def _take(a, idx):
    return Iv(a.lo[idx], a.hi[idx])


@functools.lru_cache(maxsize=None)
def _embedding(sub, sup):
    """Where a jet on the variables `sub` puts its rows in one on `sup` (sorted tuples, sub within sup):
    gradient rows, and packed Hessian rows (triangle(len(sup)) is row-major: (r, c) is row
    r n - r (r - 1) / 2 + c - r)."""
    pos = np.searchsorted(np.asarray(sup), np.asarray(sub, dtype=int))
    k, j = triangle(len(sub))
    n = len(sup)
    return pos, pos[k] * n - pos[k] * (pos[k] - 1) // 2 + pos[j] - pos[k]


def _place(a, idx, rows):
    """The interval rows of `a` at rows `idx` of `rows` rows, exact zeros elsewhere (a point stays one)."""
    lo = np.zeros((rows,) + a.lo.shape[1:])
    lo[idx] = a.lo
    if a.lo is a.hi:
        return Iv(lo)
    hi = np.zeros((rows,) + a.hi.shape[1:])
    hi[idx] = a.hi
    return Iv(lo, hi)


def _union(a, b):
    """The sorted union of two supports."""
    return a if a == b else tuple(sorted(set(a) | set(b)))


def _lift(x, s, u, hessian):
    """Rows of the gradient (or packed Hessian) x on support s, on the larger support u."""
    if s == u:
        return x
    g_idx, h_idx = _embedding(s, u)
    return _place(x, h_idx, len(u) * (len(u) + 1) // 2) if hessian else _place(x, g_idx, len(u))


def _sym(a, b):
    """The packed triangle of outer(a, b) + outer(b, a): a_k b_j + b_k a_j (a_k b_k twice on the diagonal)."""
    k, j = triangle(len(a.lo))
    return _take(a, k) * _take(b, j) + _take(b, k) * _take(a, j)


def _square(a):
    """The packed triangle of outer(a, a)."""
    k, j = triangle(len(a.lo))
    return _take(a, k) * _take(a, j)


class Jet2:
    """Value (S,), gradient (n, S) and the upper triangle of the symmetric Hessian (n (n + 1) / 2, S),
    all intervals. S is 1 for what depends on the parameters alone (numpy broadcasts it to the
    positions where an angle enters), so the stand's own constants are computed once, not per position.

    `e` (None: 0), a bound (S,) on |f - phi| over the box: the jet is that of a smooth phi, and the
    function f it stands for may differ from phi by at most e (|x| where x may be 0: see __abs__).
    Each operation carries e, so the Taylor remainder of phi plus e bounds f's.

    `s`, the support: the variables (sorted indices of the n) the jet depends on; g and h hold the rows
    of those alone (the others are exactly 0). A reading's factors each depend on a few errors, so
    most products are of small jets."""

    __slots__ = ("v", "g", "h", "e", "s", "n")
    __array_ufunc__ = None            # ndarray * jet defers to the jet's own __rmul__

    def __init__(self, v, g, h, e=None, s=None, n=None):
        self.v, self.g, self.h, self.e = v, g, h, e
        self.s = tuple(range(len(g.lo))) if s is None else s
        self.n = len(self.s) if n is None else n

    def _like(self, v, g, h, e):
        return Jet2(v, g, h, e, self.s, self.n)

    @staticmethod
    def variables(lo, hi, shape):
        """One jet per variable k over [lo_k, hi_k], of the given shape (positions; (1,) for none)."""
        n = len(lo)
        one, zero = Iv(np.ones((1,) + shape)), Iv(np.zeros((1,) + shape))
        return [Jet2(Iv(np.full(shape, lo[k]), np.full(shape, hi[k])), one, zero, None, (k,), n) for k in range(n)]

    def hessian(self):
        """The full symmetric Hessian over all n variables, intervals of shape (n, n, S)."""
        n, h = self.n, self.packed()
        k, j = triangle(n)
        out = []
        for half in (h.lo, h.hi):
            full = np.empty((n, n) + half.shape[1:])
            full[k, j] = half
            full[j, k] = half
            out.append(full)
        return Iv(*out)

    def packed(self):
        """The packed Hessian over all n variables (triangle(n) rows), exact zeros off the support."""
        return _lift(self.h, self.s, tuple(range(self.n)), hessian=True)

    def __add__(self, o):
        if isinstance(o, Jet2):
            e = None if self.e is None and o.e is None else _up(_zero(self.e), _zero(o.e))
            u = _union(self.s, o.s)
            g = _lift(self.g, self.s, u, False) + _lift(o.g, o.s, u, False)
            h = _lift(self.h, self.s, u, True) + _lift(o.h, o.s, u, True)
            return Jet2(self.v + o.v, g, h, e, u, self.n)
        return self._like(self.v + o, self.g, self.h, self.e)

    __radd__ = __add__

    def __neg__(self):
        return self._like(-self.v, -self.g, -self.h, self.e)

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, Jet2):
            c = Iv(np.asarray(o, float))
            return self._like(self.v * c, self.g * c, self.h * c, None if self.e is None else _up(self.e * c.mag()))
        e = None                                  # (phi1 + d1)(phi2 + d2) - phi1 phi2 = phi1 d2 + phi2 d1 + d1 d2
        if self.e is not None or o.e is not None:
            e1, e2 = _zero(self.e), _zero(o.e)
            e = _up(self.v.mag() * e2, o.v.mag() * e1, e1 * e2)
        u = _union(self.s, o.s)                   # each part on its own support, then lifted to the union
        g1, g2 = _lift(self.g, self.s, u, False), _lift(o.g, o.s, u, False)
        g = _lift(self.g * o.v, self.s, u, False) + _lift(o.g * self.v, o.s, u, False)
        h = _lift(self.h * o.v, self.s, u, True) + _lift(o.h * self.v, o.s, u, True) + _sym(g1, g2)
        return Jet2(self.v * o.v, g, h, e, u, self.n)

    __rmul__ = __mul__

    def _chain(self, f1, f2, e=None):
        """f(self) from f = value, f1 = f', f2 = f'' (intervals over the value's box); `e`, f's own error
        bound (self's carried through f by the caller)."""
        return lambda f0: self._like(f0, self.g * f1, _square(self.g) * f2 + self.h * f1, e)

    def sin(self):
        """sin of the jet (value, first and second derivatives by the chain rule; |sin'| <= 1 carries e)."""
        s, c = self.v.sin(), self.v.cos()
        return self._chain(c, -s, self.e)(s)

    def cos(self):
        """cos of the jet (value, first and second derivatives by the chain rule; |cos'| <= 1 carries e)."""
        s, c = self.v.sin(), self.v.cos()
        return self._chain(-s, -c, self.e)(c)

    def __pow__(self, n):
        """The jet to a whole power n >= 0 (a quadratic scale factor's w^2): n v^(n-1), n (n-1) v^(n-2);
        e becomes n (|v| + e)^(n-1) e (the mean value theorem)."""
        if not float(n).is_integer() or n < 0:
            raise TypeError(f"a jet to the power {n}: the generated readings take whole powers only")
        n = int(n)
        if n < 2:
            return self if n == 1 else 1.0
        e = None if self.e is None else _up(n * (self.v.mag() + self.e) ** (n - 1) * self.e)
        return self._chain(_power(self.v, n - 1) * n, _power(self.v, n - 2) * (n * (n - 1)), e)(_power(self.v, n))

    def __abs__(self):
        """|x|, position by position. Where the sign of x is proven over the whole box (its value interval
        excludes 0) it is the jet or its negative. Where x may be 0, |x| has no second derivative: the
        jet is that of phi = s x for a sign s in [-1, 1] (the linearisation's own, sign(x) at the centre,
        whatever it is), and |x| - s x, at most 2 |x|, joins the error bound e. Exact at the centre, so
        the remainder of the readings stays that of phi plus e."""
        pos, neg = self.v.lo > 0, self.v.hi < 0
        cross = ~pos & ~neg
        sign = Iv(np.where(pos, 1.0, -1.0), np.where(neg, -1.0, 1.0))
        e = None
        if cross.any() or self.e is not None:
            e = np.where(cross, _up(2 * self.v.mag(), 2 * _zero(self.e)), _zero(self.e))
        return self._like(self.v * sign, self.g * sign, self.h * sign, e)


def _zero(e):
    return 0.0 if e is None else e


def _up(*parts):
    """A sum of nonnegative bounds, rounded up."""
    total = sum(parts[1:], parts[0])
    return np.asarray(total, float) * (1 + SUM_ERROR) + 1e-300


def _power(v, k):
    """The interval v^k, k >= 0, by squaring (an even power's lower end 0 where v straddles 0)."""
    if k == 0:
        return Iv(np.ones_like(v.lo))
    if k == 1:
        return v
    half = _power(v, k // 2).square()
    return half if k % 2 == 0 else half * v


class _Vector(list):
    """What np.array([...]) of jets becomes: a list that scales by a number."""

    def __rmul__(self, c):
        return _Vector(x * c for x in self)

    __mul__ = __rmul__


def _constant_sqrt(x):
    if isinstance(x, Jet2):
        raise TypeError("sqrt of a jet: the generated readings take square roots of constants only")
    return np.sqrt(x)


def _namespace():
    ns = types.SimpleNamespace(**{k: getattr(np, k) for k in ("broadcast_arrays", "zeros_like", "ones_like", "pi")})
    ns.asarray = lambda x, dtype=None: x if isinstance(x, list) else np.asarray(x, dtype)
    ns.sin = lambda x: x.sin() if isinstance(x, Jet2) else np.sin(x)
    ns.cos = lambda x: x.cos() if isinstance(x, Jet2) else np.cos(x)
    ns.sqrt = _constant_sqrt                  # constants of a tilted axis or a wedge, never of a jet
    ns.array = lambda rows: _Vector(rows) if any(isinstance(r, Jet2) for r in rows) else np.array(rows)
    return ns


JET_NUMPY = _namespace()


def with_jets(fn):
    """The generated function fn, evaluated with jets: its globals with np replaced."""
    return types.FunctionType(fn.__code__, {**fn.__globals__, "np": JET_NUMPY}, fn.__name__, fn.__defaults__)


SUM_ERROR = 1e-12     # relative: covers the float rounding of a sum or product of a few hundred terms


def packed_hessian(mod, angles, L, lo, hi, mounts=None, variables=(), centre=None):
    """Enclosure of the Hessian of z_exact(L v) with respect to v over the hull of the box [lo, hi]
    and the centre of the expansion (default 0), at every position, upper triangles packed
    (`triangle`): (lower, upper), each (N, 3, P). The physical parameters are p = L v (L: n x nv),
    coordinates in which the directions no data can see are variables of their own, so that their
    exact invariances cost nothing. lo and hi are (nv,), one box for all positions, or (nv, N), a box
    per position. Also E (N, 3): the jets' error bounds e (0 where the readings are smooth over the box),
    to be added to the remainder."""
    c = np.zeros(np.shape(lo)[:1]) if centre is None else np.asarray(centre, float)
    c = c.reshape((-1,) + (1,) * (np.ndim(lo) - 1))
    lo, hi = np.minimum(lo, c), np.maximum(hi, c)
    per_position = np.ndim(lo) == 2
    L = np.asarray(L, float)
    angles = [np.atleast_1d(np.asarray(a, float)) for a in angles]
    N, nv = len(angles[0]), L.shape[1]
    P = nv * (nv + 1) // 2
    H_lo, H_hi, E = np.zeros((N, 3, P)), np.zeros((N, 3, P)), np.zeros((N, 3))
    groups = [(None, np.arange(N))] if mounts is None else [(k, np.flatnonzero(mounts == k))
                                                              for k in np.unique(mounts)]
    chunks = [(k, rows[c:c + CHUNK]) for k, rows in groups for c in range(0, len(rows), CHUNK)]
    physical = None if per_position else _linear_jets(L, lo, hi)
    for k, rows in chunks:
        fn = getattr(mod, f"_readings_{0 if k is None else k}")     # the function itself (its np rebound)
        if per_position:
            physical = _linear_jets(L, lo[:, rows], hi[:, rows])
        extra = [np.asarray(v, float)[rows] for v in variables]
        f = with_jets(fn)(*[a[rows] for a in angles], physical, 1.0, *extra)
        for i, fi in enumerate(f):
            if isinstance(fi, Jet2):
                h = fi.packed()
                H_lo[rows, i] = h.lo.T
                H_hi[rows, i] = h.hi.T
                if fi.e is not None:
                    E[rows, i] = fi.e
    return H_lo, H_hi, E


def midrad(lo, hi):
    """[lo, hi] as midpoint and radius, the radius rounded up: [lo, hi] lies in [mid - rad, mid + rad]."""
    mid = 0.5 * (lo + hi)
    return mid, np.maximum(hi - mid, mid - lo) * (1 + SUM_ERROR) + 1e-300


def pair_weights(P_abs):
    """w with w . packed(M) = 1/2 sum_kj P_k P_j M_kj for a symmetric M: 1/2 P_k^2 on the diagonal,
    P_k P_j off it (each pair counted twice)."""
    k, j = triangle(len(P_abs))
    return np.where(k == j, 0.5, 1.0) * P_abs[k] * P_abs[j]


def remainder_bound(mod, angles, L, lo, hi, mounts=None, variables=()):
    """Proven bound of |z_exact(L v) - H^T R L v| for every v in the box, per position and component,
    shape (N, 3): by Taylor's theorem (Lagrange form) around v = 0, 1/2 sum_kj |v_k| |v_j| sup |H_kj|."""
    H_lo, H_hi, E = packed_hessian(mod, angles, L, lo, hi, mounts, variables)
    P = np.maximum(-np.minimum(lo, 0.0), np.maximum(hi, 0.0))
    return (np.maximum(-H_lo, H_hi) @ pair_weights(P) + E) * (1 + SUM_ERROR)


class Interpolation:
    """The Hessian at many positions from its values at a few nodes, for readings that are a
    trigonometric polynomial of degree d_i in each angle i (the module's TRIG_DEGREE; derive counts it).

    With 2 d_i + 1 equispaced nodes x_j per angle, every such polynomial, and so every entry of its
    Hessian in v for each fixed v, equals sum_j w_j(x) h(x_j) exactly, w_j the tensor product of
    w(x - x_j) = (1 + 2 sum_{m <= d} cos(m (x - x_j))) / (2 d + 1). The enclosures [h_j] at the nodes
    (interval Taylor arithmetic, once per box) then enclose h(x) by sum_j w_j [h_j]: a proof at
    every position for the cost of a matrix product. WEIGHT_ERROR bounds the float error of each
    computed w_j and is added, times sum_j |h_j|. With |x| <= MAX_ANGLE, d <= 3 and at most 3 angles:
    x - x_j is within 1.2e-14 of its value, m (x - x_j) within 5e-14, each cosine (libm, under an
    ulp) within 6e-14, one angle's weight within 1.5e-13, a product of three weights (each of size
    <= 1) within 5e-13; the float nodes differ from 2 pi j / n by an ulp, which moves the Lagrange
    weights by about 1e-14. 1e-11 covers all of it 20 times over."""

    WEIGHT_ERROR = 1e-11
    MAX_ANGLE = 100.0            # rad
    MAX_DEGREE = 3

    def __init__(self, degrees):
        self.degrees = tuple(degrees)
        grids = [2 * np.pi * np.arange(2 * d + 1) / (2 * d + 1) for d in self.degrees]
        self.nodes = [g.ravel() for g in np.meshgrid(*grids, indexing="ij")]

    @classmethod
    def usable(cls, mod, angles, variables):
        """Whether the identity applies (and pays): a trigonometric polynomial, no row variables, the
        angles within range and more positions than nodes."""
        degrees = mod.TRIG_DEGREE
        if degrees is None or variables or len(degrees) > 3 or max(degrees, default=0) > cls.MAX_DEGREE:
            return False
        nodes = int(np.prod([2 * d + 1 for d in degrees]))
        return len(angles[0]) > nodes and max(np.abs(a).max() for a in angles) <= cls.MAX_ANGLE

    def weights(self, angles):
        """w_j at each position: (N, number of nodes)."""
        W = np.ones((len(angles[0]), 1))
        for x, d in zip(angles, self.degrees):
            n = 2 * d + 1
            delta = x[:, None] - 2 * np.pi * np.arange(n)[None, :] / n
            w = (1 + 2 * sum((np.cos(m * delta) for m in range(1, d + 1)), np.zeros_like(delta))) / n
            W = (W[:, :, None] * w[:, None, :]).reshape(len(x), -1)
        return W

    def at_nodes(self, mod, L, boxes, mount=None, centre=None):
        """For each box (lo, hi): (midpoints, radii) of the node enclosures, (nodes, 3 P) each, and
        sum_j |h_j| (3 P,). The boxes share one evaluation: the nodes repeated box by box."""
        M, B = len(self.nodes[0]), len(boxes)
        lo = np.repeat(np.stack([b[0] for b in boxes], axis=1), M, axis=1)
        hi = np.repeat(np.stack([b[1] for b in boxes], axis=1), M, axis=1)
        H_lo, H_hi, E = packed_hessian(mod, [np.tile(x, B) for x in self.nodes], L, lo, hi,
                                       None if mount is None else np.full(M * B, mount), centre=centre)
        assert not E.any(), "a trigonometric polynomial is smooth: no jet error"
        mid, rad = midrad(H_lo, H_hi)
        mid, rad = mid.reshape(B, M, -1), rad.reshape(B, M, -1)
        return [(m, r, (np.abs(m) + r).sum(axis=0)) for m, r in zip(mid, rad)]

    def enclose(self, W, mid, rad, total):
        """(midpoints, radii) of sum_j w_j [h_j] at positions with weights W: every rounding (the
        products, the weights) inside the radii."""
        m = W @ mid
        r = (np.abs(W) @ (rad + SUM_ERROR * np.abs(mid))) * (1 + SUM_ERROR) + self.WEIGHT_ERROR * total
        return m, r


def _linear_jets(L, lo, hi):
    """p = L v as jets: value intervals (lo, hi of shape (nv,): one position, broadcast to all;
    (nv, S): a box per position), constant gradients, zero Hessians (rows of L that are zero give the
    number 0). The values in midpoint-radius form, L mid +- |L| rad, every rounding inside the radius."""
    nv = L.shape[1]
    shape = np.shape(lo)[1:] or (1,)
    lo, hi = np.asarray(lo, float).reshape(nv, -1), np.asarray(hi, float).reshape(nv, -1)
    mid, rad = midrad(lo, hi)
    centre = L @ mid
    radius = (np.abs(L) @ (rad + SUM_ERROR * np.abs(mid))) * (1 + SUM_ERROR) + 1e-300
    out = []
    for row, c, r in zip(L, centre, radius):
        s = tuple(int(k) for k in np.flatnonzero(row))          # the support: the variables the row mixes
        out.append(Jet2(Iv((c - r).reshape(shape), (c + r).reshape(shape)), Iv(row[list(s), None].copy()),
                        Iv(np.zeros((len(s) * (len(s) + 1) // 2, 1))), None, s, nv) if s else 0.0)
    return out


STEP = 1e-30          # the complex step: Im f(p + i h d) / h is f'(p) d to rounding (h^2 terms are below it)


def _complex_namespace():
    ns = types.SimpleNamespace(**{k: getattr(np, k) for k in ("broadcast_arrays", "zeros_like", "ones_like", "pi",
                                                               "sin", "cos", "sqrt")})
    ns.asarray = lambda x, dtype=None: np.asarray(x, complex if dtype is float else dtype)
    ns.array = lambda rows: np.array(np.broadcast_arrays(*rows))
    return ns


COMPLEX_NUMPY = _complex_namespace()


def _complex_abs(x):
    """|x| for the complex step: x sign(Re x), whose imaginary part carries the derivative sign(x) x'
    (the modulus would drop it); 0 at x = 0, a subgradient, as the jets' |x| allows (Jet2.__abs__)."""
    return x * np.sign(np.real(x))
BLOCK = 2048          # positions per evaluation of the Jacobian: (3, nv, BLOCK) complex arrays stay small


def jacobian(mod, angles, L, p0, mounts=None, variables=()):
    """The exact readings over g at p0, and their derivatives along the columns of L (p = p0 + L v),
    at every position: (value (N, 3), J (N, 3, nv)). By the complex step: the generated function is
    evaluated once per block of positions at p0 + i h L_k for every k at once (its np replaced by a
    namespace that keeps complex numbers), and J = Im / h, exact to rounding since nothing is
    subtracted; a relative error of SUM_ERROR covers it (the generated readings are analytic)."""
    L = np.asarray(L, float)
    angles = [np.atleast_1d(np.asarray(a, float)) for a in angles]
    N, nv = len(angles[0]), L.shape[1]
    physical = (np.asarray(p0, float)[:, None] + 1j * STEP * L)[:, :, None]       # (n, nv, 1)
    value, J = np.empty((N, 3)), np.empty((N, 3, nv))
    groups = [(None, np.arange(N))] if mounts is None else [(k, np.flatnonzero(mounts == k))
                                                              for k in np.unique(mounts)]
    for k, rows in groups:
        fn = getattr(mod, f"_readings_{0 if k is None else k}")     # the function itself (its np rebound)
        fn = types.FunctionType(fn.__code__, {**fn.__globals__, "np": COMPLEX_NUMPY, "abs": _complex_abs},
                                fn.__name__, fn.__defaults__)
        for b in range(0, len(rows), BLOCK):
            sel = rows[b:b + BLOCK]
            f = fn(*[a[sel] for a in angles], physical, 1.0, *[np.asarray(v, float)[sel] for v in variables])
            f = np.broadcast_to(f, (3, nv, len(sel)))
            value[sel] = f[:, 0, :].real.T
            J[sel] = np.moveaxis(f.imag / STEP, 2, 0)
    return value, J
