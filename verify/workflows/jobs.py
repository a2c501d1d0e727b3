"""The jobs a user runs, one function each, from their inputs (paths or arrays) to the result object.

The command (cli/) parses its options, calls one of these and prints the result; the notebook API
(api.py) calls the same function and returns the result: the two cannot disagree. Results are the
objects of io/results.py (a dict whose keys are also attributes, with `to_json()`).
"""
from __future__ import annotations

import os
from typing import TYPE_CHECKING, Callable, Iterator, Mapping, Optional, Sequence, Union

import numpy as np

from .. import models
from ..errors import DataError, opt
from .. import options
from ..defaults import FORMATS
from ..options import by_the_job, constraints, real_array
from ..io import results
from .premises import G_DEFAULT, premises as make_premises

if TYPE_CHECKING:                          # the types of the seams, for readers and type checkers (not loaded)
    import pandas

    #: A file the user names.
    Path = Union[str, os.PathLike]
    #: Readings at positions: a positions CSV (or a means file, imucal's session), or an array / DataFrame.
    Data = Union[Path, np.ndarray, pandas.DataFrame, Sequence[Sequence[float]]]
    #: A raw log: a path of any supported format, an array (N, 4) of time (s) and three axes, or a DataFrame.
    Log = Union[Path, np.ndarray, pandas.DataFrame]


@constraints(model=options.model, data=by_the_job("jobs.positions_of"), sigma=options.noise,
             g=options.gravity, g_uncertainty=options.small, prior=options.small, bound=options.bounds,
             mount=options.text, gamma=options.one_of("lower", "symmetric"), imu=options.imu, which_run=options.text,
             format=options.one_of(*FORMATS), sections=options.path, thermal_degree=options.degree,
             progress=options.callback)
def estimate(model: Path, data: Data, sigma: float, *, g: Optional[float] = None,
             g_uncertainty: Optional[float] = None, prior: Optional[float] = None,
             bound: Optional[Mapping[str, float]] = None, mount: Optional[str] = None, gamma: str = "lower",
             imu: Optional[int] = None, which_run: Optional[str] = None, format: Optional[str] = None,
             sections: Optional[Path] = None, thermal_degree: Optional[int] = None,
             progress: Optional[Callable[[str], None]] = None) -> results.Estimate:
    """The verdict, q with guaranteed errors and (where the stand separates them) the block's errors, from
    positions: `garant estimate --json`.

    Parameters
    ----------
    model : str
        A built-in stand's name or a STAND.toml path.
    data : path, DataFrame or array
        A positions CSV, a means file (then `imu` and `which_run`), imucal's session (then format="imucal" and
        `sections`, its section list, unless it has a part column), a DataFrame or an array (N, angles + 3).
    sigma : float
        The noise bound (5) of 000, dimensionless (units of g).
    g : float, optional
        Local gravity, m/s^2 (None: 9.81, with the uncertainty of an assumed g).
    g_uncertainty : float, optional
        The bound on |Delta_g/g|.
    prior : float, optional
        One a-priori bound for every stand, mounting and block error (over the description's bounds).
    bound : dict, optional
        {parameter: a-priori bound} (rad or dimensionless), over the description's and `prior`, as
        --bound NAME=VALUE.
    mount : str, optional
        A mounting like "+y+z+x" (two-axis): also the block's physical errors, (28)-(29) of 000.
    gamma : {"lower", "symmetric"}
        The form of Gamma in (29).
    imu, which_run, format, sections
        Which IMU and run of a means file; the data's format and imucal's section list.
    thermal_degree : int, optional
        D (1-3): each block parameter a polynomial of degree D in T (the temp_c column), each q with one bound
        over the range ("thermal", docs/thermal.md); the calibration holds the block at T0 and its polynomial.
    progress : callable, optional
        Hears a line of progress on long work.

    Returns
    -------
    Estimate
        Its "premises" say what the bounds assume; "premises_refuted" lists each q the readings put beyond what
        those a-priori bounds allow (then no bound is guaranteed and no calibration given). A consistent result
        with the block's errors holds "calibration", the dictionary `apply` takes.
    """
    from . import estimate as est
    if models.kind(model) == "norm":
        raise DataError("model norm: the norm relation (2.2) of 001 has no stand positions to estimate from; "
                        "calibrate a static log with calibrate_norm (garant calibrate-norm)", param="model")
    if format == "imucal" and model != "six-face":
        raise DataError(f"{opt('format')} imucal: imucal's Ferraris session holds the unit on the faces of a cube, "
                        f"the six-face model; {str(model)[:60]!r} is another stand's: give --model six-face",
                        param="format")
    mod = models.load(model)
    remount = None if str(model).endswith(".toml") else models.load_remount(model)
    thermal = None
    if thermal_degree is not None:
        from . import thermal as th
        base = positions_of(mod, data, imu, which_run, fmt=format, sections=sections)
        T = th.temperatures(base, base.path)
        thermal = (thermal_degree, th.reference(T, thermal_degree, base.path))
        base_q = mod.Q_DEFINITIONS
        mod = models.thermal(model, *thermal)
        if tuple(mod.Q_DEFINITIONS[:len(base_q)]) != tuple(base_q):     # the remount formulas index the base's q
            raise RuntimeError(f"the thermal extension of {model} does not keep the base model's q first")
    if mount and (remount is None or mount not in remount.MOUNTS):
        raise DataError(f"{opt('mount')} needs a model with the remount formulas (two-axis) and a mounting like "
                        f"+y+z+x; got {mount!r}")
    prem = make_premises(mod, sigma, G_DEFAULT if g is None else g, g_given=g is not None,
                         g_uncertainty=g_uncertainty, prior=prior, bound=bound)
    res = est.estimate(mod, base if thermal else positions_of(mod, data, imu, which_run, fmt=format, sections=sections),
                       sigma, prem.g,
                       remount=remount, mount=mount,
                       gamma=gamma, premises=prem, progress=progress, thermal=thermal)
    section = res.pop("thermal_file", None)
    block_set = res["block"].pop("_set", None) if isinstance(res.get("block"), dict) else None
    lower_set = res.pop("_set", None)                 # the files', not the result's
    if res["consistent"] and not res.get("premises_refuted") and ("physical" in res or "block" in res):
        from ..io import calibration
        res["calibration"] = calibration.from_stand(res, lower_set) if "physical" in res else calibration.from_block(
            res, None if "thermal" in res else block_set)     # a thermal file's bound is its block's (apply_thermal)
        if "thermal" in res:
            if section is None:
                del res["calibration"]
            else:
                st = section.pop("_set", None)
                res["calibration"]["thermal"] = {"t0_c": res["thermal"]["t0_c"], "range_c": res["thermal"]["range_c"],
                                                 "degree": res["thermal"]["degree"], **section}
                if st is not None:
                    calibration.with_set(res["calibration"], st, st["g_uncertainty"])
    return results.Estimate(res)


