"""The calibration files a command writes, one registry entry each: its option, what it takes, its checks, its writer.

A new export format is one `Export(...)` in EXPORTS, its writer in `verify/io/`, and its test: the commands
named in `commands` then offer the option (`add`), refuse it where it cannot be written (`check`, before any
work), write it (`write`), list it among the outputs checked before any work (`outputs`) and refuse it in a
batch or on a still-only warm-up.
"""
from dataclasses import dataclass

from ..errors import DataError


@dataclass(frozen=True)
class Export:
    """One calibration file a command can write."""

    option: str                 # the option that names the file, e.g. --export-imu-tk
    metavar: str
    what: str                   # the file in words, for messages ("the imu_tk calibration file")
    help: str
    commands: tuple             # the commands that offer it
    takes: str                  # "calibration" (the block's, when consistent), "thermal" (needs --thermal-degree) or
                                # "noise" (the log's noise figures: calibrate-norm only)
    temperature: bool = True    # whether it can carry a calibration in T (False: refused with --thermal-degree)
    effects: bool = True        # whether it carries the effects of --effect (False: a note says they are dropped)
    options: tuple = ()         # its own further options: (flags, argparse keywords), added with it
    check: object = None        # check(args) before any work, raising DataError
    write: object = None        # write(path, res, args) -> the line saying what was written

    @property
    def dest(self):
        """The argparse attribute of the option."""
        return self.option.lstrip("-").replace("-", "_")


def _save(path, res, args):
    from ..io import calibration
    calibration.write(path, res["calibration"])
    not_applied = res["calibration"].get("effects", {}).get("not_applied", {})
    return f"wrote {path}" + "".join(f"\nnote: {path} does not apply {n}: {why}" for n, why in not_applied.items())


def _imu_tk(path, res, args):
    from ..io import calibration
    calibration.write_imu_tk(path, res["calibration"])
    return f"wrote {path}"


def _imucal(path, res, args):
    from ..io import imucal, report
    gyro = imucal.read_calibration(args.imucal_gyro) if args.imucal_gyro else None
    report.write_json(path, imucal.calibration_json(res["calibration"], gyro))
    return f"wrote {path}" + ("" if gyro else " (gyroscope not calibrated: --imucal-gyro CAL.json carries an imucal "
                                              "calibration's)")


def _check_imucal(args):
    """--imucal-gyro read now (a bad file stops here)."""
    if args.imucal_gyro:
        from ..io import imucal
        imucal.read_calibration(args.imucal_gyro)


def _kalibr(path, res, args):
    from ..io import calibration, report
    walk, why = res["random_walk"], res["random_walk_note"]
    report.write_text(path, calibration.kalibr_text(res["noise_density"], res["rate_hz"], walk, args.kalibr_gyro,
                                                    args.kalibr_topic, why))
    missing = ([] if walk is not None else [f"accelerometer_random_walk ({why})"]) + (
        [] if args.kalibr_gyro else ["the gyroscope's two fields (--kalibr-gyro ND,RW)"])
    return f"wrote {path}" + (f"; Kalibr's reader also needs: {'; '.join(missing)}" if missing
                              else ": every field Kalibr's reader needs")


def _topic(text):
    """--kalibr-topic: a ROS graph name (letters, digits, _ and / separating them; at most 200 characters), so that
    the YAML holds it as one plain scalar: no key, newline or flow syntax can ride in it."""
    import argparse
    import re
    if not re.fullmatch(r"/?[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*", text) or len(text) > 200:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is no ROS topic name (letters, digits and _ between /, "
                                         "e.g. /imu0)")
    return text


def _gyro(text):
    """--kalibr-gyro ND,RW: two finite numbers > 0."""
    import argparse

    from .flags import positive
    parts = text.split(",")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"{text[:40]!r}: give ND,RW, e.g. 1.7e-4,1.9e-5")
    return tuple(positive(p) for p in parts)


def _ardupilot(path, res, args):
    from ..io import tcal
    log = res.get("flight") or {}
    imu = args.ardupilot_imu or (log["instance"] + 1 if log.get("stack") == "ardupilot" else 1)
    tcal.write(path, res, imu)
    return f"wrote {path} (IMU {imu}" + (", the log's accelerometer)" if args.ardupilot_imu is None and log else ")")


