"""The trusted base of every proof: interval arithmetic (verify/solve/interval.py), interval jets
(verify/solve/taylor.py) and the number field Q(sqrt2, sqrt3) (verify/solve/field.py), each checked
against mpmath at 60 digits on values hypothesis draws.

An enclosure must hold the exact result of the real operation on the exact binary values: point
intervals are the sharpest test, since without outward rounding a sum or product of two doubles
misses its exact value about half the time (dropping `_out` from interval.py turns these red).
"""
from fractions import Fraction

import mpmath
import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

from garant.verify.solve import field
from garant.verify.solve.interval import Iv, box_variables, mean_value_enclosure
from garant.verify.solve.taylor import Jet2

mpmath.mp.dps = 60
VALUES = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_subnormal=False)
SMALL = st.floats(min_value=-4.0, max_value=4.0, allow_nan=False, allow_subnormal=False)
FRACTION = st.floats(min_value=0.0, max_value=1.0)


def inside(iv, exact):
    """Whether the exact value (mpf) lies in the interval (a scalar Iv), compared exactly."""
    return mpmath.mpf(float(iv.lo)) <= exact <= mpmath.mpf(float(iv.hi))


def interval(a, b):
    return Iv(min(a, b), max(a, b))


def point_in(iv, t):
    """A double inside the interval, a fraction t of the way."""
    return float(np.clip(float(iv.lo) + t * (float(iv.hi) - float(iv.lo)), iv.lo, iv.hi))


@settings(max_examples=400, deadline=None)
@given(VALUES, VALUES, VALUES, VALUES, FRACTION, FRACTION)
def test_interval_operations_hold_the_exact_result(a, b, c, d, s, t):
    X, Y = interval(a, b), interval(c, d)
    x, y = point_in(X, s), point_in(Y, t)
    mx, my = mpmath.mpf(x), mpmath.mpf(y)
    assert inside(X + Y, mx + my) and inside(X - Y, mx - my) and inside(X * Y, mx * my)
    assert inside(X.square(), mx * mx) and inside(X * 3.7, mx * mpmath.mpf(3.7))
    if not (float(X.lo) <= 0 <= float(X.hi)):
        assert inside(X.recip(), 1 / mx)
    if float(X.lo) >= 0:
        assert inside(X.sqrt(), mpmath.sqrt(mx))
    assert inside(X.sin(), mpmath.sin(mx)) and inside(X.cos(), mpmath.cos(mx))


@settings(max_examples=400, deadline=None)
@given(VALUES, VALUES)
def test_point_intervals_round_outward(x, y):
    # The sharp case: [x, x] op [y, y] must hold the exact x op y, which a double rarely equals.
    X, Y, mx, my = Iv(x), Iv(y), mpmath.mpf(x), mpmath.mpf(y)
    assert inside(X + Y, mx + my) and inside(X * Y, mx * my) and inside(X - Y, mx - my)
    assert inside(X.sin(), mpmath.sin(mx)) and inside(X.cos(), mpmath.cos(mx))
    if x > 0:
        assert inside(X.sqrt(), mpmath.sqrt(mx)) and inside(X.recip(), 1 / mx)


def f_iv(s, t):
    """A test function written once for Iv, Grad and Jet2: sin(s t) + cos(s) t - s^2."""
    return (s * t).sin() + s.cos() * t - s * s


def f_mp(s, t):
    """The same, its partial derivatives by (order in s, order in t), exactly as formulas (a numerical
    derivative would lose values far below its step)."""
    sin, cos = mpmath.sin, mpmath.cos
    return {(0, 0): sin(s * t) + cos(s) * t - s * s,
            (1, 0): t * cos(s * t) - sin(s) * t - 2 * s,
            (0, 1): s * cos(s * t) + cos(s),
            (2, 0): -t * t * sin(s * t) - cos(s) * t - 2,
            (1, 1): cos(s * t) - s * t * sin(s * t) - sin(s),
            (0, 2): -s * s * sin(s * t)}


