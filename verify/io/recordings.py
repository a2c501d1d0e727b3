"""Raw accelerometer logs: reading the supported formats and finding the still intervals."""
import os
import warnings
from typing import NamedTuple      # loaded with numpy anyway; dataclasses would add inspect to a small log's run

import numpy as np

from ..errors import DataError, opt
from . import files, flight, mimu
from ..defaults import FORMATS, SENSORS



class Log(NamedTuple):
    """A raw log: time (s) and three accelerometer columns in the sensor's own unit."""

    path: str
    t: np.ndarray          # s
    raw: np.ndarray        # (N, 3), the sensor's own units (counts or m/s^2)
    step: float = None     # quantisation step in raw units when the format states it
    note: str = ""         # what the reader did (skipped bytes, the IMU read)
    dt: float = None       # median sample interval, s (computed when None)
    fmt: str = ""          # the format it was read as (FORMATS), or "array"
    temp: np.ndarray = None   # C, each sample's temperature where the log has a column of it (TEMP_COLUMNS)
    meta: dict = None      # a flight controller's log: its stack, the sensor's instance and device id, its parameters


#: Time column names of a `csv` log, and the unit each one states (factor to seconds).
TIME_COLUMNS = {"time_s": 1.0, "t_s": 1.0, "time": 1.0, "t": 1.0, "timestamp": 1.0, "time_ms": 1e-3, "t_ms": 1e-3,
                "time_us": 1e-6, "t_us": 1e-6}
#: Accelerometer column names of a `csv` log, in the order x, y, z (any one set).
ACCEL_COLUMNS = (("x", "y", "z"), ("ax", "ay", "az"), ("acc_x", "acc_y", "acc_z"), ("accel_x", "accel_y", "accel_z"),
                 ("f1", "f2", "f3"))
MIN_SAMPLES = 100
#: The largest magnitude of a reading or time stamp (microseconds since 1970 are 1.7e15).
MAX_VALUE = 1e17
#: The largest log read (1e7 samples of four numbers are about 650 MB as text).
MAX_LOG_BYTES = 4_000_000_000


def median(x, axis=None):
    """np.median without NaN handling (which loads numpy.ma, a fifth of a small log's run): the middle of
    the sorted values, or the mean of the two middle ones, along `axis` (all values when None)."""
    x = np.asarray(x, dtype=float)
    if axis is None:
        x, axis = x.ravel(), 0
    n = x.shape[axis]
    if n == 0:
        return np.nan
    lo, hi = (n - 1) // 2, n // 2
    p = np.partition(x, (lo, hi), axis=axis)
    return 0.5 * (np.take(p, lo, axis=axis) + np.take(p, hi, axis=axis))


def guess_format(path):
    """The log's format from its first bytes: mimu (binary packets), openaxes, csv or imu_tk."""
    with open(path, "rb") as fh:
        start = fh.read(4096)
    if flight.looks_like(start):
        return flight.looks_like(start)
    if mimu.looks_like(start[: 4 * mimu.PACKET]):
        return "mimu"
    if start.startswith(b"\x93NUMPY"):
        return "npy"
    head = start.split(b"\n", 1)[0].decode("utf-8", errors="replace")
    if ";" in head and "TIME" in head:
        return "openaxes"
    return "csv" if "," in head else "imu_tk"


def _header(path, delimiter):
    with open(path, encoding="utf-8-sig", errors="replace") as fh:
        line = files.header_line(fh, path, param="log")
    if not line.strip():
        raise DataError(f"{path}: empty file; expected a header line", param="log")
    return [h.strip() for h in line.rstrip("\r\n").split(delimiter)]


