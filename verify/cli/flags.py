"""Arguments several commands share, stated once with their units."""
from .. import options
from ..models import STANDS
from ..defaults import G_DEFAULT

#: The argparse types of the shared checks (verify/options.py: the API checks its arguments with the same).
positive, small, noise, positive_int, count, seed, gravity, rate = (
    options.argtype(k) for k in (options.positive, options.small, options.noise, options.positive_int, options.count,
                                options.seed, options.gravity, options.rate))


def temperatures(text):
    """T1,T2,...: two to twenty distinct temperatures within +-200 C."""
    import argparse
    import math
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text[:60]!r}: give temperatures in C, e.g. -20,0,20,40,60") from None
    if not (2 <= len(values) <= 20 and len(set(values)) == len(values)
            and all(math.isfinite(v) and abs(v) <= 200 for v in values)):
        raise argparse.ArgumentTypeError(f"{text[:60]!r}: two to twenty distinct temperatures within +-200 C")
    return values


def log_format(p, extra=(), more=""):
    """--format of a command that reads logs: one of defaults.FORMATS (and `extra`), listed in the help."""
    from ..defaults import FORMATS
    p.add_argument("--format", choices=FORMATS + tuple(extra), metavar="FORMAT",
                   help=f"log format, one of {', '.join(FORMATS + tuple(extra))} (guessed when omitted){more}")


def sensor(p, default=None):
    """--sensor: the accelerometer of an OpenAXES log, in any case (options.sensor: the API's check)."""
    from ..defaults import SENSORS
    p.add_argument("--sensor", type=options.argtype(options.sensor), default=default,
                   metavar="{" + ",".join(sorted(SENSORS)) + "}",
                   help="accelerometer of an OpenAXES log (default adxl355)")


def model(p):
    """--model: a built-in stand or a STAND.toml (every command that takes a model spells it so)."""
    p.add_argument("--model", required=True, help=f"a built-in stand ({', '.join(STANDS)}) or a STAND.toml")


def sigma(p, help_="bound on each residual component, dimensionless (units of g), (5) of 000"):
    """--sigma: the noise bound (5) of 000, dimensionless (units of g)."""
    p.add_argument("--sigma", type=noise, required=True, help=help_)


def g(p, help_="model gravity, m/s^2 (default 9.81)", default=G_DEFAULT):
    """--g; with default None the command knows whether g was given (its uncertainty depends on it)."""
    p.add_argument("--g", type=gravity, default=default, help=help_)


def json(p):
    """--json FILE: the result as JSON too."""
    p.add_argument("--json", metavar="FILE", help="also write the result as JSON")


def units(p):
    """--units si|human: human also prints ppm, mrad/urad and mg/ug beside SI."""
    p.add_argument("--units", choices=("si", "human"), default="si",
                   help="human: also print scale factors and misalignments in ppm, angles in mrad or urad, biases "
                        "in mg or ug (beside SI)")


def premises(p):
    """The a-priori bounds a guaranteed bound assumes (verify/workflows/premises.py)."""
    p.add_argument("--g-uncertainty", type=small, metavar="REL",
                   help="relative uncertainty of g, the bound on Delta_g/g (default 1e-5 with a local --g, "
                        "5e-3 without: 9.81 m/s^2 is off by up to 3e-3 at sea level)")
    p.add_argument("--bound", action="append", type=named_bound, metavar="NAME=VALUE", default=[],
                   help="the a-priori bound of one parameter (rad, or dimensionless), over the description's and "
                        "--prior; repeatable, e.g. --bound kappa=3e-4")
    p.add_argument("--prior", type=small,
                   help="override: one a-priori bound for every stand, mounting and block error (rad, or "
                        "dimensionless); default: each parameter's bound from the stand description, else "
                        "the default of its kind (stand 1e-3, mounting 1e-2, block 0.1)")


def named_bound(text):
    """An argparse type: NAME=VALUE, a parameter's name and its a-priori bound (a small error)."""
    import argparse
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"{text[:40]!r}: give NAME=VALUE, e.g. kappa=3e-4")
    return name.strip(), small(value)


def say_gravity(g_given, premises):
    """The gravity line (workflows/premises.gravity_line) on a line of its own, when --g was not given."""
    from ..workflows.premises import gravity_line
    line = gravity_line(g_given, premises["g_uncertainty"], premises["g_source"])
    if line:
        print(line)