def positions_of(mod, data, imu=None, which_run=None, empty_ok=False, fmt=None, sections=None):
    """Positions for `mod` from a positions CSV, a means file with known nominal directions (its run
    `which_run` of IMU `imu`, the directions turned into the stand's angles), imucal's six-face session
    (`fmt` "imucal", with its section list `sections` or a `part` column), a DataFrame or an array.
    `empty_ok`: a CSV of a header alone gives no positions rather than an error."""
    from ..io import means
    from ..io.positions import Positions, from_columns, read_positions
    from .directions import angles_for
    names, mounts = models.layout(mod)
    if isinstance(data, Positions):                  # read already (next reads them once for its sizing)
        return data
    if fmt == "imucal":
        from ..io import imucal
        U, F, _ = imucal.means(data, sections)
        norm = float(np.median(np.linalg.norm(F, axis=1)))
        if not 0.8 * G_DEFAULT < norm < 1.2 * G_DEFAULT:
            raise DataError(f"{data}: the six faces read {norm:.4g} in the file's unit, not about g: estimate takes a "
                            "session in m/s^2 (imucal's from_acc_unit m/s^2); calibrate raw counts through the norm "
                            "with garant calibrate-norm", param="data")
        return Positions(str(data), angles_for(mod, U, data), F)
    if sections is not None:
        raise DataError(f"{opt('sections')} applies to {opt('format')} imucal")
    if not (isinstance(data, (str, bytes)) or hasattr(data, "__fspath__")):
        return from_columns(data, names, mounts)
    if not means.looks_like(data):
        if imu is not None or which_run is not None:
            raise DataError(f"{opt('imu')} and {opt('which_run')} apply to a means file; {data} is a positions file")
        return read_positions(data, names, mounts, empty_ok)
    runs = means.read(data, imu)
    keys = [r.name.rsplit("=", 1)[-1] for r in runs]
    if which_run is None and len(runs) > 1:
        raise DataError(f"{data}: holds runs {', '.join(keys)}; choose one with {opt('which_run')} R")
    if which_run is not None and which_run not in keys:
        raise DataError(f"{opt('which_run')} {which_run}: {data} holds runs {', '.join(keys)}")
    run = runs[keys.index(which_run)] if which_run is not None else runs[0]
    if run.nominal is None:
        raise DataError(f"{data}: no nominal directions (nom_x, nom_y, nom_z); estimate needs known positions "
                        "(garant calibrate-norm and repeatability need none)", param="data")
    return Positions(str(data), angles_for(mod, run.nominal, data), np.array([st.mean for st in run.stills]))


def _misalignment_bounds(bound):
    """{misalignment: bound} of `bound` (--bound NAME=VALUE), each name alpha, beta or gamma, each bound a positive
    number of rad; None when none is given."""
    if not bound:
        return None
    if not isinstance(bound, dict):
        raise DataError(f"bound: give the misalignments' bounds as a dict, e.g. {{'alpha': 1e-3}}, not "
                        f"{type(bound).__name__}", param="bound")
    out = {}
    for name, value in bound.items():
        if name not in ("alpha", "beta", "gamma"):
            raise DataError(f"{opt('bound')} {str(name)[:40]}: calibrate-norm takes bounds of the misalignments "
                            "alpha, beta, gamma (rad)", param="bound")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < 0.5:
            raise DataError(f"{opt('bound')} {name}={str(value)[:40]}: give a bound in rad, above 0 and below 0.5",
                            param="bound")
        out[name] = float(value)
    return out


