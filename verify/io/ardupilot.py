"""ArduPilot's thermal compensation parameters (INS_TCALn_*) from a thermal estimate.

ArduPilot corrects each accelerometer axis (m/s^2, sensor frame) by

    a = raw - (P(T) - P(T_cal)),   P(x) = sum_{p=1..3} ACCp x^p with x = T - 35 C,

T held within [TMIN, TMAX] and T_cal the temperature of its offset calibration (INS_ACCn_CALTEMP); the
parameters are stored times 1e6 (its Tools/scripts/tempcal_IMU.py, TEMP_REF = 35, SCALE_FACTOR = 1e6).
P is garant's bias polynomial of each axis, g b_i(T), re-expanded about 35 C; its constant term is what the
offset calibration holds and is not written. A scale factor's drift with T has no ArduPilot parameter.
"""
from math import comb

import numpy as np

from ..errors import DataError
from . import files

TEMP_REF = 35.0
SCALE_FACTOR = 1.0e6
ORDER = 3


def offset_polynomials(res):
    """{axis index: ACC1..ACC3 in m/s^2 per C^p about 35 C} from the thermal section of a result, and the
    bound over the range of each axis's bias in m/s^2; DataError when an axis's bias is not one q alone."""
    th, g = res["thermal"], res["g"]
    out, bounds = {}, {}
    for i in range(3):
        name = next((q for q, d in res["definitions"].items() if d.strip() == f"bias{i + 1}" and q in th["q"]), None)
        if name is None:
            raise DataError(f"--export-ardupilot: this stand's q do not hold the bias of accelerometer {i + 1} alone; "
                            "ArduPilot's offsets need each axis's bias")
        c = g * np.asarray(th["q"][name], float)                # m/s^2 per C^k about t0
        shift = TEMP_REF - th["t0_c"]                         # (T - t0) = (T - 35) + shift
        d = [sum(c[k] * comb(k, m) * shift ** (k - m) for k in range(m, len(c))) for m in range(len(c))]
        out[i] = (d[1:] + [0.0] * ORDER)[:ORDER]
        bounds[i] = g * th["bound"][name]
    return out, bounds


def text(res, imu=1):
    """The .parm file: comments stating what it holds and rests on, then NAME VALUE lines."""
    th = res["thermal"]
    if th["degree"] > ORDER:
        raise DataError(f"--export-ardupilot: ArduPilot holds a polynomial of degree {ORDER}")
    poly, bounds = offset_polynomials(res)
    lo, hi = th["range_c"]
    lines = [f"# garant estimate --temperature {th['degree']}: accelerometer offset polynomials for ArduPilot, "
             f"IMU {imu}",
             f"# valid over [{lo:g}, {hi:g}] C (TMIN, TMAX); T0 of the estimate {th['t0_c']} C; ArduPilot's "
             "reference 35 C",
             "# guaranteed bound of each axis's bias over the range (m/s^2): "
             + ", ".join(f"{'XYZ'[i]} {bounds[i]:.3e}" for i in range(3)),
             f"# premise: {th['premise']}",
             "# scale-factor drift with T has no ArduPilot parameter: see garant's JSON (thermal)",
             f"INS_TCAL{imu}_ENABLE 1",
             f"INS_TCAL{imu}_TMIN {lo:.1f}",
             f"INS_TCAL{imu}_TMAX {hi:.1f}"]
    for p in range(ORDER):
        for i in range(3):
            lines.append(f"INS_TCAL{imu}_ACC{p + 1}_{'XYZ'[i]} {poly[i][p] * SCALE_FACTOR:.9f}")
    return "\n".join(lines) + "\n"


def write(path, res, imu=1):
    """Write the .parm file (files.write: atomic, never over an input)."""
    files.write(path, [text(res, imu)], "w")