def _load(path, delimiter, usecols, skip):
    """The numeric columns `usecols` of a delimited text file, read in C; one line naming the first bad
    cell when a cell is not a finite number; a file with no line break in its first MiB is no log of a sample per line
    (refused before it is parsed whole)."""
    with open(path, "rb") as fh:
        head = fh.read(1 << 20)
    if len(head) == 1 << 20 and b"\n" not in head:
        raise DataError(f"{path}: no line break in its first MiB: a log holds one sample per line", param="log")
    try:
        data = _blocks(path, delimiter, usecols, skip)
    except (ValueError, UnicodeDecodeError) as e:
        raise DataError(f"{path}: {_first_bad_cell(path, delimiter, usecols, skip) or e}", param="log") from None
    if data.shape[0] == 0:
        raise DataError(f"{path}: no data rows", param="log")
    if not np.isfinite(data.sum()):                  # a NaN or an infinity makes the sum one (so can
        bad = np.flatnonzero(~np.isfinite(data).all(axis=1))             # an overflow: then no row is bad)
        if bad.size:
            raise DataError(f"{path} line {int(bad[0]) + skip + 1}: NaN or infinite value", param="log")
    if len(data) and max(data.max(), -data.min()) > MAX_VALUE:       # (no temporary of the file's size unless so)
        row, col = (int(v[0]) for v in np.nonzero(np.abs(data) > MAX_VALUE))
        raise DataError(f"{path} line {row + skip + 1}: {data[row, col]:g} is beyond any reading or time stamp "
                        f"(|value| > {MAX_VALUE:g})", param="log")
    return data


#: Rows parsed at a time into a text log's array: the array is made once at its final size (its lines counted
#: first), so reading costs the numbers and one block, not a growing parser's copies.
BLOCK_ROWS = 1 << 18


def _blocks(path, delimiter, usecols, skip):
    """np.loadtxt of the file, BLOCK_ROWS rows at a time into one array of the file's line count (trimmed)."""
    with open(path, "rb") as fh:
        lines, last = 0, b""
        while block := fh.read(1 << 24):
            lines, last = lines + block.count(b"\n"), block[-1:]
    out = np.empty((max(lines + (last not in (b"\n", b"")) - skip, 0), len(usecols)))
    n = 0
    with open(path, encoding="utf-8-sig") as fh, warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)                  # "input contained no data": said by the caller
        for _ in range(skip):
            fh.readline()
        while n < len(out):
            part = np.loadtxt(fh, delimiter=delimiter, usecols=usecols, ndmin=2, dtype=float, comments=None,
                              max_rows=BLOCK_ROWS)
            if not len(part):
                break
            out[n:n + len(part)] = part
            n += len(part)
    return out[:n]


#: The rows of a binary log whose time is checked before the whole file is read.
EARLY_ROWS = 4096


def _load_npy(path):
    """A NumPy .npy array of shape (N, 4), float: t (s), x, y, z (binary: no text parsing, for large logs).
    Never unpickled: an object array is refused like any other file that is not numbers."""
    fmt = np.lib.format
    try:
        with open(path, "rb") as fh:               # the header first: its shape must fit the file's bytes
            version = fmt.read_magic(fh)
            shape, _, dtype = (fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0)(fh)
            room = os.fstat(fh.fileno()).st_size - fh.tell()
        if len(shape) != 2 or not all(0 <= n <= 2 ** 40 for n in shape) or shape[0] * shape[1] * dtype.itemsize > room:
            raise ValueError(f"its header says shape {str(shape)[:60]}, which the file's bytes do not hold")
        data = np.load(path, mmap_mode="r", allow_pickle=False)
    except (ValueError, OverflowError, TypeError) as e:
        raise DataError(f"{path}: not a NumPy array of numbers ({str(e)[:200]})", param="log") from None
    if data.ndim != 2 or data.shape[1] != 4 or data.dtype.kind not in "fiu":
        raise DataError(f"{path}: a .npy log must be an array of numbers of shape (N, 4): t (s), x, y, z; "
                        f"this one is {data.dtype} of shape {data.shape}", param="log")
    head = np.asarray(data[:EARLY_ROWS, 0], dtype=float)
    if len(data) > 1 and np.all(head == head[0]):       # before the whole file is read: a time that never moves
        raise DataError(f"{path}: the time column does not move in its first {len(head):,} rows (all {head[0]:g}): "
                        "no log of samples in time", param="log")
    data = np.asarray(data, dtype=float)
    if not np.isfinite(data.sum()):
        bad = np.flatnonzero(~np.isfinite(data).all(axis=1))
        if bad.size:
            raise DataError(f"{path} row {int(bad[0]) + 1}: NaN or infinite value", param="log")
    if np.abs(data).max(initial=0.0) > MAX_VALUE:
        raise DataError(f"{path}: a value beyond any reading or time stamp (|value| > {MAX_VALUE:g})", param="log")
    return data


