"""garant estimate: q with guaranteed error bounds from readings at any positions ((6)-(8) of 000)."""
import sys

from ..outcomes import Exit
from ..errors import DataError
from . import flags
from . import exports



def add(sub):
    """The `garant estimate` subcommand and its flags."""
    p = sub.add_parser("estimate", help="estimate q with guaranteed bounds from readings at positions")
    p.add_argument("data", metavar="DATA.csv", help="CSV: <angle>_deg for each angle (alpha_deg,beta_deg on the "
                   "two-axis stand), f1,f2,f3 in m/s^2, and mount when the stand uses several mountings")
    flags.model(p)
    flags.sigma(p)
    flags.g(p, "local gravity, m/s^2 (default 9.81, with an uncertainty of 5e-3 relative)", default=None)
    p.add_argument("--format", choices=("imucal",), help="imucal: a Ferraris session (acc_x, acc_y, acc_z in m/s^2) "
                                                         "with "
                   "--sections or a part column, for --model six-face")
    p.add_argument("--sections", metavar="LIST.json", help="imucal's section list of the session (x_p, x_a, ...)")
    p.add_argument("--imu", type=int, metavar="K", help="IMU K of a means file with an imu column")
    p.add_argument("--run", dest="which_run", metavar="R", help="run R of a means file with a run column (exp or run)")
    p.add_argument("--mount", metavar="Q", help="mounting of the block, e.g. +y+z+x (block axis 1 along "
                   "table +y, ...): also report the block's physical errors, (28)-(29) of 000")
    p.add_argument("--gamma", choices=("lower", "symmetric"), default="lower",
                   help="convention that splits Gamma + hat(theta_k) (default lower-triangular Gamma)")
    flags.premises(p)
    flags.units(p)
    flags.json(p)
    p.add_argument("--plot", metavar="FILE.png", help="residuals of the minimax fit against each stand angle")
    p.add_argument("--report", metavar="DIR", help="DIR/index.html (one self-contained page: verdict, premises, "
                                                   "tables, what the calibration guarantees downstream (garant "
                                                   "budget), plots, the command, inputs SHA-256) and DIR/report.md")
    p.add_argument("--thermal-degree", type=int, choices=(1, 2, 3), metavar="D",
                   help="each block parameter a polynomial of degree D (1-3) in T, the temp_c column (C): each q's "
                        "coefficients and one guaranteed "
                   "bound over the whole temperature range")
    p.add_argument("--thermal-plot", metavar="FILE.png", help="with --thermal-degree: each q(T) with its guaranteed "
                   "band over the range, and the estimate and bound at each chamber temperature")
    exports.add(p, "estimate")
    return p


def run(args):
    """`garant estimate`: parse, call the job, print; the exit status."""
    from .. import models
    from ..io import report
    from ..workflows import jobs
    if args.thermal_plot and args.thermal_degree is None:
        raise DataError("--thermal-plot needs --thermal-degree D", param="thermal_plot")
    exports.check(args, "estimate")
    res = jobs.estimate(args.model, args.data, args.sigma, g=args.g, g_uncertainty=args.g_uncertainty, prior=args.prior,
                        bound=dict(args.bound), mount=args.mount, gamma=args.gamma, imu=args.imu,
                        which_run=args.which_run, format=args.format, sections=args.sections,
                        thermal_degree=args.thermal_degree,
                        progress=lambda text: print(f"estimate: {text} ...", file=sys.stderr, flush=True))
    mod = (models.thermal(args.model, args.thermal_degree, res["thermal"]["t0_c"]) if "thermal" in res
           else models.load(args.model))
    wanted = exports.asked(args, "estimate", "calibration")
    if wanted and res["consistent"] and "calibration" not in res and not res.get("premises_refuted"):
        why = res.get("block_not_separated", "this model has no block parameters")
        raise DataError(f"{wanted[0].option}: {why}; nothing written", param=wanted[0].dest)
    if args.json:
        report.write_json(args.json, res)
    if (args.plot or args.report) and "residual_minimax" in res:
        from ..io import pages
        command = report.command_line(args, f"garant estimate --model {args.model} {args.data} --sigma "
                                            f"{args.sigma:g} --g {res['g']:g}")
        from .budget import downstream
        page = pages.estimate(res, mod.ANGLES, mod.Q_NAMES, args.sigma, args.data, args.model, args.plot, args.report,
                              command, lambda: downstream(res, args.data))
        if page:
            print(f"wrote {page}")
    code = print_verdict(res, mod, args.data) if not res["consistent"] else print_estimate(res, mod, args)
    flags.say_gravity(args.g is not None, res["premises"])
    return code


