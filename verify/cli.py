"""The `garant` command: verify, plan, estimate."""
import argparse
import sys

import numpy as np
import time
import warnings

from . import calibrate, checks, estimate as estimate_mod, exact, models, norm_checks, plans, recordings, redundancy_checks, report
from .data import DataError, read_positions
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


def cmd_plan(args):
    mod = models.load(args.model)
    names, mounts = models.layout(mod)
    r = plans.search(mod)
    plan = _preferred_plan(mod, r)
    multi = len(mounts) > 1

    def fmt(s):
        return [*(float(v) for v in r.angles_deg[s]), *([mounts[r.mounts[s]]] if multi else [])]
    from . import certificate, continuum
    cont = continuum.solve(certificate.stacked_H(mod), len(names), np.eye(len(mod.Q_NAMES))).values
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
    if args.diagnose:
        raw = np.array([st.mean for st in stills])
        fit = calibrate.fit(mod, raw, args.g, args.params)
        d = calibrate.diagnose_norm(mod, stills, fit, args.g, args.params)
        res["diagnosis"] = d
        print(f"\nmodel discrepancy (residuals in units of each interval's noise, {d['noise_bound']}):")
        print(f"  {args.params}-parameter model: worst {d['max_residual_before']:.1f} -> "
              + ("consistent" if d["consistent_before"] else "INCONSISTENT"))
        for step in d["scores"]:
            print("  try: " + ", ".join(f"{k} {v:.1f}" for k, v in sorted(step.items(), key=lambda kv: kv[1])))
        for group in d["indistinguishable"]:
            print("  indistinguishable with these orientations: " + " / ".join(group))
        print("  added: " + (", ".join(d["effects"]) or "nothing") + f"; worst now {d['max_residual_after']:.1f} -> "
              + ("consistent" if d["consistent_after"] else "still INCONSISTENT: an effect outside the catalogue, "
                 "or a noise bound too tight"))
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


def cmd_derive(args):
    from pathlib import Path

    from derive import codegen, description
    try:
        model = description.load(args.stand)
        t0 = time.perf_counter()
        files = codegen.model_files(model, module_dir=args.out, docs_dir=args.out)
    except description.DescriptionError as e:
        raise DataError(str(e)) from None
    for rel, text in files.items():
        Path(rel).parent.mkdir(parents=True, exist_ok=True)
        Path(rel).write_text(text)
        print(f"wrote {rel}")
    mod = models.from_description(args.stand)
    print(f"{model.stand.title}: {len(model.parameters)} physical parameters, {len(mod.Q_NAMES)} "
          f"identifiable combinations, {len(mod.UNSEPARABLE)} unseparable directions "
          f"(derived in {time.perf_counter() - t0:.1f} s)")
    for q, d in zip(mod.Q_NAMES, mod.Q_DEFINITIONS):
        print(f"  {q} = {d}")
    return 0


def _base_model(name):
    from derive import description
    from derive.builtin import MODELS as BUILTIN
    if name.endswith(".toml"):
        try:
            return description.load(name)
        except description.DescriptionError as e:
            raise DataError(str(e)) from None
    key = name.replace("-", "_")
    if key not in BUILTIN:
        raise DataError(f"unknown stand {name!r}; use {', '.join(models.STANDS)} or a STAND.toml")
    return BUILTIN[key]


def cmd_simulate(args):
    from derive.effects import CATALOGUE
    from . import simulate
    base = _base_model(args.model)
    mod = models.load(args.model)
    effects = [simulate.parse_effect(e, CATALOGUE) for e in args.effect]
    P, f, t, T, _ = simulate.simulate(base, mod, args.plan, effects, args.sigma, args.seed, args.g, args.size)
    simulate.write(args.output, P, f, t, T)
    hidden = ", ".join(f"{n}={','.join(f'{v:g}' for v in vals)}" for n, vals in effects) or "none"
    print(f"wrote {args.output}: {len(P)} positions, noise within +-{args.sigma:g} g, effects: {hidden}")
    return 0


