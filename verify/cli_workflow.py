"""Commands for workflows on data: calibrate-norm, simulate, diagnose."""
import sys
import time

import numpy as np

from . import calibrate, models, recordings, report
from .data import DataError, read_positions


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
    P, f, t, T, _, mounts = simulate.simulate(base, mod, args.plan, effects, args.sigma, args.seed, args.g,
                                              args.size)
    names, mount_names = models.layout(mod)
    simulate.write(args.output, P, f, t, T, names, mounts, mount_names)
    hidden = ", ".join(f"{n}={','.join(f'{v:g}' for v in vals)}" for n, vals in effects) or "none"
    print(f"wrote {args.output}: {len(P)} positions, noise within +-{args.sigma:g} g, effects: {hidden}")
    return 0


def cmd_diagnose(args):
    from . import diagnose
    base = _base_model(args.model)
    mod = models.load(args.model)
    names, mounts = models.layout(mod)
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
        report.table(("position", *(f"{a}_deg" for a in names), "component", "residual/sigma"),
                     [(d["position"], *(f"{d[a + '_deg']:g}" for a in names), d["component"],
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
        print(f"  to separate {' and '.join(s['effects'])}, measure at ({', '.join(names)}) = "
              + "; ".join("(" + ", ".join(f"{p[a + '_deg']:g}" for a in names)
                          + (f", {p['mount']}" if "mount" in p else "")
                          + f") [differ by {p['predicted_difference'] / args.sigma:.1f} sigma]" for p in s["positions"]))
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
