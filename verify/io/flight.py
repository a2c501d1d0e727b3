"""Flight controllers' own logs: PX4 ULog (`sensor_accel`) and ArduPilot DataFlash (`IMU`, `IMU2`, ...), read by
the projects' own readers (pyulog, pymavlink: the optional extra garant[flight]).

Each accelerometer instance is one sensor: `--imu K` picks it by its instance number (0, 1, ...: PX4's multi id,
ArduPilot's IMU message instance) or by its device id. The log's own parameters (PX4's CAL_ACCn_ID and TC_An_ID at
start, ArduPilot's PARM) travel with the readings (`meta`), so that an export knows the sensor and its slot.
"""
import numpy as np

from ..errors import DataError, opt

#: The install line said when the readers are missing.
EXTRA = "pip install 'garant[flight]'"
#: The first bytes of each format.
ULOG_MAGIC = b"ULog\x01\x12\x35"
DATAFLASH_MAGIC = b"\xa3\x95"
ROSBAG_MAGIC = b"#ROSBAG V2.0"


def looks_like(start):
    """"ulog", "dataflash", "rosbag" or None for a file's first bytes."""
    if start.startswith(ULOG_MAGIC):
        return "ulog"
    if start.startswith(ROSBAG_MAGIC):
        return "rosbag"
    if start[:2] == DATAFLASH_MAGIC and b"FMT" in start[:64]:
        return "dataflash"
    return None


def _need(module, path):
    """Import the reader or say in one line which install adds it."""
    import importlib
    try:
        return importlib.import_module(module)
    except ImportError:
        raise DataError(f"{path}: reading this log needs {module.split('.')[0]} ({EXTRA})", param="log") from None


def _pick(path, instances, imu, stack):
    """The instance `imu` names (its number or its device id) among {number: device id}; the only one when None."""
    listed = ", ".join(f"{k} ({'topic' if isinstance(d, str) else 'device id'} {d})" for k, d in instances.items())
    if not instances:
        raise DataError(f"{path}: no accelerometer readings in this {stack} log", param="log")
    if imu is None:
        if len(instances) == 1:
            return next(iter(instances))
        raise DataError(f"{path}: {len(instances)} accelerometers in this {stack} log: {listed}; choose one with "
                        f"{opt('imu')} K (its number or device id)", param="imu")
    for k, d in instances.items():
        if imu == d and d and not isinstance(d, str):
            return k
    if imu in instances:
        return imu
    raise DataError(f"{path}: no accelerometer {imu} in this {stack} log: {listed}", param="imu")


def instances(path, fmt):
    """{number: device id (a bag: its topic)} of the accelerometers of a ULog, DataFlash log or ROS bag (`--imu all`
    calibrates each)."""
    return {"ulog": _load_ulog, "dataflash": _load_dataflash, "rosbag": _load_rosbag}[fmt](path)[1]


def _load_ulog(path):
    """(sensor_accel data by instance number, {number: device id}, the vehicle's parameters at start)."""
    ulog = _need("pyulog", path)
    try:
        log = ulog.ULog(str(path), ["sensor_accel"])
    except Exception as e:                        # pyulog raises bare exceptions on a damaged file
        raise DataError(f"{path}: not a readable ULog ({str(e)[:80]})", param="log") from None
    topics = {d.multi_id: d.data for d in log.data_list if d.name == "sensor_accel"}
    ids = {k: int(d["device_id"][0]) if "device_id" in d and len(d["device_id"]) else 0
           for k, d in sorted(topics.items())}
    return topics, ids, dict(log.initial_parameters)


def read_ulog(path, imu=None):
    """(t s, raw (N, 3) m/s^2, temperature C or None, meta) of one `sensor_accel` instance of a PX4 ULog."""
    topics, ids, parameters = _load_ulog(path)
    k = _pick(path, ids, imu, "PX4")
    d = topics[k]
    missing = [f for f in ("timestamp", "x", "y", "z") if f not in d]
    if missing:
        raise DataError(f"{path}: sensor_accel instance {k} has no field {missing[0]}", param="log")
    t = np.asarray(d.get("timestamp_sample", d["timestamp"]), float) * 1e-6
    raw = np.column_stack([np.asarray(d[a], float) for a in "xyz"])
    temp = np.asarray(d["temperature"], float) if "temperature" in d else None
    if temp is not None and not np.any(temp):             # a sensor without one logs 0
        temp = None
    params = {n: v for n, v in parameters.items() if n.startswith(("CAL_ACC", "TC_A"))}
    meta = {"stack": "px4", "instance": k, "device_id": ids[k], "instances": ids, "parameters": params}
    return t, raw, temp, meta