def _first_bad_cell(path, delimiter, usecols, skip):
    with open(path, encoding="utf-8-sig", errors="replace") as fh:
        for k, line in enumerate(fh, 1):
            if k <= skip:
                continue
            cells = line.split(delimiter)
            if len(cells) <= max(usecols):
                return f"line {k}: {len(cells)} columns, expected at least {max(usecols) + 1}"
            for c in usecols:
                try:
                    float(cells[c])
                except ValueError:
                    text = cells[c].strip()
                    return f"line {k}: {text[:40]!r}{'...' if len(text) > 40 else ''} is not a number"
    return None


def _csv_columns(path, header):
    """(time column, its factor to s, three accelerometer columns) of a `csv` log header."""
    low = [h.lower() for h in header]
    if len(set(low)) != len(low):
        raise DataError(f"{path}: duplicate column names in the header {','.join(header)}", param="log")
    times = [h for h in low if h in TIME_COLUMNS]
    if len(times) != 1:
        raise DataError(f"{path}: expected one time column named {', '.join(TIME_COLUMNS)} "
                        f"(the suffix states the unit); header is {','.join(header)}", param="log")
    t = low.index(times[0])
    for names in ACCEL_COLUMNS:
        if all(n in low for n in names):
            return t, TIME_COLUMNS[times[0]], [low.index(n) for n in names]
    rest = [k for k in range(len(low)) if k != t and low[k] not in TEMP_COLUMNS]
    if len(rest) < 3:
        raise DataError(f"{path}: a csv log needs a time column and three accelerometer columns; header is "
                        f"{','.join(header)}", param="log")
    return t, TIME_COLUMNS[times[0]], rest[:3]


def _check_time(path, t, named_unit):
    """Time must increase and be in seconds: a reset or a unit that is not seconds is refused, and so is a
    time column whose stamps mostly repeat. Returns (the median sample interval, how many steps are 0)."""
    dt = np.diff(t)
    if np.all(dt == 0):
        raise DataError(f"{path}: the time column is constant", param="log")
    back = np.flatnonzero(dt < 0)
    if back.size:
        raise DataError(f"{path}: time goes back at data row {int(back[0]) + 2} (a reset or a merged log); "
                        "split the log or fix the time column", param="log")
    step = float(median(dt))
    repeats = int(np.count_nonzero(dt == 0))
    if step == 0:
        raise DataError(f"{path}: {repeats} of {dt.size} time steps are 0 (each time stamp repeated): the time "
                        "column does not give the sample times; fix it or give one row per sample", param="log")
    if named_unit and not 1e-5 <= step <= 0.5:
        raise DataError(f"{path}: the time column has a median step of {step:g} s; a static calibration finds its "
                        "still intervals in a moving window of samples at least every 0.5 s (and at most 1e5 a "
                        "second): give the raw samples, or name the column time_ms or time_us if it is in "
                        "milliseconds or microseconds", param="log")
    return step, repeats


class Read(NamedTuple):
    """What a format's reader gives: time (its unit named or not), the three raw axes, the quantisation
    step the format states (or None) and a note."""

    t: np.ndarray
    raw: np.ndarray
    unit: bool             # the time's unit is stated by the format (else it is checked to be seconds)
    step: float = None
    note: str = ""
    temp: np.ndarray = None
    meta: dict = None


#: Temperature column names of a `csv` log (degrees C).
TEMP_COLUMNS = ("temp_c", "temperature_c", "temperature", "temp")


