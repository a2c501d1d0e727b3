"""garant calibrate-norm: a real static log calibrated through the norm relation (2.2) of 001."""
import os
import sys

from ..outcomes import Exit
from ..errors import FLAGS, DataError
from ..defaults import NORM_EFFECTS
from . import flags
from . import exports


def add(sub):
    """The `garant calibrate-norm` subcommand and its flags."""
    p = sub.add_parser("calibrate-norm", help="calibrate a real static log through the norm relation of 001")
    p.add_argument("logs", metavar="LOG", nargs="+", help="a log; several (or --out): a batch, one process, every core")
    flags.log_format(p)
    flags.sensor(p)
    p.add_argument("--imu", metavar="K|all", help="IMU K of a multi-IMU stream (--format mimu: 1-8; a flight "
                   "controller's log: its number or device id), or all of them "
                   "in turn (then --json holds one result per IMU)")
    flags.g(p, "local gravity, m/s^2 (default: 9.81 assumed, with |Delta_g/g| <= 5e-3 in the bounds)", default=None)
    p.add_argument("--g-uncertainty", type=flags.small, metavar="REL",
                   help="the bound on |Delta_g/g| (default 1e-5 with a local --g, 5e-3 without)")
    p.add_argument("--params", type=int, choices=(9, 12), default=9,
                   help="9: scale, misalignment, bias; 12: also the nonlinearity (pendulosity) of 001")
    p.add_argument("--window", type=flags.positive, default=1.0, help="moving-variance window, s")
    p.add_argument("--still-factor", "--k", dest="k", type=flags.positive, default=10.0,
                   help="still when the moving variance is below this factor times that of the first 5 s")
    p.add_argument("--min-still", type=flags.positive, default=2.0, help="shortest still interval kept, s")
    p.add_argument("--delta-sigma", type=flags.noise, metavar="D",
                   help="bound on |delta_sigma| of (2.2) (units of g) for the guaranteed errors; default: the "
                   "noise rule from the data (3 standard errors of each interval's mean plus half a count)")
    p.add_argument("--diagnose", action="store_true",
                   help="test the model against each interval's noise and try the effect catalogue")
    p.add_argument("--effect", metavar="NAME[,NAME...]", action="append",
                   help="add catalogue effects to the norm relation and calibrate them with it ("
                        + ", ".join(NORM_EFFECTS) + "; repeatable, the names join; --diagnose names the ones the data "
                        "need)")
    p.add_argument("--thermal-degree", type=int, metavar="D",
                   help="on a warm-up log with the IMU's own temperature (temp_c, C): the biases and scale factors "
                        "polynomials of degree D (1-3) in T, each still interval cut where T moves, one guaranteed "
                        "bound over the logged range; with --export-ardupilot / --export-px4")
    p.add_argument("--bound", action="append", type=flags.named_bound, metavar="NAME=RAD", default=[],
                   help="a misalignment's a-priori bound (alpha, beta, gamma; rad), repeatable: where every "
                        "orientation lies along an axis (six faces) the scale factors and biases are calibrated with "
                        "the misalignments held within it, a premise printed with the bounds")
    flags.units(p)
    flags.json(p)
    p.add_argument("--plot", metavar="FILE.png", help="residual per interval, before and after")
    p.add_argument("--report", metavar="DIR", help="DIR/index.html (one self-contained page: verdict, premises, "
                                                   "tables, what the calibration guarantees downstream (garant "
                                                   "budget), plots, the command, inputs SHA-256) and DIR/report.md")
    exports.add(p, "calibrate-norm")
    p.add_argument("--rate", type=flags.rate, metavar="HZ", help="sample rate of a log of sample indices "
                   "(--format imucal: imucal's session)")
    p.add_argument("--out", metavar="DIR", help="a batch's folder: DIR/<log>.json (each unit's calibration), "
                   "DIR/summary.csv and DIR/index.html (each unit's parameters, bounds, verdict)")
    p.add_argument("--jobs", type=flags.positive_int, metavar="N",
                   help="processes for a batch (default: every core); the files are the same whatever N")
    p.add_argument("--spec", metavar="SPEC.toml", help="the unit's specification ([limits], [bound_limits] of "
                   "scale, misalignment, bias; [nominal] sensitivity, counts per g, for logs in raw counts): each "
                   "unit a guaranteed pass, a fail or undecided, or retest where the log proves nothing, with the "
                   "reason")
    return p