def _norm_premises(premises, g_uncertainty, g_source, statement=""):
    """A norm calibration's premises completed by the job: the gravity's uncertainty and source (the same type as an
    estimate's premises: the statement and the figures it names)."""
    return {**premises, "statement": premises["statement"] + statement, "g_uncertainty": g_uncertainty,
            "g_source": g_source}


@constraints(log=by_the_job("jobs.read_log"), g=options.gravity, g_uncertainty=options.small, bound=options.bounds,
             delta_sigma=options.noise, params=options.one_of(9, 12), format=options.one_of(*FORMATS),
             sensor=options.sensor, imu=options.imu, rate=options.rate, window=options.positive,
             k=options.positive, min_still=options.positive, diagnose=options.flag,
             effects=by_the_job("norm_effects.parse"), thermal_degree=options.degree)
def calibrate_norm(log: Log, *, g: Optional[float] = None, g_uncertainty: Optional[float] = None,
                   bound: Optional[Mapping[str, float]] = None, delta_sigma: Optional[float] = None, params: int = 9,
                   format: Optional[str] = None, sensor: Optional[str] = None, imu: Optional[int] = None,
                   rate: Optional[float] = None, window: float = 1.0, k: float = 10.0, min_still: float = 2.0,
                   diagnose: bool = False, effects: Union[str, Sequence[str], None] = None,
                   thermal_degree: Optional[int] = None) -> results.NormCalibration:
    """Calibrate a static log through the norm relation (2.2) of 001: `garant calibrate-norm --json`.

    Parameters
    ----------
    log : path, array or DataFrame
        A log path (formats of docs/formats.md), an array (N, 4): time in s, then x, y, z raw, or a pandas
        DataFrame as `apply` takes it (acc_x, acc_y, acc_z; a time column or `rate`).
    g : float, optional
        Local gravity, m/s^2 (None: 9.81 assumed, |Delta_g/g| <= 5e-3 in the calibration's bounds).
    g_uncertainty : float, optional
        The bound on |Delta_g/g| (default 1e-5 with g, 5e-3 without).
    bound : dict, optional
        A-priori bounds of the misalignments, rad (`--bound alpha=1e-3`: {"alpha": 1e-3, ...}), taken where
        the orientations cannot identify them (each along an axis, as six faces): the scale factors and biases
        are then calibrated with the misalignments held within them, a premise printed with the bounds.
    delta_sigma : float, optional
        A guaranteed bound on |delta_sigma| of (2.2), units of g (None: the noise rule).
    params : {9, 12}
        9 (scale, misalignment, bias) or 12 (also the nonlinearity).
    format, sensor, imu, rate
        The log's format, an OpenAXES accelerometer, an IMU of a multi-IMU stream, Hz for a log of sample
        indices (--format imucal, a DataFrame without a time column).
    window, k, min_still : float
        Still when the moving variance over `window` s is below `k` times the first seconds', for at least
        `min_still` s.
    diagnose : bool
        Also test the effect catalogue.
    effects : str or sequence of str, optional
        Catalogue effects added to the relation and calibrated with it (`--effect`): names of the generated norm
        module's EFFECTS (`garant calibrate-norm --help` and docs/diagnose.md list them).
    thermal_degree : int, optional
        D (`--thermal-degree D`, 1-3): on a log with a temperature column, each still interval (cut where the
        temperature moves) at its own mean temperature, the biases and scale factors polynomials of degree D in
        T with one guaranteed bound over the logged range (`thermal`), for --export-ardupilot / --export-px4.

    Returns
    -------
    NormCalibration
        When consistent, its "calibration" is the dictionary `apply` takes.
    """
    from ..io import calibration
    from . import calibrate_norm as cn
    from .stills import still_intervals
    from .premises import gravity_uncertainty
    data = read_log(log, format, sensor, imu, rate)
    g_given, g = g is not None, G_DEFAULT if g is None else g
    g_unc, g_src = gravity_uncertainty(g_given, g_uncertainty)
    stills, note = still_intervals(data, window=window, k=k, min_still=min_still)
    bound, scale_drift = _scale_drift(bound)
    p = _norm_problem(data, stills, note, g, params, delta_sigma, bound, effects, thermal_degree,
                      (window, k, min_still),
                      scale_drift)
    if isinstance(p, dict):                   # a still warm-up: one orientation, the still-only path's result
        p["premises"] = _norm_premises(p["premises"], g_unc, g_src)
        if data.meta:
            p["flight"] = {k: data.meta[k] for k in ("stack", "instance", "device_id", "parameters")}
        return results.NormCalibration(p)
    if scale_drift is not None:
        raise DataError(f"{data.path}: {opt('bound')} scale_drift is the premise of a still warm-up (one "
                        "orientation while it heats); turned through orientations, the warm-up calibrates the "
                        "scale's drift itself", param="bound")
    res = cn.run(p, diagnose)
    res.update({"g_given": g_given, "g_uncertainty": g_unc, "g_source": g_src})
    res["premises"] = _norm_premises(res["premises"], g_unc, g_src, (
        f"; |Delta_g/g| <= {g_unc:g} ({g_src}): the printed scale factors are relative to g = {g:g} m/s^2 (lambda* of "
        "(2.2) of 001), the calibration's bounds include it"))
    _log_figures(res, data, p, note, sensor)
    if "thermal" in res:
        res["thermal"].update(command="calibrate-norm", premise=res["premises"]["statement"])
    if res["consistent"]:
        res["calibration"] = calibration.from_norm(res, p.mod.AXES)
        if p.ext is not None:
            from . import norm_effects, norm_thermal
            res["calibration"].update(norm_effects.file_entry(res, p.ext.names, None if p.temps is None else
                                                              list(norm_thermal.sample_range(data, p.stills))))
    res.pop("_information_set", None)             # the file's, not the result's
    return results.NormCalibration(res)


