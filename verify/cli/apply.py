"""garant apply: correct a raw log with a calibration, with the worst-case error of every sample."""
import os
import sys

from ..outcomes import Exit
from . import flags


def add(sub):
    """The `garant apply` subcommand and its flags."""
    p = sub.add_parser("apply", help="correct a raw log with a calibration (garant JSON): specific force in "
                                     "m/s^2 and its worst-case error per sample")
    p.add_argument("calibration", metavar="CAL", help="a garant-calibration-1 file (calibrate-norm --save), or a "
                   "batch's folder (calibrate-norm LOG... --out DIR): each log takes DIR/<its name>.json")
    p.add_argument("logs", metavar="LOG", nargs="+", help="a log; several (or --out): each corrected into --out DIR")
    flags.log_format(p)
    flags.sensor(p, "adxl355")
    p.add_argument("--imu", type=int, metavar="K", help="IMU K of a multi-IMU stream (--format mimu: 1-8), or the "
                   "accelerometer of a flight controller's log (ulog, dataflash: its number or device id)")
    p.add_argument("--rate", type=flags.rate, metavar="HZ", help="sample rate of a log of sample indices "
                   "(--format imucal: imucal's session)")
    p.add_argument("--trust-units", action="store_true",
                   help="apply even when the log's scale does not look like the calibration's raw unit (m/s^2 or "
                        "counts)")
    p.add_argument("--frame", choices=("garant", "imu_tk"), default="garant",
                   help="the frame of the corrected output: garant's (default), or that of the imu_tk export "
                        "(--export-imu-tk; for a norm calibration turned into imu_tk's upper-triangular T)")
    p.add_argument("--outside", choices=("drop", "refuse"), default="drop",
                   help="samples outside a calibration's temperature range (a warm-up's first ones, before its first "
                        "still interval): dropped and counted on the summary line (default), or the log refused")
    p.add_argument("--bound-over", choices=("set", "box"), default="set",
                   help="each sample's bound over the calibration's information set (default: the sharpest the "
                        "readings prove; LPs: seconds to minutes on a long moving log, progress said) or over its box "
                        "alone (fast, wider)")
    p.add_argument("--attitude", action="store_true",
                   help="also roll_rad, pitch_rad and their guaranteed bounds per sample, for still samples (a moving "
                        "sample's specific force is not its vertical): roll = atan2(ay, az), pitch = atan2(-ax, "
                        "hypot(ay, az)); docs/navigation.md")
    p.add_argument("-o", "--output", metavar="OUT.csv",
                   help="CSV: time_s (12 digits), ax, ay, az (m/s^2, 8 significant digits), bound_x, bound_y, "
                        "bound_z (m/s^2, worst case, 4 digits rounded up); - for standard output (the line that says "
                        "what was written then goes to standard error)")
    p.add_argument("--out", metavar="DIR", help="several logs: DIR/<log name>.csv each (as --output), a bad log "
                   "said on its line while the others go on; exit status 2 when any failed (the count printed)")
    return p


def _frame_said(args, path):
    """The output's frame in words, with its turn from the other one."""
    from ..io import calibration
    cal = calibration.read(path)
    turn = calibration.frame_turn_deg(calibration.imu_tk_form(cal)[2])
    if turn == 0:
        why = "a stand calibration" if cal["kind"] != "norm" else "M holds no turn"
        return f"garant's, which is also the imu_tk export's ({why})" if args.frame == "garant" else \
            f"the imu_tk export's, which is garant's ({why})"
    other = "--frame imu_tk" if args.frame == "garant" else "--frame garant"
    return (f"{'garant' if args.frame == 'garant' else 'the imu_tk export'}'s; the "
            f"{'imu_tk export' if args.frame == 'garant' else 'garant'} frame is turned {turn:.3g} degrees from it "
            f"({other})")


#: Samples corrected and written per piece: the output is never whole in memory.
CHUNK = 1 << 17


def run(args):
    """One log into --output, or several (or --out) each into DIR/<log name>.csv."""
    from ..errors import DataError, opt
    if len(args.logs) > 1 or args.out:
        if args.output:
            raise DataError(f"several logs: give {opt('out')} DIR (each log's CSV is DIR/<log name>.csv), not "
                            f"{opt('output')}")
        if not args.out:
            raise DataError(f"several logs: give {opt('out')} DIR for the corrected CSVs")
        return _batch(args)
    if not args.output:
        raise DataError(f"give {opt('output')} OUT.csv for the corrected log (-o - writes it to standard output)")
    if os.path.isdir(args.calibration):
        raise DataError(f"{args.calibration} is a folder: a batch's calibrations apply to several logs with "
                        f"{opt('out')} DIR; for one log give its calibration file")
    if args.output == "-" and getattr(sys.stdout, "stream", sys.stdout) is None:      # started with >&-
        raise DataError(f"-o -: standard output is closed; give {opt('output')} OUT.csv", param="output")
    said = _apply(args, args.calibration, args.logs[0], args.output)
    print(said, file=sys.stderr if args.output == "-" else sys.stdout)
    return Exit.OK