#: DataFlash messages of the accelerometers, in instance order (older logs: IMU, IMU2, IMU3; newer: IMU with I).
DATAFLASH_IMU = ("IMU", "IMU2", "IMU3")


#: The parameters of ArduPilot's correction of a logged reading (`ardupilot_raw`).
CORRECTION = ("INS_ACC", "INS_TCAL", "AHRS_ORIENTATION")


def _load_dataflash(path):
    """(accelerometer rows by instance number, {number: device id}, the PARM values at start)."""
    dfreader = _need("pymavlink.DFReader", path)
    try:
        reader = dfreader.DFReader_binary(str(path), zero_time_base=True)
    except Exception as e:
        raise DataError(f"{path}: not a readable DataFlash log ({str(e)[:80]})", param="log") from None
    rows, params = {}, {}
    while True:
        try:
            m = reader.recv_match(type=[*DATAFLASH_IMU, "PARM"])      # a list: pymavlink takes no tuple
        except Exception:                              # a cut log ends in a partial message
            break
        if m is None:
            break
        kind = m.get_type()
        if kind == "PARM":                             # the value at start; a correction changed later is said
            value = float(m.Value)
            if not rows:
                params[m.Name] = value
            elif params.setdefault(m.Name, value) != value and m.Name.startswith(CORRECTION):
                raise DataError(f"{path}: {m.Name} changed during the log ({params[m.Name]:g} -> {value:g}): its "
                                "readings before and after are corrected differently by ArduPilot; log again with the "
                                "parameters fixed", param="log")
            continue
        fields = [getattr(m, f, None) for f in ("TimeUS", "AccX", "AccY", "AccZ")]
        if any(f is None for f in fields):             # a message of another layout: not an accelerometer's
            continue
        k = int(getattr(m, "I", DATAFLASH_IMU.index(kind)))
        rows.setdefault(k, []).append((*fields, getattr(m, "T", np.nan)))
    names = {0: "INS_ACC_ID", 1: "INS_ACC2_ID", 2: "INS_ACC3_ID"}
    return rows, {k: int(params.get(names.get(k, ""), 0)) for k in sorted(rows)}, params


def read_dataflash(path, imu=None):
    """(t s, raw (N, 3) m/s^2, temperature C or None, meta) of one accelerometer of an ArduPilot DataFlash log: the
    IMU message's reading with the vehicle's own correction undone (`ardupilot_raw`), so that a calibration of it
    is one ArduPilot applies as loaded."""
    rows, ids, params = _load_dataflash(path)
    k = _pick(path, ids, imu, "ArduPilot")
    a = np.array(rows[k], float)
    temp = a[:, 4] if np.all(np.isfinite(a[:, 4])) else None
    raw, undone = ardupilot_raw(a[:, 1:4], temp, params, k, path)
    meta = {"stack": "ardupilot", "instance": k, "device_id": ids[k], "instances": ids, "undone": undone,
            "parameters": {n: v for n, v in params.items() if n.startswith(CORRECTION)}}
    return a[:, 0] * 1e-6, raw, temp, meta