def _scale_drift(bound):
    """(the misalignments' bounds, the scale drift's bound per C or None) of `bound` (--bound NAME=VALUE)."""
    if not isinstance(bound, dict) or "scale_drift" not in bound:
        return bound, None
    rest = {k: v for k, v in bound.items() if k != "scale_drift"}
    v = bound["scale_drift"]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v <= 0.01:
        raise DataError(f"{opt('bound')} scale_drift={str(v)[:40]}: give the drift of the scale factors and "
                        "misalignments per C, above 0 and at most 0.01 (the datasheet's, e.g. 1e-4 for 100 ppm/C)",
                        param="bound")
    return rest or None, float(v)


def _norm_problem(data, stills, note, g, params, delta_sigma, bound, effects, temperature, still, scale_drift=None):
    """The norm_problem.NormProblem of a log's still intervals with the options asked for (the effects, or the
    thermal degree's, built once), or, for a still warm-up (one orientation), the result of the still-only path.
    `still`: (window, k, min_still) of the stillness detector, for the line that refuses too few intervals."""
    from ..io import recordings
    from . import norm_problem                      # (the effects' and thermal modules only where they are used)
    mod = models.load("norm")
    thermal = None
    if temperature is not None or data.temp is not None:
        from . import norm_thermal
    if temperature is not None:
        norm_thermal.check_degree(temperature)
        if data.temp is None:
            raise DataError(f"{data.path}: {opt('thermal_degree')} needs each sample's temperature, the IMU's "
                            f"own: a column {' or '.join(recordings.TEMP_COLUMNS)} (C)", param="thermal_degree")
        if effects is not None:
            raise DataError(f"{opt('thermal_degree')} and {opt('effects')} are not taken together "
                            f"({opt('thermal_degree')} adds {', '.join(norm_thermal.names(temperature))} itself)",
                            param="thermal_degree")
        stills = norm_thermal.split(data, stills, still[2])
        if stills and norm_thermal.one_orientation(stills):
            from . import still_warm_up
            return still_warm_up.fit(data, stills, note, g, recordings.quantum(data), temperature, scale_drift)
    if len(stills) < params + 3:
        raise DataError(_too_few_stills(data, len(stills), params, *still), param="log")
    if temperature is not None:
        t_range = norm_thermal.sample_range(data, stills)
        thermal = dict(names=norm_thermal.names(temperature), temp_ref=round(0.5 * sum(t_range), 1),
                       option=f"--thermal-degree {temperature} ({', '.join(norm_thermal.names(temperature))})",
                       thermal_range=t_range)
    temps, rates = (None, None) if data.temp is None else norm_thermal.of_intervals(data, stills)
    ext = None
    if effects is not None or thermal is not None:
        from . import norm_effects
    if effects is not None:
        ext = norm_effects.Extension(mod, norm_effects.parse(effects, mod), stills, temps, data.path, rates)
    elif thermal is not None:
        ext = norm_effects.Extension(mod, thermal.pop("names"), stills, temps, data.path, rates, **thermal)
    p = norm_problem.problem(mod, stills, g, params, data.path, delta_sigma, recordings.quantum(data), ext,
                             _misalignment_bounds(bound), temps, rates)
    if thermal is not None and not p.si:
        raise DataError(f"{data.path}: {opt('thermal_degree')} takes a log in m/s^2 (the flight stacks' unit); "
                        "this one is in counts", param="log")
    return p


def _log_figures(res, data, p, note, sensor):
    """What the log itself says beside the calibration: its samples, duration, rate, noise density and random walk."""
    from ..io import recordings
    from . import stills
    dt = float(recordings.median(np.diff(data.t)))
    per_sample = recordings.median([st.std_error * np.sqrt(st.samples) for st in p.stills], axis=0)      # raw units
    res.update({"samples": len(data.t), "duration_s": float(data.t[-1]), "still_note": note, "log_note": data.note,
                "format": data.fmt, "sensor": (sensor or "adxl355") if data.fmt == "openaxes" else None,
                "rate_hz": 1 / dt,
                "noise_density": float(np.linalg.norm(np.abs(np.array(res["matrix"])) @ per_sample)
                                       / np.sqrt(3) * np.sqrt(dt))})
    res["random_walk"], res["random_walk_note"] = stills.random_walk(data, p.stills, res["matrix"], res["bias"])
    if data.meta:                             # a flight controller's log: the sensor, and the slots its vehicle holds
        res["flight"] = {k: data.meta[k] for k in ("stack", "instance", "device_id", "parameters")}


