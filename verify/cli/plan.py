"""garant plan: optimal guaranteed errors and a minimal optimal plan of a stand."""
import numpy as np

from ..errors import DataError
from . import args as a


def add(sub):
    p = sub.add_parser("plan", help="optimal guaranteed errors and optimal plans of a model")
    p.add_argument("model", help="a built-in stand (two-axis, single-axis, three-axis), a STAND.toml, or norm "
                   "(the coarse stand of 001: which orientations to hold the IMU in)")
    a.json(p)
    p.add_argument("--grid", type=a.positive, metavar="STEP", help="search positions every STEP degrees (detents "
                   "and ranges honoured; exact on multiples of 15); default: detents or quarter turns")
    p.add_argument("--count-seconds", type=a.positive, default=5.0, metavar="S",
                   help="time allowed for counting the optimal plans on a large grid (default 5 s)")
    p.add_argument("--certificates", metavar="DIR", help="write a certificate of the plan's optimality for each "
                   "q (garant check-certificate re-checks it without any solver)")
    p.add_argument("--csv", metavar="PLAN.csv", help="write the plan: <angle>_deg columns (and mount), for "
                   "`garant simulate --plan PLAN.csv` and for the stand operator")
    return p


def run(args):
    if args.model == "norm":
        return run_norm(args)
    from .. import models
    from ..io import report
    from ..proof import build
    from ..solve import continuum, plans
    mod = models.load(args.model)
    names, mounts = models.layout(mod)
    if args.grid is not None and 360 % args.grid:
        raise DataError(f"--grid {args.grid:g}: give a step that divides 360 degrees")
    P, M = _grid(mod, args.grid or 90.0) if args.grid else plans.grid(mod)
    r = plans.search(mod, P, M, count_seconds=args.count_seconds)
    n = len(names)
    ranges = getattr(mod, "ANGLE_RANGES_DEG", ((0, 360),) * n)
    detents = getattr(mod, "ANGLE_DETENTS_DEG", ((),) * n)
    finite = all(len(d) for d in detents)
    cont, added = None, 0
    if not finite:                          # the continuum of reachable angles: the exchange method there
        sol = continuum.solve(build.stacked_H(mod), n, np.eye(len(mod.Q_NAMES)), ranges_deg=ranges)
        cont = sol.values
        if any(e > c + 1e-7 for e, c in zip(r.errors, cont)):   # the exchange positions become candidates
            X = _snap(np.rad2deg(sol.positions), ranges, detents)
            base = P[M == 0]
            new_all = [x for x in X if not np.any(np.all(np.isclose(base, x), axis=1))]
            exact = [x for x in new_all if np.all(x % 15 == 0)]
            for new in ([exact, new_all] if exact and len(exact) < len(new_all) else [new_all]):
                if not new:
                    continue                 # exact candidates first (multiples of 15 degrees), then all
                k = len(mounts)
                P2 = np.vstack([base, np.array(new)])
                P, M = np.tile(P2, (k, 1)), np.repeat(np.arange(k), len(P2))
                r, added = plans.search(mod, P, M, count_seconds=args.count_seconds), len(new)
                if all(e <= c + 1e-7 for e, c in zip(r.errors, cont)):
                    break
    plan = _preferred_plan(mod, r)
    multi = len(mounts) > 1

    def fmt(s):
        return [*(float(v) for v in r.angles_deg[s]), *([mounts[r.mounts[s]]] if multi else [])]
    report.table(("q", "definition", "optimal error on the candidates (sigma)",
                  "continuum optimum (exchange)", "candidates are"),
                 [(q, d, f"{e:g}", "-" if c is None else f"{c:.6g}",
                   "optimal on every reachable position (detents)" if finite else "optimal (proven)" if pr else
                   "optimal" if abs(c - e) < 1e-6 else "NOT optimal: use intermediate angles")
                  for q, d, e, c, pr in zip(mod.Q_NAMES, mod.Q_DEFINITIONS, r.errors,
                                            cont if cont is not None else [None] * len(r.errors), r.proven)])
    if added:
        print(f"candidates: the grid and {added} position(s) of the exchange method's optimum on the continuum")
    exact = r.exact_errors()
    if any(e is not None and not e.lstrip("-").isdigit() and "/" not in e for e in exact):
        print("exact optimal errors: " + ", ".join(f"{q} {e}" for q, e in zip(mod.Q_NAMES, exact) if e))
    where = (f"grid of {args.grid:g}-degree steps" if args.grid else "grid of detents/quarter turns") + (
        " and the exchange positions" if added else "") + (
        " x mountings" if multi else "")
    print(f"\nminimal number of positions optimal for every q ({where}, {len(r.angles_deg)} positions): "
          f"{r.min_positions}")
    on_quarter = all(np.all(np.isclose(r.angles_deg[list(p)] % 90, 0)) for p in r.optimal_plans)
    print(f"optimal plans of {r.min_positions} positions on that grid: "
          + (f"{len(r.optimal_plans)}" if r.exhaustive else f"at least {len(r.optimal_plans)} (counting stopped; "
                                                             "--count-seconds for more)")
          + f"; counted by {r.method}" + ("; every one on quarter turns" if on_quarter and args.grid else ""))
    print(f"plan ({', '.join(a + '_deg' for a in names)}{', mounting' if multi else ''}): "
          + ", ".join("(" + ", ".join(f"{v:g}" if not isinstance(v, str) else v for v in fmt(s)) + ")"
                      for s in plan))
    if args.json:
        report.write_json(args.json, {
            "model": args.model, "angles": names, "mountings": mounts, "q_names": list(mod.Q_NAMES),
            "definitions": list(mod.Q_DEFINITIONS), "guaranteed_errors": list(r.errors),
            "proven_on_continuum": list(r.proven),
            "continuum_errors": None if cont is None else [float(c) for c in cont],
            "reachable_set": "detents" if finite else "continuum", "exchange_candidates_added": added,
            "guaranteed_errors_exact": exact, "grid_step_deg": args.grid, "count_method": r.method,
            "min_positions": r.min_positions,
            "optimal_plans_count": len(r.optimal_plans) if r.exhaustive else None,
            "optimal_plans_on_quarter_turns": bool(on_quarter),
            "plan": [fmt(s) for s in plan],
            "optimal_plans": [[fmt(s) for s in pl] for pl in r.optimal_plans]})
    if args.certificates:
        _certificates(mod, args, r, plan)
    if args.csv:
        header = [f"{a}_deg" for a in names] + (["mount"] if multi else [])
        report.write_text(args.csv, "\n".join([",".join(header)] + [",".join(
            f"{v:g}" if not isinstance(v, str) else v for v in fmt(s)) for s in plan]) + "\n")
        print(f"wrote {args.csv}")
    return 0