def run(args):
    """`garant calibrate-norm`: parse, call the job, print; the exit status."""
    if args.thermal_degree is not None:
        from ..workflows.norm_thermal import check_degree
        check_degree(args.thermal_degree)
    exports.check(args, "calibrate-norm")
    if len(args.logs) > 1 or args.out:
        return _batch(args)
    if args.jobs or args.spec:
        raise DataError("--jobs and --spec apply to a batch: give several logs, or --out DIR", param="jobs")
    args.log = args.logs[0]
    if args.imu is None or args.imu != "all":
        if args.imu is not None:
            try:
                args.imu = int(args.imu)
            except ValueError:
                raise DataError(f"--imu {args.imu!r}: give an IMU number or all", param="imu") from None
        return _run(args)
    import copy

    from ..io import flight, mimu, recordings, report
    exports.refuse(args, "calibrate-norm", "writes one sensor's calibration: give one IMU with --imu K")
    for opt in ("plot", "report"):
        if getattr(args, opt):
            raise DataError(f"--{opt} is of one sensor: give one IMU with --imu K", param=opt)
    fmt = args.format or recordings.guess_format(args.log)
    each = (list(flight.instances(args.log, fmt)) if fmt in ("ulog", "dataflash", "rosbag")
            else range(1, mimu.IMUS + 1))
    results, codes = {}, []
    for k in each:
        print(f"\n== IMU {k}")
        one = copy.copy(args)
        one.imu, one.json = k, None
        try:
            codes.append(_run(one, results.setdefault(f"IMU {k}", {})))
        except DataError as e:                   # one sensor's log unusable: said, the others go on (as a batch)
            print(f"IMU {k}: not calibrated: {e}")
            results[f"IMU {k}"] = {"error": str(e)}
            codes.append(Exit.BAD_INPUT)
    if args.json:
        report.write_json(args.json, results)
    return max(codes)


def _batch(args):
    """Many logs in one process (workflows/batch.py): each unit's calibration file in --out, the summary as
    CSV and a page, a progress line on standard error; the exit status is `batch_status`'s."""
    from ..io import files, pages, report
    from ..workflows import batch
    from ..workflows.norm_bounds import PARAM_LABELS
    exports.refuse(args, "calibrate-norm", "concerns one log: a batch writes each unit's calibration to --out DIR")
    single = [o for o in ("plot", "report", "json", "effect", "thermal_degree") if getattr(args, o)]
    if single or args.imu == "all" or args.diagnose:
        first = (single or ["imu all" if args.imu == "all" else "diagnose"])[0]
        flag = FLAGS.get(first, "--" + first.replace("_", "-"))
        raise DataError(f"{flag} concerns one log: a batch writes each unit's files to --out DIR",
                        param=first.split()[0])
    if not args.out:
        raise DataError("several logs: give --out DIR for each unit's calibration and the summary", param="out")
    spec = batch.read_spec(args.spec) if args.spec else None
    imu = int(args.imu) if args.imu is not None else None
    folder = files.make_folder(args.out)             # before any work: a folder that cannot hold them stops here
    earlier = [n for n in ["summary.csv", "index.html", *(f"{s}.json" for s in batch.stems(args.logs))]
               if os.path.lexists(folder / n)]
    if earlier:                                      # an earlier batch's results are kept, never replaced unseen
        raise DataError(f"{folder} already holds {earlier[0]}" + (f" and {len(earlier) - 1} more of this batch's "
                        "outputs" if len(earlier) > 1 else "") + " (an earlier batch?): give a new or empty --out "
                        "folder; nothing was calibrated", param="out")

    live = sys.stderr.isatty()

    def progress(done, total):                  # one line rewritten on a terminal, a line a step into a file
        print(("\r" if live else "") + f"calibrate-norm: {done}/{total} logs",
              end="" if live and done < total else "\n", file=sys.stderr, flush=True)
    rows = batch.calibrate_many(args.logs, args.jobs, spec, progress, g=args.g, params=args.params, format=args.format,
                                sensor=args.sensor, imu=imu, window=args.window, k=args.k, min_still=args.min_still,
                                delta_sigma=args.delta_sigma, g_uncertainty=args.g_uncertainty, rate=args.rate)
    names = batch.stems(args.logs)
    for stem, row in zip(names, rows):
        if row["result"] and row["result"].get("calibration"):
            row["file"] = f"{stem}.json"
            report.write_json(folder / row["file"], row["result"]["calibration"])
    head, table = batch.summary_rows(rows)
    report.write_text(folder / "summary.csv", _csv_text([head, *table]))
    counts = {s: sum(r["status"] == s for r in rows) for s in batch.STATUSES}
    verdicts = {v: sum(r.get("verdict") == v for r in rows) for v in batch.VERDICTS} if spec else {}
    said = (f"{len(rows)} logs: {counts[batch.CONSISTENT]} calibrated, {counts[batch.REFUTED]} refuted their noise "
            f"bound, {counts[batch.ERROR]} could not be calibrated" + (
                f"; against {args.spec}: {verdicts[batch.PASS]} pass (guaranteed), {verdicts[batch.FAIL]} fail, "
                f"{verdicts[batch.UNDECIDED]} undecided, {verdicts[batch.RETEST]} retest (the recording proves "
                "nothing of the unit)" if spec else ""))
    report.write_page(folder, f"Batch: {len(rows)} logs", report.command_line(args, "garant calibrate-norm ..."),
                      pages.batch_sections(rows, names, spec, args.spec, said, PARAM_LABELS[:9], batch.SPEC_KEYS),
                      args.logs)
    for row in rows:
        print(f"{row['log']}: {row['status']}" + (f", {row['verdict']} ({row['reason']})" if spec else
                                                  f": {row['message']}" if row["message"] else ""))
    print(said)
    print(f"wrote {folder}/summary.csv, {folder}/index.html and {counts[batch.CONSISTENT]} calibration file(s)")
    return batch_status(rows, spec is not None)