#: The stillness thresholds tried when a log yields too few still intervals (--still-factor, --min-still).
STILL_TRIES = ((20.0, None), (50.0, None), (5.0, None), (10.0, 1.0), (20.0, 1.0))


def _too_few_stills(data, found, params, window, k, min_still):
    """The one line for a log with too few still intervals: what was found with the thresholds used and, where
    other thresholds find enough, the options to add (a higher --still-factor merges more samples into stillness
    and may join two orientations; a lower one splits or drops them: the count says which helps here)."""
    from . import stills
    need = params + 3
    for k2, ms in STILL_TRIES:
        ms = min_still if ms is None else ms
        if (k2, ms) == (k, min_still):
            continue
        try:
            count = len(stills.still_intervals(data, window=window, k=k2, min_still=ms)[0])
        except DataError:
            continue
        if count >= need:
            option = f"--still-factor {k2:g}" + (f" --min-still {ms:g}" if ms != min_still else "")
            return (f"{data.path}: found only {found} still interval(s) with {opt('k')} {k:g} and {opt('min_still')} "
                    f"{min_still:g} s; a {params}-parameter calibration needs at least {need}. With {option} the "
                    f"detector finds {count}: run the same command with {option} added (check that each interval is "
                    "one orientation held still), or record more orientations")
    return (f"{data.path}: found only {found} still interval(s) with {opt('k')} {k:g} and {opt('min_still')} "
            f"{min_still:g} s; a {params}-parameter calibration needs at least {need}, and no other stillness "
            f"threshold tried finds that many: record more orientations, each held still for at least {min_still:g} s")


def read_log(log, fmt=None, sensor=None, imu=None, rate=None):
    """A Log from a path (any supported format), a DataFrame (see `_frame`) or an array (N, 4): time (s),
    three raw axes."""
    from ..io import recordings
    if isinstance(log, (str, bytes)) or hasattr(log, "__fspath__"):
        return recordings.read_log(log, fmt, sensor or "adxl355", imu, rate)
    if hasattr(log, "columns"):
        t, raw = _frame(log, rate)
    else:
        arr = real_array(log, "log")
        if arr.ndim != 2 or arr.shape[1] != 4:
            raise DataError(f"log: expected an array of shape (N, 4), N >= {recordings.MIN_SAMPLES}: time in s, x, y, "
                            f"z; got shape {arr.shape}", param="log")
        t, raw = arr[:, 0], arr[:, 1:]
    if len(t) < recordings.MIN_SAMPLES:
        raise DataError(f"log: expected at least {recordings.MIN_SAMPLES} samples: time in s, x, y, z; got {len(t)}",
                        param="log")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(raw))) or np.any(np.diff(t) <= 0):
        raise DataError("log: every value must be finite and the times increasing", param="log")
    return recordings.Log("array", np.subtract(t, t[0], out=t), raw, fmt="array")       # t: our own copy


def _frame(df, rate=None):
    """Time (s, N) and x, y, z (N, 3) of a pandas DataFrame log: the accelerometer columns by the names a csv
    log may have (acc_x, acc_y, acc_z, as imucal's, among them), time from a time column (its suffix the
    unit) or, with none, from the index over `rate` (imucal's sample index)."""
    from ..io import recordings
    if getattr(df.columns, "nlevels", 1) > 1:
        raise DataError("log: a DataFrame with columns of several levels (a MultiIndex); give one level, e.g. "
                        "df.droplevel(0, axis=1)", param="log")
    names = [str(c).lower() for c in df.columns]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise DataError(f"log: the DataFrame has the column {twice[0]} more than once", param="log")
    low = {str(c).lower(): c for c in df.columns}
    acc = next((names for names in recordings.ACCEL_COLUMNS if all(n in low for n in names)), None)
    if acc is None:
        raise DataError(f"log: a DataFrame needs accelerometer columns such as acc_x, acc_y, acc_z; it has "
                        f"{', '.join(map(str, df.columns))}", param="log")
    times = [c for c in low if c in recordings.TIME_COLUMNS]
    if times:
        t = real_array(df[low[times[0]]], f"log: column {times[0]}") * recordings.TIME_COLUMNS[times[0]]
    elif rate is not None:
        t = real_array(df.index, "log: the index") / rate
    else:
        raise DataError("log: a DataFrame without a time column (time_s, time_ms, ...) needs rate=HZ: its index "
                        "counts samples", param="log")
    return t, np.column_stack([real_array(df[low[n]], f"log: column {n}", copy=False) for n in acc])


@constraints(model=options.model, data=by_the_job("jobs.positions_of"), sigma=options.noise,
             g=options.gravity, g_uncertainty=options.small, prior=options.small, bound=options.bounds,
             mount=options.text, gamma=options.one_of("lower", "symmetric"), target=options.positive,
             grid=options.positive, search_seconds=options.positive, max_candidates=options.positive_int)
