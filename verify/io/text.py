"""Numbers to CSV text fast: whole columns formatted at once with numpy, not one Python string per value.

`garant apply` writes seven numbers per sample; at 1e7 samples formatting them one by one ("%.10g")
took most of its 38 s and 4 GB. Here each column becomes a fixed-width block of bytes (sign, digits in
groups of four looked up in a table, exponent) by integer arithmetic on whole arrays, and a chunk of
rows is written in one call: "+9.8100000e+00,-1.2345678e-03". A column marked `up` is rounded towards
+infinity, so a printed bound is never below the computed one (rounding to nearest could lower it by
half a unit in the last digit).
"""
import numpy as np

#: "0000" .. "9999" as bytes, one row per place: the digits of a group of four.
_GROUPS_T = np.ascontiguousarray(
    np.frombuffer("".join(f"{i:04d}" for i in range(10_000)).encode(), np.uint8).reshape(10_000, 4).T)


def _decimal(a, mode, digits):
    """Mantissa (int64 of `digits` digits, or 0) and exponent of nonnegative finite `a` between 1e-290 and
    1e290 (or 0), so that m * 10**(e - digits + 1) is `a` rounded to `digits` significant digits: to
    nearest, or in magnitude "up" or "down"."""
    zero = a == 0
    a = np.where(zero, 1.0, a)
    e = np.floor(np.log10(a)).astype(np.int64)
    scaled = a * 10.0 ** (digits - 1 - e)
    fix = (scaled >= 10 ** digits).astype(np.int64) - (scaled < 10 ** (digits - 1))
    if fix.any():                               # log10 can be one off next to a power of ten: one step
        e += fix                                # (a value that rounds to 10**digits is handled below)
        scaled = a * 10.0 ** (digits - 1 - e)
    # the scaling is correct to a few units in the last place: a directed rounding that the widening by
    # 1e-15 could change is decided exactly (rational arithmetic, the few values next to a whole number)
    if mode == "nearest":
        m = np.rint(scaled)
    else:
        r = np.ceil if mode == "up" else np.floor
        m, other = r(scaled * (1 - 1e-15)), r(scaled * (1 + 1e-15))
        for i in np.flatnonzero((m != other) & ~zero):
            m[i] = _directed(a[i], int(digits - 1 - e[i]), mode)
    over = m >= 10 ** digits                    # 9.9999999996 rounded: one digit more
    if over.any():
        m[over] = {"up": np.ceil, "down": np.floor, "nearest": np.rint}[mode](m[over] / 10)
        e += over
    under = m < 10 ** (digits - 1)              # rounded down below the first digit: one digit less
    if under.any():
        m[under], e[under] = 10 ** digits - 1, e[under] - 1
    m[zero] = 0
    return m.astype(np.int64), e


def _directed(a, shift, mode):
    """a * 10**shift rounded up or down, exactly."""
    import math
    from fractions import Fraction
    v = Fraction(a) * Fraction(10) ** shift
    return float(math.ceil(v) if mode == "up" else math.floor(v))


def _exact(x, up, digits):
    """Mantissa and exponent of one value by exact decimal arithmetic (the rare extremes)."""
    import decimal
    ctx = decimal.Context(prec=digits, rounding=decimal.ROUND_CEILING if up else decimal.ROUND_HALF_EVEN,
                          Emin=-999, Emax=999)
    sign, ds, exp = ctx.plus(decimal.Decimal(float(x))).as_tuple()
    m = int("".join(map(str, ds)))
    m, exp = m * 10 ** (digits - len(ds)), exp - (digits - len(ds))
    return m, exp + digits - 1


def column_bytes(x, up=False, digits=8):
    """(N,) bytes of width digits + 6 (+ 1 when some value needs a three-digit exponent): each value of
    finite float array `x` as fixed-width text, its sign always written ("+9.8100000e+00" for digits = 8);
    rounded to nearest, or towards +infinity when `up`. `digits` is a multiple of 4. Built one character
    place at a time over all values (contiguous rows), then turned into one string per value."""
    assert digits % 4 == 0
    x = np.asarray(x, float)
    a = np.abs(x)
    extreme = (a > 1e290) | ((a < 1e-290) & (a > 0))
    a = np.where(extreme, 1.0, a)
    if up:                                      # towards +infinity: up in magnitude, down below zero
        m, e = _decimal(a, "up", digits)
        neg = x < 0
        if neg.any():
            m[neg], e[neg] = _decimal(a[neg], "down", digits)
    else:
        m, e = _decimal(a, "nearest", digits)
    for i in np.flatnonzero(extreme):
        m[i], e[i] = _exact(x[i], up, digits)
    e[m == 0] = 0
    wide = bool(np.any(np.abs(e) >= 100))
    out = np.empty((digits + 6 + wide, len(x)), np.uint8)
    out[0] = np.where(np.signbit(x) & (m > 0), ord("-"), ord("+"))
    for k in range(digits // 4 - 1, 0, -1):     # groups of four, last first; '.' after the first digit
        m, r = np.divmod(m, 10_000)
        out[4 * k + 2:4 * k + 6] = _GROUPS_T[:, r]
    first = _GROUPS_T[:, m]
    out[1] = first[0]
    out[2] = ord(".")
    out[3:6] = first[1:]
    out[digits + 2] = ord("e")
    out[digits + 3] = np.where(e < 0, ord("-"), ord("+"))
    out[digits + 4:] = _GROUPS_T[2 - wide:, np.abs(e)]
    return np.ascontiguousarray(out.T).view(f"S{out.shape[0]}").ravel()


def csv_bytes(columns, up=(), digits=8):
    """The rows of equal-length float `columns` as CSV bytes (newline line ends); the columns whose index is in
    `up` rounded towards +infinity; `digits`: significant digits (a multiple of 4), one for all or one per
    column."""
    digits = list(digits) if np.ndim(digits) else [digits] * len(columns)
    texts = [column_bytes(col, up=j in up, digits=digits[j]) for j, col in enumerate(columns)]
    fields = []
    for j, t in enumerate(texts):
        fields += [(f"v{j}", t.dtype), (f"s{j}", "S1")]
    out = np.empty(len(texts[0]), fields)
    for j, t in enumerate(texts):
        out[f"v{j}"] = t
        out[f"s{j}"] = b"," if j < len(texts) - 1 else b"\n"
    return out.tobytes()