#: A batch's exit statuses, apart from 1 (a check failed), 2 (bad input) and 3 (refuted) of one log.
BATCH_JUDGED, BATCH_FAILED, BATCH_UNJUDGED = Exit.OK, Exit.SPEC_FAILED, Exit.RETEST


def batch_status(rows, judged):
    """0 every unit has a verdict (pass, fail or undecided; without --spec: every log calibrated), 4 some unit
    failed its specification, 5 some log could not be judged (not calibrated, or refuted its noise bound:
    retest), which outranks 4."""
    from ..workflows import batch
    if any(r["status"] != batch.CONSISTENT for r in rows):
        return BATCH_UNJUDGED
    return BATCH_FAILED if judged and any(r.get("verdict") == batch.FAIL for r in rows) else BATCH_JUDGED


def _csv_text(rows):
    """CSV text by the csv module: a cell with a comma, a quote or a line break is quoted; a text cell a spreadsheet
    would run as a formula (=, +, -, @, a tab or a return first, and not a number) gets a leading quote, as OWASP
    advises for CSV injection."""
    import csv
    import io

    def cell(v):
        if isinstance(v, str) and v[:1] in ("=", "+", "-", "@", "\t", "\r"):
            try:
                float(v)
            except ValueError:
                return "'" + v
        return v
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows([[cell(v) for v in row] for row in rows])
    return buf.getvalue()


