"""The fast CSV number formatter of `garant apply` (verify/io/text.py): every value read back is the value
rounded to the stated digits, and a column rounded up never prints below the value (checked exactly with
rational arithmetic). Deciding the values next to a whole number without exact arithmetic, or rounding
bounds to nearest, turns the exact checks red."""
import pytest
from fractions import Fraction

import numpy as np
from hypothesis import given, settings, strategies as st

from garant.verify.io.text import csv_bytes

FINITE = st.floats(allow_nan=False, allow_infinity=False)


def _read(data, ncol):
    rows = data.decode().splitlines()
    assert all(r.count(",") == ncol - 1 for r in rows)
    return [[Fraction(v) for v in r.split(",")] for r in rows]


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(st.lists(FINITE, min_size=1, max_size=50), st.sampled_from([4, 8, 12]))
def test_up_never_below_and_nearest_within_half_a_unit(values, digits):
    x = np.array(values)
    rows = _read(csv_bytes([x, x], up=(1,), digits=digits), 2)
    for v, (near, up) in zip(values, rows):
        exact = Fraction(v)
        assert up >= exact                                          # a bound is never printed lower
        if exact:
            unit = Fraction(10) ** (_exponent(exact) - digits + 1)   # one unit in the last printed digit
            assert up - exact < unit and abs(near - exact) <= unit / 2 * (1 + Fraction(1, 10**6))
        else:
            assert near == up == 0


def _exponent(f):
    e = len(str(abs(f.numerator) // abs(f.denominator))) - 1 if abs(f) >= 1 else -1
    while Fraction(10) ** e > abs(f):
        e -= 1
    while Fraction(10) ** (e + 1) <= abs(f):
        e += 1
    return e


def test_known_texts():
    # Hand-written expectations: 9.81 as a float is 9.8100000000000004973..., so upwards it is 9.811e+00 at
    # four digits; the extremes go through exact decimal arithmetic.
    x = np.array([9.81, -0.0018965461377165183, 0.0, 9.99999999996, 5e-324])
    text = csv_bytes([x, x], up=(1,), digits=(8, 4)).decode().splitlines()
    assert text == ["+9.8100000e+000,+9.811e+000", "-1.8965461e-003,-1.896e-003", "+0.0000000e+000,+0.000e+000",
                    "+1.0000000e+001,+1.000e+001", "+4.9406565e-324,+4.941e-324"]
    assert csv_bytes([np.array([9.81])]).decode() == "+9.8100000e+00\n"   # two exponent digits when they suffice


@pytest.mark.slow
def test_next_to_every_power_of_ten():
    # Where log10 is one off and the scaled value lands on 10**digits (1e-12 at 12 digits printed 1e-13
    # before the fix): every power of ten from 1e-300 to 1e299 and its two float neighbours.
    vals = [f(10.0 ** k) for k in range(-300, 300) for f in (lambda v: v, lambda v: np.nextafter(v, 0),
                                                             lambda v: np.nextafter(v, np.inf))]
    x = np.array(vals)
    for digits in (4, 8, 12):
        for v, (near, up) in zip(vals, _read(csv_bytes([x, x], up=(1,), digits=digits), 2)):
            exact = Fraction(v)
            unit = Fraction(10) ** (_exponent(exact) - digits + 1)
            assert up >= exact and up - exact < unit and abs(near - exact) <= unit / 2 * (1 + Fraction(1, 10**6)), v
