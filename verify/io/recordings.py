"""Raw accelerometer logs: reading the supported formats and finding the still intervals."""
import csv
from dataclasses import dataclass

import numpy as np

from ..errors import DataError

FORMATS = ("imu_tk", "csv", "openaxes")
SENSORS = {"adxl355": "ACCEL_ADXL355_{}", "bmi160": "ACCEL_BMI160_{}"}


@dataclass
class Log:
    path: str
    t: np.ndarray          # s
    raw: np.ndarray        # (N, 3), the sensor's own units (counts or m/s^2)


def guess_format(path):
    with open(path, errors="replace") as fh:
        head = fh.readline()
    if ";" in head and "TIME" in head:
        return "openaxes"
    return "csv" if "," in head else "imu_tk"


def _floats(rows, path, first_line):
    try:
        return np.array(rows, dtype=float)
    except ValueError:
        for k, r in enumerate(rows):
            for cell in r:
                try:
                    float(cell)
                except ValueError:
                    raise DataError(f"{path} line {first_line + k}: {cell!r} is not a number") from None
        raise


def read_log(path, fmt=None, sensor="adxl355"):
    """Time (s) and three accelerometer columns of a log; one clear line on any problem."""
    try:
        fmt = fmt or guess_format(path)
        with open(path, newline="", errors="replace") as fh:
            if fmt == "imu_tk":
                rows = [line.split() for line in fh if line.strip()]
                first = 1
            else:
                rows = list(csv.reader(fh, delimiter=";" if fmt == "openaxes" else ","))
                first = 2
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror})") from None
    if fmt == "openaxes":
        header, rows = rows[0], rows[1:]
        cols = ["TIME"] + [SENSORS[sensor].format(i) for i in range(3)]
        missing = [c for c in cols if c not in header]
        if missing:
            raise DataError(f"{path}: missing column(s) {', '.join(missing)} for an OpenAXES log")
        idx = [header.index(c) for c in cols]
        data = _floats([[r[i] for i in idx] for r in rows if r], path, first)
        data[:, 0] *= 1e-6                                        # microseconds -> s
    elif fmt == "csv":
        header, rows = rows[0], rows[1:]
        if len(header) < 4:
            raise DataError(f"{path}: a csv log needs a header and columns time_s, x, y, z")
        data = _floats([r[:4] for r in rows if r], path, first)
    elif fmt == "imu_tk":
        bad = next((k for k, r in enumerate(rows) if len(r) < 4), None)
        if bad is not None:
            raise DataError(f"{path} line {bad + 1}: expected columns t x y z, got {len(rows[bad])}")
        data = _floats([r[:4] for r in rows], path, first)
    else:
        raise DataError(f"unknown log format {fmt!r}; use one of {', '.join(FORMATS)}")
    if len(data) < 100:
        raise DataError(f"{path}: only {len(data)} samples; a static calibration needs a long recording")
    if not np.all(np.isfinite(data)):
        raise DataError(f"{path}: the log contains NaN or infinite values")
    return Log(path, data[:, 0] - data[0, 0], data[:, 1:4])


@dataclass
class Still:
    start: float           # s
    stop: float            # s
    mean: np.ndarray       # (3,) raw units
    std_error: np.ndarray  # (3,) standard error of the mean, raw units
    samples: int


def moving_variance(x, n):
    c = np.cumsum(np.vstack([np.zeros(3), x]), axis=0)
    c2 = np.cumsum(np.vstack([np.zeros(3), x**2]), axis=0)
    mean = (c[n:] - c[:-n]) / n
    return ((c2[n:] - c2[:-n]) / n - mean**2).sum(axis=1)


def still_intervals(log, window=1.0, init=5.0, k=10.0, min_still=2.0):
    """Still intervals: moving variance (window s) below k times that of the first `init` seconds.

    Returns (intervals, note): the note says how the threshold was set.
    """
    dt = float(np.median(np.diff(log.t)))
    n = max(int(round(window / dt)), 5)
    var = moving_variance(log.raw, n)
    first = var[: max(int(init / dt) - n, 1)]
    floor = np.quantile(var, 0.05)
    base = float(np.median(first))
    note = f"threshold {k:g} x the moving variance of the first {init:g} s"
    if base > 20 * floor:
        base, note = floor, (f"the first {init:g} s are not still; threshold {k:g} x the 5th "
                             "percentile of the moving variance")
    still = var < k * base
    out, i = [], 0
    while i < len(still):
        if not still[i]:
            i += 1
            continue
        j = i
        while j < len(still) and still[j]:
            j += 1
        a, b = i + n // 2, j + n // 2            # window centre indices
        if log.t[min(b, len(log.t) - 1)] - log.t[a] >= min_still:
            seg = log.raw[a:b]
            out.append(Still(float(log.t[a]), float(log.t[min(b, len(log.t) - 1)]), seg.mean(axis=0),
                             seg.std(axis=0, ddof=1) / np.sqrt(len(seg)), len(seg)))
        i = j
    return out, note
