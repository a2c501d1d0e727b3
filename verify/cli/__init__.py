"""The `garant` command: one module per subcommand (`add` its arguments, `run` it), one-line errors.

A command module imports what its work needs inside `run`, so `garant --help` and a light command do
not pay for SymPy, cvxpy or matplotlib.
"""
import argparse
import sys
import warnings

from ..errors import DataError, LPFailed
from . import (calibrate_norm, check_certificate, derive, diagnose, estimate, identify, plan, simulate,
               verify)

COMMANDS = (verify, plan, estimate, calibrate_norm, identify, derive, simulate, diagnose, check_certificate)


def parser():
    ap = argparse.ArgumentParser(prog="garant", description="Guaranteed calibration of accelerometer blocks.")
    sub = ap.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.add(sub).set_defaults(run=command.run)
    return ap


def main(argv=None):
    args = parser().parse_args(argv)
    warnings.filterwarnings("ignore", category=RuntimeWarning, module="cvxpy")
    try:
        return args.run(args)
    except (DataError, LPFailed, ValueError) as e:
        print(f"garant: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"garant: error: {e.filename or ''}: {e.strerror}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
