"""garant identify: what a model can estimate, what it confounds, and what a plan cannot separate."""
from . import args as a


def add(sub):
    p = sub.add_parser("identify", help="estimable combinations, confounded parameters, a plan's blind spots")
    p.add_argument("model", help="a built-in stand (two-axis, single-axis, three-axis), a STAND.toml, or "
                   "003-example1 / 003-example2")
    p.add_argument("--plan", metavar="FILE", help="CSV with <angle>_deg columns (and mount): what this plan "
                   "cannot separate")
    a.json(p)
    return p


def run(args):
    from ..io import report
    from ..workflows import identify
    res = identify.report(args.model, args.plan)
    identify.print_report(res)
    if args.json:
        report.write_json(args.json, res)
    return 0
