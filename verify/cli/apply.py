"""garant apply: correct a raw log with a calibration, with the worst-case error of every sample."""
from ..io.recordings import FORMATS, SENSORS


def add(sub):
    """The `garant apply` subcommand and its options."""
    p = sub.add_parser("apply", help="correct a raw log with a calibration (garant JSON): specific force in "
                                     "m/s^2 and its worst-case error per sample")
    p.add_argument("calibration", metavar="CAL.json", help="a garant-calibration-1 file (calibrate-norm --save)")
    p.add_argument("log", metavar="LOG")
    p.add_argument("--format", choices=FORMATS, help="log format (guessed when omitted)")
    p.add_argument("--sensor", choices=sorted(SENSORS), default="adxl355", help="accelerometer of an OpenAXES log")
    p.add_argument("--imu", type=int, metavar="K", help="IMU K of a multi-IMU stream (--format mimu: 1-8)")
    p.add_argument("--trust-units", action="store_true",
                   help="apply even when the log's scale does not look like the calibration's raw unit (m/s^2 or counts)")
    p.add_argument("--frame", choices=("garant", "imu_tk"), default="garant",
                   help="the frame of the corrected output: garant's (default), or that of the imu_tk export "
                        "(--export-imu-tk; for a norm calibration turned into imu_tk's upper-triangular T)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.csv",
                   help="CSV: time_s (12 digits), ax, ay, az (m/s^2, 8 significant digits), bound_x, bound_y, "
                        "bound_z (m/s^2, worst case, 4 digits rounded up)")
    return p


def _frame_said(args):
    """The output's frame in words, with its turn from the other one."""
    from ..io import calibration
    cal = calibration.read(args.calibration)
    turn = calibration.frame_turn_deg(calibration.imu_tk_form(cal)[2])
    if turn == 0:
        return "garant's, which is also the imu_tk export's (a stand calibration)" if args.frame == "garant" else \
            "the imu_tk export's, which is garant's (a stand calibration)"
    other = "--frame imu_tk" if args.frame == "garant" else "--frame garant"
    return (f"{'garant' if args.frame == 'garant' else 'the imu_tk export'}'s; the "
            f"{'imu_tk export' if args.frame == 'garant' else 'garant'} frame is turned {turn:.3g} degrees from it "
            f"({other})")


#: Samples corrected and written per piece: the output is never whole in memory.
CHUNK = 1_000_000


def run(args):
    """Correct the log with the calibration and write the CSV piece by piece (CHUNK samples at a time)."""
    import numpy as np

    from ..io.report import write_chunks
    from ..io.text import csv_bytes
    from ..workflows import jobs
    pieces = jobs.apply(args.calibration, args.log, args.format, args.sensor, args.imu, args.trust_units, chunk=CHUNK,
                        frame=args.frame)
    worst, total, n, kind = np.zeros(3), 0.0, 0, ""

    def rows():
        nonlocal total, n, kind
        yield b"time_s,ax,ay,az,bound_x,bound_y,bound_z\n"
        for c in pieces:
            np.maximum(worst, c.bound.max(axis=0, initial=0.0), out=worst)
            total, n, kind = total + c.bound.sum(), n + len(c.t), c.kind
            yield csv_bytes([c.t, *c.a.T, *c.bound.T], up=(4, 5, 6), digits=(12, 8, 8, 8, 4, 4, 4))
    write_chunks(args.output, rows())
    print(f"wrote {args.output}: {n} samples corrected by {args.calibration} ({kind} calibration); "
          f"worst-case error per component up to {worst.max():.3e} m/s^2 (mean {total / max(3 * n, 1):.3e}); "
          f"frame: {_frame_said(args)}")
    return 0
