"""The `garant` command: the argument parser, `verify`, `check-certificate`, and one-line errors."""
import argparse
import sys
import time
import warnings

from . import checks, cli_stand, cli_workflow, models, norm_checks, recordings, redundancy_checks, report
from .data import DataError
from .lp import LPFailed

G_DEFAULT = 9.81  # m/s^2


def cmd_verify(args):
    groups = (checks.all_groups(models.load("two-axis"), models.load_remount("two-axis"))
              + norm_checks.all_groups(models.load("norm")) + redundancy_checks.all_groups()
              + [(checks.certificates, (args.certificates,))])
    rows = []
    for group, group_args in groups:
        t0 = time.perf_counter()
        got = list(group(*group_args))
        rows += got
        print(f"[{group.__module__.rsplit('.', 1)[-1]}.{group.__name__}] {len(got)} checks in "
              f"{time.perf_counter() - t0:.2f} s", file=sys.stderr)
    report.table(("check", "source", "expected", "got", "pass"),
                 [(r.name, r.source, r.expected, r.got, "PASS" if r.passed else "FAIL") for r in rows])
    failed = [r for r in rows if not r.passed]
    print(f"\n{len(rows) - len(failed)} passed, {len(failed)} failed")
    if args.json:
        report.write_json(args.json, {"checks": [
            {"name": r.name, "source": r.source, "expected": r.expected, "got": r.got,
             "passed": bool(r.passed)} for r in rows]})
    return 1 if failed else 0


def cmd_check_certificate(args):
    from . import certificate
    try:
        cert = certificate.read(args.file)
    except (OSError, ValueError) as e:
        raise DataError(f"{args.file}: cannot read a certificate ({e})") from None
    try:
        steps = certificate.check(cert)
    except (KeyError, TypeError, IndexError, SyntaxError) as e:
        raise DataError(f"{args.file}: malformed certificate ({type(e).__name__}: {e})") from None
    print(f"{cert.get('claim', '?')} ({cert.get('model', '?')}), value {cert.get('value', '?')}")
    for step, ok, detail in steps:
        print(f"  {'PASS' if ok else 'FAIL'} {step}: {detail}")
    ok = all(ok for _, ok, _ in steps)
    print("certificate holds" if ok else "certificate REJECTED")
    return 0 if ok else 1


