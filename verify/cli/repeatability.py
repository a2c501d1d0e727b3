"""garant repeatability: several runs of one sensor, compared against their own guaranteed bounds; the
effect named when they disagree, and the between-run envelope to expect of the next run."""
import sys

from ..outcomes import Exit
from . import flags


def add(sub):
    """The `garant repeatability` subcommand and its flags."""
    from ..defaults import MAX_RUNS
    p = sub.add_parser("repeatability", help="compare runs of one sensor against their guaranteed bounds; "
                       "name the effect when they disagree; the between-run envelope")
    p.add_argument("logs", metavar="LOG", nargs="+", help="one log per run, or a means file with a run column "
                   "(exp or run) holding every run")
    flags.log_format(p, ("means",), "; means: a positions file of per-position means (docs/formats.md)")
    flags.sensor(p)
    p.add_argument("--imu", metavar="K|all", help="IMU K of a multi-IMU stream or means file, or all of them")
    flags.g(p, "local gravity, m/s^2 (default 9.81)")
    p.add_argument("--params", type=int, choices=(9, 12), default=9, help="9 or 12 parameters (as calibrate-norm)")
    p.add_argument("--count", type=flags.small, metavar="STEP",
                   help="quantisation step of the readings a means file averaged, m/s^2, below 1 (the noise rule adds "
                   "half of it; a raw log states its own)")
    p.add_argument("--rate", type=flags.rate, metavar="HZ", help="sample rate of a means file's start_sample and "
                   "stop_sample columns (gives the runs a time, for the bias_drift effect)")
    p.add_argument("--max-runs", type=flags.positive_int, default=MAX_RUNS, metavar="N",
                   help=f"refuse more than N runs (default {MAX_RUNS}; the effect test grows with the square of the "
                        f"runs)")
    flags.json(p)
    p.add_argument("--plot", metavar="FILE.png", help="each parameter per run with its bound and the envelope")
    p.add_argument("--markdown", metavar="FILE.md", help="the tables and coverage figures as Markdown")
    p.add_argument("--report", metavar="DIR", help="DIR/index.html (one self-contained page: the tables, the "
                   "coverage, the effects, the plot, the command, inputs SHA-256) and DIR/report.md")
    return p


def _imus(args, fmt):
    from ..errors import DataError
    from ..io import means, mimu
    if args.imu is None:
        return [None]
    if args.imu == "all":
        if fmt == "mimu":
            return list(range(1, mimu.IMUS + 1))
        if fmt == "means":
            return means.imus(args.logs[0])
        raise DataError(f"--imu all applies to a multi-IMU stream or a means file, not to a {fmt} log", param="imu")
    try:
        return [int(args.imu)]
    except ValueError:
        raise DataError(f"--imu {args.imu!r}: give an IMU number or all", param="imu") from None


def _runs(args, fmt, imu):
    from ..errors import DataError
    from ..io import means, recordings
    from ..workflows.stills import still_intervals
    if fmt == "means":
        return [r for path in args.logs for r in means.read(path, imu, args.rate, args.count or 0.0)]
    if args.count or args.rate:
        raise DataError("--count and --rate apply to a means file; a raw log states its own", param="count")
    out = []
    for path in args.logs:
        try:
            log = recordings.read_log(path, fmt, args.sensor or "adxl355", imu)
            stills, _ = still_intervals(log)
        except DataError as e:                   # one unusable log is left out, said in one line
            out.append(means.Run(path, [], refused=str(e)))
            continue
        out.append(means.Run(path, stills, None, recordings.quantum(log)))
    return out


