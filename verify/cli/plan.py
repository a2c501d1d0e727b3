"""garant plan: optimal guaranteed errors and a minimal optimal plan of a stand."""
import sys

from ..outcomes import Exit
from ..errors import DataError
from ..models import STANDS, kind
from ..defaults import COUNT_NODES, COUNT_SECONDS, MAX_CANDIDATES, SEARCH_NODES, SEARCH_SECONDS
from . import flags


def add(sub):
    """The `garant plan` subcommand and its flags."""
    p = sub.add_parser("plan", help="optimal guaranteed errors and optimal plans of a model")
    p.add_argument("--model", required=True, help=f"a built-in stand ({', '.join(STANDS)}), a STAND.toml, or norm "
                   "(the coarse stand of 001: which orientations to hold the IMU in)")
    flags.json(p)
    p.add_argument("--grid", type=flags.positive, metavar="STEP", help="search positions every STEP degrees (detents "
                   "and ranges honoured; exact on multiples of 15); default: detents or quarter turns")
    p.add_argument("--search-nodes", type=flags.positive_int, default=SEARCH_NODES, metavar="N",
                   help=f"work allowed for proving the fewest positions: branch-and-bound nodes (default "
                        f"{SEARCH_NODES:,}; the same plan on every machine); when they run out, the plan found is "
                        "printed with a proven lower bound on the fewest")
    p.add_argument("--count-nodes", type=flags.count, default=COUNT_NODES, metavar="N",
                   help=f"work allowed for counting the optimal plans on a large grid, in nodes (default "
                        f"{COUNT_NODES:,}; 0: the plan alone, not counted)")
    p.add_argument("--search-seconds", type=flags.positive, default=SEARCH_SECONDS, metavar="S",
                   help=f"safety stop of the search (default {SEARCH_SECONDS:g} s; a stop it causes is said, for it "
                        "depends on the machine)")
    p.add_argument("--count-seconds", type=flags.positive, default=COUNT_SECONDS, metavar="S",
                   help=f"safety stop of the count (default {COUNT_SECONDS:g} s)")
    p.add_argument("--max-candidates", type=flags.positive_int, default=MAX_CANDIDATES, metavar="N",
                   help=f"refuse a --grid of more than N candidate positions (times mountings; default "
                        f"{MAX_CANDIDATES:,}: "
                        "a 3-degree grid on the two-axis stand takes about 30 s)")
    p.add_argument("--certificates", metavar="DIR", help="write a certificate of the plan's optimality for each "
                   "q (garant check-certificate re-checks it without any solver)")
    p.add_argument("--route", action="store_true", help="order the plan's positions for the least total stand "
                   "time (the description's speed_deg_s, acceleration_deg_s2, settle_s, remount_s), or without speeds "
                   "for the least largest angle per move; print the schedule (-o carries it)")
    p.add_argument("--plot", metavar="FILE.png", help="the up-direction in block axes at each position of the plan "
                   "(in the route's order with --route): arrows on the unit sphere, the faces that point up")
    p.add_argument("-o", "--output", metavar="PLAN.csv", help="write the plan: <angle>_deg columns (and mount), for "
                   "`garant simulate --plan PLAN.csv` and for the stand operator")
    p.add_argument("--temperatures", type=flags.temperatures, metavar="T1,T2,...",
                   help="chamber temperatures (C; write --temperatures=-20,...): which positions at which temperature "
                        "identify every coefficient of the thermal model (--thermal-degree D), the fewest per "
                        "temperature")
    p.add_argument("--thermal-degree", dest="temperature", type=int, choices=(1, 2, 3), metavar="D",
                   help="with --temperatures: the degree of each block parameter's polynomial in T (default 2, or one "
                        "less than the temperatures given)")
    return p


