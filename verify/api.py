"""The notebook API: a few functions with the same content as the commands' JSON (docs/api.md).

Each returns a result object (verify/io/results.py): a dict of the command's JSON fields, also reachable
as attributes, with numpy arrays, `to_dict()`, `to_json()` and a short repr; errors are raised as
DataError.
"""

import os

from . import models, options as checks
from .errors import DataError
from .io import results
from .io.recordings import FORMATS, SENSORS
from .workflows import jobs


#: The check of each argument (verify/options.py: the same function as the command's option type).
CHECKS = {"sigma": checks.noise, "delta_sigma": checks.noise, "g": checks.gravity, "g_uncertainty": checks.small,
          "prior": checks.small, "grid": checks.positive, "target": checks.positive,
          "count_seconds": checks.positive, "search_seconds": checks.positive, "max_candidates": checks.positive_int,
          "search_nodes": checks.positive_int, "count_nodes": checks.positive_int,
          "window": checks.positive, "k": checks.positive, "min_still": checks.positive,
          "params": checks.one_of(9, 12), "fmt": checks.one_of(*FORMATS), "sensor": checks.one_of(*sorted(SENSORS)),
          "gamma": checks.one_of("lower", "symmetric"), "mount": checks.text, "which_run": checks.text,
          "trust_units": checks.flag, "diagnose": checks.flag, "bound": checks.bounds,
          "frame": checks.one_of("garant", "imu_tk"), "rate": checks.rate, "jobs": checks.positive_int,
          "temperature": checks.degree}


def _api(fn):
    """The API's form of a job: each argument checked as the command checks its option (CHECKS), a
    DataError's options named as the API's arguments (`imu=`: errors.opt), and the input files the result
    came from remembered, so that `result.to_json(path)` never writes over one of them."""
    import functools
    import inspect
    signature = inspect.signature(fn)

    @functools.wraps(fn)
    def call(*args, **kwargs):
        bound = signature.bind(*args, **kwargs)
        for name, value in bound.arguments.items():
            if name in CHECKS:
                bound.arguments[name] = checks.check(name, value, CHECKS[name])
            elif name == "imu" and value != "all":
                bound.arguments[name] = checks.check(name, value, checks.positive_int)
        try:
            out = fn(*bound.args, **bound.kwargs)
        except DataError as e:
            raise DataError(e.render("api"), param=e.param) from None
        if isinstance(out, results.Result):
            out._inputs = tuple(str(v) for v in bound.arguments.values()
                               if isinstance(v, (str, os.PathLike)) and os.path.isfile(v))
        return out
    return call


@_api
def plan(model, grid=None, count_seconds=None, max_candidates=None, search_seconds=None, search_nodes=None,
         count_nodes=None):
    """Optimal guaranteed errors (units of sigma), the minimal optimal plans and the preferred one, exactly
    as `garant plan MODEL --json` (workflows/plan.py does both); `norm` gives the orientations of 001.
    `max_candidates` bounds the size of the search, `search_nodes` and `count_nodes` its work (the same plan
    on every machine), `search_seconds` and `count_seconds` are its safety stops (None: the command's
    defaults)."""
    from .workflows.plan import COUNT_SECONDS, MAX_CANDIDATES, SEARCH_SECONDS, norm_plan, plan as search_plan
    mod = models.load(model)
    if model == "norm":
        return results.Plan(norm_plan(mod))
    return results.Plan(search_plan(mod, model, grid, count_seconds or COUNT_SECONDS, max_candidates or MAX_CANDIDATES,
                                    search_seconds or SEARCH_SECONDS, search_nodes=search_nodes,
                                    count_nodes=count_nodes).to_dict())