def run(args):
    """`garant repeatability`: parse, call the job, print; the exit status."""
    from .. import models
    from ..io import means, plots, recordings, report
    from ..workflows import repeatability
    fmt = args.format or ("means" if means.looks_like(args.logs[0]) else recordings.guess_format(args.logs[0]))
    mod = models.load("norm")
    results = {}
    imus = _imus(args, fmt)
    for k, imu in enumerate(imus, 1):
        label = f"IMU {imu}" if imu is not None else "sensor"
        if len(imus) > 1:
            print(f"[{k}/{len(imus)}] {label}", file=sys.stderr)
        runs = _runs(args, fmt, imu)
        results[label] = res = repeatability.run(mod, runs, args.g, args.params, args.max_runs)
        _print(label, res)
    if len(results) > 1:
        _summary(results)
    if args.json:
        report.write_json(args.json, results if len(results) > 1 else next(iter(results.values())))
    if args.plot:
        plots.repeatability(results, args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    command = report.command_line(args, "garant repeatability " + " ".join(args.logs))
    if args.markdown:
        report.write_text(args.markdown, report.markdown_page(_title(args), command, sections(results)))
        print(f"wrote {args.markdown}", file=sys.stderr)
    if args.report:
        from pathlib import Path

        from ..io import files
        files.make_folder(args.report)
        plots.repeatability(results, Path(args.report) / "runs.png")
        page = sections(results) + [("Each parameter per run with its bound; dashed: the envelope",
                                     report.Image("runs.png"))]
        print(f"wrote {report.write_page(args.report, _title(args), command, page, args.logs)}", file=sys.stderr)
    return Exit.OK if all("envelope" in r for r in results.values()) else Exit.REFUTED


def _fmt(v, e=None):
    return f"{v:+.3e}" + (f" ± {e:.1e}" if e is not None else "")


def _rows(res):
    rows = []
    for name in res["parameters"]:
        env = res["envelope"][name]
        rows.append([name] + [_fmt(r["parameters"][name], r["guaranteed_error"][name]) for r in res["runs"]]
                    + [f"[{env['lo']:+.3e}, {env['hi']:+.3e}]"])
    return ["parameter"] + [f"run {r['run']}" for r in res["runs"]] + ["envelope"], rows


def _print(label, res):
    from ..io import report
    print(f"\n{label}: {len(res['runs'])} runs, each calibrated by the norm relation with the noise rule")
    for x in res.get("refused_runs", []):
        print(f"  left out: {x['reason'] if x['reason'].startswith(x['log']) else x['log'] + ': ' + x['reason']}")
    if "inconsistent_runs" in res:
        print("  INCONSISTENT run(s), no comparison: " + ", ".join(res["inconsistent_runs"])
              + " (garant calibrate-norm --diagnose on each says why)")
        return
    report.table(*_rows(res))
    print("  (estimate ± guaranteed error per run; units: lambda 1, alpha/beta/gamma rad, eps over g)")
    print(f"  run pairs x parameters inside their per-run bounds: {res['coverage_per_run_bounds']:.1%}")
    print(f"  with the envelope, judged on runs left out of it: run pairs "
          f"{_pct(res['coverage_with_envelope_pairs'], PAIRS_NEED)}, each run against the envelope of the others "
          f"{_pct(res['coverage_with_envelope_leave_one_out'], OTHERS_NEED)}")
    print("  runs: " + "; ".join(f"{r['run']} {r['log']}" for r in res["runs"]))
    print("  effects, all runs fitted at once (worst exact residual in noise units; <= 1 is consistent): "
          + ", ".join(f"{x['effect']} {x['worst_in_noise_units']:.2f}" if "skipped" not in x
                      else f"{x['effect']} (skipped: {x['skipped']})" for x in res["effects"]))
    named = next((x for x in res["effects"] if x["effect"] == res["named_effect"]), None)
    if named is None:
        print("  no candidate makes the runs consistent: an effect outside the list, or noise bounds too tight")
    else:
        print(f"  named: {named['effect']}: {named['physics']}")
        for pair, ch in named["changes"].items():
            print(f"    {pair}: " + ", ".join(f"{k} {v:+.2e}" for k, v in ch.items()))
    out = [c for c in res["comparisons"] if not c["inside"]]
    if out:
        print(f"  outside the per-run bounds ({len(out)}): " + "; ".join(
            f"runs {c['runs'][0]}-{c['runs'][1]} {c['parameter']} {c['gap'] / c['bound']:.1f}x"
            + ("" if c.get("explained_by") else " UNEXPLAINED") for c in out))


#: Runs the envelope needs to be judged on runs left out of it: each pair against the envelope of the others
#: needs two others (4 runs), each run against the envelope of the others two (3 runs).
PAIRS_NEED, OTHERS_NEED = 4, 3


def _pct(x, need):
    return f"n/a (needs at least {need} runs)" if x is None else f"{x:.1%}"


def _coverage(results):
    import numpy as np
    ok = [r for r in results.values() if "envelope" in r]
    comps = [c for r in ok for c in r["comparisons"]]
    loo = [x for r in ok for x in r["envelope_judged"]["leave_one_out"]]
    pairs = [x for r in ok for x in r["envelope_judged"]["pairs"]]
    mean = lambda xs: float(np.mean([x["inside"] for x in xs])) if xs else None    # noqa: E731
    return comps, mean(comps), mean(pairs), mean(loo)


def _summary(results):
    from ..io import report
    print("\nsummary")
    rows = [[label, r.get("coverage_per_run_bounds", "inconsistent"), r.get("coverage_with_envelope_pairs"),
             r.get("coverage_with_envelope_leave_one_out"), r.get("named_effect"),
             len(r.get("unexplained", []))] for label, r in results.items()]
    report.table(["sensor", "pairs in per-run bounds", "pairs with envelope", "runs in envelope of others",
                  "named effect", "unexplained"],
                 [[_p(x) if x is None or isinstance(x, float) else x for x in row] for row in rows])
    comps, per_run, pairs, loo = _coverage(results)
    print(f"all: {per_run:.1%} of {len(comps)} run-pair x parameter comparisons inside the per-run bounds; with the "
          f"envelope {_pct(pairs, PAIRS_NEED)} (pairs), {_pct(loo, OTHERS_NEED)} (runs against the envelope of the "
          "others)")


def sections(results):
    """The comparison of the runs as report sections (io/report.py): the rules, the coverage of every
    sensor, then per sensor its table, the effects tried, the one named and the comparisons outside."""
    from ..io import report
    comps, per_run, pairs, loo = _coverage(results)
    first = next(iter(results.values()))
    out = [("Rules", f"Comparison: {first['comparison_rule']}. Envelope: {first['envelope_rule']}. Judged on runs left "
                     "out of it: each run pair (i, j) against e_i + e_j + D with D from the other runs, and each run "
                     "against the envelope of the others."),
           ("Coverage", report.Table(["sensor", "pairs inside per-run bounds", "pairs inside with the envelope",
                                      "runs inside the envelope of the others", "named effect", "unexplained"],
                                     [[k, _p(r.get("coverage_per_run_bounds")),
                                       _p(r.get("coverage_with_envelope_pairs")),
                                       _p(r.get("coverage_with_envelope_leave_one_out")),
                                       r.get("named_effect") or "none",
                                       len(r.get("unexplained", []))] for k, r in results.items()])),
           ("All sensors", f"{_p(per_run)} of {len(comps)} run-pair x parameter comparisons inside the per-run bounds; "
                           f"with the envelope {_p(pairs)} (pairs) and {_p(loo)} (runs against the envelope of the "
                           f"others).")]
    out.append(("Premises", "Each run's bounds are those of calibrate-norm, on its own premises; run 1 of "
                f"{next(iter(results))}: {first['runs'][0]['premises']['statement']}."))
    for label, res in results.items():
        if "envelope" not in res:
            out.append((label, "Inconsistent run(s): " + ", ".join(res["inconsistent_runs"])))
            continue
        out.append((f"{label}: estimate ± guaranteed error per run (lambda 1, alpha/beta/gamma rad, eps over g)",
                    report.Table(*_rows(res))))
        text = ["Effects, all runs fitted at once (worst exact residual in noise units): "
                + ", ".join(f"{x['effect']} {x['worst_in_noise_units']:.2f}" for x in res["effects"]
                            if "skipped" not in x) + "."]
        named = next((x for x in res["effects"] if x["effect"] == res["named_effect"]), None)
        if named and named["changes"]:
            text.append(f"Named: **{named['effect']}** ({named['physics']}); changes from run 1: "
                        + "; ".join(f"{pair}: " + ", ".join(f"{k} {v:+.1e}" for k, v in ch.items())
                                    for pair, ch in named["changes"].items()) + ".")
        outside = [c for c in res["comparisons"] if not c["inside"]]
        if outside:
            text.append("Outside the per-run bounds: " + "; ".join(
                f"runs {c['runs'][0]}-{c['runs'][1]} {c['parameter']} ({c['gap'] / c['bound']:.2f}x, "
                + (f"explained by {c['explained_by']})" if c.get("explained_by") else "UNEXPLAINED)")
                for c in outside) + ".")
        out.append((f"{label}: effects", " ".join(text)))
    return out


def _title(args):
    return "Repeatability: " + ", ".join(args.logs)


def _p(x):
    return "n/a" if x is None else f"{x:.1%}"