def run(args):
    """`garant plan`: parse, call the job, print; the exit status."""
    if args.temperature is not None and args.temperatures is None:
        raise DataError("--thermal-degree D applies with --temperatures T1,T2,...", param="temperature")
    if args.temperatures is not None:
        return run_thermal(args)
    if kind(args.model) == "norm":
        given = [opt for opt, v in (("--grid", args.grid), ("--certificates", args.certificates),
                                    ("--route", args.route or None)) if v is not None]
        if given:
            raise DataError(f"{' and '.join(given)} {'apply' if len(given) > 1 else 'applies'} to a stand with angles; "
                            f"`plan norm` gives the orientations "
                            "of 001 on the sphere, held by hand (their certificates: garant verify --certificates DIR)",
                            param=given[0].lstrip("-"))
        return run_norm(args)
    from .. import models
    from ..io import report
    from ..workflows.plan import plan as search_plan
    mod = models.load(args.model)
    names, mounts = models.layout(mod)
    res = search_plan(mod, args.model, args.grid, args.count_seconds, args.max_candidates, args.search_seconds,
                      progress=lambda text: print(f"plan: {text} ...", file=sys.stderr, flush=True),
                      certify=bool(args.certificates), search_nodes=args.search_nodes, count_nodes=args.count_nodes)
    d = res.to_dict()
    if args.route:
        from ..workflows.plan import route
        d["route"] = route(res)
    certs = _certificates(mod, args, res.search, res.plan) if args.certificates else None   # before any file
    _print(mod, res, d, args.grid, names, counted=args.count_nodes > 0)
    if args.route:
        _print_route(d["route"], names, res.multi)
    if args.json:
        report.write_json(args.json, d)
    if certs is not None:
        _write_certificates(mod, args.certificates, certs)
    if args.plot:
        _plot(mod, d, args)
    if args.output:
        header = [f"{a}_deg" for a in names] + (["mount"] if res.multi else [])
        rows = [[*pos] for pos in d["plan"]]
        if args.route:
            rt = d["route"]
            header += ["order",
                       "move_s" if rt["arrive_s"] else "largest_turn_deg"] + (["arrive_s"] if rt["arrive_s"] else [])
            rows = [[*pos, k + 1, mv, *([rt["arrive_s"][k]] if rt["arrive_s"] else [])]
                    for k, (pos, mv) in enumerate(zip(rt["positions"], rt["move"]))]
        report.write_text(args.output, "\n".join([",".join(header)] + [",".join(
            f"{v:g}" if not isinstance(v, str) else v for v in row) for row in rows]) + "\n")
        print(f"wrote {args.output}")
    return Exit.OK


def _print(mod, res, d, grid, names, counted=True):
    """The optimal errors per q (candidates and continuum), the minimal number of positions, the plan (the
    plans of that size counted unless `counted` is False: --count-nodes 0)."""
    from ..io import report
    r, cont = res.search, res.continuum
    report.table(("q", "definition", "optimal error on the candidates (sigma)",
                  "continuum optimum (exchange)", "candidates are"),
                 [(q, dq, f"{e:g}", "-" if c is None else f"{c:.6g}",
                   "optimal on every reachable position (detents)" if res.finite else "optimal (proven)" if pr else
                   "optimal" if abs(c - e) < 1e-6 else "NOT optimal: use intermediate angles")
                  for q, dq, e, c, pr in zip(mod.Q_NAMES, mod.Q_DEFINITIONS, r.errors,
                                             cont if cont is not None else [None] * len(r.errors), r.proven)])
    if res.added:
        print(f"candidates: the grid and {res.added} position(s) of the exchange method's optimum on the continuum")
    exact = d["guaranteed_errors_exact"]
    if any(e is not None and not e.lstrip("-").isdigit() and "/" not in e for e in exact):
        print("exact optimal errors: " + ", ".join(f"{q} {e}" for q, e in zip(mod.Q_NAMES, exact) if e))
    where = (f"grid of {grid:g}-degree steps" if grid else "grid of detents/quarter turns") + (
        " and the exchange positions" if res.added else "") + (" x mountings" if res.multi else "")
    print(f"\nminimal number of positions optimal for every q ({where}, {len(r.angles_deg)} positions): "
          + (f"{r.min_positions}" if r.floor is None else
             f"at most {r.min_positions}, at least {r.floor} (the search stopped "
             + (f"at its safety stop, --search-seconds {res.search_seconds:g}: another machine may go further"
                if r.clock else f"after --search-nodes {res.search_nodes:,}") + "; raise it to prove the fewest)"))
    if r.floor is not None:
        print(f"a plan of {r.min_positions} positions optimal for every q (not proven the fewest), found by {r.method}")
    elif not (r.exhaustive or counted):
        print(f"optimal plans of {r.min_positions} positions on that grid: not counted (--count-nodes 0); "
              f"found by {r.method}")
    else:
        print(f"optimal plans of {r.min_positions} positions on that grid: "
              + (f"{len(r.optimal_plans)}" if r.exhaustive else f"at least {len(r.optimal_plans)} (counting stopped"
                 + (" at its safety stop, --count-seconds: another machine may count more" if r.clock else
                    " after --count-nodes; raise it for more") + ")")
              + f"; counted by {r.method}"
              + ("; every one on quarter turns" if d["optimal_plans_on_quarter_turns"] and grid else ""))
    print(f"plan ({', '.join(a + '_deg' for a in names)}{', mounting' if res.multi else ''}): "
          + ", ".join("(" + ", ".join(f"{v:g}" if not isinstance(v, str) else v for v in pos) + ")"
                      for pos in d["plan"]))