@_api
def estimate(model, data, sigma, g=None, g_uncertainty=None, prior=None, mount=None, gamma="lower",
             imu=None, which_run=None, bound=None, fmt=None, sections=None, temperature=None):
    """The verdict, q and guaranteed errors from positions, as `garant estimate --json` (the same
    function: workflows/jobs.py).

    Parameters
    ----------
    model : a built-in stand's name or a STAND.toml path.
    data : a positions CSV, a means file (then `imu` and `which_run`), imucal's session (then fmt="imucal" and
        `sections`, its section list, unless it has a part column), a DataFrame or an array (N, angles + 3).
    sigma : the noise bound (5) of 000, dimensionless (units of g).
    g : local gravity, m/s^2 (None: 9.81, with the uncertainty of an assumed g).
    g_uncertainty : the bound on Delta_g/g. prior : one a-priori bound for every stand, mounting and block
        error (an override of the description's bounds). bound : {parameter: a-priori bound} (rad or
        dimensionless), over the description's and `prior`, as --bound NAME=VALUE. mount : a mounting like
        "+y+z+x" (two-axis): also the block's physical errors, (28)-(29) of 000. gamma : "lower" or
        "symmetric", (29). temperature : D (1-3), as --temperature D: each block parameter a polynomial of
        degree D in T (the data's temp_c column), each q's polynomial with one bound over the range ("thermal",
        docs/thermal.md).

    Returns
    -------
    Estimate; its "premises" say what the bounds assume, and "premises_refuted" lists each q the readings
    put beyond what those a-priori bounds allow (then no bound is guaranteed and no calibration given).
    """
    return jobs.estimate(model, data, sigma, g, g_uncertainty, prior, mount, gamma, imu, which_run, bound=bound,
                         fmt=fmt, sections=sections, temperature=temperature)


@_api
def calibrate_norm(log, g=None, params=9, fmt=None, sensor=None, delta_sigma=None, imu=None, window=1.0,
                   k=10.0, min_still=2.0, diagnose=False, g_uncertainty=None, rate=None):
    """Calibrate a static log through the norm relation (2.2) of 001, as `garant calibrate-norm --json`.

    Parameters
    ----------
    log : a log path (formats of docs/formats.md), an array (N, 4): time in s, then x, y, z raw, or a pandas
        DataFrame as `apply` takes it (acc_x, acc_y, acc_z; a time column or `rate`).
    rate : Hz, for a log of sample indices (--format imucal, a DataFrame without a time column).
    g : local gravity, m/s^2 (None: 9.81 assumed, |Delta_g/g| <= 5e-3 in the calibration's bounds).
    g_uncertainty : the bound on |Delta_g/g| (default 1e-5 with g, 5e-3 without).
    params : 9 (scale, misalignment, bias) or 12 (also the nonlinearity).
    fmt, sensor, imu : the log's format, an OpenAXES accelerometer, an IMU of a multi-IMU stream.
    delta_sigma : a guaranteed bound on |delta_sigma| of (2.2), units of g (None: the noise rule).
    window, k, min_still : still when the moving variance over `window` s is below k times the first
        seconds', for at least `min_still` s. diagnose : also test the effect catalogue.

    Returns
    -------
    NormCalibration; when consistent its "calibration" is the dictionary `apply` takes.
    """
    return jobs.calibrate_norm(log, g, params, fmt, sensor, imu, window, k, min_still, delta_sigma, diagnose,
                               g_uncertainty, rate)