#: ArduPilot's board orientations (AHRS_ORIENTATION, the enum Rotation of AP_Math/rotations.h): (roll, pitch, yaw)
#: in degrees; its matrix is Rz(yaw) Ry(pitch) Rx(roll) and v.rotate(r) is that matrix times v (AP_Math's
#: examples/rotations test checks both). Values past 37 (irregular angles, custom rotations) are refused.
AP_ROTATIONS = ((0, 0, 0), (0, 0, 45), (0, 0, 90), (0, 0, 135), (0, 0, 180), (0, 0, 225), (0, 0, 270), (0, 0, 315),
                (180, 0, 0), (180, 0, 45), (180, 0, 90), (180, 0, 135), (0, 180, 0), (180, 0, 225), (180, 0, 270),
                (180, 0, 315), (90, 0, 0), (90, 0, 45), (90, 0, 90), (90, 0, 135), (270, 0, 0), (270, 0, 45),
                (270, 0, 90), (270, 0, 135), (0, 90, 0), (0, 270, 0), (0, 180, 90), (0, 180, 270), (90, 90, 0),
                (180, 90, 0), (270, 90, 0), (90, 180, 0), (270, 180, 0), (90, 270, 0), (180, 270, 0), (270, 270, 0),
                (90, 180, 90), (90, 0, 270))


