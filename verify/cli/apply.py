"""garant apply: correct a raw log with a calibration, with the worst-case error of every sample."""
from ..io.recordings import FORMATS, SENSORS


def add(sub):
    p = sub.add_parser("apply", help="correct a raw log with a calibration (garant JSON): specific force in "
                                     "m/s^2 and its worst-case error per sample")
    p.add_argument("calibration", metavar="CAL.json", help="a garant-calibration-1 file (calibrate-norm --save)")
    p.add_argument("log", metavar="LOG")
    p.add_argument("--format", choices=FORMATS, help="log format (guessed when omitted)")
    p.add_argument("--sensor", choices=sorted(SENSORS), default="adxl355", help="accelerometer of an OpenAXES log")
    p.add_argument("--imu", type=int, metavar="K", help="IMU K of a multi-IMU stream (--format mimu: 1-8)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.csv",
                   help="CSV: time_s, ax, ay, az (m/s^2), bound_x, bound_y, bound_z (m/s^2, worst case)")
    return p


def run(args):
    import numpy as np

    from ..io import calibration, recordings
    from ..io.report import write_text
    cal = calibration.read(args.calibration)
    log = recordings.read_log(args.log, args.format, args.sensor, args.imu)
    a, bound = calibration.apply(cal, log.raw)
    lines = ["time_s,ax,ay,az,bound_x,bound_y,bound_z"]
    lines += [",".join(f"{v:.10g}" for v in row) for row in np.column_stack([log.t, a, bound])]
    write_text(args.output, "\n".join(lines) + "\n")
    print(f"wrote {args.output}: {len(a)} samples corrected by {args.calibration} ({cal['kind']} calibration); "
          f"worst-case error per component up to {bound.max():.3e} m/s^2 (median {np.median(bound):.3e})")
    return 0
