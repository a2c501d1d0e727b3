"""The notebook API: a few functions with the same content as the commands' JSON (docs/api.md).

Each returns a result object (verify/io/results.py): a dict of the command's JSON fields, also reachable
as attributes, with numpy arrays, `to_dict()`, `to_json()` and a short repr; errors are raised as
DataError.
"""
import numpy as np

from . import models
from .errors import DataError
from .cli.args import G_DEFAULT
from .io import results


#: The commands' options by the API's argument names: an error raised below names what the caller wrote.
ARGUMENTS = {"--imu": "imu", "--format": "fmt", "--sigma": "sigma", "--g-uncertainty": "g_uncertainty",
             "--g": "g", "--prior": "prior", "--delta-sigma": "delta_sigma", "--mount": "mount",
             "--trust-units": "trust_units=True", "--params": "params", "--sensor": "sensor", "--grid": "grid"}


def _api_names(fn):
    """Re-raise a DataError with each command option in its text replaced by the API's argument name."""
    import functools
    import re

    @functools.wraps(fn)
    def call(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except DataError as e:
            text = re.sub(r"--[a-z][a-z-]*", lambda m: ARGUMENTS.get(m.group(0), m.group(0)), str(e))
            raise DataError(text) from None
    return call


@_api_names
def plan(model, grid=None, count_seconds=5.0):
    """Optimal guaranteed errors (units of sigma), the minimal optimal plans and the preferred one, exactly
    as `garant plan MODEL --json` (workflows/plan.py does both); `norm` gives the orientations of 001."""
    from .workflows.plan import norm_plan, plan as search_plan
    mod = models.load(model)
    if model == "norm":
        return results.Plan(norm_plan(mod))
    return results.Plan(search_plan(mod, model, grid, count_seconds).to_dict())


@_api_names
def positions(model_module, data):
    """Positions from a CSV path, a pandas DataFrame (columns as in the CSV) or an array (N, angles + 3):
    the stand's angles in degrees, then f1, f2, f3 in m/s^2 (and, for a stand with several mountings,
    a last column with the mounting's index)."""
    from .io.positions import Positions, read_positions
    names, mounts = models.layout(model_module)
    if isinstance(data, (str, bytes)) or hasattr(data, "__fspath__"):
        return read_positions(data, names, mounts)
    cols = [f"{a}_deg" for a in names] + ["f1", "f2", "f3"]
    multi = len(mounts) > 1
    if hasattr(data, "columns"):                       # a pandas DataFrame, read by column name
        missing = [c for c in cols + (["mount"] * multi) if c not in data.columns]
        if missing:
            raise DataError(f"data: missing column(s) {', '.join(missing)}")
        values = np.column_stack([np.asarray(data[c], float) for c in cols])
        m = None if not multi else np.array([mounts.index(v) if v in mounts else -1 for v in data["mount"]])
    else:
        try:
            arr = np.asarray(data, float)
        except (TypeError, ValueError):
            raise DataError("data: expected a CSV path, a DataFrame or an array of numbers") from None
        width = len(cols) + multi
        if arr.ndim != 2 or arr.shape[1] != width:
            raise DataError(f"data: expected an array of shape (N, {width}): {', '.join(cols)}"
                            + (", mounting index" if multi else "") + f"; got shape {arr.shape}")
        values, m = arr[:, :len(cols)], (arr[:, -1].astype(int) if multi else None)
    if not np.all(np.isfinite(values)):
        raise DataError("data: every angle and reading must be a finite number")
    if m is not None and (np.any(m < 0) or np.any(m >= len(mounts))):
        raise DataError(f"data: a mounting is not one of the stand's ({', '.join(mounts)})")
    return Positions("data", values[:, :len(names)], values[:, len(names):], m)


@_api_names
def estimate(model, data, sigma, g=None, g_uncertainty=None, prior=None, mount=None, gamma="lower"):
    """The verdict, q and guaranteed errors from positions (a CSV path, a DataFrame or an array: see
    `positions`), as `garant estimate --json`.

    g: local gravity in m/s^2 (None: 9.81, with the uncertainty of an assumed g); g_uncertainty: the
    bound on Delta_g/g; prior: one a-priori bound for every stand, mounting and block error (an
    override of the description's bounds). The result's "premises" says what the bounds assume."""
    from .workflows.estimate import estimate as run
    from .workflows.premises import premises
    mod = models.load(model)
    remount = None if str(model).endswith(".toml") else models.load_remount(model)
    prem = premises(mod, sigma, G_DEFAULT if g is None else g, g_given=g is not None,
                    g_uncertainty=g_uncertainty, prior=prior)
    return results.Estimate(run(mod, positions(mod, data), sigma, prem.g, remount=remount, mount=mount, gamma=gamma,
                                premises=prem))


@_api_names
def calibrate_norm(log, g=G_DEFAULT, params=9, fmt=None, sensor="adxl355", delta_sigma=None, imu=None):
    """Calibrate a static log through the norm relation (as `garant calibrate-norm --json`); when the data
    are consistent the result holds "calibration", the dictionary `apply` takes."""
    from .io import calibration, recordings
    from .workflows import calibrate_norm as cn
    mod = models.load("norm")
    data = recordings.read_log(log, fmt, sensor, imu)
    stills, _ = recordings.still_intervals(data)
    res = cn.run(mod, stills, g, params, log, delta_sigma, recordings.quantum(data))
    if res["consistent"]:
        res["calibration"] = calibration.from_norm(res, mod.AXES)
    return results.NormCalibration(res)


@_api_names
def diagnose(model, data, sigma, g=G_DEFAULT, prior=None, g_uncertainty=None):
    """The missing-effect workflow on positions (a CSV path, a DataFrame or an array: see `positions`),
    as `garant diagnose --json`."""
    from .workflows import diagnose as dg
    mod = models.load(model)
    res = dg.diagnose(models.stand_model(model), mod, positions(mod, data), sigma, g, prior, g_uncertainty)
    res.pop("_study")
    return results.Diagnosis(res)


@_api_names
def apply(calibration, log, fmt=None, sensor="adxl355", imu=None, trust_units=False):
    """Correct a raw log: a Correction with t (s), a (N, 3) m/s^2 and bound (N, 3) m/s^2, the worst-case
    error of each component; it unpacks as (t, a, bound).
    `calibration` is a garant-calibration-1 file or the dictionary `calibrate_norm` returns; either is
    checked as `garant apply` checks it (schema, a well-conditioned M, the log's unit unless
    `trust_units`)."""
    from .io import calibration as cal_io, recordings
    cal = cal_io.checked(calibration) if isinstance(calibration, dict) else cal_io.read(calibration)
    data = recordings.read_log(log, fmt, sensor, imu)
    if not trust_units:
        cal_io.check_units(cal, log, data.raw[:100_000], "the calibration")
    a, bound = cal_io.apply(cal, data.raw)
    return results.Correction(t=data.t, a=a, bound=bound)