def ap_rotation(code):
    """The matrix of ArduPilot's board orientation `code` (AP_ROTATIONS), rounded to the exact 0, +-1 of right
    angles."""
    r, p, y = np.radians(AP_ROTATIONS[code])
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    R = np.array([[cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
                  [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
                  [-sp, sr * cp, cr * cp]])
    return np.where(np.abs(R) < 1e-12, 0.0, np.where(np.abs(np.abs(R) - 1) < 1e-12, np.sign(R), R))


def ardupilot_raw(acc, temp, params, k, path):
    """(raw (N, 3), what was undone) of accelerometer k's IMU readings `acc`. ArduPilot logs them corrected
    (AP_InertialSensor_Backend.cpp, _rotate_and_correct_accel, before the filter and get_accel that IMU logs):
    in the driver's axes v = raw - (P(T) - P(T_cal)) when INS_TCALn_ENABLE is 1 (TCal::correct_sensor, as
    io/tcal.py writes it), then a = (v - INS_ACCOFFS) * INS_ACCSCAL per axis, then a.rotate(AHRS_ORIENTATION). The
    inverse, with the parameters the log recorded: v = R^T a / INS_ACCSCAL + INS_ACCOFFS, raw = v + P(T) -
    P(T_cal). Affine, so the low-pass filter between commutes with it. A parameter the log does not hold is taken
    as ArduPilot's default (no offset, unit scale, no rotation, no thermal correction) and said."""
    n = "" if k == 0 else str(k + 1)
    offs = np.array([params.get(f"INS_ACC{n}OFFS_{a}", 0.0) for a in "XYZ"], float)
    scal = np.array([params.get(f"INS_ACC{n}SCAL_{a}", 1.0) for a in "XYZ"], float)
    code = int(params.get("AHRS_ORIENTATION", 0))
    if not 0 <= code < len(AP_ROTATIONS):
        raise DataError(f"{path}: AHRS_ORIENTATION {code} (a custom or irregular board rotation) cannot be undone "
                        "here: log with AHRS_ORIENTATION 0 to 37", param="log")
    if np.any(scal <= 0):
        raise DataError(f"{path}: INS_ACC{n}SCAL_* of accelerometer {k} is {scal.tolist()}: not the scale "
                        "ArduPilot corrected this log with (it must be positive)", param="log")
    v = acc @ ap_rotation(code) / scal + offs
    held = [name for name in (f"INS_ACC{n}OFFS_X", f"INS_ACC{n}SCAL_X", "AHRS_ORIENTATION") if name in params]
    said = (f"ArduPilot's correction undone (INS_ACC{n}OFFS_* {offs.round(6).tolist()} m/s^2, INS_ACC{n}SCAL_* "
            f"{scal.round(6).tolist()}, AHRS_ORIENTATION {code}" + ("" if len(held) == 3 else
                                                                     ", the rest ArduPilot's defaults: not in the log"))
    if int(params.get(f"INS_TCAL{k + 1}_ENABLE", 0)) == 1:
        if temp is None:
            raise DataError(f"{path}: INS_TCAL{k + 1}_ENABLE is 1 but the log holds no temperature of accelerometer "
                            f"{k}: its thermal correction cannot be undone", param="log")
        lo, hi = (float(params.get(f"INS_TCAL{k + 1}_{x}", 0.0)) for x in ("TMIN", "TMAX"))
        c = np.array([[params.get(f"INS_TCAL{k + 1}_ACC{p}_{a}", 0.0) for a in "XYZ"] for p in (1, 2, 3)], float)
        t_cal = float(params.get(f"INS_ACC{k + 1}_CALTEMP", 35.0))

        def P(T):
            x = (np.clip(np.atleast_1d(T), lo, hi) - 35.0)[:, None]
            return (c[0] + (c[1] + c[2] * x) * x) * x * 1e-6
        v = v + P(temp) - P([t_cal])
        said += f", INS_TCAL{k + 1}_* about INS_ACC{k + 1}_CALTEMP {t_cal:g} C"
    return v, said + "): the raw readings"


def px4_slot(meta, device_id):
    """(the TC_A slot for `device_id`, the CAL_ACC slot, the other TC_A slots holding it): the slot that already
    holds the device (TC_An_ID, else CAL_ACCn_ID), or the first free one, from the ULog's parameters at start. PX4
    applies the first TC_A slot whose TC_An_ID matches (TemperatureCompensation set_sensor_id) and the CAL_ACC slot
    whose CAL_ACCn_ID matches (FindCurrentCalibrationIndex), so a lower slot holding the same id must be cleared."""
    p = (meta or {}).get("parameters", {})
    tc = holders(meta, device_id)
    cal = [n for n in range(4) if int32(p.get(f"CAL_ACC{n}_ID", 0)) == int32(device_id)]
    free = [n for n in range(4) if not int(p.get(f"TC_A{n}_ID", 0))]
    slot = tc[0] if tc else cal[0] if cal and cal[0] in free else free[0] if free else 0
    return slot, cal[0] if cal else slot, [n for n in tc if n != slot]


def holders(meta, device_id):
    """The TC_A slots whose TC_An_ID is `device_id` in the log's parameters at start."""
    p = (meta or {}).get("parameters", {})
    return [n for n in range(4) if int32(p.get(f"TC_A{n}_ID", 0)) == int32(device_id)]


def int32(device_id):
    """A device id as PX4's INT32 parameters hold it: a uint32 device_id of 2^31 or more is the negative number;
    beyond 32 bits refused."""
    v = int(device_id)
    if not -2 ** 31 <= v < 2 ** 32:
        raise DataError(f"--px4-device-id {v}: no 32-bit device id", param="px4_device_id")
    return v - 2 ** 32 if v >= 2 ** 31 else v


#: The ROS message a bag's accelerometer topic carries (Kalibr's users record sensor_msgs/Imu).
IMU_MSG = "sensor_msgs/msg/Imu"


def _load_rosbag(path):
    """(the Imu messages' (stamp s, ax, ay, az) by topic number, {number: topic}, None) of a ROS 1 bag."""
    highlevel = _need("rosbags.highlevel", path)
    from pathlib import Path
    rows = {}
    try:
        with highlevel.AnyReader([Path(path)]) as reader:
            conns = sorted((c for c in reader.connections if c.msgtype == IMU_MSG), key=lambda c: c.topic)
            topics = {k: c.topic for k, c in enumerate(dict((c.topic, c) for c in conns).values())}
            number = {t: k for k, t in topics.items()}
            for conn, _, raw in reader.messages(connections=conns):
                m = reader.deserialize(raw, conn.msgtype)
                a, st = m.linear_acceleration, m.header.stamp
                rows.setdefault(number[conn.topic], []).append((st.sec + st.nanosec * 1e-9, a.x, a.y, a.z))
    except DataError:
        raise
    except Exception as e:                         # the reader's own errors on a damaged bag
        raise DataError(f"{path}: not a readable ROS bag ({str(e)[:80]})", param="log") from None
    return rows, topics, None


def read_rosbag(path, imu=None):
    """(t s, raw (N, 3) m/s^2, None, meta) of one sensor_msgs/Imu topic of a ROS 1 bag (its header stamps)."""
    rows, topics, _ = _load_rosbag(path)
    k = _pick(path, topics, imu, "ROS bag")
    a = np.array(rows.get(k, []), float).reshape(-1, 4)
    return a[:, 0], a[:, 1:4], None, {"stack": "ros", "instance": k, "device_id": 0, "topic": topics[k],
                                      "instances": topics, "parameters": {}}
