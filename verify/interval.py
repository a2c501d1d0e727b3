"""Rigorous interval arithmetic on numpy arrays, with first derivatives (for the mean-value form).

Every operation rounds outward (np.nextafter), so an enclosure computed here contains every value
the real function takes on the box: a bound proven this way is a proof, not a sample. Used to show
that a dual certificate |H^T lambda| <= 1 holds on a whole continuum (the sphere of 001).
"""
import numpy as np

INF = np.inf


def _out(lo, hi):
    return np.nextafter(lo, -INF), np.nextafter(hi, INF)


class Iv:
    """Intervals [lo, hi], elementwise over arrays."""

    __slots__ = ("lo", "hi")

    def __init__(self, lo, hi=None):
        self.lo = np.asarray(lo, float)
        self.hi = self.lo if hi is None else np.asarray(hi, float)

    def __add__(self, o):
        o = _iv(o)
        return Iv(*_out(self.lo + o.lo, self.hi + o.hi))

    __radd__ = __add__

    def __neg__(self):
        return Iv(-self.hi, -self.lo)

    def __sub__(self, o):
        return self + (-_iv(o))

    def __rsub__(self, o):
        return _iv(o) + (-self)

    def __mul__(self, o):
        o = _iv(o)
        p = np.stack([self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi])
        return Iv(*_out(p.min(axis=0), p.max(axis=0)))

    __rmul__ = __mul__

    def square(self):
        lo2, hi2 = self.lo**2, self.hi**2
        straddle = (self.lo <= 0) & (self.hi >= 0)
        lo = np.where(straddle, 0.0, np.minimum(lo2, hi2))
        lo, hi = _out(lo, np.maximum(lo2, hi2))
        return Iv(np.maximum(lo, 0.0), hi)

    def recip(self):
        """1/x for intervals that do not contain 0."""
        if np.any((self.lo <= 0) & (self.hi >= 0)):
            raise ZeroDivisionError("interval contains 0")
        return Iv(*_out(1 / self.hi, 1 / self.lo))

    def sqrt(self):
        return Iv(*_out(np.sqrt(np.maximum(self.lo, 0)), np.sqrt(self.hi)))

    def hull(self, o):
        return Iv(np.minimum(self.lo, o.lo), np.maximum(self.hi, o.hi))

    def intersect(self, o):
        return Iv(np.maximum(self.lo, o.lo), np.minimum(self.hi, o.hi))

    def mag(self):
        return np.maximum(np.abs(self.lo), np.abs(self.hi))


def _iv(x):
    return x if isinstance(x, Iv) else Iv(x)


class Grad:
    """An interval value with interval partial derivatives in two coordinates (s, t)."""

    __slots__ = ("v", "d")

    def __init__(self, v, d):
        self.v, self.d = v, d

    def __add__(self, o):
        if not isinstance(o, Grad):
            return Grad(self.v + o, self.d)
        return Grad(self.v + o.v, [a + b for a, b in zip(self.d, o.d)])

    __radd__ = __add__

    def __neg__(self):
        return Grad(-self.v, [-a for a in self.d])

    def __sub__(self, o):
        return self + (-o)

    def __mul__(self, o):
        if not isinstance(o, Grad):
            return Grad(self.v * o, [a * o for a in self.d])
        return Grad(self.v * o.v, [a * o.v + self.v * b for a, b in zip(self.d, o.d)])

    __rmul__ = __mul__

    def recip(self):
        r = self.v.recip()
        r2 = r.square()
        return Grad(r, [-(a * r2) for a in self.d])

    def sqrt(self):
        r = self.v.sqrt()
        half = (r * 2).recip()
        return Grad(r, [a * half for a in self.d])


def variables(s_lo, s_hi, t_lo, t_hi):
    """Box enclosures of (s, t) with unit derivatives, and the box centres as points."""
    s, t = Iv(s_lo, s_hi), Iv(t_lo, t_hi)
    one, zero = Iv(np.ones_like(s.lo)), Iv(np.zeros_like(s.lo))
    return Grad(s, [one, zero]), Grad(t, [zero, one])


def mean_value_enclosure(f, s_lo, s_hi, t_lo, t_hi):
    """Enclosure of f over boxes: the naive one intersected with f(c) + grad f(box) . (box - c)."""
    S, T = variables(s_lo, s_hi, t_lo, t_hi)
    box = f(S, T)
    cs, ct = (s_lo + s_hi) / 2, (t_lo + t_hi) / 2
    Cs, Ct = variables(cs, cs, ct, ct)
    centre = f(Cs, Ct).v
    mv = centre + box.d[0] * Iv(s_lo - cs, s_hi - cs) + box.d[1] * Iv(t_lo - ct, t_hi - ct)
    return box.v.intersect(mv)
