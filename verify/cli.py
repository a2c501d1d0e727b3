"""The `garant` command: verify, plan, estimate."""
import argparse
import sys
import time
import warnings

from . import calibrate, checks, estimate as estimate_mod, exact, models, norm_checks, plans, recordings, redundancy_checks, report
from .data import DataError, read_positions
from .lp import LPFailed

G_DEFAULT = 9.81  # m/s^2


def cmd_verify(args):
    groups = (checks.all_groups(models.load("two-axis"), models.load_remount("two-axis"))
              + norm_checks.all_groups(models.load("norm")) + redundancy_checks.all_groups())
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


def cmd_plan(args):
    mod = models.load(args.model)
    m = len(mod.Q_NAMES)
    errors = []
    for nu in range(m):
        e = [int(i == nu) for i in range(m)]
        lower = exact.dual_lower_bound(mod.H_SUP, e, e)
        upper = exact.l1(exact.terms_from_generated(mod, nu))
        errors.append(float(upper) if lower == upper else None)
    r = plans.search(mod.H)
    plan = [[int(a), int(b)] for a, b in mod.PLAN_DEG]
    report.table(("q", "definition", "optimal guaranteed error (sigma)"),
                 [(q, d, "unproven" if e is None else f"{e:g}")
                  for q, d, e in zip(mod.Q_NAMES, mod.Q_DEFINITIONS, errors)])
    print(f"\nminimal number of positions optimal for every q (quarter-turn grid): {r.min_positions}")
    print(f"optimal plans of {r.min_positions} positions on the quarter-turn grid: {len(r.optimal_plans)}")
    print("plan (alpha_deg, beta_deg): " + ", ".join(f"({a}, {b})" for a, b in plan))
    if args.json:
        report.write_json(args.json, {
            "model": args.model, "q_names": list(mod.Q_NAMES), "definitions": list(mod.Q_DEFINITIONS),
            "guaranteed_errors": errors, "min_positions": r.min_positions,
            "optimal_plans_count": len(r.optimal_plans), "plan": plan,
            "optimal_plans": [[list(p) for p in r.plan_deg(pl)] for pl in r.optimal_plans]})
    return 0


def cmd_estimate(args):
    mod = models.load(args.model)
    remount = models.load_remount(args.model)
    if args.mount and args.mount not in remount.MOUNTS:
        raise DataError(f"unknown mounting {args.mount!r}; use one of {', '.join(remount.MOUNTS)}")
    res = estimate_mod.estimate(mod, read_positions(args.data), args.sigma, args.g, remount=remount,
                                mount=args.mount, gamma=args.gamma)
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
    phys, bound = res["physical"], res["physical_bound"]
    rows = [(k, f"{phys[k]:+.6e}", f"{bound[k]:.3e}", "rad") for k in ("kappa", "dalpha_plus_astar", "epsilon")]
    rows += [(f"bias{i + 1}", f"{phys['bias'][i]:+.6e}", f"{bound['bias'][i]:.3e}", "m/s^2") for i in range(3)]
    rows += [(f"Gamma{i + 1}{j + 1}", f"{phys['Gamma'][i][j]:+.6e}", f"{bound['Gamma'][i][j]:.3e}", "1")
             for i in range(3) for j in range(3)]
    rows += [(f"theta_k{i + 1}", f"{phys['theta_k'][i]:+.6e}", f"{bound['theta_k'][i]:.3e}", "rad") for i in range(3)]
    print(f"\nblock errors in block axes, mounting {res['mount']}, Gamma {res['gamma']} (29) of 000:")
    report.table(("parameter", "estimate", "guaranteed error", "unit"), rows)
    print(res["physical_note"])


