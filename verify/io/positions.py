"""Reading measured positions from CSV, with one clear line for every way a file can be wrong."""
import csv
import math
import os
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..errors import DataError
from ..options import real_array
from . import files


@dataclass
class Positions:
    """Readings at stand positions: angles as read (degrees), mountings, specific force f (m/s^2)."""

    path: str
    angles_deg: np.ndarray             # (N, n_angles)
    f: np.ndarray                      # (N, 3), m/s^2
    mounts: np.ndarray = None          # (N,) mounting index, or None for a single mounting
    extra: dict = field(default_factory=dict)   # other columns: time_s and temp_c as numbers, the rest as text

    @property
    def alpha_deg(self):
        """The first angle as read, degrees."""
        return self.angles_deg[:, 0]

    @property
    def beta_deg(self):
        """The second angle as read, degrees."""
        return self.angles_deg[:, 1]

    @property
    def radians(self):
        """Each angle as read, radians, one array per angle."""
        return tuple(np.deg2rad(self.angles_deg[:, i]) for i in range(self.angles_deg.shape[1]))

    def at(self, rows):
        """The positions at these rows (indices), every column with them."""
        return Positions(self.path, self.angles_deg[rows], self.f[rows],
                         None if self.mounts is None else self.mounts[rows],
                         {k: np.asarray(v)[rows] for k, v in self.extra.items()})


def _number(text, path, line, col):
    try:
        v = float(text)
    except ValueError:
        shown = text.strip() if len(text.strip()) <= 40 else text.strip()[:40] + "..."
        raise DataError(f"{path} line {line}: column {col}: {shown!r} is not a number", param="data") from None
    if not math.isfinite(v):
        raise DataError(f"{path} line {line}: column {col}: {text.strip()} is not a finite number", param="data")
    return v


#: The largest positions or plan file read (1e7 rows of five numbers are about 600 MB).
MAX_BYTES = 2_000_000_000


#: The most data rows of a positions file: 2e6 readings (the verdict's remainder and fits grow with
#: the distinct positions; 1e6 rows at 96 positions take seconds). Readings of one position are
#: better averaged before (the means format).
MAX_ROWS = 2_000_000


#: The columns of a model's variables (the time of a row, s; its temperature, C): numbers, checked cell by cell.
VARIABLE_COLUMNS = ("time_s", "temp_c")