def cmd_diagnose(args):
    from . import diagnose
    base = _base_model(args.model)
    mod = models.load(args.model)
    names, mounts = models.layout(mod)
    if len(mounts) > 1 or len(names) != 2:
        raise DataError("diagnose works on two-angle stands with one mounting for now")
    pos = read_positions(args.data, names, mounts)
    t0 = time.perf_counter()
    res = diagnose.diagnose(base, mod, pos, args.sigma, args.g, args.prior)
    study = res.pop("_study")
    lim = args.sigma + res["remainder_allowance"]
    print(f"current model: minimax residual {res['max_residual_before'] / args.sigma:.2f} sigma "
          f"(limit {lim / args.sigma:.2f} with the linearisation remainder): "
          + ("consistent" if res["consistent_before"] else "INCONSISTENT"))
    if res["disagreements"]:
        worst = sorted(res["disagreements"], key=lambda d: -d["excess_over_sigma"])[:8]
        report.table(("position", "alpha_deg", "beta_deg", "component", "residual/sigma"),
                     [(d["position"], f"{d['alpha_deg']:g}", f"{d['beta_deg']:g}", d["component"],
                       f"{d['residual'] / args.sigma:+.2f}") for d in worst])
        print(f"({len(res['disagreements'])} residual components exceed the limit; largest shown)")
    for h in res["history"]:
        print(f"step {h['step']}: " + ", ".join(f"{e} {v / args.sigma:.2f}" for e, v in
                                               sorted(h["scores"].items(), key=lambda kv: kv[1])))
    if res["effects"]:
        print("added: " + ", ".join(res["effects"]))
        report.table(("parameter", "estimate", "guaranteed error", "unit", "combination"),
                     [(k, f"{v['value']:+.4e}", f"{v['bound']:.3e}", v["unit"], v["q"])
                      for k, v in res["estimates"].items()])
    for group in res["indistinguishable"]:
        print("indistinguishable on this plan: " + " / ".join(group))
    for s in res["separating_positions"]:
        print(f"  to separate {' and '.join(s['effects'])}, measure at (alpha, beta) = "
              + "; ".join(f"({p['alpha_deg']:g}, {p['beta_deg']:g}) [differ by "
                          f"{p['predicted_difference'] / args.sigma:.1f} sigma]" for p in s["positions"]))
    print(f"after: minimax residual {res['max_residual_after'] / args.sigma:.2f} sigma: "
          + ("consistent" if res["consistent_after"] else "still INCONSISTENT"))
    print("this plan is blind to: " + (", ".join(res["blind_to"]) or "nothing in the catalogue"))
    for e, why in res["skipped"].items():
        print(f"not tried: {e} ({why})")
    print(f"diagnosis took {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    if args.report:
        for f in diagnose.write_module(study, res["effects"], args.report):
            print(f"wrote {f}")
    if args.plot:
        diagnose.plot(res, args.plot, f"{args.data}: residuals before and after")
    if args.json:
        report.write_json(args.json, res)
    return 0


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
    p.set_defaults(run=cmd_plan)
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
    c.add_argument("--diagnose", action="store_true",
                   help="test the model against each interval's noise and try the effect catalogue")
    c.add_argument("--json", metavar="FILE")
    c.add_argument("--plot", metavar="FILE.png", help="residual per interval, before and after")
    c.set_defaults(run=cmd_calibrate_norm)
    i = sub.add_parser("identify", help="estimable combinations, confounded parameters, a plan's blind spots")
    i.add_argument("model", choices=("two-axis", "003-example1", "003-example2"))
    i.add_argument("--plan", metavar="FILE", help="CSV with alpha_deg, beta_deg: what this plan cannot separate")
    i.add_argument("--json", metavar="FILE")
    i.set_defaults(run=cmd_identify)
    dv = sub.add_parser("derive", help="derive a stand description: generated module and derivation report")
    dv.add_argument("stand", metavar="STAND.toml")
    dv.add_argument("--out", default=".", help="directory for the module and report (default: here)")
    dv.set_defaults(run=cmd_derive)
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
    sm.set_defaults(run=cmd_simulate)
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
    dg.set_defaults(run=cmd_diagnose)
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