def _print_route(rt, names, multi):
    """The schedule: each position in route order, the angles turned to reach it, the move's cost."""
    from ..io import report
    timed = rt["arrive_s"] is not None
    print(f"\nroute ({rt['method']}; least {rt['objective']}):")
    report.table(("#", ", ".join(f"{a}_deg" for a in names) + (", mounting" if multi else ""),
                  "turned (deg)", "move (s)" if timed else "largest turn (deg)", *(("arrive (s)",) if timed else ())),
                 [(k + 1, ", ".join(f"{v:g}" if not isinstance(v, str) else v for v in pos),
                   ", ".join(f"{t:g}" for t in turned), f"{mv:.3g}", *((f"{rt['arrive_s'][k]:.4g}",) if timed else ()))
                  for k, (pos, turned, mv) in enumerate(zip(rt["positions"], rt["turned_deg"], rt["move"]))])
    print(f"total stand time: {rt['total']:.4g} s" if timed else
          f"largest angle in one move: {rt['total']:g} deg (no speeds in the description: speed_deg_s per angle "
          "gives a schedule in seconds)")
    if rt["lower_bound"] is not None:
        print(f"lower bound on any order: {rt['lower_bound']:.4g} s "
              f"(the route is within {100 * rt['gap']:.1f} % of it)")
    for note in rt["notes"]:
        print(f"note: {note}")


def _certificates(mod, args, r, plan):
    """The plan's certificates in memory, [(path, q, certificate)]: built before anything is written."""
    from pathlib import Path

    from ..proof import build
    stem = Path(args.model).stem.replace("_", "-")
    return [(Path(args.certificates) / f"{stem}_plan_{q}.json", q, cert)
            for q, cert in build.for_plan(mod, args.model, r, plan, args.grid)]


def _write_certificates(mod, folder, certs):
    """Write the certificates built by `_certificates` and say which q have none."""
    from ..io import files
    from ..proof import check
    files.make_folder(folder)
    for path, _, cert in certs:
        check.write(cert, path)
    missing = [q for q in mod.Q_NAMES if q not in {q for _, q, _ in certs}]
    print(f"wrote {len(certs)} certificate(s) to {folder}/ (garant check-certificate FILE re-checks each)"
          + (f"; none for {', '.join(missing)}: no exact dual or estimator (off the 15-degree grid?)"
             if missing else ""))


def run_norm(args):
    """The coarse stand of 001: optimal errors on the sphere (units of delta_sigma_max) and the fewest
    orientations optimal for the 9 linear parameters and for all 12 (unit vectors, -gravity in sensor axes)."""
    from .. import models
    from ..io import report
    from ..workflows.plan import norm_plan
    mod = models.load("norm")
    d = norm_plan(mod)
    report.table(("q", "optimal guaranteed error (delta_sigma_max)"),
                 [(q, f"{e:.6g}") for q, e in zip(d["q_names"], d["guaranteed_errors"])])
    for k in ("9", "12"):
        print(f"\nfewest orientations optimal for {'the 9 linear parameters' if k == '9' else 'all 12 parameters'}: "
              f"{d['min_positions'][k]} (unit vectors n, the direction of -gravity in sensor axes; exact forms in "
              "generated/norm.py)")
        for n in d["directions"][k]:
            print("   (" + ", ".join(f"{v:+.4f}" for v in n) + ")")
    if args.json:
        report.write_json(args.json, d)
    if args.output:
        report.write_text(args.output, "n1,n2,n3\n" + "\n".join(",".join(f"{v:.17g}" for v in n)
                                                              for n in d["directions"]["12"]) + "\n")
        print(f"wrote {args.output}")
    if args.plot:
        import numpy as np

        from ..io import plots
        U = np.array(d["directions"]["12"], float)
        plots.plan_directions(U, args.plot, f"garant plan --model norm: the {len(U)} orientations optimal for all 12 "
                                            "parameters (-gravity in sensor axes)")
        print(f"wrote {args.plot}")
    return Exit.OK