def next_position(model: Path, data: Data, sigma: float, *, g: Optional[float] = None,
                  g_uncertainty: Optional[float] = None, prior: Optional[float] = None,
                  bound: Optional[Mapping[str, float]] = None, mount: Optional[str] = None, gamma: str = "lower",
                  target: Optional[float] = None, grid: Optional[float] = None,
                  search_seconds: Optional[float] = None,
                  max_candidates: Optional[int] = None) -> results.NextPosition:
    """The position to measure next, from the positions measured so far: `garant next --json`.

    Parameters
    ----------
    model : str
        A built-in stand's name or a STAND.toml.
    data : path, DataFrame or array
        The positions measured so far (a CSV path, a header alone at the start, a DataFrame or an array of 0 or
        more rows).
    sigma : float
        The noise bound (units of g).
    g, g_uncertainty, prior, bound
        The premises of the verdict on the data, as in `estimate`.
    mount, gamma
        Target the block's parameters in this mounting ((28)-(29) of 000, two-axis) instead of the q's.
    target : float, optional
        The guaranteed error wanted for every q (units of q); None: sigma times the stand's optimal errors.
    grid : float, optional
        Candidate step in degrees (at most `max_candidates` positions; None: the command's default).
    search_seconds : float, optional
        A safety stop of the search.

    Returns
    -------
    NextPosition
        `next` (None when `done`), `still_needed`, the errors before and after; once every q has an estimator,
        the verdict of `estimate` on the data (`consistent`; `disagreements` when the data refute sigma).
    """
    from ..solve import lp
    from .estimate import distinct_positions, repeated_disagree
    from .next import next_position as suggest, printed_bounds, sized, target_names
    mod = models.load(model)
    pos = positions_of(mod, data, empty_ok=True)
    mounts = pos.mounts if pos.mounts is not None else np.zeros(len(pos.angles_deg), int)
    found = sized(mod, pos.angles_deg, mounts, grid, max_candidates)          # the search's size, before any work
    verdict, printed = None, None
    distinct, spread, _ = distinct_positions(pos)
    if len(pos.angles_deg) and (len(repeated_disagree(distinct, spread, sigma, G_DEFAULT if g is None else g))
                                or not lp.unidentifiable(lp.measurement_matrix(
                                    mod, np.deg2rad(distinct.angles_deg), distinct.mounts))):  # a verdict is possible
        verdict = estimate(model, pos, sigma, g=g, g_uncertainty=g_uncertainty, prior=prior, bound=bound,
                           mount=mount, gamma=gamma)
    floor = None
    if verdict is not None and verdict["consistent"] and not verdict.get("premises_refuted"):
        printed, floor = printed_bounds(verdict, target_names(mod, model, mount, gamma))
    out = results.NextPosition(suggest(mod, model, pos.angles_deg, mounts, sigma, target, grid, search_seconds,
                                       max_candidates, mount, gamma, printed=printed, floor=floor,
                                       candidates=found).to_dict())
    out["consistent"] = None if verdict is None else verdict["consistent"]
    out["bounds_from"] = ("estimate on the readings so far (what `garant estimate` prints)" if printed is not None
                          else "the plan's optimal estimators at nominal H (no estimate yet)")
    if verdict is not None and not verdict["consistent"]:
        out["disagreements"] = verdict.get("disagreements") or verdict.get("repeated_disagree")
        out["next"] = None                           # no position helps until the cause is found
    if verdict is not None and verdict.get("premises_refuted"):
        out["premises_refuted"], out["next"] = verdict["premises_refuted"], None
    return out


@constraints(model=options.model, data=by_the_job("jobs.positions_of"), sigma=options.noise,
             g=options.gravity, g_uncertainty=options.small, prior=options.small, bound=options.bounds)
def diagnose(model: Path, data: Data, sigma: float, *, g: Optional[float] = None,
             g_uncertainty: Optional[float] = None, prior: Optional[float] = None,
             bound: Optional[Mapping[str, float]] = None) -> results.Diagnosis:
    """The missing-effect workflow on positions: `garant diagnose --json`.

    Parameters
    ----------
    model : str
        A built-in stand's name or a STAND.toml.
    data : path, DataFrame or array
        Positions, as `estimate` takes them.
    sigma : float
        The noise bound (units of g).
    g, g_uncertainty, prior, bound
        The premises, as in `estimate`.

    Returns
    -------
    Diagnosis
        The verdict of the current model, the catalogue effects the data need, their estimates and what
        separates the rest. Its attribute `study` (not a field: not in JSON) is what `diagnose.write_module`
        needs.
    """
    from . import diagnose as diagnosis
    mod = models.load(model)
    prem = make_premises(mod, sigma, G_DEFAULT if g is None else g, g_given=g is not None,
                         g_uncertainty=g_uncertainty, prior=prior, bound=bound)
    positions = positions_of(mod, data)
    if len(positions.f) == 0:
        raise DataError("data: no positions to diagnose (every row of the data is read, none is left)", param="data")
    res = diagnosis.diagnose(models.stand_model(model), mod, positions, sigma, prem)
    study = res.pop("_study")
    if not res["consistent_before"] and (model in models.STANDS or str(model).endswith(".toml")):
        from . import thermal
        levels = thermal.chamber_levels(positions)
        if len(levels) >= 2:                       # a chamber session: the degree in T its data need
            res["thermal_degree"] = thermal.degree_needed(
                levels, lambda d: estimate(model, data, sigma, g=g, g_uncertainty=g_uncertainty, prior=prior,
                                           bound=bound, thermal_degree=d))
    out = results.Diagnosis(res)
    out.study = study
    return out