def _read_mimu(path, sensor, imu, rate):
    if imu is None:
        raise DataError(f"{path}: a MIMU4444BT stream holds {mimu.IMUS} IMUs; choose one with {opt('imu')} K")
    t, raw, step, skipped, jumps = mimu.read(path, imu)
    note = (f"MIMU4444BT IMU {imu}, array frame, {mimu.COUNTS_PER_G} counts per g = {mimu.G_DATASHEET} m/s^2; "
            f"{len(t)} packets" + (f", {skipped} bytes outside valid packets skipped" if skipped else "")
            + (f"; {jumps} time stamp(s) repeat, go back or jump (a reset?): time taken from the packet count at "
               f"{mimu.RATE_HZ:g} Hz" if jumps else ""))
    return Read(t, raw, True, step, note)


def _read_openaxes(path, sensor, imu, rate):
    header = _header(path, ";")
    cols = ["TIME"] + [SENSORS[sensor].format(i) for i in range(3)]
    missing = [c for c in cols if c not in header]
    if missing:
        raise DataError(f"{path}: missing column(s) {', '.join(missing)} for an OpenAXES log", param="log")
    data = _load(path, ";", [header.index(c) for c in cols], 1)
    return Read(data[:, 0] * 1e-6, data[:, 1:4], False)                   # TIME in microseconds


def _read_csv(path, sensor, imu, rate):
    header = _header(path, ",")
    ti, factor, acc = _csv_columns(path, header)
    low = [h.lower() for h in header]
    temp = [low.index(n) for n in TEMP_COLUMNS if n in low][:1]
    data = _load(path, ",", [ti] + acc + temp, 1)
    return Read(data[:, 0] * factor, data[:, 1:4], factor == 1.0, temp=data[:, 4].copy() if temp else None)


def _read_imu_tk(path, sensor, imu, rate):
    data = _load(path, None, [0, 1, 2, 3], 0)
    return Read(data[:, 0], data[:, 1:4], True)


def _read_npy(path, sensor, imu, rate):
    data = _load_npy(path)
    return Read(data[:, 0].copy(), data[:, 1:4], True)


def _read_imucal(path, sensor, imu, rate):
    if rate is None:
        raise DataError(f"{path}: an imucal session has a sample index, no time: give {opt('rate')} HZ (imucal's "
                        "example sessions: 102.4)")
    header = _header(path, ",")
    index = next((c for c in ("n_samples", "samples") if c in header), None)
    missing = [c for c in ("acc_x", "acc_y", "acc_z") if c not in header] + ([] if index else ["n_samples"])
    if missing:
        raise DataError(f"{path}: missing column(s) {', '.join(missing)} for an imucal session", param="log")
    data = _load(path, ",", [header.index(c) for c in (index, "acc_x", "acc_y", "acc_z")], 1)
    data = data[np.argsort(data[:, 0], kind="stable")]
    return Read(data[:, 0] / rate, data[:, 1:4], True)


#: Each log format and its reader (path, sensor, imu, rate) -> Read: one place to add a format.
def _read_flight(reader):
    """A reader of a flight controller's log (io/flight.py): one accelerometer instance (`imu`: its number or device
    id), m/s^2, its temperature and the log's parameters."""
    def read(path, sensor, imu, rate):
        t, raw, temp, meta = reader(path, imu)
        which = f"topic {meta['topic']}" if "topic" in meta else f"device id {meta['device_id']}"
        note = f"{meta['stack']} accelerometer {meta['instance']} ({which}) of {len(meta['instances'])}" + (
            f"; {meta['undone']}" if meta.get("undone") else "")
        return Read(t, raw, True, None, note, temp, meta)
    return read


READERS = {"imu_tk": _read_imu_tk, "csv": _read_csv, "openaxes": _read_openaxes, "mimu": _read_mimu,
           "npy": _read_npy, "imucal": _read_imucal, "ulog": _read_flight(flight.read_ulog),
           "dataflash": _read_flight(flight.read_dataflash), "rosbag": _read_flight(flight.read_rosbag)}
#: The formats a log may be read as (`--format`).
assert tuple(READERS) == FORMATS, "defaults.FORMATS names READERS in order"