def _certificates(mod, args, r, plan):
    from pathlib import Path

    from ..proof import build, check
    folder = Path(args.certificates)
    folder.mkdir(parents=True, exist_ok=True)
    certs = build.for_plan(mod, args.model, r, plan)
    stem = Path(args.model).stem.replace("_", "-")
    for q, cert in certs:
        check.write(cert, folder / f"{stem}_plan_{q}.json")
    missing = [q for q in mod.Q_NAMES if q not in {q for q, _ in certs}]
    print(f"wrote {len(certs)} certificate(s) to {folder}/ (garant check-certificate FILE re-checks each)"
          + (f"; none for {', '.join(missing)}: no exact dual or estimator (off the 15-degree grid?)"
             if missing else ""))


def _snap(X, ranges, detents, step=15.0, tol=1e-6):
    """Exchange positions (degrees): onto multiples of 15 degrees where within tol (then exact), within
    the range of each angle; positions a stand cannot take are dropped."""
    from ..models import unreachable
    k = np.round(X / step) * step
    X = np.where(np.abs(X - k) < tol, k, X) % 360
    return [x for x in X if unreachable(ranges, detents, x[None]) is None]


def _grid(mod, step):
    """Positions every `step` degrees that the stand can take, in every mounting."""
    from ..models import layout, reachable_grid
    n = len(mod.ANGLES)
    P = reachable_grid(getattr(mod, "ANGLE_RANGES_DEG", ((0, 360),) * n),
                       getattr(mod, "ANGLE_DETENTS_DEG", ((),) * n), step)
    k = len(layout(mod)[1])
    return np.tile(P, (k, 1)), np.repeat(np.arange(k), len(P))


def _preferred_plan(mod, r):
    """The model's own plan (PLAN_DEG) when it is among the optimal ones, else the first found."""
    own = getattr(mod, "PLAN_DEG", np.zeros((0, 0)))
    if len(own):
        idx = tuple(sorted(int(np.flatnonzero(np.all(r.angles_deg == p, axis=1))[0]) for p in own))
        if idx in r.optimal_plans:
            return [int(np.flatnonzero(np.all(r.angles_deg == p, axis=1))[0]) for p in own]
    return list(r.optimal_plans[0])


def run_norm(args):
    """The coarse stand of 001: optimal errors on the sphere (units of delta_sigma_max) and the fewest
    orientations optimal for the 9 linear parameters and for all 12 (unit vectors, -gravity in sensor axes)."""
    from .. import models
    from ..io import report
    from ..papers import norm_001
    from ..solve import lp
    mod = models.load("norm")
    _, errors = lp.primal(mod.H(mod.PLAN.T))
    plans = {k: norm_001.minimal_plan(mod, range(k)) for k in (9, 12)}
    report.table(("q", "optimal guaranteed error (delta_sigma_max)"), [(q, f"{e:.6g}") for q, e in zip(mod.Q_NAMES, errors)])
    for k, idx in plans.items():
        print(f"\nfewest orientations optimal for {'the 9 linear parameters' if k == 9 else 'all 12 parameters'}: "
              f"{len(idx)} (unit vectors n, the direction of -gravity in sensor axes; exact forms in generated/norm.py)")
        for i in idx:
            print("   (" + ", ".join(f"{v:+.4f}" for v in mod.PLAN[i]) + ")")
    if args.json:
        report.write_json(args.json, {"model": "norm", "q_names": list(mod.Q_NAMES),
                                      "guaranteed_errors": [float(e) for e in errors],
                                      "min_positions": {"9": len(plans[9]), "12": len(plans[12])},
                                      "directions": {str(k): [mod.PLAN[i].tolist() for i in idx] for k, idx in plans.items()},
                                      "directions_exact": {str(k): [mod.PLAN_EXACT[i] for i in idx] for k, idx in plans.items()}})
    if args.csv:
        report.write_text(args.csv, "n1,n2,n3\n" + "\n".join(",".join(f"{v:.17g}" for v in mod.PLAN[i]) for i in plans[12]) + "\n")
        print(f"wrote {args.csv}")
    return 0