#: What `apply` does with samples outside a calibration's temperature range.
OUTSIDE = ("drop", "refuse")


#: What `apply` takes each sample's bound over.
BOUND_OVER = ("set", "box")


@constraints(calibration=by_the_job("calibration.checked / read"), log=by_the_job("jobs.read_log"),
             format=options.one_of(*FORMATS), sensor=options.sensor, imu=options.imu, rate=options.rate,
             trust_units=options.flag, frame=options.one_of("garant", "imu_tk"), chunk=options.positive_int,
             outside=options.one_of(*OUTSIDE), bound_over=options.one_of(*BOUND_OVER))
def apply(calibration: Union[Path, Mapping], log: Log, *, format: Optional[str] = None, sensor: Optional[str] = None,
          imu: Optional[int] = None, rate: Optional[float] = None, trust_units: bool = False, frame: str = "garant",
          chunk: Optional[int] = None, outside: str = "drop", bound_over: str = "set"
          ) -> Union[results.Correction, pandas.DataFrame, Iterator[results.Correction]]:
    """Correct a raw log with a calibration: `garant apply`.

    Parameters
    ----------
    calibration : path or dict
        A garant-calibration-1 file or the dictionary a result's "calibration" holds; either is checked as
        `garant apply` checks it (schema, a well-conditioned M, the log's unit unless `trust_units`).
    log : path, array or DataFrame
        A log path, an array (N, 4): time in s, then x, y, z raw, or a pandas DataFrame with columns acc_x,
        acc_y, acc_z (or x, y, z, ...) and a time column (time_s, time_ms, ...) or, without one, `rate` (Hz)
        over its index: then a calibrated copy of the DataFrame is returned (its accelerometer columns
        corrected, m/s^2, and bound_x, bound_y, bound_z added), as imucal's calibrate_df.
    format, sensor, imu, rate
        The log's format, an OpenAXES accelerometer, an IMU of a multi-IMU stream, Hz over a sample index.
    trust_units : bool
        Skip the check that the log is in the calibration's unit.
    frame : {"garant", "imu_tk"}
        M as calibrated, or the frame of the imu_tk export (a norm calibration turned into imu_tk's
        upper-triangular T).
    chunk : int, optional
        Return an iterator of Corrections of at most `chunk` samples (a long log piece by piece).
    outside : {"drop", "refuse"}
        A calibration over temperature holds only within its calibrated range: the log's samples outside it (a
        warm-up's first ones, before its first still interval) are dropped, each Correction saying how many of
        its piece (`outside`), or the log is refused.
    bound_over : {"set", "box"}
        Each sample's bound over the calibration's information set where the file carries one (the sharpest the
        readings prove; LPs, by cells of nearby samples: seconds to minutes on a long moving log), or over its box
        alone (fast; wider).

    Returns
    -------
    Correction
        t (s), a (N, 3) m/s^2 and bound (N, 3) m/s^2, the worst-case error of each component; it unpacks as
        (t, a, bound). `outside`: the samples of its piece dropped as outside the calibrated temperature range.
    """
    from ..io import calibration as cal_io, recordings
    from . import sample_set
    if not isinstance(calibration, (dict, str, os.PathLike)):
        raise DataError(f"calibration: a calibration file's path or the dictionary a result's calibration holds, "
                        f"not {type(calibration).__name__}", param="calibration")
    cal = cal_io.checked(calibration) if isinstance(calibration, dict) else cal_io.read(calibration)
    if bound_over == "box":
        cal.pop("information_set", None)
    data = read_log(log, format, sensor, imu, rate)
    if not trust_units:
        cal_io.check_units(cal, data.path, data.raw[:100_000],
                           "the calibration" if isinstance(calibration, dict) else str(calibration))

    if "thermal" in cal:
        if data.temp is None:
            raise DataError(f"{data.path}: the calibration holds a temperature polynomial; the log needs each "
                            f"sample's temperature (a csv log with a column {' or '.join(recordings.TEMP_COLUMNS)}, C)",
                            param="log")
        if frame != "garant":
            raise DataError(f"{opt('frame')} imu_tk: the imu_tk form holds no temperature polynomial")

    keep = _within_range(cal, data, outside)

    n = len(data.t)

    def piece(i, j):                                  # the log's samples i..j-1 (those within range)
        j = min(j, n)
        k = slice(i, j) if keep is None else keep[slice(*np.searchsorted(keep, [i, j]))]
        if "thermal" in cal:
            a, bound = sample_set.apply_thermal(cal, data.raw[k], data.temp[k], data.path)
        elif cal.get("effects") and cal["effects"]["names"]:
            from . import norm_effects
            a, bound = norm_effects.apply(cal, data.raw[k], frame, None if data.temp is None else data.temp[k],
                                          data.path)
        else:
            a, bound = sample_set.apply(cal, data.raw[k], frame)
        return results.Correction(t=data.t[k], a=a, bound=bound, kind=cal["kind"],
                                  outside=0 if keep is None else (j - i) - len(k))
    if chunk is None and hasattr(log, "columns"):       # a DataFrame in, a calibrated copy out (imucal's habit)
        return _corrected_frame(log, keep, piece, n)
    if chunk is None:
        return piece(0, n)
    return (piece(i, i + chunk) for i in range(0, n, chunk))


