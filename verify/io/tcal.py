"""Thermal compensation parameters of the flight stacks from a thermal estimate: ArduPilot's INS_TCALn_* and
PX4's TC_An_*, each with the accelerometer calibration it is applied with, so that a file is right as loaded.

ArduPilot (libraries/AP_InertialSensor/AP_InertialSensor_tempcal.cpp, TCal::correct_sensor, and
AP_InertialSensor_Backend.cpp, _rotate_and_correct_accel) corrects each axis, in the IMU's axes after its
driver's fixed rotation and before the board's orientation, by

    v = raw - (P(T) - P(T_cal)),  a = (v - INS_ACCOFFS) * INS_ACCSCAL,  P(x) = sum_{p=1..3} ACCp x^p, x = T - 35 C,

T and T_cal = INS_ACCn_CALTEMP held within [TMIN, TMAX], the parameters stored times 1e6 (SCALE_FACTOR). P is
garant's bias polynomial of each axis, g b_i(T), re-expanded about 35 C without its constant; the file sets
T_cal = T0 of the estimate, INS_ACCOFFS = g b_i(T0) and INS_ACCSCAL = 1 / (1 + the scale q at T0). A scale
factor's drift with T has no ArduPilot parameter.

PX4 (src/modules/temperature_compensation/TemperatureCompensation.cpp, calc_thermal_offsets_3D and
set_sensor_id; src/lib/sensor_calibration/Accelerometer.hpp, Correct) corrects the accelerometer whose device id
is TC_An_ID by

    a = (raw - thermal_offset(T) - CAL_ACCn_xOFF) * CAL_ACCn_xSCALE,  thermal_offset = X0 + X1 d + X2 d^2 + X3 d^3,

d = T - TREF with T held within [TMIN, TMAX]. As PX4's Tools/process_sensor_caldata.py writes them, the thermal
offset is relative (X0 = 0: none at TREF = T0) and the constant is CAL_ACCn_xOFF = g b_i(T0); CAL_ACCn_xSCALE =
1 / (1 + the scale q at T0). PX4 holds the scale constant in T and has no misalignment.
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
                        "parameters need it", param=option.lstrip("-").replace("-", "_"))
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


def _at_t0(res, option):
    """(g b_i(T0) in m/s^2, 1 / (1 + scale q_i at T0)) per axis: the accelerometer calibration at the estimate's
    T0 that the thermal polynomial is applied with."""
    poly, _ = offset_polynomials(res, res["thermal"]["t0_c"], option)
    return [poly[i][0] for i in range(3)], [1.0 / (1.0 + res["thermal"]["q"][_scale_q(res, i, option)][0])
                                            for i in range(3)]


def text(res, imu=1):
    """The .parm file: comments stating what it holds and rests on, then NAME VALUE lines."""
    th = res["thermal"]
    if th["degree"] > ORDER:
        raise DataError(f"--export-ardupilot: ArduPilot holds a polynomial of degree {ORDER}", param="export_ardupilot")
    poly, bounds = offset_polynomials(res, TEMP_REF)
    poly = {i: (d[1:] + [0.0] * ORDER)[:ORDER] for i, d in poly.items()}
    relative = th.get("offsets_only", False)          # a still warm-up: the drift, not the calibration at T0
    offs, scal = (None, None) if relative else _at_t0(res, "--export-ardupilot")
    lo, hi = th["range_c"]
    n = "" if imu == 1 else str(imu)
    lines = [f"# garant {th.get('command', 'estimate')} --thermal-degree {th['degree']}: accelerometer thermal "
             "compensation for ArduPilot, "
             f"IMU {imu}, with the accelerometer calibration it is applied with",
             f"# valid over [{lo:g}, {hi:g}] C (TMIN, TMAX) of the IMU's own temperature; ArduPilot's reference 35 C",
             (f"# INS_ACC{imu}_CALTEMP, INS_ACC{n}OFFS_* and INS_ACC{n}SCAL_* are left as the vehicle has them: a "
              "still warm-up gives each axis's drift, not the calibration (ArduPilot's correction P(T) - P(CALTEMP) "
              "is relative)" if relative else
              f"# INS_ACC{imu}_CALTEMP, INS_ACC{n}OFFS_* and INS_ACC{n}SCAL_* are garant's calibration at T0 = "
              f"{th['t0_c']:g} C: loading them replaces an earlier accelerometer calibration (a later one sets them "
              "again, at its own temperature)"),
             "# axes: the IMU's, after its driver's fixed rotation and before the board's orientation "
             "(AHRS_ORIENTATION), as AP_InertialSensor_Backend corrects them",
             "# guaranteed bound of each axis's bias over the range (m/s^2): "
             + ", ".join(f"{'XYZ'[i]} {bounds[i]:.3e}" for i in range(3)),
             f"# premise: {th['premise']}",
             "# scale-factor drift with T has no ArduPilot parameter: see garant's JSON (thermal)",
             f"INS_TCAL{imu}_ENABLE 1",
             f"INS_TCAL{imu}_TMIN {_celsius(lo)}",
             f"INS_TCAL{imu}_TMAX {_celsius(hi)}"]
    for p in range(ORDER):
        for i in range(3):
            lines.append(f"INS_TCAL{imu}_ACC{p + 1}_{'XYZ'[i]} {poly[i][p] * SCALE_FACTOR:.9f}")
    if not relative:
        lines.append(f"INS_ACC{imu}_CALTEMP {th['t0_c']:.2f}")
        lines += [f"INS_ACC{n}OFFS_{'XYZ'[i]} {offs[i]:.9f}" for i in range(3)]
        lines += [f"INS_ACC{n}SCAL_{'XYZ'[i]} {scal[i]:.9f}" for i in range(3)]
    return "\n".join(lines) + "\n"


#: PX4's accelerometer slots (TemperatureCompensation.h ACCEL_COUNT_MAX, Accelerometer.hpp MAX_SENSOR_COUNT).
PX4_INSTANCES = 4


def _celsius(x):
    """A temperature as written: up to 4 decimals, at least one (20.0, 20.1501): the range is not rounded inwards
    or outwards."""
    text = f"{x:.4f}".rstrip("0")
    return text + "0" if text.endswith(".") else text


def px4_text(res, instance=0, device_id=None, cal_instance=None, clear=()):
    """PX4's parameter file (QGroundControl's tab-separated .params: vehicle, component, name, value, type 9 for
    a float, 6 for an integer): TC_A_ENABLE, TC_An_ID (the device id PX4 matches, set_sensor_id), TREF/TMIN/TMAX,
    X0..X3 per axis (X0 = 0), and CAL_ACCn_ID, CAL_ACCn_xOFF, CAL_ACCn_xSCALE."""
    th = res["thermal"]
    if th["degree"] > ORDER:
        raise DataError(f"--export-px4: PX4 holds a polynomial of degree {ORDER}", param="export_px4")
    if device_id is None:
        raise DataError(PX4_NEEDS_ID, param="px4_device_id")
    poly, bounds = offset_polynomials(res, th["t0_c"], "--export-px4")
    relative = th.get("offsets_only", False)          # a still warm-up: the drift, not the calibration at TREF
    offs, scal = (None, None) if relative else _at_t0(res, "--export-px4")
    lo, hi = th["range_c"]
    cal_instance = instance if cal_instance is None else cal_instance
    a, c = f"TC_A{instance}", f"CAL_ACC{cal_instance}"
    from .flight import int32
    device_id = int32(device_id)
    params = [("TC_A_ENABLE", 1, 6), (f"{a}_ID", device_id, 6), (f"{a}_TREF", float(th["t0_c"]), 9),
              (f"{a}_TMIN", float(lo), 9), (f"{a}_TMAX", float(hi), 9)]
    for n in range(ORDER + 1):
        for i in range(3):
            params.append((f"{a}_X{n}_{i}", poly[i][n] if 0 < n < len(poly[i]) else 0.0, 9))
    params += [(f"TC_A{m}_ID", 0, 6) for m in clear]             # PX4 applies the first slot whose id matches
    if not relative:
        params.append((f"{c}_ID", int(device_id), 6))
        params += [(f"{c}_{'XYZ'[i]}OFF", offs[i], 9) for i in range(3)]
        params += [(f"{c}_{'XYZ'[i]}SCALE", scal[i], 9) for i in range(3)]
    head = [f"# garant {th.get('command', 'estimate')} --thermal-degree {th['degree']}: accelerometer thermal "
            "compensation for PX4, instance "
            f"{instance}, device id {device_id}; valid over [{lo:g}, {hi:g}] C of the IMU's own temperature"
            + (f"; TC_A{', TC_A'.join(map(str, clear))}_ID set to 0: it held the same device id, and PX4 applies the "
               "first slot that matches" if clear else ""),
            f"# the thermal offset is relative to TREF = {th['t0_c']:g} C (X0 = 0, as PX4's process_sensor_caldata.py "
            + ("writes it); CAL_ACCn_* are left as the vehicle has them: a still warm-up gives each axis's drift, not "
               "the calibration" if relative else
               f"writes it); CAL_ACC{cal_instance}_*OFF and *SCALE are garant's calibration at TREF: loading them "
               "replaces an earlier accelerometer calibration"),
            "# guaranteed bound of each axis's bias over the range (m/s^2): "
            + ", ".join(f"{'XYZ'[i]} {bounds[i]:.3e}" for i in range(3)),
            f"# premise: {th['premise']}" + ("" if relative else "; the scale factors are those at TREF (PX4 holds "
                                                                 "them constant in T)"),
            "# Vehicle-Id\tComponent-Id\tName\tValue\tType"]
    return "\n".join(head + [f"1\t1\t{n}\t{v:.9g}\t{t}" if t == 9 else f"1\t1\t{n}\t{v}\t{t}"
                              for n, v, t in params]) + "\n"


PX4_NEEDS_ID = ("--export-px4 needs --px4-device-id N: PX4 applies TC_An_* only to the accelerometer whose device "
                "id is TC_An_ID (its CAL_ACCn_ID, or device_id in the sensor_accel log)")


def _scale_q(res, i, option="--export-px4"):
    """The q of accelerometer i's scale factor: Gamma_ii alone, or Gamma_ii less Delta_g (relative to the
    model's g)."""
    th = res["thermal"]
    for q, d in res["definitions"].items():
        if q in th["q"] and d.replace(" ", "") in (f"Gamma{i + 1}{i + 1}", f"Gamma{i + 1}{i + 1}-Delta_g"):
            return q
    raise DataError(f"{option}: this stand's q do not hold the scale of accelerometer {i + 1} alone",
                    param=option.lstrip("-").replace("-", "_"))


def write(path, res, imu=1):
    """Write ArduPilot's .parm file (files.write: atomic, never over an input)."""
    files.write(path, [text(res, imu)], "w")


def write_px4(path, res, instance=0, device_id=None, cal_instance=None, clear=()):
    """Write PX4's .params file."""
    files.write(path, [px4_text(res, instance, device_id, cal_instance, clear)], "w")