def read_log(path, fmt=None, sensor="adxl355", imu=None, rate=None):
    """Time (s) and three accelerometer columns of a log, by the format's reader (READERS); one clear
    line on any problem. `imu` picks one IMU of a multi-IMU stream (mimu: 1-8); `rate` (Hz) times a log
    of sample indices (imucal's session: a column n_samples or samples, acc_x, acc_y, acc_z; rows in any
    order, sorted by index)."""
    files.regular(path, "the log", MAX_LOG_BYTES, param="log")
    try:
        fmt = fmt or guess_format(path)
        if imu is not None and fmt not in ("mimu", "ulog", "dataflash", "rosbag"):
            raise DataError(f"{opt('imu')} applies to a multi-IMU stream ({opt('format')} mimu) or a flight "
                            f"controller's log or a ROS bag (ulog, dataflash, rosbag), not to a {fmt} log")
        if fmt not in READERS:
            raise DataError(f"unknown log format {fmt!r}; use one of {', '.join(FORMATS)}", param="format")
        got = READERS[fmt](path, sensor, imu, rate)
        t, raw, unit, step, note = got.t, got.raw, got.unit, got.step, got.note
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror})", param="log") from None
    if len(t) < MIN_SAMPLES:
        raise DataError(f"{path}: only {len(t)} sample{'s' if len(t) != 1 else ''}; a static calibration needs a long "
                        f"recording (at least {MIN_SAMPLES} samples)", param="log")
    _check_temperature(path, got.temp)
    dt, repeats = _check_time(path, t, unit)
    if repeats:
        note = "; ".join(filter(None, (note, f"{repeats} time stamp(s) repeat the one before (kept)")))
    return Log(path, np.subtract(t, t[0], out=t), raw, step, note, dt, fmt, got.temp,     # t: the reader's own array
               got.meta)


#: The temperatures an IMU's own reading may take (C): the parts are rated to -40..85 or so; a value far outside is
#: no Celsius (a kelvin column, or a column switching to it) and is refused rather than calibrated "over" it.
TEMP_RANGE_C = (-100.0, 200.0)


def _check_temperature(path, temp):
    """One line for a temperature column that is not finite Celsius within TEMP_RANGE_C."""
    if temp is None:
        return
    lo, hi = TEMP_RANGE_C
    bad = np.flatnonzero(~np.isfinite(temp) | (temp < lo) | (temp > hi))
    if bad.size:
        k = int(bad[0])
        raise DataError(f"{path}: sample {k + 1}: temperature {temp[k]:g} is not in C within {lo:g} to {hi:g} (a "
                        "kelvin column? give C)", param="log")


def quantum(log):
    """The quantisation step of the raw readings: the format's own when it states one, 1 count for an
    integer log, else 0 (already scaled)."""
    if log.step is not None:
        return log.step
    head = log.raw[:1000]
    if not np.all(head == np.round(head)):          # a fraction in the first rows settles it
        return 0.0
    return 1.0 if np.all(log.raw == np.round(log.raw)) else 0.0


class Still(NamedTuple):
    """A still interval of a log: its span (s), mean (raw units) and the mean's standard errors."""

    start: float           # s
    stop: float            # s
    mean: np.ndarray       # (3,) raw units
    std_error: np.ndarray  # (3,) standard error of the mean if the noise were white: std / sqrt(n), raw units
    samples: int
    batch_error: np.ndarray = None   # (3,) standard error of the mean by BATCHES batch means (any correlation
                                     # shorter than a batch), raw units; None where no samples were read


def raw_unit(raw, g):
    """What readings (N, 3) are measured in: "m/s^2" when their median norm is within 20 % of g, else
    "count" (a raw-count log). calibrate-norm starts from it and records it; apply checks a log against it."""
    norm = float(median(np.linalg.norm(raw, axis=1))) if len(raw) else 0.0
    return "m/s^2" if abs(norm / g - 1) < 0.2 else "count"


BATCHES = 8            # batch means per still interval: the standard error of its mean under correlated noise
