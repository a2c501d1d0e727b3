"""The notebook API: a few functions with the same content as the commands' JSON (docs/api.md).

Each returns plain Python objects (dicts, lists, numpy arrays); errors are raised as DataError.
"""
import numpy as np

from . import models
from .cli.args import G_DEFAULT


def plan(model):
    """Optimal guaranteed errors (units of sigma) and a minimal optimal plan of a stand."""
    from .solve import plans
    mod = models.load(model)
    names, mounts = models.layout(mod)
    r = plans.search(mod)
    best = list(r.optimal_plans[0])
    return {"model": model, "angles": names, "q_names": list(mod.Q_NAMES), "definitions": list(mod.Q_DEFINITIONS),
            "guaranteed_errors": [float(e) for e in r.errors], "min_positions": r.min_positions,
            "plan_deg": r.angles_deg[best].tolist(),
            "plan_mountings": [mounts[k] for k in r.mounts[best]] if len(mounts) > 1 else None}


def estimate(model, data, sigma, g=None, g_uncertainty=None, prior=None, mount=None, gamma="lower"):
    """The verdict, q and guaranteed errors from a positions CSV (as `garant estimate --json`).

    g: local gravity in m/s^2 (None: 9.81, with the uncertainty of an assumed g); g_uncertainty: the
    bound on Delta_g/g; prior: one a-priori bound for every stand, mounting and block error (an
    override of the description's bounds). The result's "premises" says what the bounds assume."""
    from .io.positions import read_positions
    from .workflows.estimate import estimate as run
    from .workflows.premises import premises
    mod = models.load(model)
    names, mounts = models.layout(mod)
    remount = None if str(model).endswith(".toml") else models.load_remount(model)
    prem = premises(mod, sigma, G_DEFAULT if g is None else g, g_given=g is not None,
                    g_uncertainty=g_uncertainty, prior=prior)
    return run(mod, read_positions(data, names, mounts), sigma, prem.g, remount=remount, mount=mount, gamma=gamma,
               premises=prem)


def calibrate_norm(log, g=G_DEFAULT, params=9, fmt=None, sensor="adxl355", delta_sigma=None):
    """Calibrate a static log through the norm relation (as `garant calibrate-norm --json`); when the data
    are consistent the result holds "calibration", the dictionary `apply` takes."""
    from .io import calibration, recordings
    from .workflows import calibrate_norm as cn
    mod = models.load("norm")
    data = recordings.read_log(log, fmt, sensor)
    stills, _ = recordings.still_intervals(data)
    res = cn.run(mod, stills, g, params, log, delta_sigma, recordings.quantum(data))
    if res["consistent"]:
        res["calibration"] = calibration.from_norm(res, mod.AXES)
    return res


def diagnose(model, data, sigma, g=G_DEFAULT, prior=None):
    """The missing-effect workflow (as `garant diagnose --json`)."""
    from .io.positions import read_positions
    from .workflows import diagnose as dg
    mod = models.load(model)
    names, mounts = models.layout(mod)
    res = dg.diagnose(models.stand_model(model), mod, read_positions(data, names, mounts), sigma, g, prior)
    res.pop("_study")
    return res


def apply(calibration, log, fmt=None, sensor="adxl355"):
    """Correct a raw log: (time s, specific force (N, 3) m/s^2, worst-case error (N, 3) m/s^2).
    `calibration` is a garant-calibration-1 file or the dictionary `calibrate_norm` returns."""
    from .io import calibration as cal_io, recordings
    if isinstance(calibration, dict):
        cal = {k: np.asarray(v, float) if isinstance(v, list) else v for k, v in calibration.items()}
    else:
        cal = cal_io.read(calibration)
    data = recordings.read_log(log, fmt, sensor)
    a, bound = cal_io.apply(cal, data.raw)
    return data.t, a, bound
