"""A positions file of per-position means (docs/formats.md): one row per still position (and IMU, and
run) with the mean specific force, its per-sample scatter and the number of samples averaged, so the
noise rule can be applied without the raw log. Optional columns: the run (`exp` or `run`), the IMU
(`imu`), the nominal up-direction (`nom_x, nom_y, nom_z`) and the sample range (`start_sample,
stop_sample`, read as time with --rate). Lines starting with # are comments."""
import csv
import math
from dataclasses import dataclass

import numpy as np

from ..errors import DataError, opt
from . import files
from .positions import _number
from .recordings import Still

REQUIRED = ("f_x", "f_y", "f_z", "std_x", "std_y", "std_z", "n_samples")
MAX_ROWS = 1_000_000
#: The largest means file read: 200 bytes per row on average, refused by size before it is read.
MAX_BYTES = 200 * MAX_ROWS


@dataclass
class Run:
    """One run of a means file: the still positions' means (m/s^2), their nominal directions if given."""

    name: str
    stills: list                   # Still per position, mean in m/s^2
    nominal: np.ndarray = None     # (K, 3) nominal up-directions, when the file gives them
    quantum: float = 0.0           # quantisation step of the readings averaged (m/s^2), 0 when not stated
    refused: str = None            # why the run could not be read (then it is left out of a comparison)


def _rows(path):
    files.regular(path, "the means file", MAX_BYTES, param="data")
    lines = []
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            for k, line in enumerate(fh, 1):          # streamed: refused at the first row over the limit
                if line.strip() and not line.lstrip().startswith("#"):
                    lines.append((k, line))
                    if len(lines) > MAX_ROWS + 1:
                        raise DataError(f"{path}: more than {MAX_ROWS:,} rows (line {k})", param="data")
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror})", param="data") from None
    except UnicodeDecodeError:
        raise DataError(f"{path}: not a UTF-8 text CSV file", param="data") from None
    if not lines:
        raise DataError(f"{path}: empty file; expected a header with {', '.join(REQUIRED)}", param="data")
    if len(lines) > MAX_ROWS + 1:                     # the header and MAX_ROWS rows
        raise DataError(f"{path}: more than {MAX_ROWS:,} rows", param="data")
    try:
        table = list(csv.reader(line for _, line in lines))
    except csv.Error as e:
        raise DataError(f"{path}: not a CSV file ({e})", param="data") from None
    return [k for k, _ in lines], [h.strip().lower() for h in table[0]], table[1:]


def _num(path, line, col, text, integer=False):
    v = _number(text, path, line, col)
    if integer and v != int(v):
        raise DataError(f"{path} line {line}: column {col}: {text.strip()} is not an integer", param="data")
    return v


def looks_like(path):
    """True when the first non-comment line is a means-file header."""
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as fh:
            head = next((line for line in fh if line.strip() and not line.lstrip().startswith("#")), "")
    except OSError:
        return False
    cells = {c.strip().lower() for c in head.split(",")}
    return all(c in cells for c in REQUIRED)


def imus(path):
    """The IMU numbers of a means file, in order of first appearance."""
    lines, head, body = _rows(path)
    if "imu" not in head:
        raise DataError(f"{opt('imu')} all: {path} has no imu column")
    k = head.index("imu")
    out = []
    for line, cells in zip(lines[1:], body):
        if len(cells) != len(head):
            raise DataError(f"{path} line {line}: {len(cells)} cells, the header has {len(head)}", param="data")
        v = int(_num(path, line, "imu", cells[k], True))
        if v not in out:
            out.append(v)
    return out


def read(path, imu=None, rate=None, quantum=0.0):
    """The runs of a means file for one IMU: [Run], in file order of the run column (one run when the
    file has none). `imu` must be given exactly when the file has an `imu` column."""
    lines, head, body = _rows(path)
    if len(set(head)) != len(head):
        raise DataError(f"{path}: duplicate column names in the header", param="data")
    missing = [c for c in REQUIRED if c not in head]
    if missing:
        raise DataError(f"{path}: missing column(s) {', '.join(missing)} of a means file (docs/formats.md)",
                        param="data")
    run_col = next((c for c in ("exp", "run") if c in head), None)
    if "imu" in head and imu is None:
        raise DataError(f"{path}: the file holds several IMUs (column imu); choose one with {opt('imu')} K or "
                        f"{opt('imu')} all")
    if imu is not None and "imu" not in head:
        raise DataError(f"{opt('imu')} {imu}: {path} has no imu column")
    col = {c: head.index(c) for c in head}
    runs = {}
    for line, cells in zip(lines[1:], body):
        if len(cells) != len(head):
            raise DataError(f"{path} line {line}: {len(cells)} cells, the header has {len(head)}", param="data")
        get = lambda c, integer=False: _num(path, line, c, cells[col[c]], integer)   # noqa: E731
        if imu is not None and get("imu", True) != imu:
            continue
        n = get("n_samples", True)
        if n < 2:
            raise DataError(f"{path} line {line}: column n_samples: {cells[col['n_samples']]} samples; a mean "
                            "with a scatter needs at least 2", param="data")
        std = np.array([get(f"std_{a}") for a in "xyz"])
        if np.any(std < 0):
            raise DataError(f"{path} line {line}: a negative standard deviation", param="data")
        if "start_sample" in col and "stop_sample" in col and rate:
            start, stop = get("start_sample") / rate, get("stop_sample") / rate
        else:
            start = stop = float("nan")
        still = Still(start, stop, np.array([get(f"f_{a}") for a in "xyz"]), std / math.sqrt(n), int(n))
        nominal = [get(f"nom_{a}") for a in "xyz"] if all(f"nom_{a}" in col for a in "xyz") else None
        key = cells[col[run_col]].strip() if run_col else "1"
        runs.setdefault(key, ([], []))
        runs[key][0].append(still)
        runs[key][1].append(nominal)
    if not runs:
        raise DataError(f"{path}: no rows" + (f" for IMU {imu}" if imu is not None else ""), param="data")
    out = []
    for key, (stills, nominal) in runs.items():
        nom = None if any(v is None for v in nominal) else np.array(nominal)
        if nom is not None:
            norms = np.linalg.norm(nom, axis=1)
            if np.any(np.abs(norms - 1) > 1e-3):
                k = int(np.flatnonzero(np.abs(norms - 1) > 1e-3)[0])
                raise DataError(f"{path}: run {key}, position {k + 1}: the nominal direction is not a unit vector "
                                f"(length {norms[k]:.4f})", param="data")
        out.append(Run(f"{path}#{run_col}={key}" if run_col else path, stills, nom, quantum))
    return out