def print_verdict(res, mod, path):
    """The data refute sigma: one clear line, the smallest sigma they support, where they disagree."""
    s = res["sigma"]
    names = list(mod.ANGLES)
    if "repeated_disagree" in res:
        d = res["repeated_disagree"]
        print(f"INCONSISTENT: readings repeated at one position disagree by more than 2 sigma = {2 * s:g}: the data "
              f"refute sigma = {s:g} (they need sigma >= {res['sigma_min_supported']:.3g}); no bound is given. "
              f"{len(d)} position component(s), largest first: " + "; ".join(
                  f"position {x['position']} (" + ", ".join(f"{x[a + '_deg']:g}" for a in names)
                  + f") f{x['component']} spread {x['spread']:.3g}" for x in d[:5]))
        print(f"premises: {res['premises']['statement']}")
        return Exit.REFUTED
    how = ("the a-priori box, too wide for the remainder to contract from, split into pieces with the remainder proven "
           "over each: no q of any piece fits every reading within sigma" if res.get("split_refuted") else
           "no q fits every reading within sigma plus the proven remainder left after absorption into q "
           f"({res['remainder_left_bound']:.2e})")
    support = (f"the data support sigma >= {res['sigma_min_supported']:.3g} (to {res['sigma_min_tolerance']:.0%})"
               if res["sigma_min_supported"] > s else "the fit lies within sigma outside that box: it is the a-priori "
               "bounds that the data refute (raise them: --prior, --bound)")
    print(f"INCONSISTENT: the data refute sigma = {s:g} (or a premise): {how}; {support}. "
          "No bound is given. Look for the missing effect with `garant diagnose`.")
    print(f"premises: {res['premises']['statement']}")
    d = res["disagreements"]
    if not d:
        return Exit.REFUTED
    print(f"{len(d)} residual components disagree, e.g. " + "; ".join(
        f"position {x['position']} (" + ", ".join(f"{x[a + '_deg']:g}" for a in names) + f") f{x['component']}"
        for x in d[:5]))
    return Exit.REFUTED


BOUNDS_LEGEND = (
    "guaranteed error: what these readings prove, the half-width of the set of q that fit every reading within sigma "
    "plus the proven remainder (the information set; estimate: its midpoint); a priori: what this plan guarantees for "
    "any readings within sigma, the optimal estimator's sigma sum |Phi| plus its remainder ((7)-(8) of 000; the "
    "guaranteed error never exceeds it); {wider}: the guaranteed error had sigma been that much larger (a "
    "sensitivity, the remainder as proven for sigma). The data fit "
    "within sigma >= {fit:.3g} ({ratio:.2f} sigma): the smaller the set, the more it rests on sigma being right")


def print_estimate(res, mod, args):
    """The consistent result: the premises, q with guaranteed errors, the block's errors, the files written."""
    from ..io import report
    print(f"consistent: the minimax residual of the exact model is {res['minimax_residual']:.3e} "
          f"({res['minimax_residual'] / args.sigma:.2f} sigma); linearised at that fit, the proven remainder left "
          f"after absorption into q is <= {res['remainder_left_bound']:.2e} per reading")
    print(f"premises: {res['premises']['statement']}")
    if res["premises"]["meaning"]:
        print(res["premises"]["meaning"])
    print(f"method: {res['method']}")
    parts = res["remainder_parts"]
    worst = max(parts, key=lambda k: max(parts[k].values()))
    print(f"remainder part of the errors, largest term: {worst.replace('_', ' ')} "
          f"(<= {max(parts[worst].values()):.1e})" + (
              ": the a-priori bounds of the parameters no plan separates (premises) set it; tighter bounds "
              "tighten it" if worst in ("unseparable", "absorbed_into_q") else ""))
    print("model: z = f/g - u(angles) = H^T q + rho, (1)-(3) of 000; q in the unit shown (1: dimensionless; a "
          "bias q is over g)")
    human = args.units == "human"
    bias = {q: d.split()[0].startswith("bias") for q, d in res["definitions"].items()}
    wider = f"sigma x{res['sigma_wider'] / res['sigma']:g}"
    report.table(("q", "definition", "estimate", "guaranteed error", "a priori", wider, "unit")
                 + (("estimate", "guaranteed error") if human else ()),
                 [(q, res["definitions"][q], f"{res['q'][q]:+.6e}", f"{res['guaranteed_error'][q]:.3e}",
                   f"{res['a_priori']['guaranteed_error'][q]:.3e}", f"{res['guaranteed_error_sigma_wider'][q]:.3e}",
                   res["units"][q]) + ((report.human(res["q"][q], res["units"][q], bias[q]),
                                        report.human(res["guaranteed_error"][q], res["units"][q], bias[q]).lstrip("+"))
                                       if human else ()) for q in mod.Q_NAMES])
    print(BOUNDS_LEGEND.format(wider=wider, fit=res["sigma_fit"], ratio=res["sigma_fit"] / res["sigma"]))
    for line in res["warnings"]:
        print(f"note: {line}")
    print(f"\n{res['positions']} positions ({res['distinct_positions']} distinct), g = {res['g']:g} m/s^2, "
          f"sigma = {args.sigma:g} (dimensionless, units of g)")
    if res.get("premises_refuted"):
        print_refuted(res["premises_refuted"], "estimate")
        return Exit.REFUTED
    if args.mount:
        print_physical(res)
    elif "block" in res:
        print_block(res, args.units == "human")
    elif "block_not_separated" in res:
        print(f"\nthe block: {res['block_not_separated']}")
    if "thermal" in res:
        print_thermal(res, args)
    exports.write(args, res, "estimate")
    return Exit.OK