@settings(max_examples=200, deadline=None)
@given(SMALL, SMALL, st.floats(0.0, 0.5), st.floats(0.0, 0.5), FRACTION, FRACTION)
def test_gradient_and_mean_value_enclosures_hold_the_exact_ones(s0, t0, ws, wt, a, b):
    lo, hi = [s0, t0], [s0 + ws, t0 + wt]
    g = f_iv(*box_variables([np.array(v) for v in lo], [np.array(v) for v in hi]))
    s, t = point_in(Iv(lo[0], hi[0]), a), point_in(Iv(lo[1], hi[1]), b)
    ms, mt = mpmath.mpf(s), mpmath.mpf(t)
    exact = f_mp(ms, mt)
    assert inside(g.v, exact[0, 0]) and inside(g.d[0], exact[1, 0]) and inside(g.d[1], exact[0, 1])
    mv = mean_value_enclosure(f_iv, np.array(lo[0]), np.array(hi[0]), np.array(lo[1]), np.array(hi[1]))
    assert inside(mv, exact[0, 0])


@settings(max_examples=200, deadline=None)
@given(SMALL, SMALL, st.floats(0.0, 0.5), st.floats(0.0, 0.5), FRACTION, FRACTION)
def test_jets_hold_the_exact_value_gradient_and_hessian(s0, t0, ws, wt, a, b):
    S, T = Jet2.variables([s0, t0], [s0 + ws, t0 + wt], (1,))
    jet = f_iv(S, T)
    s, t = point_in(Iv(s0, s0 + ws), a), point_in(Iv(t0, t0 + wt), b)
    ms, mt = mpmath.mpf(s), mpmath.mpf(t)
    H, exact = jet.hessian(), f_mp(ms, mt)
    assert inside(Iv(jet.v.lo[0], jet.v.hi[0]), exact[0, 0])
    for k, order in enumerate([(1, 0), (0, 1)]):
        assert inside(Iv(jet.g.lo[k, 0], jet.g.hi[k, 0]), exact[order])
    for (k, j), order in {(0, 0): (2, 0), (0, 1): (1, 1), (1, 1): (0, 2)}.items():
        assert inside(Iv(H.lo[k, j, 0], H.hi[k, j, 0]), exact[order])


RATIONAL = st.fractions(min_value=-50, max_value=50, max_denominator=1000)


def qf_mp(x):
    a, b, c, d = (mpmath.mpf(v.numerator) / v.denominator for v in x.c)
    return a + b * mpmath.sqrt(2) + c * mpmath.sqrt(3) + d * mpmath.sqrt(6)


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(st.lists(RATIONAL, min_size=4, max_size=4), st.lists(RATIONAL, min_size=4, max_size=4))
def test_field_arithmetic_is_that_of_the_reals(u, v):
    x, y = field.QF(*u), field.QF(*v)
    mx, my = qf_mp(x), qf_mp(y)
    tol = mpmath.mpf(10) ** -40
    assert abs(qf_mp(x + y) - (mx + my)) < tol and abs(qf_mp(x * y) - mx * my) < tol
    assert x.sign() == (0 if mx == 0 else 1 if mx > 0 else -1)
    assume(not x.is_zero())
    assert x * x.inverse() == 1 and abs(qf_mp(y / x) - my / mx) < tol * (1 + abs(my / mx))


def test_sign_decides_numbers_within_1e_30_of_zero():
    # 1 + sqrt2 - sqrt3 - ... near cancellations: sign must be exact, not a float comparison.
    r2 = Fraction(1414213562373095048801688724209698, 10**33)          # just below sqrt 2
    x = field.QF(-r2, 1, 0, 0)                                         # sqrt2 - r2 > 0, about 8e-34
    assert x.sign() == 1 and float(x) == 0.0
    assert field.QF(r2, -1, 0, 0).sign() == -1


@pytest.mark.parametrize("columns, target, expected", [
    ([[1, 0], [1, 1]], [3, 2], [Fraction(1), Fraction(2)]),
    ([[1, 2], [2, 4]], [1, 2], None),                     # dependent columns
    ([[1, 0, 0], [0, 1, 0]], [0, 0, 1], None),           # target outside the span
])
def test_the_one_exact_solver(columns, target, expected):
    from garant.derive.linear import solve_exact
    assert solve_exact(columns, target) == expected
    sqrt2 = field.QF(0, 1)
    qf = solve_exact([[sqrt2, 0], [0, 1]], [1, 0], field.QF.of)     # sqrt2 x = 1: x = sqrt2 / 2
    assert qf == [field.QF(0, Fraction(1, 2)), field.QF(0)]
