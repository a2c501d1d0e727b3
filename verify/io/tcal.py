"""Thermal compensation parameters of the flight stacks from a thermal estimate: ArduPilot's INS_TCALn_*
and PX4's TC_An_*.

ArduPilot corrects each accelerometer axis (m/s^2, sensor frame) by

    a = raw - (P(T) - P(T_cal)),   P(x) = sum_{p=1..3} ACCp x^p with x = T - 35 C,

T held within [TMIN, TMAX] and T_cal the temperature of its offset calibration (INS_ACCn_CALTEMP); the
parameters are stored times 1e6 (its Tools/scripts/tempcal_IMU.py, TEMP_REF = 35, SCALE_FACTOR = 1e6).
P is garant's bias polynomial of each axis, g b_i(T), re-expanded about 35 C; its constant term is what the
offset calibration holds and is not written. A scale factor's drift with T has no ArduPilot parameter.

PX4 corrects each axis by (raw - offset) * SCL, offset = X0 + X1 d + X2 d^2 + X3 d^3, d = T - TREF, T held
within [TMIN, TMAX] (its sensor-thermal-calibration guide): X0..X3 are g times the bias polynomial about
TREF = T0, and SCL = 1 / (1 + the scale q at T0), the scale factor relative to the model's g; PX4 holds the
scale constant in T and has no misalignment.
"""
from math import comb

import numpy as np

from ..errors import DataError
from . import files

TEMP_REF = 35.0
SCALE_FACTOR = 1.0e6
ORDER = 3


def _q_of(res, definition, what, option):
    """The q whose definition is `definition` and that has a thermal polynomial; DataError naming `what`."""
    th = res["thermal"]
    name = next((q for q, d in res["definitions"].items() if d.strip() == definition and q in th["q"]), None)
    if name is None:
        raise DataError(f"{option}: this stand's q do not hold {what} alone ({definition}); the flight stack's "
                        "parameters need it")
    return name


def offset_polynomials(res, about, option="--export-ardupilot"):
    """{axis index: the bias polynomial of the axis in m/s^2 per C^p about `about` C, p = 0..degree} and the
    bound over the range of each axis's bias in m/s^2."""
    th, g = res["thermal"], res["g"]
    out, bounds = {}, {}
    for i in range(3):
        name = _q_of(res, f"bias{i + 1}", f"the bias of accelerometer {i + 1}", option)
        c = g * np.asarray(th["q"][name], float)                # m/s^2 per C^k about t0
        shift = about - th["t0_c"]                            # (T - t0) = (T - about) + shift
        out[i] = [sum(c[k] * comb(k, m) * shift ** (k - m) for k in range(m, len(c))) for m in range(len(c))]
        bounds[i] = g * th["bound"][name]
    return out, bounds


def text(res, imu=1):
    """The .parm file: comments stating what it holds and rests on, then NAME VALUE lines."""
    th = res["thermal"]
    if th["degree"] > ORDER:
        raise DataError(f"--export-ardupilot: ArduPilot holds a polynomial of degree {ORDER}")
    poly, bounds = offset_polynomials(res, TEMP_REF)
    poly = {i: (d[1:] + [0.0] * ORDER)[:ORDER] for i, d in poly.items()}
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


def px4_text(res, instance=0):
    """PX4's parameter file (QGroundControl's tab-separated .params: vehicle, component, name, value, type 9 for
    a float, 6 for an integer): TC_A_ENABLE, TC_An_TREF/TMIN/TMAX, X0..X3 per axis and SCL per axis."""
    th = res["thermal"]
    if th["degree"] > ORDER:
        raise DataError(f"--export-px4: PX4 holds a polynomial of degree {ORDER}")
    poly, bounds = offset_polynomials(res, th["t0_c"], "--export-px4")
    lo, hi = th["range_c"]
    a = f"TC_A{instance}"
    params = [("TC_A_ENABLE", 1, 6), (f"{a}_TREF", float(th["t0_c"]), 9), (f"{a}_TMIN", float(lo), 9),
              (f"{a}_TMAX", float(hi), 9)]
    for n in range(ORDER + 1):
        for i in range(3):
            params.append((f"{a}_X{n}_{i}", poly[i][n] if n < len(poly[i]) else 0.0, 9))
    for i in range(3):
        scale = th["q"][_scale_q(res, i)][0]
        params.append((f"{a}_SCL_{i}", 1.0 / (1.0 + scale), 9))
    head = [f"# garant estimate --temperature {th['degree']}: accelerometer thermal compensation for PX4, instance "
            f"{instance}; valid over [{lo:g}, {hi:g}] C",
            "# guaranteed bound of each axis's bias over the range (m/s^2): "
            + ", ".join(f"{'XYZ'[i]} {bounds[i]:.3e}" for i in range(3)),
            f"# premise: {th['premise']}; the scale factors are those at TREF (PX4 holds them constant in T)",
            "# Vehicle-Id\tComponent-Id\tName\tValue\tType"]
    return "\n".join(head + [f"1\t1\t{n}\t{v:.9g}\t{t}" if t == 9 else f"1\t1\t{n}\t{v}\t{t}"
                              for n, v, t in params]) + "\n"


def _scale_q(res, i):
    """The q of accelerometer i's scale factor: Gamma_ii alone, or Gamma_ii less Delta_g (relative to the
    model's g)."""
    th = res["thermal"]
    for q, d in res["definitions"].items():
        if q in th["q"] and d.replace(" ", "") in (f"Gamma{i + 1}{i + 1}", f"Gamma{i + 1}{i + 1}-Delta_g"):
            return q
    raise DataError(f"--export-px4: this stand's q do not hold the scale of accelerometer {i + 1} alone")


def write(path, res, imu=1):
    """Write ArduPilot's .parm file (files.write: atomic, never over an input)."""
    files.write(path, [text(res, imu)], "w")


def write_px4(path, res, instance=0):
    """Write PX4's .params file."""
    files.write(path, [px4_text(res, instance)], "w")