def _batch(args):
    """Each log corrected by the calibration (or by DIR/<its name>.json of a batch's folder) into
    --out/<its name>.csv; a log that fails is said on its line and the others go on."""
    from ..errors import DataError
    from ..io import files
    from ..workflows import batch
    folder = files.make_folder(args.out)
    failed = 0
    for k, (stem, log) in enumerate(zip(batch.stems(args.logs), args.logs), 1):
        cal = (os.path.join(args.calibration, os.path.splitext(os.path.basename(log))[0] + ".json")
               if os.path.isdir(args.calibration) else args.calibration)
        try:
            if not os.path.isfile(cal):
                raise DataError(f"no calibration {cal} for this log (the batch's folder holds one per log it "
                                f"calibrated)", param="calibration")
            print(f"[{k}/{len(args.logs)}] {_apply(args, cal, log, folder / f'{stem}.csv')}")
        except DataError as e:
            failed += 1
            print(f"[{k}/{len(args.logs)}] {log}: not corrected: {e}")
    print(f"{len(args.logs)} logs: {len(args.logs) - failed} corrected into {folder}, {failed} failed")
    return Exit.BAD_INPUT if failed else Exit.OK


def _apply(args, calibration, log, output):
    """Correct one log and write its CSV piece by piece (CHUNK samples at a time); the line that says so."""
    import numpy as np

    from ..io.report import write_chunks
    from ..io.text import csv_bytes
    from ..workflows import jobs
    from ..io import calibration as cal_io
    pieces = jobs.apply(calibration, log, format=args.format, sensor=args.sensor, imu=args.imu, rate=args.rate,
                        trust_units=args.trust_units, frame=args.frame, chunk=CHUNK, outside=args.outside,
                        bound_over=args.bound_over)
    worst, total, n, kind, dropped = np.zeros(3), 0.0, 0, cal_io.read(calibration)["kind"], 0

    def rows():
        nonlocal total, n, kind, dropped
        from ..workflows.budget import attitude
        yield b"time_s,ax,ay,az,bound_x,bound_y,bound_z" + (
            b",roll_rad,pitch_rad,roll_bound_rad,pitch_bound_rad" if args.attitude else b"") + b"\n"
        for c in pieces:
            np.maximum(worst, c.bound.max(axis=0, initial=0.0), out=worst)
            total, n, kind, dropped = total + c.bound.sum(), n + len(c.t), c.kind, dropped + c.outside
            if n >= CHUNK:                         # a log of more than one piece: progress, a line a piece
                print(f"apply: {n} samples corrected ...", file=sys.stderr, flush=True)
            extra = list(attitude(c.a, c.bound)) if args.attitude else []
            yield csv_bytes([c.t, *c.a.T, *c.bound.T, *extra], up=(4, 5, 6) + ((9, 10) if extra else ()),
                            digits=(12, 8, 8, 8, 4, 4, 4) + ((12, 12, 4, 4) if extra else ()))
    if output == "-":                            # a reader that stops (| head) ends the writing and the work
        written = 0
        try:
            for chunk in rows():
                sys.stdout.buffer.write(chunk)
                written = n
            sys.stdout.buffer.flush()
        except BrokenPipeError:
            sys.stdout.stopped = True
            return (f"standard output: the reader stopped after at most {written} corrected samples (the rest not "
                    f"corrected; -o OUT.csv writes the whole log) by {calibration} ({kind} calibration)")
    else:
        write_chunks(output, rows())
    return (f"wrote {'standard output' if output == '-' else output}: {n} samples corrected by {calibration} "
            f"({kind} calibration)" + (f", {dropped} dropped as outside its temperature range (no bound holds there; "
                                       "--outside refuse refuses such a log)" if dropped else "")
            + f"; worst-case error per component up to {worst.max():.3e} m/s^2 (mean "
            f"{total / max(3 * n, 1):.3e}); frame: {_frame_said(args, calibration)}{_effects_said(calibration)}"
            + ("; roll and pitch hold for still samples only" if args.attitude else ""))


def _effects_said(path):
    """The catalogue effects the file takes out of each sample and those it does not carry, or nothing."""
    from ..io import calibration
    eff = calibration.read(path).get("effects")
    if not eff:
        return ""
    return ("; effects taken out of each sample: " + (", ".join(eff["names"]) or "none")
            + "".join(f"; not applied: {name} ({why})" for name, why in eff["not_applied"].items()))