def _px4(path, res, args):
    """PX4's file for the device the user names or the ULog holds, in the slot the vehicle's parameters give it
    (io/flight.px4_slot) unless --px4-instance says; another TC_A slot holding the same id is cleared."""
    from ..io import flight, tcal
    log = res.get("flight") if (res.get("flight") or {}).get("stack") == "px4" else None
    device = args.px4_device_id if args.px4_device_id is not None else (log or {}).get("device_id")
    slot, cal, clear = flight.px4_slot(log, device) if log else (0, 0, [])
    if args.px4_instance is not None:
        slot = cal = args.px4_instance
        clear = [n for n in flight.holders(log, device) if n != slot]
    tcal.write_px4(path, res, slot, device, cal, clear)
    cal_rows = "" if res["thermal"].get("offsets_only") else f", CAL_ACC{cal}"
    said = f"wrote {path} (TC_A{slot}{cal_rows}, device id {device}"
    if log and args.px4_instance is None:
        said += ", the slots the log's parameters give it"
    return said + (")" if not clear else f"; TC_A{', TC_A'.join(map(str, clear))}_ID cleared: it held the same id)")


def _check_px4(args):
    """--export-px4 needs the device id PX4 matches: --px4-device-id, or a PX4 ULog that holds it."""
    if args.export_px4 and args.px4_device_id is None:
        from ..io import recordings
        from ..io.tcal import PX4_NEEDS_ID
        logs = getattr(args, "logs", None) or [getattr(args, "data", None)]
        try:
            fmt = getattr(args, "format", None) or recordings.guess_format(logs[0])
        except (OSError, TypeError):
            fmt = None
        if fmt != "ulog":
            raise DataError(PX4_NEEDS_ID, param="px4_device_id")


def _device_id(text):
    """A PX4 device id: PX4 stores it in an INT32 parameter, so an id of 2^31 or more (a uint32 device_id) is the
    negative number PX4 shows; ids beyond 32 bits are refused."""
    import argparse
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a whole number") from None
    if not -2 ** 31 <= v < 2 ** 32 or v == 0:
        raise argparse.ArgumentTypeError(f"{text[:40]} is no 32-bit device id (PX4 holds -2147483648 to 2147483647, "
                                         "or a uint32 device_id below 4294967296; not 0)")
    return v


BOTH = ("estimate", "calibrate-norm")

#: Every calibration file garant writes, in the order of --help.
EXPORTS = (
    Export("--save", "CAL.json", "the calibration file", "write the calibration (garant-calibration-1, "
           "docs/formats.md) for `garant apply`, from any stand; with --thermal-degree it holds the polynomials in T",
           BOTH, "calibration", write=_save),
    Export("--export-imu-tk", "FILE", "the imu_tk calibration file", "also write the calibration in imu_tk's form "
           "(T, K, B)", BOTH, "calibration", temperature=False, effects=False, write=_imu_tk),
    Export("--export-imucal", "FILE.json", "the imucal calibration file", "also write the calibration as imucal's "
           "FerrarisCalibrationInfo (load_calibration_info reads it); the bounds in its comment", BOTH, "calibration",
           temperature=False, effects=False,
           options=((("--imucal-gyro",), dict(metavar="CAL.json", help="the imucal calibration whose gyroscope part "
                     "--export-imucal carries (else the gyroscope is written as not calibrated)")),),
           check=_check_imucal, write=_imucal),
    Export("--export-kalibr", "FILE.yaml", "the Kalibr YAML", "write the IMU file Kalibr's reader takes (imu.yaml: "
           "rate, noise density, random walk; the gyroscope's from --kalibr-gyro, else written as missing)",
           ("calibrate-norm",), "noise",
           options=((("--kalibr-gyro",), dict(metavar="ND,RW", type=_gyro, help="the gyroscope's noise density "
                     "(rad/s/sqrt(Hz)) and random walk (rad/s^2/sqrt(Hz)) for --export-kalibr (an accelerometer log "
                     "does not measure them)")),
                    (("--kalibr-topic",), dict(default="/imu0", metavar="TOPIC", type=_topic,
                                               help="the rostopic of --export-kalibr"))),
           write=_kalibr),
    Export("--export-ardupilot", "FILE.parm", "the ArduPilot parameter file", "with --thermal-degree: ArduPilot's "
           "INS_TCALn_* parameters (TMIN, TMAX, the offset polynomial ACC1-3 about 35 C, x 1e6) and INS_ACCn_CALTEMP, "
           "INS_ACCOFFS, INS_ACCSCAL at T0", BOTH, "thermal",
           options=((("--ardupilot-imu",), dict(type=int, choices=(1, 2, 3), metavar="N", help="the IMU the "
                     "ArduPilot parameters are for (INS_TCALN_*; default: a DataFlash log's own accelerometer, else "
                     "1)")),),
           write=_ardupilot),
    Export("--export-px4", "FILE.params", "the PX4 parameter file", "with --thermal-degree and a device id: PX4's "
           "TC_A* parameters (QGroundControl's .params: ID, TREF, TMIN, TMAX, the offset polynomial X0-X3 relative to "
           "TREF) and CAL_ACCn_ID, xOFF, xSCALE at TREF", BOTH, "thermal",
           options=((("--px4-instance",), dict(type=int, choices=(0, 1, 2, 3), metavar="N", help="the "
                     "accelerometer slot the PX4 parameters are for (TC_AN_*, CAL_ACCN_*; default: from a ULog's "
                     "parameters the slot that holds the device or the first free one, else 0)")),
                    (("--px4-device-id",), dict(type=_device_id, metavar="ID", help="the accelerometer's device id "
                     "(CAL_ACCn_ID on the vehicle): PX4 applies TC_AN_* only to the sensor whose id is TC_AN_ID "
                     "(default: a ULog's own sensor_accel device_id)"))),
           check=_check_px4, write=_px4),
)