def parser():
    ap = argparse.ArgumentParser(prog="garant", description="Guaranteed calibration of accelerometer blocks.")
    sub = ap.add_subparsers(dest="command", required=True)
    v = sub.add_parser("verify", help="run every check of the built-in models against the papers")
    v.add_argument("--json", metavar="FILE", help="also write the checks as JSON")
    v.add_argument("--certificates", metavar="DIR", help="write every optimality certificate (JSON) here")
    v.set_defaults(run=cmd_verify)
    p = sub.add_parser("plan", help="optimal guaranteed errors and optimal plans of a model")
    p.add_argument("model", help=f"a built-in stand ({', '.join(models.STANDS)}) or a STAND.toml")
    p.add_argument("--json", metavar="FILE")
    p.set_defaults(run=cli_stand.cmd_plan)
    e = sub.add_parser("estimate", help="estimate q with guaranteed bounds from readings at positions")
    e.add_argument("data", metavar="DATA.csv", help="CSV: <angle>_deg for each angle (alpha_deg,beta_deg on the "
                   "two-axis stand), f1,f2,f3 in m/s^2, and mount when the stand uses several mountings")
    e.add_argument("--model", required=True, help=f"a built-in stand ({', '.join(models.STANDS)}) or a STAND.toml")
    e.add_argument("--sigma", type=float, required=True,
                   help="bound on each residual component, dimensionless (units of g), (5) of 000")
    e.add_argument("--g", type=float, default=G_DEFAULT, help="model gravity, m/s^2 (default 9.81)")
    e.add_argument("--mount", metavar="Q", help="mounting of the block, e.g. +y+z+x (block axis 1 along "
                   "table +y, ...): also report the block's physical errors, (28)-(29) of 000")
    e.add_argument("--gamma", choices=("lower", "symmetric"), default="lower",
                   help="convention that splits Gamma + hat(theta_k) (default lower-triangular Gamma)")
    e.add_argument("--json", metavar="FILE")
    e.set_defaults(run=cli_stand.cmd_estimate)
    c = sub.add_parser("calibrate-norm", help="calibrate a real static log through the norm relation of 001")
    c.add_argument("log", metavar="LOG")
    c.add_argument("--format", choices=recordings.FORMATS, help="log format (guessed when omitted)")
    c.add_argument("--sensor", choices=sorted(recordings.SENSORS), default="adxl355",
                   help="accelerometer of an OpenAXES log")
    c.add_argument("--g", type=float, default=G_DEFAULT, help="local gravity, m/s^2 (default 9.81)")
    c.add_argument("--params", type=int, choices=(9, 12), default=9,
                   help="9: scale, misalignment, bias; 12: also the nonlinearity (pendulosity) of 001")
    c.add_argument("--window", type=float, default=1.0, help="moving-variance window, s")
    c.add_argument("--k", type=float, default=10.0, help="still when the moving variance < k x the initial one")
    c.add_argument("--min-still", type=float, default=2.0, help="shortest still interval kept, s")
    c.add_argument("--delta-sigma", type=float, metavar="D",
                   help="bound on |delta_sigma| of (2.2) (units of g) for the guaranteed errors; "
                   "default: the minimax residual of the fit, the smallest bound the data allow")
    c.add_argument("--diagnose", action="store_true",
                   help="test the model against each interval's noise and try the effect catalogue")
    c.add_argument("--json", metavar="FILE")
    c.add_argument("--plot", metavar="FILE.png", help="residual per interval, before and after")
    c.set_defaults(run=cli_workflow.cmd_calibrate_norm)
    i = sub.add_parser("identify", help="estimable combinations, confounded parameters, a plan's blind spots")
    i.add_argument("model", choices=("two-axis", "003-example1", "003-example2"))
    i.add_argument("--plan", metavar="FILE", help="CSV with alpha_deg, beta_deg: what this plan cannot separate")
    i.add_argument("--json", metavar="FILE")
    i.set_defaults(run=cli_stand.cmd_identify)
    dv = sub.add_parser("derive", help="derive a stand description: generated module and derivation report")
    dv.add_argument("stand", metavar="STAND.toml")
    dv.add_argument("--out", default=".", help="directory for the module and report (default: here)")
    dv.set_defaults(run=cli_stand.cmd_derive)
    sm = sub.add_parser("simulate", help="readings from the exact model with hidden effects (for testing)")
    sm.add_argument("--model", required=True)
    sm.add_argument("--plan", required=True, help="optimal10, quarter16 or grid:AxB (alpha, beta steps in degrees)")
    sm.add_argument("--effect", action="append", default=[], metavar="NAME=v1,v2,...",
                    help="a catalogue effect and its parameter values (repeatable)")
    sm.add_argument("--sigma", type=float, required=True, help="noise bound, units of g")
    sm.add_argument("--seed", type=int, default=0)
    sm.add_argument("--g", type=float, default=G_DEFAULT)
    sm.add_argument("--size", type=float, default=1e-4, help="bound of the random stand and block errors")
    sm.add_argument("-o", "--output", required=True, metavar="DATA.csv")
    sm.set_defaults(run=cli_workflow.cmd_simulate)
    dg = sub.add_parser("diagnose", help="find the effect missing from the model, add it, show the gap shrink")
    dg.add_argument("data", metavar="DATA.csv", help="as for estimate; optional columns time_s, temp_c")
    dg.add_argument("--model", required=True)
    dg.add_argument("--sigma", type=float, required=True, help="noise bound, units of g")
    dg.add_argument("--g", type=float, default=G_DEFAULT)
    dg.add_argument("--prior", type=float, default=1e-3,
                    help="size of the stand and block errors, for the linearisation remainder")
    dg.add_argument("--json", metavar="FILE")
    dg.add_argument("--plot", metavar="FILE.png")
    dg.add_argument("--report", metavar="DIR", help="write the extended model's module and report here")
    dg.set_defaults(run=cli_workflow.cmd_diagnose)
    cc = sub.add_parser("check-certificate", help="re-check an optimality certificate, independently of any solver")
    cc.add_argument("file", metavar="FILE.json")
    cc.set_defaults(run=cmd_check_certificate)
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