def read_positions(path, angles=("alpha", "beta"), mountings=None, empty_ok=False):
    """Read a CSV with columns <angle>_deg for each angle, f1, f2, f3 (m/s^2), and `mount` (a name
    such as +y+z+x) when the stand uses several mountings; other columns are kept. More than MAX_ROWS
    lines are refused before any is parsed; a header alone is refused unless `empty_ok` (a session
    that has measured nothing yet)."""
    files.regular(path, "the positions file", MAX_BYTES, param="data")
    if os.path.getsize(path) > 10 * MAX_ROWS and _lines(path) > MAX_ROWS + 1:       # a row has at least 10 bytes
        raise DataError(f"{path}: more than {MAX_ROWS:,} rows, the most a positions file may have: average the "
                        "readings of each position first (the means format, docs/formats.md)", param="data")
    angle_cols = [f"{a}_deg" for a in angles]
    required = angle_cols + ["f1", "f2", "f3"] + (["mount"] if mountings and len(mountings) > 1 else [])
    fast = _numeric(path, required)
    if fast is not None and set(fast[0]) <= {*required, *VARIABLE_COLUMNS}:     # other columns stay text: below
        header, data = fast
        pos = Positions(path, data[:, [header.index(c) for c in angle_cols]],
                        data[:, [header.index(c) for c in ("f1", "f2", "f3")]], None,
                        {c: data[:, header.index(c)] for c in VARIABLE_COLUMNS if c in header})
        _check_degrees(path, angle_cols, pos)
        return pos
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            files.header_line(fh, path, param="data")
            fh.seek(0)
            rows = list(csv.reader(fh))
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror})", param="data") from None
    except UnicodeDecodeError:
        raise DataError(f"{path}: not a UTF-8 text CSV file", param="data") from None
    except csv.Error as e:
        raise DataError(f"{path}: not a CSV file of positions ({e})", param="data") from None
    if not rows:
        raise DataError(f"{path}: empty file; expected a header {','.join(required)}", param="data")
    header = [h.strip() for h in rows[0]]
    if len(set(header)) != len(header):
        dup = sorted({h for h in header if header.count(h) > 1})
        raise DataError(f"{path}: duplicate column(s) {', '.join(dup)} in the header", param="data")
    missing = [c for c in required if c not in header]
    if missing:
        raise DataError(f"{path}: missing column(s) {', '.join(missing)}; header is {','.join(header)}", param="data")
    numeric = [c for c in required if c != "mount"] + [c for c in VARIABLE_COLUMNS if c in header]
    data = {c: [] for c in header}
    for line, row in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise DataError(f"{path} line {line}: {len(row)} fields, header has {len(header)}", param="data")
        for c, cell in zip(header, row):
            if c == "mount" and "mount" in required and cell.strip() not in mountings:
                raise DataError(f"{path} line {line}: mount {cell.strip()!r} is not one of {', '.join(mountings)}",
                                param="data")
            data[c].append(_number(cell, path, line, c) if c in numeric else cell.strip())
    if not data[required[0]] and empty_ok:
        return Positions(path, np.zeros((0, len(angle_cols))), np.zeros((0, 3)),
                         np.zeros(0, int) if "mount" in required else None)
    if not data[required[0]]:
        raise DataError(f"{path}: no data rows after the header", param="data")
    mounts = (np.array([list(mountings).index(m) for m in data["mount"]]) if "mount" in required else None)
    pos = Positions(path, np.column_stack([data[c] for c in angle_cols]),
                    np.array([data["f1"], data["f2"], data["f3"]]).T, mounts,
                    {c: v for c, v in data.items() if c not in required})
    _check_degrees(path, angle_cols, pos)
    return pos


def _lines(path, chunk=1 << 24):
    """The number of line ends in a file, counted in chunks (no line is decoded)."""
    n = 0
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            n += block.count(b"\n")
    return n


#: The largest angle as read, degrees (ten turns): a stand's encoder reads within a turn or a few.
MAX_DEGREES = 3600.0


def _check_degrees(path, angle_cols, pos):
    for c, v in zip(angle_cols, pos.angles_deg.T):
        if len(v) and np.abs(v).max() > MAX_DEGREES:
            raise DataError(f"{path}: column {c} holds {v[np.argmax(np.abs(v))]:g} degrees, beyond ten turns "
                            f"(+-{MAX_DEGREES:g}); an angle as read lies within a turn or a few", param="data")
        if len(v) > 2 and np.abs(v).max() <= 2 * math.pi + 1e-9 and np.any(np.abs(v) > 1e-9):
            raise DataError(f"{path}: column {c} lies within +-2pi ({v.min():g} to {v.max():g}): "
                            "these look like radians; the column is in degrees", param="data")


def _numeric(path, required):
    """(header, data) when every cell of the file is a finite number, every row has every column, and
    the columns, each named once, include the required ones: read in C (a large file). None otherwise:
    the cell-by-cell reader then finds and names any problem."""
    try:
        with open(path, encoding="utf-8-sig") as fh:
            header = [h.strip() for h in files.header_line(fh, path, param="data").split(",")]
            if "mount" in header or any(c not in header for c in required) or len(set(header)) != len(header):
                return None
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)        # no data rows: said by the reader below
                data = np.loadtxt(fh, delimiter=",", dtype=float, comments=None, ndmin=2)
    except (OSError, ValueError, UnicodeDecodeError):
        return None
    if not len(data) or data.shape[1] != len(header) or not np.isfinite(data).all():
        return None
    return header, data