def outputs():
    """The output options of the exports: (attribute, what it is, "file"), for the paths checked before any work."""
    return tuple((e.dest, e.what, "file") for e in EXPORTS)


def of(command):
    """The exports a command offers."""
    return [e for e in EXPORTS if command in e.commands]


def add(p, command):
    """Each export's option, and its own options, on the command's parser."""
    for e in of(command):
        p.add_argument(e.option, metavar=e.metavar, help=e.help)
        for flags, keywords in e.options:
            p.add_argument(*flags, **keywords)


def asked(args, command, takes=None):
    """The exports given on the command line (of one kind with `takes`)."""
    return [e for e in of(command) if getattr(args, e.dest, None) and (takes is None or e.takes == takes)]


def check(args, command):
    """Before any work: each export asked for can be written with the options given."""
    for e in asked(args, command):
        if e.takes == "thermal" and args.thermal_degree is None:
            raise DataError(f"{e.option} needs --thermal-degree D (the file holds the drift in T)", param=e.dest)
        if not e.temperature and args.thermal_degree is not None:
            could = ", ".join(x.option for x in of(command) if x.temperature)
            raise DataError(f"{e.option}: that file holds no polynomial in T; with --thermal-degree give {could}",
                            param=e.dest)
    for e in of(command):
        for flags, keywords in e.options:                # an export's own option without the export: not ignored
            dest = flags[0].lstrip("-").replace("-", "_")
            if not getattr(args, e.dest, None) and getattr(args, dest, None) != keywords.get("default"):
                raise DataError(f"{flags[0]} goes with {e.option}, which was not given: give {e.option} "
                                f"{e.metavar}, or leave {flags[0]} out", param=dest)
        if e.check:
            e.check(args)


def refuse(args, command, why):
    """DataError naming the first export asked for, when the run cannot write any (a batch, a still-only log)."""
    given = asked(args, command)
    if given:
        raise DataError(f"{given[0].option} {why}", param=given[0].dest)


def write(args, res, command):
    """Write every export asked for that this result carries; print what was written (with the effects a format
    drops)."""
    effects = res.get("effect_names") or []
    for e in asked(args, command):
        if e.takes != "noise" and not res.get("consistent", True):
            print(f"{e.option}: not written: the data refute the noise bound, so the calibration has no guaranteed "
                  "bounds")
            continue
        if e.takes == "calibration" and "calibration" not in res or e.takes == "thermal" and not res.get("thermal"):
            continue
        print(e.write(getattr(args, e.dest), res, args))
        if effects and not e.effects:
            print(f"note: {e.option} has no parameter for {', '.join(effects)}: it carries M and b only and drops "
                  "them; `garant apply` with the --save file takes them out of each sample")
