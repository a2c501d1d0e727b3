"""Every option's check, stated once: the command's argparse type and the API's argument check call the
same function, so the API accepts exactly what the command accepts.

A check takes the command's text or the API's value and returns the value, or raises Bad with the reason
(without the option's name: argparse and `check` put it in front)."""
import math
import numbers

from .errors import DataError


class Bad(ValueError):
    """A value an option does not take; the message says why."""


def _number(value):
    """A float from the command's text or the API's real number (not text, not bool, not complex)."""
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            raise Bad(f"{value[:40]!r} is not a number") from None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise Bad(f"must be a real number, not {type(value).__name__} {_shown(value)}")
    try:
        return float(value)
    except OverflowError:                         # a Python int beyond any float (10**400)
        raise Bad(f"{_shown(value)} is too large for a number") from None


def _shown(value):
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def positive(value):
    """A finite number > 0 (nan, inf, 0 and negatives refused)."""
    v = _number(value)
    if not math.isfinite(v) or v <= 0:
        raise Bad(f"{_shown(value)} must be a finite number > 0")
    return v


def small(value):
    """A bound of a small error, a finite number > 0 and < 1 (rad, dimensionless, units of g, or m/s^2 for a
    count): a bound of 1 or more is no premise the linearised model can use."""
    v = positive(value)
    if v >= 1:
        raise Bad(f"{_shown(value)} must be < 1 (the bound of a small error)")
    return v


#: The smallest noise bound taken (units of g): readings of about 10 m/s^2 in double precision resolve
#: about 2e-16 of g, and the model's own evaluation rounds to some 1e-15; a bound under 1e-12 asks the
#: arithmetic for more than it holds.
SIGMA_MIN = 1e-12


def noise(value):
    """The noise bound (5) of 000, units of g: at least SIGMA_MIN and < 1."""
    v = small(value)
    if v < SIGMA_MIN:
        raise Bad(f"{_shown(value)} must be at least {SIGMA_MIN:g} (units of g): double-precision readings do not "
                  "resolve a smaller bound")
    return v


def whole(value, least=1):
    """A whole number >= `least`: the command's decimal digits (at most 18), or the API's int."""
    if isinstance(value, str):
        if not value.isdigit() or len(value) > 18 or int(value) < least:
            raise Bad(f"{value[:40]!r} must be a whole number >= {least} (at most 18 digits)")
        return int(value)
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not least <= value < 10 ** 18:
        raise Bad(f"{_shown(value)} must be a whole number >= {least} (at most 18 digits)")
    return int(value)


def positive_int(value):
    """A whole number >= 1."""
    return whole(value, 1)


def count(value):
    """A whole number >= 0 (a budget that may be none at all)."""
    return whole(value, 0)


def degree(value):
    """A degree in T of the thermal model: a whole number 1 to 3."""
    d = whole(value, 1)
    if d > 3:
        raise Bad(f"{_shown(value)} is not 1, 2 or 3")
    return d


def seed(value):
    """A random seed, a whole number >= 0."""
    return whole(value, 0)


def gravity(value):
    """Gravity in m/s^2, between 0.1 and 100 (9.78-9.83 on the Earth's surface; 1 for readings in units
    of g)."""
    v = positive(value)
    if not 0.1 <= v <= 100:
        raise Bad(f"{_shown(value)} must be a gravity in m/s^2 between 0.1 and 100 (9.78 to 9.83 on the Earth's "
                  "surface; 1 for readings in units of g)")
    return v


def rate(value):
    """A sample rate in Hz, between 0.01 and 1e6."""
    v = positive(value)
    if not 0.01 <= v <= 1e6:
        raise Bad(f"{_shown(value)} must be a sample rate in Hz between 0.01 and 1e6")
    return v


def one_of(*choices):
    """A check that takes one of `choices` (the API's form of argparse's choices)."""
    def choice(value):
        if value not in choices:
            raise Bad(f"{_shown(value)} is not one of {', '.join(map(str, choices))}")
        return value
    choice.takes_text = True
    return choice


def sensor(value):
    """A sensor of the log readers (defaults.SENSORS) in any case, as the command's --sensor takes it: BMI160 is
    bmi160."""
    from .defaults import SENSORS
    if isinstance(value, str) and value.lower() in SENSORS:
        return value.lower()
    raise Bad(f"{_shown(value)} is not one of {', '.join(sorted(SENSORS))} (any case)")


sensor.takes_text = True


def text(value):
    """A short piece of text (a run's name, a mounting such as +y+z+x)."""
    if not isinstance(value, str) or len(value) > 200:
        raise Bad(f"{_shown(value)} must be text of at most 200 characters")
    return value


