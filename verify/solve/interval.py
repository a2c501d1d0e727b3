"""Rigorous interval arithmetic on numpy arrays, with first derivatives (for the mean-value form).

Every operation rounds outward (np.nextafter), so an enclosure computed here contains every value
the real function takes on the box: a bound proven this way is a proof, not a sample. Used to show
that a dual certificate |H^T lambda| <= 1 holds on a whole continuum (the sphere of 001).

Hand-written rather than mpmath.iv: every operation here acts on whole numpy arrays (thousands of
positions at once), where mpmath's intervals are scalar Python objects. tests/solve/test_arithmetic.py
checks each operation against mpmath at 60 digits.
"""
import numpy as np

INF = np.inf


REL = 2.0 ** -51     # at least one ulp of any normal double, as a fraction of its magnitude
TINY = 1e-300        # covers results at or below the normal range


def _out(lo, hi):
    """Widen by at least one ulp: a correctly rounded result is within half an ulp of the exact value,
    and |x| 2^-51 is one ulp or more, so [lo - d, hi + d] holds it (the scaling by a power of 2 is
    exact; the subtraction's own rounding is half an ulp, inside the margin)."""
    d = np.abs(lo)                   # in place: -(|lo| 2^-51 + TINY) + lo is lo - (|lo| 2^-51 + TINY) exactly
    d *= -REL
    d -= TINY
    d += lo
    e = np.abs(hi)
    e *= REL
    e += TINY
    e += hi
    return d, e


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
        if self.lo is self.hi and isinstance(o, Iv) and o.lo is not o.hi:
            return o * self                                 # a number times an interval: the same, in two
        if not isinstance(o, Iv) or o.lo is o.hi:          # a number: two products, not four
            c = o.lo if isinstance(o, Iv) else np.asarray(o, float)
            a, b = self.lo * c, self.hi * c
            return Iv(*_out(np.minimum(a, b), np.maximum(a, b)))
        a, b, c, d = self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi
        if np.ndim(a) == 0:                                 # numpy scalars: no out= arrays
            return Iv(*_out(min(a, b, c, d), max(a, b, c, d)))
        lo = np.minimum(a, b)
        np.minimum(lo, np.minimum(c, d), out=lo)
        np.maximum(a, b, out=a)
        np.maximum(c, d, out=c)
        return Iv(*_out(lo, np.maximum(a, c, out=a)))

    __rmul__ = __mul__

    def square(self):
        """x^2 (its lower end 0 when the interval straddles 0), rounded outward."""
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
        """sqrt of the nonnegative part, rounded outward."""
        return Iv(*_out(np.sqrt(np.maximum(self.lo, 0)), np.sqrt(self.hi)))

    def sin(self):
        """sin over the interval (the extrema it contains included), rounded outward."""
        return _trig(self, np.sin, np.pi / 2)

    def cos(self):
        """cos over the interval (the extrema it contains included), rounded outward."""
        return _trig(self, np.cos, 0.0)

    def hull(self, o):
        """The smallest interval holding both."""
        return Iv(np.minimum(self.lo, o.lo), np.maximum(self.hi, o.hi))

    def intersect(self, o):
        """The common part of both (empty where lo > hi)."""
        return Iv(np.maximum(self.lo, o.lo), np.minimum(self.hi, o.hi))

    def mag(self):
        """The largest |x| over the interval."""
        return np.maximum(np.abs(self.lo), np.abs(self.hi))


def _iv(x):
    return x if isinstance(x, Iv) else Iv(x)


def _trig(x, f, peak):
    """sin or cos of an interval: the endpoint values, widened to +-1 where the interval holds a
    maximum (peak + 2k pi) or minimum (peak + pi + 2k pi); libm's ~1 ulp error is covered by the
    outward rounding done twice."""
    a, b = f(x.lo), f(x.hi)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    k_max = np.ceil((x.lo - peak) / (2 * np.pi))
    has_max = peak + 2 * np.pi * k_max <= x.hi
    k_min = np.ceil((x.lo - peak - np.pi) / (2 * np.pi))
    has_min = peak + np.pi + 2 * np.pi * k_min <= x.hi
    wide = (x.hi - x.lo) >= 2 * np.pi
    hi = np.where(has_max | wide, 1.0, hi)
    lo = np.where(has_min | wide, -1.0, lo)
    lo, hi = _out(*_out(lo, hi))
    return Iv(np.maximum(lo, -1.0), np.minimum(hi, 1.0))


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
        """1/x with its gradient -x'/x^2."""
        r = self.v.recip()
        r2 = r.square()
        return Grad(r, [-(a * r2) for a in self.d])

    def __pow__(self, k):
        if not (isinstance(k, int) or float(k).is_integer()) or k < 1:
            raise ValueError("only positive integer powers")
        out = self
        for _ in range(int(k) - 1):
            out = out * self
        return out

    def sqrt(self):
        """sqrt with its gradient x'/(2 sqrt x)."""
        r = self.v.sqrt()
        half = (r * 2).recip()
        return Grad(r, [a * half for a in self.d])

    def sin(self):
        """sin with its gradient cos(x) x'."""
        c = self.v.cos()
        return Grad(self.v.sin(), [a * c for a in self.d])

    def cos(self):
        """cos with its gradient -sin(x) x'."""
        s = -self.v.sin()
        return Grad(self.v.cos(), [a * s for a in self.d])


def box_variables(lo, hi):
    """Box enclosures of n coordinates (lists of arrays) with unit derivatives."""
    n = len(lo)
    out = []
    for i in range(n):
        x = Iv(lo[i], hi[i])
        one, zero = Iv(np.ones_like(x.lo)), Iv(np.zeros_like(x.lo))
        out.append(Grad(x, [one if j == i else zero for j in range(n)]))
    return out


def variables(s_lo, s_hi, t_lo, t_hi):
    """Box enclosures of (s, t) with unit derivatives (two coordinates)."""
    return box_variables([s_lo, t_lo], [s_hi, t_hi])


def mean_value_enclosure(f, *bounds):
    """Enclosure of f over boxes given as lo1, hi1, lo2, hi2, ...: the naive one intersected with the
    mean-value form f(c) + grad f(box) . (box - c)."""
    lo, hi = list(bounds[0::2]), list(bounds[1::2])
    box = f(*box_variables(lo, hi))
    c = [(a + b) / 2 for a, b in zip(lo, hi)]
    centre = f(*box_variables(c, c)).v
    mv = centre
    for d, a, b, ci in zip(box.d, lo, hi, c):
        mv = mv + d * Iv(*_out(a - ci, b - ci))          # the offsets rounded outward too
    return box.v.intersect(mv)