@constraints(calibration=options.path, log=by_the_job("jobs.read_log"), g=options.gravity,
             g_uncertainty=options.small, format=options.one_of(*FORMATS), sensor=options.sensor, imu=options.count,
             bound=options.bounds, rate=options.rate, progress=options.callback)
def budget(calibration: str, *, log: Optional[str] = None, g: Optional[float] = None,
           g_uncertainty: Optional[float] = None, format: Optional[str] = None, sensor: Optional[str] = None,
           imu: Optional[int] = None, bound: Optional[Mapping[str, float]] = None, rate: Optional[float] = None,
           progress: Optional[Callable] = None) -> results.Budget:
    """What a calibration guarantees downstream: `garant budget CAL [--log LOG] --json`.

    Parameters
    ----------
    calibration : path
        A garant calibration file, or with `log` imu_tk's (text), imucal's (JSON), PX4's .params or ArduPilot's
        .parm (their constant accelerometer calibration).
    log : path, optional
        Judge the calibration against this log's information set (garant's calibration of it beside).
    g, g_uncertainty, format, sensor, imu, bound, rate
        As calibrate-norm, for the log's calibration (bound: the misalignments' premise of a six-face log; imu: the
        flight log's accelerometer, whose slot of a parameter file is judged, or that slot's number).
    progress : callable, optional
        Hears (attitudes done, attitudes).
    """
    from . import budget as bud
    from .peer_files import precheck
    picks = log is not None and _picks_imu(log, format)
    precheck(calibration, None if picks else imu, picks)     # a file budget cannot take, said before the log's work
    res = None if log is None else calibrate_norm(log, g=g, g_uncertainty=g_uncertainty, format=format,
                                                   sensor=sensor, imu=imu if picks else None, bound=bound, rate=rate)
    return bud.run(calibration, log, res, progress, None if picks else imu)


def _picks_imu(log, format):
    """Whether --imu picks one IMU of the log (a flight controller's log, a MIMU stream); for another log it names
    the slot of a parameter file."""
    from ..io import recordings
    try:
        return (format or recordings.guess_format(log)) in ("ulog", "dataflash", "rosbag", "mimu")
    except OSError:
        return False                                   # (read_log says what is wrong with the file)


#: Samples corrected at a time into a DataFrame's copy: the work's memory is this piece's, not the frame's.
FRAME_CHUNK = 1 << 16


def _corrected_frame(log, keep, piece, n):
    """The DataFrame's calibrated copy (its rows within the calibrated range), filled piece by piece: its
    accelerometer columns corrected (m/s^2) and bound_x, bound_y, bound_z added. Its other columns are the
    frame's own (shared, not copied, when every row is kept); new memory is the new columns and one piece."""
    import pandas as pd
    from ..io import recordings
    low = {str(c).lower(): c for c in log.columns}
    names = next(x for x in recordings.ACCEL_COLUMNS if all(c in low for c in x))
    rows = n if keep is None else len(keep)
    new = [np.empty(rows) for _ in range(6)]
    at = 0
    for i in range(0, n, FRAME_CHUNK):
        c = piece(i, i + FRAME_CHUNK)
        for k in range(3):
            new[k][at:at + len(c.t)], new[3 + k][at:at + len(c.t)] = c.a[:, k], c.bound[:, k]
        at += len(c.t)
    acc = {low[x]: k for k, x in enumerate(names)}
    cols = {c: new[acc[c]] if c in acc else (log[c] if keep is None else log[c].iloc[keep]) for c in log.columns}
    cols.update({f"bound_{'xyz'[k]}": new[3 + k] for k in range(3)})
    index = log.index if keep is None else log.index[keep]
    return pd.DataFrame(cols, index=index, copy=False)


def _within_range(cal, data, outside):
    """The indices of the log's samples within the calibration's temperature range (None: every sample, or a
    calibration with no range); "refuse" leaves the check to the calibration's own (a DataError naming the first)."""
    from . import norm_effects
    if outside not in OUTSIDE:
        raise DataError(f"outside: {str(outside)[:40]!r}; give one of {', '.join(OUTSIDE)}", param="outside")
    span = (cal["thermal"]["range_c"] if "thermal" in cal else
            cal["effects"]["temp_range_c"] if norm_effects.needs_temperature(cal) else None)
    if outside == "refuse" or span is None or data.temp is None:
        return None
    T = np.asarray(data.temp, float)
    ok = np.isfinite(T) & (T >= span[0]) & (T <= span[1])
    return None if ok.all() else np.flatnonzero(ok)
