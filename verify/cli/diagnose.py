"""garant diagnose: find where the model and the data disagree, name the missing effect, add it."""
import sys
import time

from ..outcomes import Exit
from . import flags


def add(sub):
    """The `garant diagnose` subcommand and its flags."""
    p = sub.add_parser("diagnose", help="find the effect missing from the model, add it, show the gap shrink")
    p.add_argument("data", metavar="DATA.csv", help="as for estimate; optional columns time_s, temp_c")
    flags.model(p)
    flags.sigma(p, "noise bound, units of g")
    flags.g(p, "local gravity, m/s^2 (default 9.81, with an uncertainty of 5e-3 relative)", default=None)
    flags.premises(p)
    flags.json(p)
    p.add_argument("--plot", metavar="FILE.png")
    p.add_argument("--report", metavar="DIR", help="DIR/index.html (one self-contained page: verdicts, premises, "
                   "selection steps, estimates, plot, the command, inputs SHA-256), DIR/report.md, and the extended "
                   "model's generated module and derivation")
    return p


def run(args):
    """`garant diagnose`: parse, call the job, print; the exit status."""
    from .. import models
    from ..io import plots, report
    from ..workflows import diagnose, jobs
    names = models.layout(models.load(args.model))[0]
    t0 = time.perf_counter()
    res = jobs.diagnose(args.model, args.data, args.sigma, g=args.g, g_uncertainty=args.g_uncertainty, prior=args.prior,
                        bound=dict(args.bound))
    study = res.study
    print(f"current model: minimax residual less the proven linearisation remainder (<= "
          f"{res['remainder_bound'] / args.sigma:.2f} sigma) is {res['max_residual_before'] / args.sigma:.2f} sigma: "
          + ("consistent" if res["consistent_before"] else "INCONSISTENT"))
    print(f"premises: {res['premises']['statement']}")
    if res["disagreements"]:
        worst = sorted(res["disagreements"], key=lambda d: -d["excess_over_sigma"])[:8]
        report.table(("position", *(f"{a}_deg" for a in names), "component", "residual/sigma"),
                     [(d["position"], *(f"{d[a + '_deg']:g}" for a in names), d["component"],
                       f"{d['residual'] / args.sigma:+.2f}") for d in worst])
        print(f"({len(res['disagreements'])} residual components exceed the limit; largest shown)")
    for h in res["history"]:
        print(f"step {h['step']}: " + ", ".join(f"{e} {v / args.sigma:.2f}" for e, v in
                                               sorted(h["scores"].items(), key=lambda kv: kv[1])))
    if res.get("thermal_degree"):
        td = res["thermal_degree"]
        print("chamber temperatures: " + "; ".join(
            f"degree {t['degree']} in T: " + ("consistent" if t["consistent"] else "not identified" if
                                               t["consistent"] is None else "INCONSISTENT") for t in td["tried"])
              + (f" -> each block parameter needs a polynomial of degree {td['needed']} in T: garant estimate ... "
                 f"--thermal-degree {td['needed']}" if td["needed"] else " -> no degree up to 3 makes them consistent"))
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
                          + f") [differ by {p['predicted_difference'] / args.sigma:.1f} sigma]"
                          for p in s["positions"]))
    print(f"after: minimax residual {res['max_residual_after'] / args.sigma:.2f} sigma (limit 1 + "
          f"{res['effect_allowance'] / args.sigma:.2f}: the added effects' rows are taken at zero errors): "
          + ("consistent" if res["consistent_after"] else "still INCONSISTENT"))
    print("this plan is blind to: " + (", ".join(res["blind_to"]) or "nothing in the catalogue"))
    for e, why in res["skipped"].items():
        print(f"not tried: {e} ({why})")
    print(f"diagnosis took {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    if args.report:
        for f in diagnose.write_module(study, res["effects"], args.report):
            print(f"wrote {f}")
        _report(res, args, names)
    if args.plot:
        plots.diagnosis(res, args.plot, f"{args.data}: residuals before and after")
    if args.json:
        report.write_json(args.json, res)
    return Exit.OK


def _report(res, args, names):
    """DIR/index.html and DIR/report.md: the verdicts before and after, the premises, where the data
    disagree, each selection step, the effects added with their estimates, and the residual plot."""
    from pathlib import Path

    from ..io import plots, report
    s = args.sigma
    plots.diagnosis(res, Path(args.report) / "residuals.png", f"{args.data}: residuals before and after")
    def verdict(key, ok):
        return (f"minimax residual {res[key] / s:.2f} sigma (less the proven remainder, <= "
                f"{res['remainder_bound'] / s:.2f} sigma): " + ("**consistent**" if ok else "**INCONSISTENT**"))
    sections = [("Current model", verdict("max_residual_before", res["consistent_before"])),
                ("Premises", res["premises"]["statement"])]
    if res["disagreements"]:
        worst = sorted(res["disagreements"], key=lambda d: -d["excess_over_sigma"])[:20]
        sections.append((f"Where the data disagree ({len(res['disagreements'])} components; the largest 20)",
                         report.Table(
            ("position", *(f"{a} (deg)" for a in names), "component", "residual / sigma"),
            [(d["position"], *(f"{d[a + '_deg']:g}" for a in names), d["component"], f"{d['residual'] / s:+.2f}")
             for d in worst])))
    if res["history"]:
        sections.append(("Selection: the worst residual (units of sigma) with each candidate effect added",
                         report.Table(
            ("step", "effect", "worst residual / sigma"),
            [(h["step"], e, f"{v / s:.2f}") for h in res["history"]
             for e, v in sorted(h["scores"].items(), key=lambda kv: kv[1])])))
    if res["effects"]:
        sections.append(("Effects added: " + ", ".join(res["effects"]), report.Table(
            ("parameter", "estimate", "guaranteed error", "unit", "combination"),
            [(k, f"{v['value']:+.4e}", f"{v['bound']:.3e}", v["unit"], v["q"]) for k, v in res["estimates"].items()])))
    notes = ["indistinguishable on this plan: " + " / ".join(g) for g in res["indistinguishable"]]
    notes += [f"to separate {' and '.join(x['effects'])}, measure at ({', '.join(names)}) = " + "; ".join(
        "(" + ", ".join(f"{p[a + '_deg']:g}" for a in names) + ")" for p in x["positions"])
        for x in res["separating_positions"]]
    notes += ["this plan is blind to: " + (", ".join(res["blind_to"]) or "nothing in the catalogue")]
    notes += [f"not tried: {e} ({why})" for e, why in res["skipped"].items()]
    sections += [("With the effects added", verdict("max_residual_after", res["consistent_after"])),
                 ("Notes", "; ".join(notes) + "."),
                 ("Residuals before and after (three components per position)", report.Image("residuals.png"))]
    command = report.command_line(args, f"garant diagnose --model {args.model} {args.data} --sigma {s:g}")
    inputs = [args.data, *([args.model] if str(args.model).endswith(".toml") else [])]
    print(f"wrote {report.write_page(args.report, f'Diagnosis: {args.data}', command, sections, inputs)}")
