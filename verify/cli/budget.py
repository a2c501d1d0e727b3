"""garant budget: what a calibration guarantees downstream (specific force, tilt, velocity, position, a filter's
bounds), over the information set; a calibration made elsewhere judged against the log it was made from."""
import sys

from ..outcomes import Exit
from . import flags


def add(sub):
    """The `garant budget` subcommand and its flags."""
    p = sub.add_parser("budget", help="what a calibration guarantees downstream: worst-case specific force, tilt, "
                                      "velocity and position error over the information set")
    p.add_argument("calibration", metavar="CAL", help="a garant calibration (calibrate-norm or estimate --save), or "
                   "with --log imu_tk's (its text file), imucal's (its JSON), PX4's .params or ArduPilot's .parm "
                   "(their constant accelerometer calibration)")
    p.add_argument("--log", metavar="LOG", help="judge CAL against this log's information set (the log it was made "
                   "from, or any static log of the same unit), garant's calibration of it beside")
    flags.log_format(p)
    flags.sensor(p, "adxl355")
    p.add_argument("--imu", type=flags.count, metavar="K", help="a flight log's accelerometer (its number or device "
                   "id), whose slot of a parameter file CAL is judged; with another log, the slot's number (PX4's "
                   "CAL_ACCK, ArduPilot's IMU K + 1)")
    flags.g(p, "local gravity, m/s^2, for the log's calibration (default 9.81, |Delta_g/g| <= 5e-3)", None)
    p.add_argument("--g-uncertainty", type=flags.small, metavar="U", help="the bound on |Delta_g/g| (default 1e-5 "
                   "with --g, 5e-3 without)")
    p.add_argument("--bound", action="append", type=flags.named_bound, metavar="NAME=RAD", default=[],
                   help="as calibrate-norm: a misalignment's a-priori bound (alpha, beta, gamma; rad) for a log of six "
                        "faces, a premise of the log's set")
    p.add_argument("--rate", type=flags.rate, metavar="HZ", help="sample rate of a log of sample indices "
                   "(--format imucal: imucal's session)")
    flags.json(p)
    p.add_argument("--report", metavar="DIR", help="DIR/index.html (one self-contained page: the figures in a table, "
                   "what they mean, the premises, the command, inputs SHA-256) and DIR/report.md")
    return p


def run(args):
    """`garant budget`: compute, print the table, write --json; the exit status (REFUTED when the readings refute
    the calibration judged)."""
    from ..io import report
    from ..workflows import jobs
    res = jobs.budget(args.calibration, log=args.log, g=args.g, g_uncertainty=args.g_uncertainty, format=args.format,
                      sensor=args.sensor, imu=args.imu, bound=dict(args.bound) or None, rate=args.rate,
                      progress=progress)
    _print(res)
    if args.json:
        report.write_json(args.json, res)
        print(f"wrote {args.json}", file=sys.stderr)
    if args.report:
        command = report.command_line(args, f"garant budget {args.calibration}")
        inputs = [args.calibration] + ([args.log] if args.log else [])
        print(f"wrote {report.write_page(args.report, _title(res), command, sections(res), inputs)}", file=sys.stderr)
    return Exit.REFUTED if res["refuted"] else Exit.OK


def progress(done, total):
    """budget's progress line on standard error (about every 1,024 attitudes)."""
    if done == total or done % 1024 < 256:
        print(f"budget: {done} of {total} attitudes ...", file=sys.stderr, flush=True)


def downstream(res, name):
    """The sections a calibration's own report page (calibrate-norm or estimate --report) gives its budget: what
    the calibration `res["calibration"]` guarantees downstream, over its own information set, in the table `garant
    budget` prints; where it carries no set or is a kind budget does not take, one line saying so."""
    from ..errors import DataError
    from ..io import calibration, report
    from ..workflows import budget
    if not res.get("consistent") or "calibration" not in res:
        return []
    heading = "What the calibration guarantees downstream (garant budget)"
    try:
        bud = budget.own(calibration.checked(res["calibration"], name), name, progress)
    except DataError as e:
        return [(heading, f"No budget on this page: {str(e).removeprefix(name + ': ')}.")]
    head, rows = _table(bud)
    said = ("Every figure is the worst case over every attitude of a still unit and every unit the readings allow "
            "(the information set), under the premises above.")
    return [(heading, said), ("The downstream figures", report.Table(head, rows)),
            ("What each downstream figure means", report.Bullets(MEANING))]


def _title(res):
    return f"What {res['calibration']} guarantees downstream" + (f", judged against {res['log']}" if res["log"] else "")


