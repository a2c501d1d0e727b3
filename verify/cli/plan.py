"""garant plan: optimal guaranteed errors and a minimal optimal plan of a stand."""
import numpy as np

from . import args as a


def add(sub):
    p = sub.add_parser("plan", help="optimal guaranteed errors and optimal plans of a model")
    p.add_argument("model", help="a built-in stand (two-axis, single-axis, three-axis), a STAND.toml, or norm "
                   "(the coarse stand of 001: which orientations to hold the IMU in)")
    a.json(p)
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
    r = plans.search(mod)
    plan = _preferred_plan(mod, r)
    multi = len(mounts) > 1

    def fmt(s):
        return [*(float(v) for v in r.angles_deg[s]), *([mounts[r.mounts[s]]] if multi else [])]
    cont = continuum.solve(build.stacked_H(mod), len(names), np.eye(len(mod.Q_NAMES))).values
    report.table(("q", "definition", "optimal error on the grid (sigma)", "continuum optimum (exchange)", "grid is"),
                 [(q, d, f"{e:g}", f"{c:.6g}", "optimal (proven)" if pr else
                   "optimal" if abs(c - e) < 1e-6 else "NOT optimal: use intermediate angles")
                  for q, d, e, c, pr in zip(mod.Q_NAMES, mod.Q_DEFINITIONS, r.errors, cont, r.proven)])
    where = "grid of " + ("detents/quarter turns" if not multi else "quarter turns x mountings")
    print(f"\nminimal number of positions optimal for every q ({where}, {len(r.angles_deg)} positions): "
          f"{r.min_positions}")
    if r.exhaustive:
        print(f"optimal plans of {r.min_positions} positions on that grid: {len(r.optimal_plans)}")
    else:
        print("optimal plan found by a mixed-integer program (too many candidate sets to count every plan)")
    print(f"plan ({', '.join(a + '_deg' for a in names)}{', mounting' if multi else ''}): "
          + ", ".join("(" + ", ".join(f"{v:g}" if not isinstance(v, str) else v for v in fmt(s)) + ")"
                      for s in plan))
    if args.json:
        report.write_json(args.json, {
            "model": args.model, "angles": names, "mountings": mounts, "q_names": list(mod.Q_NAMES),
            "definitions": list(mod.Q_DEFINITIONS), "guaranteed_errors": list(r.errors),
            "proven_on_continuum": list(r.proven), "continuum_errors": [float(c) for c in cont],
            "min_positions": r.min_positions,
            "optimal_plans_count": len(r.optimal_plans) if r.exhaustive else None,
            "plan": [fmt(s) for s in plan],
            "optimal_plans": [[fmt(s) for s in pl] for pl in r.optimal_plans]})
    if args.csv:
        header = [f"{a}_deg" for a in names] + (["mount"] if multi else [])
        report.write_text(args.csv, "\n".join([",".join(header)] + [",".join(
            f"{v:g}" if not isinstance(v, str) else v for v in fmt(s)) for s in plan]) + "\n")
        print(f"wrote {args.csv}")
    return 0


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
