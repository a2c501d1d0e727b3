"""garant next: the position to measure next at the stand, how many are still needed, and when to stop."""
from ..outcomes import Exit
from . import flags


def add(sub):
    """The `garant next` subcommand and its flags."""
    p = sub.add_parser("next", help="the reachable position to measure next, the bounds before and after it, "
                       "and how many positions are still needed")
    p.add_argument("data", metavar="DATA.csv", help="the positions measured so far, as for estimate (a header "
                   "line alone at the start of a session)")
    flags.model(p)
    flags.sigma(p)
    p.add_argument("--target", type=flags.positive, metavar="T",
                   help="the guaranteed error wanted for every q (units of q); default: sigma times the stand's "
                        "optimal errors, reached by a plan of the fewest positions")
    p.add_argument("--grid", type=flags.positive, metavar="STEP", help="candidate positions every STEP degrees "
                   "(detents and ranges honoured); default: detents or quarter turns")
    p.add_argument("--max-candidates", type=flags.positive_int, metavar="N",
                   help="refuse a --grid of more than N candidate positions (times mountings; default as for plan)")
    p.add_argument("--search-seconds", type=flags.positive, metavar="S",
                   help="safety stop of the search for the fewest positions still needed (default as for plan; "
                        "the search itself is budgeted by nodes, the same on every machine)")
    flags.g(p, "local gravity, m/s^2 (default 9.81, with an uncertainty of 5e-3 relative)", default=None)
    flags.premises(p)
    p.add_argument("--mount", metavar="Q", help="target the block's parameters in mounting Q (e.g. +y+z+x; "
                   "(28)-(29) of 000, two-axis stand) instead of the q's")
    p.add_argument("--gamma", choices=("lower", "symmetric"), default="lower",
                   help="with --mount: how Gamma + hat(theta_k) is split (as estimate)")
    flags.json(p)
    p.add_argument("--plot", metavar="FILE.png", help="each q's guaranteed error over its target, now and after "
                   "the next position")
    return p


def run(args):
    """`garant next`: parse, call the job, print; the exit status (3 when the data so far refute sigma)."""
    from ..io import report
    from ..workflows import jobs
    res = jobs.next_position(args.model, args.data, args.sigma, g=args.g, g_uncertainty=args.g_uncertainty,
                             prior=args.prior, bound=dict(args.bound), mount=args.mount, gamma=args.gamma,
                             target=args.target, grid=args.grid, search_seconds=args.search_seconds,
                             max_candidates=args.max_candidates)
    if args.json:
        report.write_json(args.json, res)
    _print(res, args)
    if args.plot:
        from ..io import plots
        state = ("done" if res["done"] else "the data refute sigma" if res["consistent"] is False else
                 "next: " + ", ".join(f"{v:g}" if not isinstance(v, str) else v for v in res["next"]))
        plots.bounds_before_after(res["names"], res["guaranteed_error_before"],
                                  res["guaranteed_error_after"] if res["next"] is not None else None,
                                  res["target"], args.plot, f"{args.data}: {len(res['measured'])} position(s) "
                                                            f"measured, "
                                  + state)
        print(f"wrote {args.plot}")
    if res["consistent"] is False or res.get("premises_refuted"):
        return Exit.REFUTED
    return Exit.OK


def _print(res, args):
    from ..io import report
    fmt = (lambda v: "no estimator yet" if v is None else f"{v:.3e}")          # noqa: E731
    after = res["guaranteed_error_after"] or [None] * len(res["names"])
    report.table(("q" if res["names"][0] == "q1" else "parameter", "target", "guaranteed error now", "after the next "
        "position"),
                 [(q, f"{t:.3e}", fmt(b), "-" if res["done"] else fmt(a))
                  for q, t, b, a in zip(res["names"], res["target"], res["guaranteed_error_before"], after)])
    print(f"{res['of']}; units: dimensionless or rad; target: {res['target_source']}; sigma = {res['sigma']:g}; "
          f"{len(res['measured'])} distinct position(s) measured, {res['candidates']} reachable candidates; "
          f"bounds now: {res['bounds_from']}")
    if res["consistent"] is False:
        print("the data so far refute sigma (as `garant estimate` says): find the cause before measuring more")
        return
    if res.get("premises_refuted"):
        from .estimate import print_refuted
        print_refuted(res["premises_refuted"], "next")
        return
    if res["done"]:
        import shlex
        verdict = ("the readings are consistent with sigma" if res["consistent"] else
                   "no verdict yet (some q has no estimator)" if res["consistent"] is None else "")
        more = [x for k, v in (("g", args.g), ("g_uncertainty", args.g_uncertainty), ("prior", args.prior))
                if v is not None for x in (f"--{k.replace('_', '-')}", f"{v:g}")]
        more += [x for name, v in args.bound for x in ("--bound", f"{name}={v:g}")]
        print(f"done: every guaranteed error is at or below its target; {verdict}")
        print("calibrate: " + shlex.join(["garant", "estimate", "--model", str(args.model), str(args.data), "--sigma",
                                          f"{args.sigma:g}", *more, *(["--mount", args.mount] if args.mount else []),
                                          "--save", "CAL.json"]))
        return
    pos = res["next"]
    print("next position: " + ", ".join(f"{a} = {v:g} deg" for a, v in zip(res["angles"], pos))
          + (f", mounting {pos[-1]}" if len(pos) > len(res["angles"]) else ""))
    print(("positions still needed, this one included: " if res["still_needed_proven"]
           else "positions still needed, this one included: at least ") + f"{res['still_needed']}")