def _run(args, into=None):
    from ..io import report
    from ..workflows import jobs
    res = jobs.calibrate_norm(args.log, g=args.g, g_uncertainty=args.g_uncertainty, delta_sigma=args.delta_sigma,
                              params=args.params, format=args.format, sensor=args.sensor, imu=args.imu, rate=args.rate,
                              window=args.window, k=args.k, min_still=args.min_still, diagnose=args.diagnose,
                              effects=args.effect, bound=dict(args.bound), thermal_degree=args.thermal_degree)
    if res.get("still_only"):
        return _still_only(res, args)
    _print(res, args)
    if args.json:
        report.write_json(args.json, res)
    if args.plot:
        from ..io import plots
        plots.norm_residuals(res, _log_of(args), args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    exports.write(args, res, "calibrate-norm")
    if args.report:
        from ..io import pages
        from .budget import downstream
        command = report.command_line(args, f"garant calibrate-norm {args.log} --params {args.params}")
        page = pages.norm(res, args.report, args.log, _log_of(args), command, lambda: downstream(res, args.log))
        print(f"wrote {page}")
    if into is not None:
        into.update(res)
    return Exit.OK if res["consistent"] else Exit.REFUTED


def _print(res, args):
    """The log, the calibration and the verdict, then the bounds (when consistent) and the diagnosis."""
    import numpy as np

    from ..io import pages, recordings
    if res["log_note"]:
        print(res["log_note"])
    if res["format"] == "openaxes":
        other = ", ".join(s for s in sorted(recordings.SENSORS) if s != res["sensor"])
        print(f"OpenAXES log: accelerometer {res['sensor']}"
              + ("" if args.sensor else f" (the default; --sensor {other} for the other)"))
    print(f"{args.log}: {res['samples']} samples over {res['duration_s']:.1f} s; {res['intervals']} still intervals "
          f"({res['still_note']})")
    print(f"calibration a = M (raw - b), {res['intervals']} still intervals, {res['iterations']} iterations "
          f"({res['start']})")
    print("M (m/s^2 per raw unit):")
    for row in res["matrix"]:
        print("   " + "  ".join(f"{v:+.6e}" for v in row))
    print("b (raw units): " + "  ".join(f"{v:+.6e}" for v in res["bias"]))
    from ..io import calibration
    T, K, R = calibration.imu_tk_form({"M": res["matrix"], "kind": "norm"})
    print(f"as --export-imu-tk writes it, X' = T K (X - B), B = b, in imu_tk's frame (T upper triangular), turned "
          f"{calibration.frame_turn_deg(R):.3g} degrees from garant's (apply --frame imu_tk gives that frame; the "
          "default is garant's): T =")
    for row in T:
        print("   " + "  ".join(f"{v:+.6e}" for v in row))
    print("K = diag(" + "  ".join(f"{v:.6e}" for v in np.diag(K)) + ")")
    dsig = res["delta_sigma_max"]
    source = res["delta_sigma_source"]
    source = "the noise rule (statistical, not guaranteed: the premises below say it)" if source.startswith(
        "noise rule") else source                            # each premise printed once
    print(f"noise bound delta_sigma_max = {dsig:.3e} (x g = {dsig * res['g']:.3e} m/s^2), from {source}; proven "
          f"remainder {res['remainder_bound']:.1e}")
    print(f"premises: {res['premises']['statement']}")
    flags.say_gravity(res["g_given"], res)
    print(f"verdict: the worst still interval's residual is {res['worst_over_bound']:.3f} of its own bound (its noise "
          "bound plus the proven remainder) at the fit minimax in those units -> "
          + ("consistent" if res["consistent"] else
             f"INCONSISTENT: no correction of the relation meets every interval's bound, so the data refute the "
             f"noise bound; no bound is given. {len(res['disagreements'])} still interval(s) lie beyond their bound at "
             f"that fit. A uniform --delta-sigma would need at least {res['sigma_min_supported']:.3e} (units of g). "
             "Try --diagnose."))
    if "model_discrepancy" in res:
        print(pages.discrepancy(res))
    if not res["consistent"]:
        print(refutations(res))
    if res["consistent"]:
        _print_bounds(res, args)
    if "diagnosis" in res:
        _print_diagnosis(res["diagnosis"], args.params, args)


def refutations(res, count=12):
    """The intervals that refute their noise bound, each with its residual at the best fit and its own bound (the
    noise rule's or the stated one, and the remainder), units of g."""
    rows = res["per_interval"]
    parts = []
    for k in res["disagreements"][:count]:
        r = rows[k - 1]
        parts.append(f"{k} ({r['start_s']:.1f}-{r['stop_s']:.1f} s): |{r['residual_after_ms2'] / res['g']:.3e}| > "
                     f"{r['noise_bound']:.3e} ({r['noise_source']}) + {r['bound'] - r['noise_bound']:.1e}")
    more = len(res["disagreements"]) - count
    return ("refuting intervals (residual at the best fit > its noise bound + remainder, units of g): " + "; ".join(
        parts) + (f"; and {more} more" if more > 0 else ""))


def _with_effect(args, names):
    """The user's command with --diagnose dropped and --effect NAMES set: what to run next."""
    import shlex
    argv = list(getattr(args, "argv", None) or ["calibrate-norm", args.log])
    out, skip = [], False
    for a in argv:
        if skip:
            skip = False
            continue
        if a == "--diagnose" or a.startswith("--effect="):
            continue
        if a == "--effect":
            skip = True
            continue
        out.append(a)
    return "garant " + shlex.join(out + ["--effect", ",".join(names)])


def _print_diagnosis(d, params, args):
    print(f"\nmodel discrepancy (the noise bound from {d['noise_bound']}):")
    print(f"  {params}-parameter model: worst {d['max_residual_before']:.2f} of its bound, the verdict's (noise plus "
          "the proven remainder) -> " + ("consistent" if d["consistent_before"] else "INCONSISTENT"))
    if d["scores"]:
        print("  the effects screened to first order, the worst residual in units of each interval's noise bound alone "
              "(stricter than the verdict); each set named is then checked by its whole calibration:")
    for step in d["scores"]:
        ranked = sorted(step.items(), key=lambda kv: kv[1])
        print("  try: " + "; ".join(f"{k} {v:.1f}" for k, v in ranked[:6])
              + (f"; and {len(ranked) - 6} more sets" if len(ranked) > 6 else ""))
    cands = d.get("candidates", {})
    if len(cands) > 1:
        print("  candidates, each consistent to first order (worst residual over the noise bound): "
              + "; ".join(f"{k} {v:.2f}" for k, v in cands.items())
              + ": these data do not single one out by fit; each is checked by its whole calibration, fewest "
                "parameters first. To tell them apart: temperature terms by a wider temperature range, or heating then "
                "cooling; terms in time by a longer log; terms in the orientation by more orientations (garant plan "
                "--model norm lists them)")
    for names, said in d.get("checked", {}).items():
        print(f"  --effect {names}: {said}")
    if d.get("add"):
        print("  named: " + ", ".join(d["named"]) + ", the fewest effects whose whole calibration is consistent"
              + ("" if d["first_order"] == d["named"] else
                 f" (to first order {', '.join(d['first_order'])} fit best, worst {d['max_residual_after']:.1f}; "
                 "its calibration is said above)"))
        for e, others in d["equivalent"].items():
            if others:
                print(f"  {e}: these orientations cannot tell it from {', '.join(others)} (beside the base model, "
                      "one's columns of (2.2) of 001 lie in the other's span); the data name the family, not the "
                      "member")
        print(f"  add them: {_with_effect(args, d['add'])}")
    elif d["named"]:
        print("  named to first order: " + ", ".join(d["named"]) + f" (worst {d['max_residual_after']:.1f}); no set "
              "calibrates with a proven remainder: the first-order fit is all the data say; state the noise bound you "
              "can stand behind (--delta-sigma), or record more orientations")
    elif not d["consistent_before"] and d["scores"]:
        print("  named: nothing in the catalogue makes the data consistent (sets of up to three tried; best worst "
              f"{d['max_residual_after']:.1f}): an effect outside the catalogue, or a noise bound too tight")
    many = d.get("too_many_parameters", {})
    if many and not d.get("add"):
        least = min(many.values())
        by_need = {}
        for k, v in many.items():
            by_need.setdefault(v, []).append(k)
        print(f"  not tried for want of intervals (a set of effects needs its parameters and the base's plus three "
              f"still intervals, or it fits anything; this log has {d['intervals']}): "
              + "; ".join(f"{len(ks)} set(s) need {v} ({ks[0]}{', ...' if len(ks) > 1 else ''})"
                          for v, ks in sorted(by_need.items()))
              + f". Record {least - d['intervals']} or more orientations (garant plan --model norm lists them; "
                "shuffled, on a warm-up) to try the smallest")
    if d["unseen"]:
        print("  unseen here: " + ", ".join(d["unseen"]) + " (the base parameters absorb them on these orientations)")
    for e, why in d["skipped"].items():
        if why != "needs stand angles":
            print(f"  not tried: {e} ({why})")


def _print_bounds(res, args=None):
    from ..io import pages, report
    pars = res["parameters"]
    if pars is None:
        print("parameters of (1.3): the log is in raw units, so only M and b above are estimated; the "
              "guaranteed errors below are those of (1.3)'s parameters of the calibrated block")
    print("model of 001, (1.1)-(1.3): f = (E + A) w + eps + B(w) w, A = [[lambda1, 0, 0], [alpha, lambda2, 0], "
          "[beta, gamma, lambda3]], w the specific force in block axes; the calibration inverts it, a = M (raw - b) "
          "with M ~ E - A: lambda1 > 0 means accelerometer 1 reads high, and M11 < 1")
    human = getattr(args, "units", "si") == "human"
    wider = f"delta_sigma x{res['sigma_wider']:g}"
    report.table(("parameter", "estimate", "guaranteed error", "a priori", wider, "on the optimal plan", "unit")
                 + (("estimate", "guaranteed error") if human else ()),
                 [(k, f"{pars[k]:+.4e}" if pars else "(raw units)", f"{v:.3e}",
                   f"{res['guaranteed_error_a_priori'][k]:.3e}", f"{res['guaranteed_error_sigma_wider'][k]:.3e}",
                   f"{res['guaranteed_error_optimal_plan'][k]:.3e}",
                   pages.unit(k)) + ((pages.side(k, pars[k]) if pars else "", pages.side(k, v).lstrip("+"))
                                     if human else ())
                  for k, v in res["guaranteed_error"].items()])
    print(f"guaranteed error: over the information set (every correction of the fit that meets each interval's noise "
          f"bound plus its remainder); a priori: the LP estimator's, what these orientations guarantee for any data "
          f"within the noise bound; {wider}: the guaranteed error had every interval's noise bound been that much "
          f"larger (a sensitivity, the remainder as proven). The data fit within a noise bound of "
          f"{res['sigma_min_supported']:.3e} (units of g, {res['sigma_min_supported'] / res['delta_sigma_max']:.2f} "
          "delta_sigma_max): the smaller the set, the more it rests on the noise bound being right")
    if res.get("effects"):
        _print_effects(res)
    if res.get("thermal"):
        _print_thermal(res)
    for line in leaning(res):
        print(f"note: {line}")
    gain = res["directions_gain"]
    if res["directions_to_add"]:
        print(f"\nadding {len(res['directions_to_add'])} orientation(s) would shrink the bound of {gain['parameter']} "
              f"{gain['factor']:.2f} times (the most of any parameter; unit vectors in sensor axes, -gravity "
              f"direction):")
        for d in res["directions_to_add"]:
            print("   (" + ", ".join(f"{v:+.3f}" for v in d["n"]) + f")  nearest present "
                                                                    f"{d['nearest_present_deg']:.0f} deg")
    elif gain["parameter"] is not None:
        print(f"\nno orientation to add: the optimal plan's missing ones would shrink no bound by "
              f"{gain['threshold']:g} "
              f"times or more (at most {gain['factor']:.2f}, for {gain['parameter']})")


def _still_only(res, args):
    """A still-only warm-up: each axis's drift in T with its bound, and what one orientation cannot separate."""
    from ..io import report
    why = "a still-only warm-up gives each axis's drift in this orientation, no calibration: turn the unit through " \
          "orientations while it warms"
    for e in exports.asked(args, "calibrate-norm"):          # the flight stacks' offset polynomials alone
        if e.takes != "thermal" or not res.get("thermal"):
            raise DataError(f"{e.option} is refused: {why}" + ("; --export-ardupilot and --export-px4 write the "
                            "offset polynomials under the scale-drift premise" if res.get("thermal") else ""),
                            param=e.dest)
    for opt in ("plot", "report"):
        if getattr(args, opt):
            raise DataError(f"--{opt} is refused: {why}", param=opt)
    lo, hi = res["range_c"]
    u = res["raw_unit"]
    print(f"{args.log}: {res['samples']} samples over {res['duration_s']:.1f} s, one orientation: "
          f"{res['intervals']} still pieces from {lo:.1f} to {hi:.1f} C (cut where the temperature moves)")
    print(f"premises: {res['premises']['statement']}")
    if not res["consistent"]:
        print("INCONSISTENT: no drift linear in T meets every piece within its noise rule")
        if args.json:
            report.write_json(args.json, res)
        return Exit.REFUTED
    print(f"each axis's raw reading r(T) = r(t0) + slope (T - {res['t0_c']:g} C), bounds over the information set:")
    report.table(("axis", f"r(t0) ({u})", "bound", f"slope ({u}/C)", "bound", f"over the range ({u})", "bound"),
                 [(a, f"{d['at_t0']:+.6e}", f"{d['at_t0_bound']:.2e}", f"{d['slope']:+.4e}", f"{d['slope_bound']:.2e}",
                   f"{d['over_range']:+.4e}", f"{d['over_range_bound']:.2e}") for a, d in res["drift"].items()])
    print(f"not separated: {res['not_separated']}")
    if res.get("thermal"):
        th = res["thermal"]
        sd = res["scale_drift"]
        print("the flight stacks' offset polynomial of each axis, relative to t0, with one bound over the range "
              "(m/s^2): " + ", ".join(f"{a} {res['g'] * th['bound'][f'bias{i + 1}']:.3e}" for i, a in enumerate("xyz"))
              + f"; premise: each entry of Gamma drifts by at most {sd['bound_per_c']:g} per C ("
              + ("--bound scale_drift" if sd["stated"] else "assumed, a typical MEMS datasheet figure: state the "
                 "sensor's with --bound scale_drift=S") + "), which one orientation cannot tell from a bias drift")
        exports.write(args, res, "calibrate-norm")
    if args.json:
        report.write_json(args.json, res)
    return Exit.OK


def _print_thermal(res):
    """--thermal-degree: each axis's raw bias and scale factor as a polynomial in T, one bound over the range."""
    from ..io import report
    th = res["thermal"]
    lo, hi = th["range_c"]
    d, t0 = th["degree"], th["t0_c"]
    print("\nover temperature (the IMU's, the log's temp_c): p(T) = c0 + "
          + " + ".join(f"c{k} (T - {t0:g} C)" + (f"^{k}" if k > 1 else "") for k in range(1, d + 1))
          + f", one guaranteed bound over [{lo:.1f}, {hi:.1f}] C, the logged range; in the raw axes, as the flight "
          "stacks correct them; c_k in the unit per C^k")
    report.table(("p", *(f"c{k}" for k in range(d + 1)), "bound over range", "unit of c0"),
                 [(k, *(f"{x:+.4e}" for x in c), f"{th['bound'][k]:.3e}", th["units"][k][0])
                  for k, c in th["q"].items()])
    print("bias_i: the raw bias over g (b_i / g at T); scale_i: Gamma_ii (P_ii - 1 at T, P = M^-1); bound over range: "
          "the largest |p(T) - p_hat(T)| over the information set for every T of the range (an LP pair at each end, "
          "proven by duality, and the bilinear part from the set's box)")


def _print_effects(res):
    """The effects added (--effect): each parameter with its estimate and guaranteed error over the same set."""
    from ..io import report
    ref = res["effect_reference"]
    from ..workflows.norm_effects import CONVENTION
    print(f"effects ({CONVENTION}; over g; time t from {ref['time_s']:g} s of the log, the middle of its still "
          f"intervals, so the biases above are those at that time; temperature T in C, (T - 20 C) read as T - "
          f"{ref['temp_c']:g} C):")
    rows = [(name, p, f"{v['estimate']:+.4e}", f"{v['guaranteed_error']:.3e}", f"{v['guaranteed_error_a_priori']:.3e}",
             v["unit"]) for name, e in res["effects"].items() for p, v in e["parameters"].items()]
    report.table(("effect", "parameter", "estimate", "guaranteed error", "a priori", "unit"), rows)
    for name, e in res["effects"].items():
        print(f"  {name}: {e['physics']}")


#: A set this many times below the a-priori bounds (median over the parameters) is said: it rests on the noise bound.
FAR_BELOW = 5.0


def leaning(res):
    """Lines for a set far below what the orientations guarantee a priori (the median ratio at least FAR_BELOW):
    the readings pin the parameters only as far as every interval's noise bound holds, and how much 10 % more
    would widen them."""
    import numpy as np

    from ..io.recordings import median                  # np.median would load numpy.ma: a tenth of a small run
    e = np.array(list(res["guaranteed_error"].values()))
    a = np.array([res["guaranteed_error_a_priori"][k] for k in res["guaranteed_error"]])
    w = np.array([res["guaranteed_error_sigma_wider"][k] for k in res["guaranteed_error"]])
    ratio = float(median(a / np.maximum(e, 1e-300)))
    if ratio < FAR_BELOW:
        return []
    return [f"the bounds are {ratio:.1f}x below what these orientations guarantee a priori (median): the readings "
            f"pin them only as far as every interval's noise bound holds; with each {res['sigma_wider']:g}x larger "
            f"they would be up to {float(np.max(w / np.maximum(e, 1e-300))):.1f}x wider. "
            + ("The stated --delta-sigma must hold for every interval" if res["delta_sigma_source"] == "--delta-sigma"
               else "State the noise bound you can stand behind (--delta-sigma) if the rule's is not")]


def _log_of(args):
    """(t, raw) of the log, read again for its plot (the calibration keeps only the still intervals)."""
    from ..workflows import jobs
    data = jobs.read_log(args.log, args.format, args.sensor, args.imu, args.rate)
    return data.t, data.raw