def sections(res):
    """The budget as report sections (io/report.py): what it says, the table, what each row means, the
    premises one a line."""
    from ..io import report
    head, rows = _table(res)
    said = ("Every figure is the worst case over every attitude of a still unit and every unit the readings allow "
            "(the information set): what the calibration guarantees if the premises below hold.")
    if res["refuted"]:
        r = res["refuted"]
        said += (f" **Refuted**: the readings rule this calibration out (still interval {r['interval']} needs "
                 f"{r['times_its_bound']:.3g} times its bound for it).")
    if res["frame_turn_deg"]:
        said += (f" Its frame is turned {res['frame_turn_deg']:.3g} degrees into garant's convention; the turn is not "
                 "counted as error (the norm relation cannot see it).")
    return [("What it says", said), ("The figures", report.Table(head, rows)),
            ("What each row means", report.Bullets(MEANING)),
            ("Premises", report.Bullets(report.clauses(res["premises"].removeprefix("the bounds hold if "))))]


#: What each row of the table means, for a reader who is not a specialist.
MEANING = ("specific force error: how far a corrected reading can be from the true specific force, at any attitude "
           "(1 mg = 9.80665e-3 m/s^2)",
           "tilt error: how far the vertical the corrected accelerometers give a still unit can be from the true one; "
           "pitch errs by at most it, roll by at most it divided by cos(pitch)",
           "velocity and position: what that error alone builds up over 1, 10 and 60 s of integration with the "
           "attitude held: not a navigation solution (no attitude, gyroscope or noise error is in it)",
           "a filter's bounds: the bias and scale error a navigation filter's accelerometer model can take")


def _table(res):
    """(headers, rows) of the figures: one column per calibration."""
    cols = [res] + ([res["garant"]] if res["garant"] else [])
    span = res.get("temperature_range_c")
    head = ["worst case over every attitude" + (f" and {span[0]:.4g} to {span[1]:.4g} C" if span else ""),
            "this calibration"] + (["garant's of the log"] if res["garant"] else [])
    rows = [["specific force error, m/s^2 (mg)"] + [f"{c['specific_force_error_mps2']:.3g} "
                                                    f"({c['specific_force_error_mg']:.3g})" for c in cols],
            ["  per axis x, y, z, m/s^2"] + [", ".join(f"{x:.2g}" for x in c["per_axis_error_mps2"]) for c in cols],
            ["tilt error, mrad (deg)"] + [f"{1e3 * c['tilt_error_rad']:.3g} ({c['tilt_error_deg']:.2g})" for c in cols]]
    for T in res["horizons_s"]:
        rows.append([f"after {T} s: velocity m/s, position m"] + [
            f"{c['velocity_error_mps'][str(T)]:.3g}, {c['position_error_m'][str(T)]:.3g}" for c in cols])
    rows += [["a filter's bias bound x, y, z, m/s^2"] + [", ".join(f"{x:.2g}" for x in c["bias_bound_mps2"])
                                                        for c in cols],
             ["a filter's scale bound x, y, z, ppm"] + [", ".join(f"{1e6 * c['slope_bound'][k][k]:.3g}"
                                                                  for k in range(3)) for c in cols]]
    return head, rows


def _print(res):
    """The figures as a table a non-specialist reads: one column per calibration."""
    from ..io import report
    judged = f" judged against {res['log']}" if res["log"] else " over its own information set"
    turn = (f"; its frame turned {res['frame_turn_deg']:.3g} deg into garant's convention (not counted: the norm "
            "relation cannot see a turn)" if res["frame_turn_deg"] else "")
    slot = f" {res['calibration_slot']}" if res.get("calibration_slot") else ""
    print(f"budget of {res['calibration']} ({res['calibration_kind']}{slot}){judged}{turn}")
    if res["refuted"]:
        r = res["refuted"]
        print(f"  REFUTED: the readings rule this calibration out: still interval {r['interval']} needs "
              f"{r['times_its_bound']:.3g} times its noise bound plus remainder for it")
    head, rows = _table(res)
    report.table(head, rows)
    print("  tilt: the angle of the vertical (pitch errs by at most it, roll by at most it / cos(pitch)); velocity and "
          "position: the calibration error alone integrated with the attitude held, not a navigation solution")
    print(f"  these hold if {res['premises'].removeprefix('the bounds hold if ')}; g = {res['g']:g} m/s^2 within "
          f"|Delta_g/g| <= {res['g_uncertainty']:g}")