text.takes_text = True


def model(value):
    """A model: a built-in name or a path (text or os.PathLike), not a list or a number."""
    import os
    if isinstance(value, os.PathLike):
        return value
    if not isinstance(value, str) or not value or len(value) > 4096:
        raise Bad(f"{_shown(value)} must be a model's name (e.g. 'two-axis') or a STAND.toml path")
    return value


model.takes_text = True


def path(value):
    """A file's path: text or os.PathLike (a dictionary or a number is no file)."""
    import os
    if not isinstance(value, (str, os.PathLike)) or isinstance(value, str) and not value:
        raise Bad(f"{_shown(value)} must be a file's path")
    return value


path.takes_text = True


def callback(value):
    """A function that hears a line of progress (or None)."""
    if not callable(value):
        raise Bad(f"{_shown(value)} must be a function taking one line of text")
    return value


callback.takes_text = True


def flag(value):
    """True or False."""
    if not isinstance(value, bool):
        raise Bad(f"{_shown(value)} must be True or False")
    return value


def real_array(value, what, copy=True):
    """An array of real numbers as floats (the API's data): complex numbers, text and objects refused,
    never converted with a part dropped. copy=False: the caller's own float array where it is one (read only)."""
    import numpy as np
    param = what.split(":")[0].strip()           # the argument's own name; the column stays in the message
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError, OverflowError):
        raise DataError(f"{what}: expected an array of numbers", param=param) from None
    if arr.dtype.kind == "c":
        raise DataError(f"{what}: complex numbers are not readings; give real numbers", param=param)
    if arr.dtype.kind not in "iuf":
        if arr.dtype.kind == "b" or any(isinstance(v, (str, bytes, bool, complex)) for v in arr.ravel()[:10 ** 6]):
            raise DataError(f"{what}: every value must be a real number (a text or a truth value found)", param=param)
        try:
            arr = arr.astype(float)
        except (TypeError, ValueError, OverflowError):      # a Python int beyond any float (10**400)
            raise DataError(f"{what}: every value must be a real number of double range", param=param) from None
    return arr.astype(float, copy=copy)


def bounds(value):
    """A-priori bounds by parameter name ({"kappa": 3e-4}): each a small error (the --bound NAME=VALUE)."""
    if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
        raise Bad(f"{_shown(value)} must be a dictionary of parameter names and bounds, e.g. {{'kappa': 3e-4}}")
    try:
        return {k: small(v) for k, v in value.items()}
    except Bad as e:
        raise Bad(f"a bound {e}") from None


def by_the_job(where):
    """The rule of a parameter the job reads and refuses in one line itself (a file or data of many shapes, effect
    names): `where` says which function does. The value passes the API's check unchanged."""
    def rule(value):
        return value
    rule.takes_text, rule.where = True, where
    return rule


def imu(value):
    """An IMU's number (a whole number >= 1), or "all" (every IMU of a stream)."""
    return value if value == "all" else positive_int(value)


imu.takes_text = True


def constraints(**rules):
    """Each parameter's check declared beside the function (as scikit-learn's `validate_params`): {name: a check
    above, or by_the_job(where)}. A function with a parameter left undeclared is refused as it is defined, so a
    new argument cannot go unchecked; the API (verify/api.py) applies the rules."""
    import inspect

    def mark(fn):
        names = list(inspect.signature(fn).parameters)
        missing, extra = [n for n in names if n not in rules], [n for n in rules if n not in names]
        if missing or extra:
            raise TypeError(f"{fn.__name__}: no constraint declared for {', '.join(missing) or '-'}; "
                            f"constraints of no parameter: {', '.join(extra) or '-'}")
        fn.constraints = dict(rules)
        return fn
    return mark


def check(name, value, kind):
    """The API's check of argument `name`: `kind` (one of the checks above) or DataError naming it; None
    passes (the default)."""
    if value is None:
        return None
    if isinstance(value, str) and not getattr(kind, "takes_text", False):
        raise DataError(f"{name}: must be {'True or False' if kind is flag else 'a number'}, not the text "
                        f"{_shown(value)}", param=name)
    try:
        return kind(value)
    except Bad as e:
        raise DataError(f"{name}: {e}", param=name) from None


def argtype(kind):
    """The argparse type of a check: its reason becomes argparse's one-line error."""
    import argparse

    def parse(text):
        try:
            return kind(text)
        except Bad as e:
            raise argparse.ArgumentTypeError(str(e)) from None
    parse.__name__ = kind.__name__
    return parse
