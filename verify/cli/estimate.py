"""garant estimate: q with guaranteed error bounds from readings at any positions ((6)-(8) of 000)."""
from ..errors import DataError
from . import args as a


def add(sub):
    p = sub.add_parser("estimate", help="estimate q with guaranteed bounds from readings at positions")
    p.add_argument("data", metavar="DATA.csv", help="CSV: <angle>_deg for each angle (alpha_deg,beta_deg on the "
                   "two-axis stand), f1,f2,f3 in m/s^2, and mount when the stand uses several mountings")
    a.model(p)
    a.sigma(p)
    a.g(p)
    p.add_argument("--mount", metavar="Q", help="mounting of the block, e.g. +y+z+x (block axis 1 along "
                   "table +y, ...): also report the block's physical errors, (28)-(29) of 000")
    p.add_argument("--gamma", choices=("lower", "symmetric"), default="lower",
                   help="convention that splits Gamma + hat(theta_k) (default lower-triangular Gamma)")
    a.json(p)
    return p


def run(args):
    from .. import models
    from ..io import report
    from ..io.positions import read_positions
    from ..workflows.estimate import estimate
    mod = models.load(args.model)
    remount = None if args.model.endswith(".toml") else models.load_remount(args.model)
    if args.mount and (remount is None or args.mount not in remount.MOUNTS):
        raise DataError(f"--mount needs a model with the remount formulas (two-axis) and a mounting like "
                        f"+y+z+x; got {args.mount!r}")
    names, mounts = models.layout(mod)
    res = estimate(mod, read_positions(args.data, names, mounts), args.sigma, args.g,
                   remount=remount, mount=args.mount, gamma=args.gamma)
    print(f"method: {res['method']}")
    report.table(("q", "definition", "estimate", "guaranteed error", "unit"),
                 [(q, res["definitions"][q], f"{res['q'][q]:+.6e}", f"{res['guaranteed_error'][q]:.3e}",
                   res["units"][q]) for q in mod.Q_NAMES])
    print(f"\n{res['positions']} positions ({res['distinct_positions']} distinct), g = {args.g} m/s^2, "
          f"sigma = {args.sigma:g} (dimensionless, units of g)")
    print(f"max |residual| after the fit: {res['residual_max']:.3e} ({res['residual_max'] / args.sigma:.2f} sigma)")
    if args.mount:
        print_physical(res)
    if args.json:
        report.write_json(args.json, res)
    return 0


def print_physical(res):
    from ..io import report
    phys, bound = res["physical"], res["physical_bound"]
    rows = [(k, f"{phys[k]:+.6e}", f"{bound[k]:.3e}", "rad") for k in ("kappa", "dalpha_plus_astar", "epsilon")]
    rows += [(f"bias{i + 1}", f"{phys['bias'][i]:+.6e}", f"{bound['bias'][i]:.3e}", "m/s^2") for i in range(3)]
    rows += [(f"Gamma{i + 1}{j + 1}", f"{phys['Gamma'][i][j]:+.6e}", f"{bound['Gamma'][i][j]:.3e}", "1")
             for i in range(3) for j in range(3)]
    rows += [(f"theta_k{i + 1}", f"{phys['theta_k'][i]:+.6e}", f"{bound['theta_k'][i]:.3e}", "rad") for i in range(3)]
    print(f"\nblock errors in block axes, mounting {res['mount']}, Gamma {res['gamma']} (29) of 000:")
    report.table(("parameter", "estimate", "guaranteed error", "unit"), rows)
    print(res["physical_note"])