def read_plan(path, angles, mountings=None):
    """A plan file: columns <angle>_deg for each angle (degrees), and `mount` when the stand uses several
    mountings (the file `garant plan -o` writes). Returns (angles_deg (N, n), mounts (N,) or None)."""
    files.regular(path, "the plan file", MAX_BYTES, param="plan")
    multi = mountings is not None and len(mountings) > 1
    cols = [f"{a}_deg" for a in angles] + (["mount"] if multi else [])
    fast = None if multi else _numeric(path, cols)
    if fast is not None:
        header, data = fast
        return data[:, [header.index(c) for c in cols]], None
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            files.header_line(fh, path, param="plan")
            fh.seek(0)
            rows = list(csv.reader(fh))
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror})", param="plan") from None
    except (UnicodeDecodeError, csv.Error):
        raise DataError(f"{path}: not a CSV plan file", param="plan") from None
    if not rows or any(c not in [h.strip() for h in rows[0]] for c in cols):
        raise DataError(f"{path}: a plan needs the columns {','.join(cols)}", param="plan")
    header = [h.strip() for h in rows[0]]
    idx = [header.index(c) for c in cols]
    body = [r for r in rows[1:] if any(x.strip() for x in r)]
    if not body:
        raise DataError(f"{path}: no positions in the plan", param="plan")
    try:
        P = np.array([[_number(r[i], path, k, c) for i, c in zip(idx, cols) if c != "mount"]
                      for k, r in enumerate(body, 2)])
    except IndexError:
        raise DataError(f"{path}: a row has fewer fields than the header", param="plan") from None
    mounts = None
    if multi:
        names = [r[idx[-1]].strip() for r in body]
        bad = next((n for n in names if n not in mountings), None)
        if bad is not None:
            raise DataError(f"{path}: mount {bad!r} is not one of {', '.join(mountings)}", param="plan")
        mounts = np.array([list(mountings).index(n) for n in names])
    return P, mounts


def from_columns(data, names, mounts):
    """Positions from a pandas DataFrame (columns as in the CSV: <angle>_deg, f1, f2, f3 and mount) or an
    array (N, angles + 3): the stand's angles in degrees, then f1, f2, f3 in m/s^2 (and, for a stand with
    several mountings, a last column with the mounting's index)."""
    cols = [f"{a}_deg" for a in names] + ["f1", "f2", "f3"]
    multi = len(mounts) > 1
    if hasattr(data, "columns"):                       # a pandas DataFrame, read by column name
        names_in = [str(c) for c in data.columns]
        twice = sorted({c for c in names_in if names_in.count(c) > 1})
        if twice:
            raise DataError(f"data: the DataFrame has the column {twice[0][:40]} more than once", param="data")
        missing = [c for c in cols + (["mount"] * multi) if c not in data.columns]
        if missing:
            raise DataError(f"data: missing column(s) {', '.join(missing)}", param="data")
        values = np.column_stack([real_array(data[c], f"data: column {c}") for c in cols])
        m = None if not multi else np.array([mounts.index(v) if v in mounts else -1 for v in data["mount"]])
    else:
        arr = real_array(data, "data")
        width = len(cols) + multi
        if arr.ndim != 2 or arr.shape[1] != width:
            raise DataError(f"data: expected an array of shape (N, {width}): {', '.join(cols)}"
                            + (", mounting index" if multi else "") + f"; got shape {arr.shape}", param="data")
        values, m = arr[:, :len(cols)], (arr[:, -1] if multi else None)
    if not np.all(np.isfinite(values)):
        raise DataError("data: every angle and reading must be a finite number", param="data")
    if m is not None and not np.all(m == np.round(m)):
        raise DataError("data: a mounting index must be a whole number", param="data")
    m = None if m is None else np.asarray(m, float).astype(int)
    if m is not None and (np.any(m < 0) or np.any(m >= len(mounts))):
        raise DataError(f"data: a mounting is not one of the stand's ({', '.join(mounts)})", param="data")
    pos = Positions("data", values[:, :len(names)], values[:, len(names):], m)
    _check_degrees("data", cols[:len(names)], pos)
    return pos
