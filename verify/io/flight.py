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


def _load_dataflash(path):
    """(accelerometer rows by instance number, {number: device id}, the PARM values)."""
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
        if kind == "PARM":
            params[m.Name] = float(m.Value)
            continue
        fields = [getattr(m, f, None) for f in ("TimeUS", "AccX", "AccY", "AccZ")]
        if any(f is None for f in fields):             # a message of another layout: not an accelerometer's
            continue
        k = int(getattr(m, "I", DATAFLASH_IMU.index(kind)))
        rows.setdefault(k, []).append((*fields, getattr(m, "T", np.nan)))
    names = {0: "INS_ACC_ID", 1: "INS_ACC2_ID", 2: "INS_ACC3_ID"}
    return rows, {k: int(params.get(names.get(k, ""), 0)) for k in sorted(rows)}, params


def read_dataflash(path, imu=None):
    """(t s, raw (N, 3) m/s^2, temperature C or None, meta) of one accelerometer of an ArduPilot DataFlash log."""
    rows, ids, params = _load_dataflash(path)
    k = _pick(path, ids, imu, "ArduPilot")
    a = np.array(rows[k], float)
    temp = a[:, 4] if np.all(np.isfinite(a[:, 4])) else None
    meta = {"stack": "ardupilot", "instance": k, "device_id": ids[k], "instances": ids,
            "parameters": {n: v for n, v in params.items() if n.startswith(("INS_ACC", "INS_TCAL"))}}
    return a[:, 0] * 1e-6, a[:, 1:4], temp, meta


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
