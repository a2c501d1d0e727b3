"""The flight stacks' parameter files read back: the constant accelerometer calibration a PX4 .params or an
ArduPilot .parm holds, as (M, b) in garant's a = M (raw - b), for `garant budget` to judge against a log.

PX4 (src/lib/sensor_calibration/Accelerometer.hpp, Correct) corrects the accelerometer whose device id is
CAL_ACCn_ID by a = R ((raw - CAL_ACCn_xOFF) * CAL_ACCn_xSCALE) (R = CAL_ACCn_ROT, a turn the norm relation
cannot see): M = diag(xSCALE), b = xOFF. ArduPilot (AP_InertialSensor_Backend.cpp, _rotate_and_correct_accel)
by a = R ((v - INS_ACCOFFS) * INS_ACCSCAL) (R = AHRS_ORIENTATION): M = diag(INS_ACCSCAL), b = INS_ACCOFFS, for
the first IMU, INS_ACC2OFFS / INS_ACC2SCAL for the second, and so on. A file whose thermal compensation is
enabled for that sensor (PX4's TC_A_ENABLE with a TC_An_ID of it, ArduPilot's INS_TCALn_ENABLE 1) is refused: its
correction depends on the temperature, which `budget` does not take yet.

The files are data: each line is a name and a number (QGroundControl's tab-separated vehicle, component, name,
value, type; or NAME VALUE, NAME,VALUE as ArduPilot's tools write them), read by float() and nothing else.
"""
import re

import numpy as np

from ..errors import DataError
from . import files

MAX_BYTES = 10_000_000
NAME = re.compile(r"[A-Z][A-Z0-9_]{0,63}\Z")


def read(path):
    """{name: value} of a parameter file; {} when no line holds a name (another kind of file); DataError naming
    the line that is neither a comment nor a name and a number."""
    files.regular(path, "the parameter file", MAX_BYTES, param="calibration")
    try:
        with open(path, encoding="utf-8", errors="strict") as fh:
            lines = fh.read(MAX_BYTES).splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise DataError(f"{path}: cannot read ({getattr(e, 'strerror', None) or 'not text'})",
                        param="calibration") from None
    if any(line.split(":", 1)[0].strip() == "accelerometer_noise_density" for line in lines):
        raise DataError(f"{path}: Kalibr's imu.yaml states the noise (accelerometer_noise_density, random walk), no "
                        "scale, misalignment or bias: there is no calibration in it to budget", param="calibration")
    out = {}
    for n, line in enumerate(lines, 1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        fields = re.split(r"[\t ,]+", text)
        pair = fields[2:4] if len(fields) == 5 else fields
        if len(pair) != 2 or not NAME.match(pair[0]):
            if not out and n <= 3 and all(_number(f) is not None for f in fields):
                return {}                                  # numbers only: not a parameter file
            raise DataError(f"{path}: line {n} is not a parameter (NAME VALUE, NAME,VALUE or QGroundControl's "
                            "vehicle, component, name, value, type)", param="calibration")
        value = _number(pair[1])
        if value is None:
            raise DataError(f"{path}: line {n}: {pair[0]} is not a finite number ({pair[1][:30]!r})",
                            param="calibration")
        out[pair[0]] = value
    return out


def _number(text):
    try:
        x = float(text)
    except ValueError:
        return None
    return x if np.isfinite(x) else None


def constant(params, path, flight=None, imu=None):
    """(stack, M, b, which) of the parameter file's constant accelerometer calibration: the slot of the log's
    accelerometer (`flight`: its stack, instance and device id) or of `imu` (a slot number), else the only one."""
    if any(k.startswith("CAL_ACC") for k in params):
        return ("px4", *_px4(params, path, flight, imu))
    if any(k.startswith("INS_ACC") for k in params):
        return ("ardupilot", *_ardupilot(params, path, flight, imu))
    raise DataError(f"{path}: a parameter file without an accelerometer calibration (no CAL_ACCn_* of PX4, no "
                    "INS_ACC*OFFS_* of ArduPilot)", param="calibration")


def _one(path, slots, named, what):
    if named is not None:
        if named not in slots:
            raise DataError(f"{path}: no {what} {named} in this file (it holds {sorted(slots)})", param="imu")
        return named
    if len(slots) != 1:
        raise DataError(f"{path}: {len(slots)} accelerometer calibrations in this file ({what} {sorted(slots)}): "
                        "choose one with --imu K, or give the flight log of that accelerometer", param="imu")
    return slots[0]


def _px4(params, path, flight, imu):
    from .flight import int32
    slots = [n for n in range(8) if all(f"CAL_ACC{n}_{a}{w}" in params for a in "XYZ" for w in ("OFF", "SCALE"))]
    named = imu
    if flight and flight.get("stack") == "px4":
        ids = [n for n in slots if int32(int(params.get(f"CAL_ACC{n}_ID", 0))) == int32(flight["device_id"])]
        named = ids[0] if ids else named
    n = _one(path, slots, named, "CAL_ACC slot")
    device = int(params.get(f"CAL_ACC{n}_ID", 0))
    if params.get("TC_A_ENABLE", 0) == 1 and any(int(params.get(f"TC_A{m}_ID", 0)) == device for m in range(4)):
        raise DataError(f"{path}: PX4's thermal compensation is enabled for CAL_ACC{n}'s sensor (TC_A_ENABLE 1): a "
                        "calibration over temperature is not budgeted yet", param="calibration")
    scale = np.array([params[f"CAL_ACC{n}_{a}SCALE"] for a in "XYZ"])
    offset = np.array([params[f"CAL_ACC{n}_{a}OFF"] for a in "XYZ"])
    return _positive(scale, path, f"CAL_ACC{n}_*SCALE"), offset, f"CAL_ACC{n} (device id {device})"


def _ardupilot(params, path, flight, imu):
    def name(k):
        return "" if k == 0 else str(k + 1)
    slots = [k for k in range(3) if all(f"INS_ACC{name(k)}{w}_{a}" in params for a in "XYZ" for w in ("OFFS", "SCAL"))
             and any(params[f"INS_ACC{name(k)}SCAL_{a}"] for a in "XYZ")]
    named = flight["instance"] if flight and flight.get("stack") == "ardupilot" else imu
    k = _one(path, slots, named, "IMU (0-based)")
    if params.get(f"INS_TCAL{k + 1}_ENABLE", 0) == 1:
        raise DataError(f"{path}: ArduPilot's thermal correction is enabled for IMU {k + 1} (INS_TCAL{k + 1}_ENABLE "
                        "1): a calibration over temperature is not budgeted yet", param="calibration")
    scale = np.array([params[f"INS_ACC{name(k)}SCAL_{a}"] for a in "XYZ"])
    offset = np.array([params[f"INS_ACC{name(k)}OFFS_{a}"] for a in "XYZ"])
    return _positive(scale, path, f"INS_ACC{name(k)}SCAL_*"), offset, f"INS_ACC{name(k)}OFFS/SCAL (IMU {k + 1})"


def _positive(scale, path, what):
    if np.any(scale <= 0):
        raise DataError(f"{path}: {what} {scale.tolist()}: a scale factor must be positive", param="calibration")
    return np.diag(scale)