def cmd_calibrate_norm(args):
    mod = models.load("norm")
    log = recordings.read_log(args.log, args.format, args.sensor)
    stills, note = recordings.still_intervals(log, window=args.window, k=args.k, min_still=args.min_still)
    print(f"{args.log}: {len(log.t)} samples over {log.t[-1]:.1f} s; {len(stills)} still intervals ({note})",
          file=sys.stderr)
    res = calibrate.run(mod, stills, args.g, args.params, args.log, args.delta_sigma)
    print(f"calibration a = M (raw - b), {res['intervals']} still intervals, {res['iterations']} iterations "
          f"({res['start']})")
    print("M (m/s^2 per raw unit):")
    for row in res["matrix"]:
        print("   " + "  ".join(f"{v:+.6e}" for v in row))
    print("b (raw units): " + "  ".join(f"{v:+.6e}" for v in res["bias"]))
    dsig = res["delta_sigma_max"]
    print(f"minimax residual of the fit: {res['delta_sigma_fit']:.3e}; delta_sigma_max = {dsig:.3e} "
          f"(x g = {dsig * args.g:.3e} m/s^2) from the {res['delta_sigma_source']}")
    pars = res["parameters"] or {}
    report.table(("parameter", "estimate", "guaranteed error", "on the optimal plan"),
                 [(k, f"{pars[k]:+.4e}" if k in pars else "-", f"{v:.3e}",
                   f"{res['guaranteed_error_optimal_plan'][k]:.3e}") for k, v in res["guaranteed_error"].items()])
    if res["directions_to_add"]:
        print(f"\nto reach the optimal bounds, add {len(res['directions_to_add'])} orientation(s) "
              "(unit vectors in sensor axes, -gravity direction):")
        for d in res["directions_to_add"]:
            print("   (" + ", ".join(f"{v:+.3f}" for v in d["n"]) + f")  nearest present {d['nearest_present_deg']:.0f} deg")
    if args.json:
        report.write_json(args.json, res)
    if args.plot:
        calibrate.plot(res, args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    return 0


def cmd_identify(args):
    from . import identify
    res = identify.report(args.model, args.plan)
    identify.print_report(res)
    if args.json:
        report.write_json(args.json, res)
    return 0


def parser():
    ap = argparse.ArgumentParser(prog="garant", description="Guaranteed calibration of accelerometer blocks.")
    sub = ap.add_subparsers(dest="command", required=True)
    v = sub.add_parser("verify", help="run every check of the built-in models against the papers")
    v.add_argument("--json", metavar="FILE", help="also write the checks as JSON")
    v.set_defaults(run=cmd_verify)
    p = sub.add_parser("plan", help="optimal guaranteed errors and optimal plans of a model")
    p.add_argument("model", choices=models.STANDS)
    p.add_argument("--json", metavar="FILE")
    p.set_defaults(run=cmd_plan)
    e = sub.add_parser("estimate", help="estimate q with guaranteed bounds from readings at positions")
    e.add_argument("data", metavar="DATA.csv", help="CSV: alpha_deg,beta_deg,f1,f2,f3 (f in m/s^2)")
    e.add_argument("--model", required=True, choices=models.STANDS)
    e.add_argument("--sigma", type=float, required=True,
                   help="bound on each residual component, dimensionless (units of g), (5) of 000")
    e.add_argument("--g", type=float, default=G_DEFAULT, help="model gravity, m/s^2 (default 9.81)")
    e.add_argument("--mount", metavar="Q", help="mounting of the block, e.g. +y+z+x (block axis 1 along "
                   "table +y, ...): also report the block's physical errors, (28)-(29) of 000")
    e.add_argument("--gamma", choices=("lower", "symmetric"), default="lower",
                   help="convention that splits Gamma + hat(theta_k) (default lower-triangular Gamma)")
    e.add_argument("--json", metavar="FILE")
    e.set_defaults(run=cmd_estimate)
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
    c.add_argument("--json", metavar="FILE")
    c.add_argument("--plot", metavar="FILE.png", help="residual per interval, before and after")
    c.set_defaults(run=cmd_calibrate_norm)
    i = sub.add_parser("identify", help="estimable combinations, confounded parameters, a plan's blind spots")
    i.add_argument("model", choices=("two-axis", "003-example1", "003-example2"))
    i.add_argument("--plan", metavar="FILE", help="CSV with alpha_deg, beta_deg: what this plan cannot separate")
    i.add_argument("--json", metavar="FILE")
    i.set_defaults(run=cmd_identify)
    return ap


def main(argv=None):
    args = parser().parse_args(argv)
    warnings.filterwarnings("ignore", category=RuntimeWarning, module="cvxpy")
    try:
        return args.run(args)
    except (DataError, LPFailed) as e:
        print(f"garant: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"garant: error: {e.filename or ''}: {e.strerror}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
