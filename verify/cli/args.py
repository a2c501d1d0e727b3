"""Arguments several commands share, stated once with their units."""
import argparse
import math

from ..models import STANDS

G_DEFAULT = 9.81  # m/s^2


def positive(text):
    """An argparse type: a finite number > 0 (nan, inf, 0 and negatives refused)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be a finite number > 0")
    return value


def model(p, *, positional=False):
    help_ = f"a built-in stand ({', '.join(STANDS)}) or a STAND.toml"
    if positional:
        p.add_argument("model", help=help_)
    else:
        p.add_argument("--model", required=True, help=help_)


def sigma(p, help_="bound on each residual component, dimensionless (units of g), (5) of 000"):
    p.add_argument("--sigma", type=positive, required=True, help=help_)


def g(p, help_="model gravity, m/s^2 (default 9.81)"):
    p.add_argument("--g", type=positive, default=G_DEFAULT, help=help_)


def json(p):
    p.add_argument("--json", metavar="FILE", help="also write the result as JSON")


def prior(p, default=1e-3):
    p.add_argument("--prior", type=positive, default=default,
                   help=f"size of every stand and block error (rad, or dimensionless for Gamma and Delta_g), "
                        f"for the proven linearisation remainder (default {default:g})")