def print_thermal(res, args):
    """Each q's polynomial in T with its one bound over the range, the largest bound at a chamber temperature
    beside it (the bound over the range is at least that), and the files asked for."""
    from ..io import report
    th = res["thermal"]
    t0, d = th["t0_c"], th["degree"]
    lo, hi = th["range_c"]
    print("\nover temperature: q(T) = c0 + " + " + ".join(f"c{k} (T - {t0} C)^{k}" if k > 1 else f"c1 (T - {t0} C)"
                                                        for k in range(1, d + 1))
          + f", one guaranteed bound over [{lo:g}, {hi:g}] C ({len(th['temperatures_c'])} chamber temperatures: "
          + ", ".join(f"{t:g}" for t in th["temperatures_c"]) + " C)")
    print(f"premise: {th['premise']}")
    constant = [q for q, dfn in res["definitions"].items() if q not in th["q"] and "_T" not in dfn]
    if constant:
        print(f"constant in T (no block parameter in them; their bounds above): {', '.join(constant)}")
    report.table(("q", "definition", *(f"c{k}" for k in range(d + 1)), "bound over range", "largest at a T", "unit"),
                 [(q, res["definitions"][q], *(f"{c:+.4e}" for c in th["q"][q]), f"{th['bound'][q]:.3e}",
                   f"{max(r['bound'] for r in th['at_temperature'][q]):.3e}", res["units"][q])
                  for q in th["q"]])
    print(f"c_k in the q's unit per C^k; bound over range: the largest |q(T) - q_hat(T)| over every q that fits the "
          f"readings, for every T in [{lo:g}, {hi:g}] C (Bernstein control points, each an LP proven by duality); "
          "largest at a T: the largest of the bounds at the chamber temperatures, which it cannot undercut")
    if args.thermal_plot:
        from ..io import plots
        plots.thermal(res, args.thermal_plot, f"{args.data}: q(T) with its guaranteed band")
        print(f"wrote {args.thermal_plot}")


def print_refuted(refuted, command):
    """The premises the data refute: each q wholly beyond what its parameters' stated bounds allow, with
    the parameters, their bounds and sources, and the option that states a wider bound."""
    print("\nPREMISE REFUTED: the readings fit sigma, but put these q beyond what the a-priori bounds allow; the "
          "bounds above assume those bounds and are not guaranteed (no calibration is given):")
    for r in refuted:
        named = ", ".join(f"|{p['name']}| <= {p['bound']:g} ({p['source']})" for p in r["parameters"])
        print(f"  {r['q']} = {r['definition']} = {r['estimate']:+.4e} +- {r['guaranteed_error']:.1e}, beyond "
              f"{r['allowed']:.3g} allowed by {named}")
    wider = " ".join(f"--bound {p['name']}={_wider(abs(r['estimate']) + r['guaranteed_error'])}"
                     for r in refuted for p in r["parameters"][:1])
    print(f"if the unit (or the stand) is that far off, state a wider bound and run again: "
          f"garant {command} ... {wider}")


def _wider(x):
    """A round bound above x: 1, 2 or 5 times a power of ten."""
    import math
    e = math.floor(math.log10(2 * x))
    return next(f"{m * 10.0 ** e:.0e}".replace("e-0", "e-") for m in (1, 2, 5, 10) if m * 10.0 ** e >= 2 * x)


def print_block(res, human=False):
    """The block's Gamma and biases with their bounds, and what each is confounded with."""
    from ..io import report
    blk, g = res["block"], res["g"]
    rows = [(f"Gamma{i + 1}{j + 1}", blk['Gamma'][i][j], blk['Gamma_bound'][i][j], "1", False)
            for i in range(3) for j in range(3)]
    rows += [(f"bias{i + 1}", g * blk['bias'][i], g * blk['bias_bound'][i], "m/s^2", True) for i in range(3)]
    print("\nthe block's errors as the stand's frame sees them (the mounting folded in; --mount gives them in the "
          "block's own axes, (28)-(29) of 000): f = (E + Gamma) a + bias, so a = (E + Gamma)^-1 (f - bias), f the "
          "readings and a the specific force (m/s^2); Gamma11 > 0: accelerometer 1 reads high")
    report.table(("parameter", "estimate", "guaranteed error", "unit") + (("estimate",
                                                                           "guaranteed error") if human else ()),
                 [(n, f"{v:+.6e}", f"{e:.3e}", u) + ((report.human(v, u, b), report.human(e, u, b).lstrip("+"))
                                                    if human else ()) for n, v, e, u, b in rows])
    with_ = {k: v for k, v in blk["confounded"].items() if v}
    if with_:
        print("confounded, so each bound holds that a-priori bound: " + "; ".join(
            f"{k} with " + ", ".join(f"{n} (<= {b:g}, {src})" for n, b, src in v) for k, v in with_.items()))


def print_physical(res):
    """The block's physical errors in its mounting, (28)-(29) of 000, with their bounds."""
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
