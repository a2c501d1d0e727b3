"""Commands for stand models: plan, estimate, derive, identify."""
import time

import numpy as np

from . import estimate as estimate_mod, models, plans, report
from .data import DataError, read_positions


def cmd_plan(args):
    mod = models.load(args.model)
    names, mounts = models.layout(mod)
    r = plans.search(mod)
    plan = _preferred_plan(mod, r)
    multi = len(mounts) > 1

    def fmt(s):
        return [*(float(v) for v in r.angles_deg[s]), *([mounts[r.mounts[s]]] if multi else [])]
    from . import certify, continuum
    cont = continuum.solve(certify.stacked_H(mod), len(names), np.eye(len(mod.Q_NAMES))).values
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
    return 0


def _preferred_plan(mod, r):
    """The model's own plan (PLAN_DEG) when it is among the optimal ones, else the first found."""
    own = getattr(mod, "PLAN_DEG", np.zeros((0, 0)))
    if len(own):
        idx = tuple(sorted(int(np.flatnonzero(np.all(r.angles_deg == p, axis=1))[0]) for p in own))
        if idx in r.optimal_plans:
            return [int(np.flatnonzero(np.all(r.angles_deg == p, axis=1))[0]) for p in own]
    return list(r.optimal_plans[0])


def cmd_estimate(args):
    mod = models.load(args.model)
    remount = None if args.model.endswith(".toml") else models.load_remount(args.model)
    if args.mount and (remount is None or args.mount not in remount.MOUNTS):
        raise DataError(f"--mount needs a model with the remount formulas (two-axis) and a mounting like "
                        f"+y+z+x; got {args.mount!r}")
    names, mounts = models.layout(mod)
    res = estimate_mod.estimate(mod, read_positions(args.data, names, mounts), args.sigma, args.g,
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
    phys, bound = res["physical"], res["physical_bound"]
    rows = [(k, f"{phys[k]:+.6e}", f"{bound[k]:.3e}", "rad") for k in ("kappa", "dalpha_plus_astar", "epsilon")]
    rows += [(f"bias{i + 1}", f"{phys['bias'][i]:+.6e}", f"{bound['bias'][i]:.3e}", "m/s^2") for i in range(3)]
    rows += [(f"Gamma{i + 1}{j + 1}", f"{phys['Gamma'][i][j]:+.6e}", f"{bound['Gamma'][i][j]:.3e}", "1")
             for i in range(3) for j in range(3)]
    rows += [(f"theta_k{i + 1}", f"{phys['theta_k'][i]:+.6e}", f"{bound['theta_k'][i]:.3e}", "rad") for i in range(3)]
    print(f"\nblock errors in block axes, mounting {res['mount']}, Gamma {res['gamma']} (29) of 000:")
    report.table(("parameter", "estimate", "guaranteed error", "unit"), rows)
    print(res["physical_note"])


def cmd_derive(args):
    from derive import codegen, description
    try:
        model = description.load(args.stand)
        t0 = time.perf_counter()
        files = codegen.model_files(model, module_dir=args.out, docs_dir=args.out)
    except description.DescriptionError as e:
        raise DataError(str(e)) from None
    for rel in codegen.write_files(files):
        print(f"wrote {rel}")
    mod = models.from_description(args.stand)
    print(f"{model.stand.title}: {len(model.parameters)} physical parameters, {len(mod.Q_NAMES)} "
          f"identifiable combinations, {len(mod.UNSEPARABLE)} unseparable directions "
          f"(derived in {time.perf_counter() - t0:.1f} s)")
    for q, d in zip(mod.Q_NAMES, mod.Q_DEFINITIONS):
        print(f"  {q} = {d}")
    return 0


def cmd_identify(args):
    from . import identify
    res = identify.report(args.model, args.plan)
    identify.print_report(res)
    if args.json:
        report.write_json(args.json, res)
    return 0
