"""imucal's Ferraris sessions in, its calibration file out.

A session is a CSV of samples (a sample index, no time; columns acc_x, acc_y, acc_z and gyr_x, gyr_y,
gyr_z) with its section list, a JSON {"x_p": {"start": i, "end": j}, ...} of sample ranges, or an
annotated session whose column `part` labels each row. The six static sections hold each block axis up
(x_p, y_p, z_p) and down (x_a, y_a, z_a); the rotations (x_rot, ...) are the gyroscope's and not read.
The file out is imucal's FerrarisCalibrationInfo JSON, acc_cal = R_a^-1 K_a^-1 (acc - b_a).
"""
import csv

import numpy as np

from ..errors import DataError, opt
from . import files

#: The six static sections and the up-direction (block axes) each holds.
FACES = {"x_p": (1, 0, 0), "x_a": (-1, 0, 0), "y_p": (0, 1, 0), "y_a": (0, -1, 0), "z_p": (0, 0, 1), "z_a": (0, 0, -1)}
ACC = ("acc_x", "acc_y", "acc_z")
MAX_BYTES = 500_000_000


def read_sections(path, sections=None, param="data"):
    """{face: (samples (n, 3) of the accelerometer, in the file's unit)} for the six static sections of a
    session: by the section list `sections` (a JSON path) or, without it, by the session's `part` column.
    `param`: the argument the session was given as (its errors name it)."""
    files.regular(path, "the imucal session", MAX_BYTES, param=param)
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            header = [h.strip() for h in next(reader, [])]
            missing = [c for c in ACC if c not in header]
            if missing:
                raise DataError(f"{path}: an imucal session needs the columns {', '.join(ACC)}; missing "
                                f"{', '.join(missing)}", param=param)
            cols = [header.index(c) for c in ACC]
            part = header.index("part") if "part" in header else None
            rows, labels = [], []
            for k, row in enumerate(reader, 2):
                try:
                    rows.append([float(row[c]) for c in cols])
                except (ValueError, IndexError):
                    raise DataError(f"{path} line {k}: an accelerometer value is missing or not a number",
                                    param=param) from None
                if part is not None:
                    labels.append(row[part].strip())
    except UnicodeDecodeError:
        raise DataError(f"{path}: not a text CSV", param=param) from None
    data = np.array(rows, float).reshape(-1, 3)
    if not np.all(np.isfinite(data)):
        raise DataError(f"{path}: an accelerometer value is not finite", param=param)
    if sections is not None:
        spans = _section_list(sections, len(data))
        out = {face: data[spans[face][0]:spans[face][1]] for face in FACES}
    elif part is not None:
        labels = np.array(labels)
        out = {face: data[labels == face] for face in FACES}
    else:
        raise DataError(f"{path}: no `part` column: give the section list with {opt('sections')} FILE.json")
    short = [f for f, x in out.items() if len(x) < 2]
    if short:
        raise DataError(f"{path}: the section(s) {', '.join(short)} hold fewer than 2 samples; a six-face session "
                        f"needs all of {', '.join(FACES)}", param=param)
    return out


def _section_list(path, n):
    """{face: (start, end)} from imucal's section list JSON, each a range of sample indices within n."""
    data = files.read_json(path, "a JSON section list", param="sections")
    out = {}
    for face in FACES:
        s = data.get(face) if isinstance(data, dict) else None
        if not isinstance(s, dict) or not all(isinstance(s.get(k), int) and not isinstance(s.get(k), bool)
                                              for k in ("start", "end")):
            raise DataError(f'{path}: {face} must be {{"start": i, "end": j}}, sample indices (imucal\'s section list)',
                            param="sections")
        if not 0 <= s["start"] < s["end"] <= n:
            raise DataError(f"{path}: {face} spans samples {s['start']} to {s['end']}, outside the session's {n}",
                            param="sections")
        out[face] = (s["start"], s["end"])
    return out


def means(path, sections=None):
    """(U (6, 3) up-directions, F (6, 3) mean readings, standard errors (6, 3)) of the six faces."""
    parts = read_sections(path, sections)
    U = np.array([FACES[f] for f in FACES], float)
    F = np.array([parts[f].mean(axis=0) for f in FACES])
    se = np.array([parts[f].std(axis=0, ddof=1) / np.sqrt(len(parts[f])) for f in FACES])
    return U, F, se


def calibration_json(cal, gyro=None, comment=""):
    """imucal's FerrarisCalibrationInfo (format 2.0) as a dictionary: the accelerometer from garant's
    calibration (a = M (raw - b): K_a R_a = M^-1, K_a the norms of M^-1's rows, R_a unit rows, b_a = b),
    the gyroscope from `gyro` (an imucal calibration dictionary) or the identity, said in the comment."""
    M, b = np.asarray(cal["M"], float), np.asarray(cal["b"], float)
    P = np.linalg.inv(M)
    k = np.linalg.norm(P, axis=1)
    unit = "m/s^2" if cal.get("raw_unit") == "m/s^2" else "a.u."
    g = gyro or {"K_g": np.eye(3).tolist(), "R_g": np.eye(3).tolist(), "K_ga": np.zeros((3, 3)).tolist(),
                 "b_g": [0.0, 0.0, 0.0], "gyr_unit": "deg/s", "from_gyr_unit": "deg/s"}
    said = "gyroscope from the imucal calibration given" if gyro else "gyroscope NOT calibrated (identity)"
    return {"acc_unit": "m/s^2", "gyr_unit": g.get("gyr_unit", "deg/s"), "from_acc_unit": unit,
            "from_gyr_unit": g.get("from_gyr_unit", "deg/s"),
            "comment": (f"garant: accelerometer from {cal.get('source', 'a garant calibration')}; worst-case error of "
                        f"a corrected sample: (I - B)^-1 (B |a| + bound_bias) with B = "
                        f"{np.round(cal['bound_matrix'], 8).tolist()}"
                        f", bound_bias = {np.round(cal['bound_bias'], 8).tolist()} m/s^2; {said}"
                        + (f"; {comment}" if comment else "")),
            "K_a": np.diag(k).tolist(), "R_a": (P / k[:, None]).tolist(), "b_a": b.tolist(),
            "K_g": g["K_g"], "R_g": g["R_g"], "K_ga": g["K_ga"], "b_g": g["b_g"],
            "cal_type": "Ferraris", "_format_version": "2.0"}


def read_calibration(path):
    """An imucal calibration file's dictionary (for its gyroscope part)."""
    data = files.read_json(path, "an imucal calibration", param="imucal_gyro")
    need = ("K_g", "R_g", "K_ga", "b_g")
    if not isinstance(data, dict) or any(k not in data for k in need):
        raise DataError(f"{path}: an imucal Ferraris calibration has {', '.join(need)}", param="imucal_gyro")
    for key, shape in (("K_g", (3, 3)), ("R_g", (3, 3)), ("K_ga", (3, 3)), ("b_g", (3,))):
        try:
            value = np.array(data[key], dtype=float)
        except (TypeError, ValueError):
            value = None
        if value is None or value.shape != shape or not np.all(np.isfinite(value)):
            raise DataError(f"{path}: {key} must be {' x '.join(map(str, shape))} finite numbers, as imucal writes it",
                            param="imucal_gyro")
    return data
