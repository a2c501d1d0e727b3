"""garant identify: what a model can estimate, what it confounds, and what a plan cannot separate."""
from ..outcomes import Exit
from ..models import STANDS
from . import flags


def add(sub):
    """The `garant identify` subcommand and its flags."""
    p = sub.add_parser("identify", help="estimable combinations, confounded parameters, a plan's blind spots")
    p.add_argument("--model", required=True,
                   help=f"a built-in stand ({', '.join(STANDS)}), a STAND.toml, or 003-example1 / 003-example2")
    p.add_argument("--plan", metavar="FILE", help="CSV with <angle>_deg columns (and mount): what this plan "
                   "cannot separate")
    flags.json(p)
    return p


def run(args):
    """`garant identify`: parse, call the job, print; the exit status."""
    from ..io import report
    from ..workflows import identify
    res = identify.report(args.model, args.plan)
    _print(res)
    if args.json:
        report.write_json(args.json, res)
    return Exit.OK


def _print(res):
    """What the model can estimate, what it confounds, and what the plan cannot separate."""
    print(f"model: {res['model']}" + (f" ({res['title']})" if "title" in res else ""))
    if "V" in res:
        print(f"constraint residual V = {res['V']}")
        print("basis functions (003, (9)): " + "; ".join(res["basis_functions"]))
    if "estimable" in res:
        print("estimable combinations, (4) of 000:")
        for e in res["estimable"]:
            print(f"  {e}")
    print("identical relations among the basis functions (directions no data can see):")
    for r in res["relations"] or ["none: every parameter is estimable for generic data"]:
        print(f"  {r}")
    print("confounded groups: " + ("; ".join("{" + ", ".join(g) + "}" for g in res["confounded_groups"])
                                   or "none"))
    for d in res.get("degenerate_trajectories", []):
        print(f"degenerate on trajectories with {d['trajectory']}: " + "; ".join(d["relations"]))
    if "plan" in res:
        p = res["plan"]
        print(f"plan {p['path']}: " + ("identifies every q" if not p["not_identifiable"] else
                                      "cannot identify " + "; ".join(p["not_identifiable"])))
        for b in p["invisible_combinations"]:
            print(f"  invisible: {b}")
