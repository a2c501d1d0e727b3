"""Exact arithmetic in the number field Q(sqrt2, sqrt3): where H lives on 15-, 30- and 45-degree grids
and on stands with 30- or 45-degree wedges (cos 15 deg = (sqrt6 + sqrt2)/4).

An element is a + b sqrt2 + c sqrt3 + d sqrt6 with rational a, b, c, d (a basis over Q, so an element
is zero exactly when its four coordinates are). Its sign is decided by rational interval bounds of
the three roots, refined until the interval excludes zero, which it must since the element is not
zero: no floating point decides anything here.
"""
from fractions import Fraction
from functools import lru_cache
from math import gcd, isqrt, lcm

ROOTS = (2, 3, 6)


class QF:
    """a + b sqrt2 + c sqrt3 + d sqrt6, exact: held as four integers over one positive denominator, in lowest
    terms (so equal numbers are equal tuples); `c` gives the four rational coordinates."""

    __slots__ = ("n", "den")

    def __init__(self, a=0, b=0, c=0, d=0):
        if type(a) is int and type(b) is int and type(c) is int and type(d) is int:
            self.n, self.den = (a, b, c, d), 1
            return
        f = [Fraction(x) for x in (a, b, c, d)]
        den = lcm(*(x.denominator for x in f))
        self.n, self.den = _lowest(tuple(x.numerator * (den // x.denominator) for x in f), den)

    @classmethod
    def _of(cls, n, den):
        """From integer coordinates over den > 0, brought to lowest terms."""
        out = object.__new__(cls)
        out.n, out.den = _lowest(n, den)
        return out

    @property
    def c(self):
        """The rational coordinates (a, b, c, d)."""
        return tuple(Fraction(x, self.den) for x in self.n)

    @staticmethod
    def of(x):
        """A QF from an int, a Fraction or a QF."""
        if isinstance(x, QF):
            return x
        if type(x) is int:
            out = object.__new__(QF)
            out.n, out.den = (x, 0, 0, 0), 1
            return out
        return QF(x)

    def __add__(self, o):
        o = QF.of(o)
        (a, b, c, d), p = self.n, self.den
        (e, f, g, h), q = o.n, o.den
        if p == q:
            return QF._of((a + e, b + f, c + g, d + h), p)
        return QF._of((a * q + e * p, b * q + f * p, c * q + g * p, d * q + h * p), p * q)

    __radd__ = __add__

    def __neg__(self):
        a, b, c, d = self.n
        out = object.__new__(QF)
        out.n, out.den = (-a, -b, -c, -d), self.den
        return out

    def __sub__(self, o):
        return self + (-QF.of(o))

    def __rsub__(self, o):
        return QF.of(o) - self

    def __mul__(self, o):
        (a, b, c, d), p = self.n, self.den
        if not isinstance(o, QF):                                        # a rational: coordinate-wise
            o = Fraction(o)
            e, q = o.numerator, o.denominator
            return QF._of((a * e, b * e, c * e, d * e), p * q)
        (e, f, g, h), q = o.n, o.den
        if not (f or g or h):
            return QF._of((a * e, b * e, c * e, d * e), p * q)
        if not (b or c or d):
            return QF._of((a * e, a * f, a * g, a * h), p * q)
        return QF._of((a * e + 2 * b * f + 3 * c * g + 6 * d * h, a * f + b * e + 3 * (c * h + d * g),
                       a * g + c * e + 2 * (b * h + d * f), a * h + d * e + b * g + c * f), p * q)

    __rmul__ = __mul__

    def inverse(self):
        """1/x in closed form: two conjugations (sqrt2 -> -sqrt2, then sqrt3 -> -sqrt3) make the norm rational."""
        if self.is_zero():
            raise ZeroDivisionError("division by an exact zero")
        # x sigma2(x) = u + v sqrt3 (sigma2: sqrt2 -> -sqrt2), and (u + v sqrt3)(u - v sqrt3) = u^2 - 3 v^2:
        # 1/x = sigma2(x) (u - v sqrt3) / (u^2 - 3 v^2), all in rationals
        a, b, c, d = self.c
        u, v = a * a + 3 * c * c - 2 * b * b - 6 * d * d, 2 * a * c - 4 * b * d
        return QF(a, -b, c, -d) * QF(u, 0, -v, 0) * (1 / (u * u - 3 * v * v))

    def __truediv__(self, o):
        return self * QF.of(o).inverse()

    def __rtruediv__(self, o):
        return QF.of(o) * self.inverse()

    def __pow__(self, n):
        out = QF(1)
        for _ in range(n):
            out = out * self
        return out

    def is_zero(self):
        """Whether every coefficient is 0."""
        return not any(self.n)

    def __bool__(self):
        return any(self.n)

    def __eq__(self, o):
        if not isinstance(o, (QF, int, Fraction)):
            return False
        o = QF.of(o)
        return self.n == o.n and self.den == o.den

    def __hash__(self):
        return hash((self.n, self.den))

    def sign(self):
        """-1, 0 or +1, exactly: that of the integer coordinates (the denominator is positive), with
        sqrt r between s / 10^k and (s + 1) / 10^k, s = isqrt(r 10^2k), in integers times 10^k."""
        a, *rest = self.n
        if not any(rest):
            return (a > 0) - (a < 0)
        k = 20
        while True:
            scale = 10 ** k
            lo = hi = a * scale
            for coef, r in zip(rest, ROOTS):
                s = isqrt(r * scale * scale)
                lo, hi = (lo + coef * s, hi + coef * (s + 1)) if coef >= 0 else (lo + coef * (s + 1), hi + coef * s)
            if lo > 0:
                return 1
            if hi < 0:
                return -1
            k *= 2

    def __abs__(self):
        return -self if self.sign() < 0 else self

    def __lt__(self, o):
        return (self - o).sign() < 0

    def __gt__(self, o):
        return (self - o).sign() > 0

    def __le__(self, o):
        return (self - o).sign() <= 0

    def __ge__(self, o):
        return (self - o).sign() >= 0

    def __float__(self):
        (a, b, c, d), den = self.n, self.den        # int / int is correctly rounded, as float(Fraction) is
        return a / den + b / den * 2 ** 0.5 + c / den * 3 ** 0.5 + d / den * 6 ** 0.5

    def sympy(self):
        """The number as a SymPy expression."""
        import sympy as sp
        return sum((sp.Rational(x.numerator, x.denominator) * (sp.sqrt(r) if r > 1 else 1)
                    for x, r in zip(self.c, (1, *ROOTS))), sp.Integer(0))

    def __repr__(self):
        return f"QF({', '.join(str(x) for x in self.c)})"


def _lowest(n, den):
    """(n, den) divided by their greatest common divisor."""
    k = gcd(*n, den)
    return (n, den) if k == 1 else (tuple(x // k for x in n), den // k)


def combination(vectors, target):
    """Exact x with sum_k x_k vectors[k] = target in QF (vectors linearly independent), or None when
    target is not in their span."""
    from garant.derive.linear import solve_exact
    return solve_exact(vectors, target, QF.of)


def from_sympy(expr):
    """A SymPy number of Q(sqrt2, sqrt3) as a QF; ValueError when it is not one."""
    import sympy as sp
    out = QF()
    basis = {sp.Integer(1): 0, sp.sqrt(2): 1, sp.sqrt(3): 2, sp.sqrt(6): 3}
    for term in sp.Add.make_args(sp.expand(expr)):
        coef, rest = term.as_coeff_Mul()
        if rest not in basis or not coef.is_Rational:
            raise ValueError(f"{expr} is not in Q(sqrt2, sqrt3)")
        c = [0, 0, 0, 0]
        c[basis[rest]] = Fraction(int(coef.p), int(coef.q))
        out = out + QF(*c)
    return out


def trig(deg):
    """(cos, sin) of an angle in degrees that is a multiple of 15, exactly; ValueError otherwise."""
    d = Fraction(deg).limit_denominator(10**6)
    if abs(float(d) - float(deg)) > 1e-9 or d.denominator != 1 or d.numerator % 15:
        raise ValueError(f"{float(deg):g} degrees is not a multiple of 15")
    return _trig(int(d) % 360)


@lru_cache(maxsize=None)
def _trig(deg):
    import sympy as sp
    x = sp.pi * deg / 180
    return from_sympy(sp.cos(x)), from_sympy(sp.sin(x))


def evaluator(exprs, symbols):
    """A function of angles in degrees (multiples of 15) giving the SymPy expressions `exprs` exactly
    as QF: sums, products, integer powers, square roots of 2, 3, 6 and sin/cos of integer combinations
    of the angles (plus rational multiples of pi). ValueError for anything else."""
    import sympy as sp
    symbols = list(symbols)

    def compile_(e):
        if e in symbols:
            raise ValueError(f"{e} appears outside sin/cos")
        if e.is_Rational:
            return lambda deg, v=QF(Fraction(int(e.p), int(e.q))): v
        if e.is_Add or e.is_Mul:
            parts = [compile_(a) for a in e.args]
            if e.is_Add:
                return lambda deg: sum((p(deg) for p in parts), QF())
            return lambda deg: _prod(p(deg) for p in parts)
        if e.is_Pow and e.exp.is_Integer and e.exp > 0:
            base, n = compile_(e.base), int(e.exp)
            return lambda deg: base(deg) ** n
        if e.is_Pow or isinstance(e, (sp.Float,)) or e.is_number:
            v = from_sympy(e)
            return lambda deg: v
        if isinstance(e, (sp.sin, sp.cos)):
            arg = e.args[0]
            coef = [int(arg.coeff(s)) if arg.coeff(s).is_Integer else None for s in symbols]
            rest = sp.simplify((arg - sum(c * s for c, s in zip(coef, symbols) if c)) * 180 / sp.pi)
            if None in coef or not rest.is_Rational:
                raise ValueError(f"{e}: not a turn by an integer combination of the angles")
            k = 0 if isinstance(e, sp.cos) else 1
            return lambda deg: trig(sum(c * d for c, d in zip(coef, deg)) + Fraction(int(rest.p), int(rest.q)))[k]
        raise ValueError(f"{e} is not an expression garant evaluates exactly")

    fns = [compile_(sp.sympify(e)) for e in exprs]
    return lambda deg: [f(deg) for f in fns]


def _prod(it):
    out = QF(1)
    for x in it:
        out = out * x
    return out
