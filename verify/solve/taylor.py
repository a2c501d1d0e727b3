"""Proven second-order remainders of a generated model, by interval Taylor arithmetic.

A `Jet2` carries a value, its gradient and its Hessian with respect to the variables, every entry an
outward-rounded interval (interval.Iv), vectorised over positions. Evaluating a generated module's
exact `readings` on jets whose values are boxes encloses the Hessian of the readings over the whole
box. With Taylor's theorem (Lagrange form), for every p of a box containing 0:

    |z(p) - z(0) - J p|_i <= 1/2 sum_kj |p_k| |p_j| sup |d2 z_i / dp_k dp_j|,

a proof of the linearisation remainder of (1) -> (2) of 000, position by position. The generated
function is evaluated unchanged: its `np` is replaced, for that call only, by a namespace whose
sin, cos, array and asarray accept jets.
"""
import types

import numpy as np

from .interval import Iv

CHUNK = 1000          # positions per evaluation: the jets of one chunk hold (nv, nv, CHUNK) intervals


def _outer(a, b):
    return Iv(a.lo[:, None], a.hi[:, None]) * Iv(b.lo[None, :], b.hi[None, :])


class Jet2:
    """Value (S,), gradient (n, S), Hessian (n, n, S), all intervals."""

    __slots__ = ("v", "g", "h")
    __array_ufunc__ = None            # ndarray * jet defers to the jet's own __rmul__

    def __init__(self, v, g, h):
        self.v, self.g, self.h = v, g, h

    @staticmethod
    def variables(lo, hi, shape):
        """One jet per variable k over [lo_k, hi_k], broadcast to positions of `shape`."""
        n = len(lo)
        eye = np.eye(n)[:, :, None] * np.ones((1, 1) + shape)
        zero = Iv(np.zeros((n, n) + shape))
        return [Jet2(Iv(np.full(shape, lo[k]), np.full(shape, hi[k])), Iv(eye[k]), zero) for k in range(n)]

    def __add__(self, o):
        if isinstance(o, Jet2):
            return Jet2(self.v + o.v, self.g + o.g, self.h + o.h)
        return Jet2(self.v + o, self.g, self.h)

    __radd__ = __add__

    def __neg__(self):
        return Jet2(-self.v, -self.g, -self.h)

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, Jet2):
            c = Iv(np.asarray(o, float))
            return Jet2(self.v * c, self.g * c, self.h * c)
        return Jet2(self.v * o.v, self.g * o.v + o.g * self.v,
                    self.h * o.v + o.h * self.v + _outer(self.g, o.g) + _outer(o.g, self.g))

    __rmul__ = __mul__

    def _chain(self, f1, f2):
        """f(self) from f = value, f1 = f', f2 = f'' (intervals over the value's box)."""
        return lambda f0: Jet2(f0, self.g * f1, _outer(self.g, self.g) * f2 + self.h * f1)

    def sin(self):
        s, c = self.v.sin(), self.v.cos()
        return self._chain(c, -s)(s)

    def cos(self):
        s, c = self.v.sin(), self.v.cos()
        return self._chain(-s, -c)(c)


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


def hessian(mod, angles, L, lo, hi, mounts=None, variables=()):
    """Enclosure of the Hessian of z_exact(L v) with respect to v over the hull of the box [lo, hi]
    and 0, at every position: (lower, upper), each of shape (N, 3, nv, nv). The physical parameters
    are p = L v (L: n x nv), coordinates in which the directions no data can see are variables of
    their own, so that their exact invariances (turns about one axis that add up) cost nothing."""
    lo, hi = np.minimum(lo, 0.0), np.maximum(hi, 0.0)
    L = np.asarray(L, float)
    angles = [np.atleast_1d(np.asarray(a, float)) for a in angles]
    N, nv = len(angles[0]), L.shape[1]
    H_lo, H_hi = np.zeros((N, 3, nv, nv)), np.zeros((N, 3, nv, nv))
    groups = [(None, np.arange(N))] if mounts is None else [(k, np.flatnonzero(mounts == k))
                                                              for k in np.unique(mounts)]
    chunks = [(k, rows[c:c + CHUNK]) for k, rows in groups for c in range(0, len(rows), CHUNK)]
    for k, rows in chunks:
        fn = mod.readings if k is None else getattr(mod, f"_readings_{k}")
        physical = _linear_jets(L, lo, hi, len(rows))
        extra = [np.asarray(v, float)[rows] for v in variables]
        f = with_jets(fn)(*[a[rows] for a in angles], physical, 1.0, *extra)
        for i, fi in enumerate(f):
            if isinstance(fi, Jet2):
                H_lo[rows, i] = np.moveaxis(fi.h.lo, -1, 0)
                H_hi[rows, i] = np.moveaxis(fi.h.hi, -1, 0)
    return H_lo, H_hi


def remainder_bound(mod, angles, L, lo, hi, mounts=None, variables=()):
    """Proven bound of |z_exact(L v) - H^T R L v| for every v in the box, per position and component,
    shape (N, 3): by Taylor's theorem (Lagrange form) around v = 0, 1/2 sum_kj |v_k| |v_j| sup |H_kj|."""
    H_lo, H_hi = hessian(mod, angles, L, lo, hi, mounts, variables)
    P = np.maximum(-np.minimum(lo, 0.0), np.maximum(hi, 0.0))
    return np.nextafter(0.5 * np.einsum("k,j,sikj->si", P, P, np.maximum(-H_lo, H_hi)), np.inf)


def _linear_jets(L, lo, hi, S):
    """p = L v as jets: value intervals by interval arithmetic, constant gradients, zero Hessians
    (rows of L that are zero give the number 0)."""
    nv = L.shape[1]
    zero_h = Iv(np.zeros((nv, nv, S)))
    out = []
    for row in L:
        if not row.any():
            out.append(0.0)
            continue
        v = Iv(np.zeros(S))
        for c, a, b in zip(row, lo, hi):
            if c:
                v = v + Iv(np.full(S, a), np.full(S, b)) * c
        out.append(Jet2(v, Iv(np.repeat(row[:, None], S, axis=1)), zero_h))
    return out