def _plot(mod, d, args):
    """The plan's up-directions on the unit sphere (io/plots.plan_directions), in the order printed."""
    from .. import models
    from ..io import plots
    from ..workflows.directions import up_in_block
    names, mounts = models.layout(mod)
    positions = d["route"]["positions"] if args.route else d["plan"]
    U = up_in_block(mod, [p[:len(names)] for p in positions],
                    [mounts.index(p[len(names)]) for p in positions] if len(mounts) > 1 else None)
    plots.plan_directions(U, args.plot, f"garant plan --model {args.model}: {len(positions)} positions"
                          + (" in the route's order" if args.route else ""))
    print(f"wrote {args.plot}")


def run_thermal(args):
    """`plan --temperatures`: the positions at each chamber temperature that identify every coefficient of
    the thermal model (workflows/thermal.py `plan`), the fewest per temperature, and whether that is proven."""
    from .. import models
    from ..io import report
    from ..workflows import thermal
    other = [o for o, v in (("--grid", args.grid), ("--certificates", args.certificates),
                            ("--route", args.route or None), ("--plot", args.plot)) if v is not None]
    if other or args.model not in models.STANDS and not str(args.model).endswith(".toml"):
        raise DataError(f"--temperatures takes a stand ({', '.join(models.STANDS)} or a STAND.toml)"
                        + (f" and not {', '.join(other)}" if other else ""), param="model")
    degree = args.temperature if args.temperature is not None else min(2, len(args.temperatures) - 1)
    plan, per, lower, mod = thermal.plan(args.model, args.temperatures, degree)
    names, mounts = models.layout(mod)
    multi = len(mounts) > 1
    total = sum(len(v) for v in plan.values())
    print(f"thermal model: each block parameter a polynomial of degree {degree} in T (about "
          f"{int(round(0.5 * (min(args.temperatures) + max(args.temperatures))))} C): {len(mod.Q_NAMES)} q to identify")
    print(f"{per} position(s) per temperature identify every q ({total} in all): "
          + ("the fewest, proven (3 readings a position: " if per == lower else "found; fewer are not excluded (the "
             "counting bound is ") + f"at least {len(mod.Q_NAMES)} / (3 x {len(plan)}) = {lower} per temperature)")
    rows = [[*pos, *([mounts[m]] if multi else []), t] for t, ps in plan.items() for pos, m in ps]
    report.table([f"{a}_deg" for a in names] + (["mount"] if multi else []) + ["temp_c"],
                 [[f"{x:g}" for x in r[:len(names)]] + r[len(names):-1] + [f"{r[-1]:g}"] for r in rows])
    print("each q identified: every coefficient has an unbiased estimator on these readings; the guaranteed errors "
          "of so few positions are large: `garant plan` at each temperature gives the optimal ones")
    if args.json:
        report.write_json(args.json, {"model": args.model, "degree": degree, "temperatures_c": args.temperatures,
                                      "per_temperature": per, "lower_bound": lower, "proven_fewest": per == lower,
                                      "plan": {f"{t:g}": [{"angles_deg": list(pos), **({"mount": mounts[m]} if multi
                                                                                      else {})} for pos, m in ps]
                                               for t, ps in plan.items()}})
    if args.output:
        header = [f"{a}_deg" for a in names] + (["mount"] if multi else []) + ["temp_c"]
        report.write_text(args.output, "\n".join(",".join(str(c) for c in r) for r in [header, *rows]) + "\n")
        print(f"wrote {args.output}")
    return Exit.OK
