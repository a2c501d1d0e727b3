"""Reading measured positions from CSV, with one clear line for every way a file can be wrong."""
import csv
import math
from dataclasses import dataclass, field

import numpy as np


class DataError(ValueError):
    """A problem with the user's input: the CLI prints it as one line and exits with status 2."""


@dataclass
class Positions:
    """Readings at stand positions: angles as read (degrees) and specific force f (m/s^2)."""

    path: str
    alpha_deg: np.ndarray
    beta_deg: np.ndarray
    f: np.ndarray                      # (N, 3), m/s^2
    extra: dict = field(default_factory=dict)   # other columns, kept as text

    @property
    def radians(self):
        return np.deg2rad(self.alpha_deg), np.deg2rad(self.beta_deg)


REQUIRED = ("alpha_deg", "beta_deg", "f1", "f2", "f3")


def _number(text, path, line, col):
    try:
        v = float(text)
    except ValueError:
        raise DataError(f"{path} line {line}: column {col}: {text.strip()!r} is not a number") from None
    if not math.isfinite(v):
        raise DataError(f"{path} line {line}: column {col}: {text.strip()} is not a finite number")
    return v


def read_positions(path):
    """Read a CSV with header alpha_deg,beta_deg,f1,f2,f3 (extra columns kept)."""
    try:
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror})") from None
    except UnicodeDecodeError:
        raise DataError(f"{path}: not a text CSV file") from None
    if not rows:
        raise DataError(f"{path}: empty file; expected a header {','.join(REQUIRED)}")
    header = [h.strip() for h in rows[0]]
    missing = [c for c in REQUIRED if c not in header]
    if missing:
        raise DataError(f"{path}: missing column(s) {', '.join(missing)}; header is {','.join(header)}")
    data = {c: [] for c in header}
    for line, row in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise DataError(f"{path} line {line}: {len(row)} fields, header has {len(header)}")
        for c, cell in zip(header, row):
            data[c].append(_number(cell, path, line, c) if c in REQUIRED else cell)
    if not data[REQUIRED[0]]:
        raise DataError(f"{path}: no data rows after the header")
    pos = Positions(path, np.array(data["alpha_deg"]), np.array(data["beta_deg"]),
                    np.array([data["f1"], data["f2"], data["f3"]]).T,
                    {c: v for c, v in data.items() if c not in REQUIRED})
    for c, v in (("alpha_deg", pos.alpha_deg), ("beta_deg", pos.beta_deg)):
        if len(v) > 2 and np.abs(v).max() <= 2 * math.pi + 1e-9 and np.any(np.abs(v) > 1e-9):
            raise DataError(f"{path}: column {c} lies within +-2pi ({v.min():g} to {v.max():g}): "
                            "these look like radians; the column is in degrees")
    return pos