@_api
def calibrate_many(logs, jobs=None, spec=None, g=None, params=9, fmt=None, sensor=None, delta_sigma=None, imu=None,
                   window=1.0, k=10.0, min_still=2.0, g_uncertainty=None, rate=None):
    """Many logs calibrated as `calibrate_norm`, in one process pool (`jobs`, default every core; the same
    results whatever it is), as `garant calibrate-norm LOG... --out DIR`: a list of rows, one per log in
    order, each {"log", "status" (consistent, refuted or error), "message", "result" (the calibration's
    dictionary, or None)} and, with `spec` (a SPEC.toml path: [limits] and [bound_limits] of scale,
    misalignment, bias), "verdict" (pass: every guaranteed interval within its limit; fail; undecided) and
    "reason". A log that cannot be calibrated is its row, never the end of the batch."""
    from .workflows import batch
    if not isinstance(logs, (list, tuple)) or not logs:
        raise DataError("logs: a list of log paths or arrays")
    return batch.calibrate_many(logs, jobs, batch.read_spec(spec) if spec else None, None, g=g, params=params,
                                fmt=fmt, sensor=sensor, imu=imu, window=window, k=k, min_still=min_still,
                                delta_sigma=delta_sigma, g_uncertainty=g_uncertainty, rate=rate)


@_api
def next_position(model, data, sigma, target=None, grid=None, g=None, g_uncertainty=None, prior=None,
                  search_seconds=None, max_candidates=None, mount=None, gamma="lower", bound=None):
    """The position to measure next, as `garant next --json` (the same function: workflows/jobs.py).

    Parameters
    ----------
    model : a built-in stand's name or a STAND.toml. data : the positions measured so far (a CSV path, a
    header alone at the start, a DataFrame or an array (0 or more rows): see `positions`). sigma : the
    noise bound (units of g). target : the guaranteed error wanted for every q (units of q); None: sigma
    times the stand's optimal errors. grid : candidate step in degrees (at most `max_candidates`
    positions; None: the command's default). g, g_uncertainty, prior, bound : the
    premises of the verdict on the data, as in `estimate`. mount, gamma : target the block's parameters
    in this mounting ((28)-(29) of 000, two-axis) instead of the q's, as `estimate --mount`.

    Returns
    -------
    NextPosition: `next` (None when `done`), `still_needed`, the errors before and after.
    """
    return jobs.next_position(model, data, sigma, target, grid, g, g_uncertainty, prior, search_seconds,
                              max_candidates, mount, gamma, bound)


@_api
def diagnose(model, data, sigma, g=None, prior=None, g_uncertainty=None, bound=None):
    """The missing-effect workflow on positions (a CSV path, a DataFrame or an array: see `positions`),
    as `garant diagnose --json`.

    Parameters
    ----------
    model : a built-in stand's name or a STAND.toml. data : positions. sigma : the noise bound (units of g).
    g : gravity, m/s^2 (None: 9.81 with the uncertainty of an assumed g). prior, g_uncertainty, bound : premises
    as in `estimate`.

    Returns
    -------
    Diagnosis.
    """
    return jobs.diagnose(model, data, sigma, g, prior, g_uncertainty, bound)


@_api
def apply(calibration, log, fmt=None, sensor=None, imu=None, trust_units=False, frame="garant", rate=None):
    """Correct a raw log with a calibration, as `garant apply`.

    Parameters
    ----------
    calibration : a garant-calibration-1 file or the dictionary a result's "calibration" holds; either is
        checked as `garant apply` checks it (schema, a well-conditioned M, the log's unit unless
        `trust_units`).
    log : a log path, an array (N, 4): time in s, then x, y, z raw, or a pandas DataFrame with columns
        acc_x, acc_y, acc_z (or x, y, z, ...) and a time column (time_s, time_ms, ...) or, without one,
        `rate` (Hz) over its index: then a calibrated copy of the DataFrame is returned (its accelerometer
        columns corrected, m/s^2, and bound_x, bound_y, bound_z added), as imucal's calibrate_df.
    frame : "garant" (M as calibrated) or "imu_tk", the frame of the imu_tk export (for a norm calibration
        turned into imu_tk's upper-triangular T; the command prints the angle between them).

    Returns
    -------
    Correction: t (s), a (N, 3) m/s^2 and bound (N, 3) m/s^2, the worst-case error of each component;
    it unpacks as (t, a, bound).
    """
    return jobs.apply(calibration, log, fmt, sensor, imu, trust_units, frame=frame, rate=rate)
