"""A production line in one process: many logs calibrated through the norm relation (2.2) of 001, on every
core, each unit judged against its specification by its guaranteed intervals.

A unit passes only if every parameter's whole guaranteed interval lies within its limit (a guaranteed
pass), fails if some parameter's whole interval lies outside it, and is undecided otherwise; each verdict
says why. One bad log is a row of the summary, never the end of the batch.
"""
import os
import sys
import tomllib

import numpy as np

from ..errors import DataError

#: What a specification may limit: the parameters of (1.3) of 001 it covers, and their unit.
SPEC_KEYS = {"scale": (("lambda1", "lambda2", "lambda3"), "1"),
             "misalignment": (("alpha", "beta", "gamma"), "rad"),
             "bias": (("eps1/g", "eps2/g", "eps3/g"), "1 (over g)")}


def read_spec(path):
    """A unit's specification: [limits] (|value| <= limit for the whole guaranteed interval) and, optionally,
    [bound_limits] (the guaranteed error itself at most this), each with keys scale, misalignment, bias."""
    from ..io import files
    files.regular(path, "the specification", 1_000_000)
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise DataError(f"{path}: not valid TOML ({str(e)[:120]})") from None
    out = {}
    for table in ("limits", "bound_limits"):
        given = data.get(table, {})
        if not isinstance(given, dict):
            raise DataError(f"{path}: [{table}] must be a table of scale, misalignment, bias")
        for key, value in given.items():
            if key not in SPEC_KEYS:
                raise DataError(f"{path}: [{table}] {key}: unknown; the keys are {', '.join(SPEC_KEYS)}")
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < 1:
                raise DataError(f"{path}: [{table}] {key} = {str(value)[:30]} must be a number > 0 and < 1")
        out[table] = {k: float(v) for k, v in given.items()}
    unknown = set(data) - {"limits", "bound_limits"}
    if unknown or not out["limits"]:
        raise DataError(f"{path}: a specification has [limits] (and optionally [bound_limits]) of "
                        f"{', '.join(SPEC_KEYS)}" + (f"; unknown: {', '.join(sorted(unknown))}" if unknown else ""))
    return out


def judge(res, spec):
    """(verdict, reason): pass, fail or undecided for one calibrated unit against `spec`."""
    if not res.get("consistent"):
        return "fail", "the log refutes its noise bound: no guaranteed interval"
    pars, errs = res.get("parameters"), res.get("guaranteed_error")
    if not pars:
        return "undecided", "a log in raw counts: its parameters are relative to the raw axes, not the spec's"
    fails, open_ = [], []
    for key, limit in spec["limits"].items():
        for name in SPEC_KEYS[key][0]:
            v, e = pars[name], errs[name]
            if abs(v) - e > limit:
                fails.append(f"{name} {v:+.3g} +- {e:.2g} beyond {limit:g}")
            elif abs(v) + e > limit:
                open_.append(f"{name} {v:+.3g} +- {e:.2g} straddles {limit:g}")
    for key, limit in spec.get("bound_limits", {}).items():
        for name in SPEC_KEYS[key][0]:
            if errs[name] > limit:
                open_.append(f"{name}'s guaranteed error {errs[name]:.2g} above {limit:g}")
    if fails:
        return "fail", "; ".join(fails)
    if open_:
        return "undecided", "; ".join(open_)
    return "pass", "every guaranteed interval within its limit"


def _one(job):
    """One log: the calibration's result, or the one-line error (run in a worker process)."""
    path, kwargs = job
    from .jobs import calibrate_norm
    try:
        return dict(calibrate_norm(path, **kwargs)), None
    except DataError as e:
        return None, str(e)
    except MemoryError:
        return None, "out of memory"


def cores():
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:                         # not on Linux
        return os.cpu_count() or 1


def calibrate_many(paths, jobs=None, spec=None, progress=None, **kwargs):
    """Each log calibrated as `calibrate_norm(path, **kwargs)` (a process pool of `jobs`, default every core;
    the same results whatever `jobs`), in the order given: a list of rows (log, status, message, the
    result or None, verdict and reason against `spec` when given). `progress(done, total)` hears of each."""
    from concurrent.futures import ProcessPoolExecutor
    work = [(str(p), kwargs) for p in paths]
    jobs = max(1, min(jobs or cores(), len(work)))
    if jobs == 1:
        outcomes = []
        for k, w in enumerate(work, 1):
            outcomes.append(_one(w))
            if progress:
                progress(k, len(work))
    else:
        import multiprocessing
        from .. import models                                 # loaded once, here: the forked workers share them
        from ..io import calibration, recordings             # noqa: F401
        from ..solve import hull                             # noqa: F401
        from . import calibrate_norm, jobs as _jobs, premises  # noqa: F401
        models.load("norm")
        context = multiprocessing.get_context("fork" if sys.platform == "linux" else None)
        with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
            outcomes = []
            for k, outcome in enumerate(pool.map(_one, work), 1):
                outcomes.append(outcome)
                if progress:
                    progress(k, len(work))
    rows = []
    for (path, _), (res, error) in zip(work, outcomes):
        status = "error" if res is None else ("consistent" if res["consistent"] else "refuted")
        row = {"log": path, "status": status, "message": error or "", "result": res}
        if spec is not None:
            row["verdict"], row["reason"] = ("fail", f"not calibrated: {error}") if res is None else judge(res, spec)
        rows.append(row)
    return rows


def stems(paths):
    """A file name stem for each log, unique in the batch (a repeated stem gets _2, _3, ...)."""
    seen, out = {}, []
    for p in paths:
        stem = os.path.splitext(os.path.basename(str(p)))[0] or "log"
        seen[stem] = seen.get(stem, 0) + 1
        out.append(stem if seen[stem] == 1 else f"{stem}_{seen[stem]}")
    return out


def summary_rows(rows):
    """The summary table: per log its status, verdict, noise bound, still intervals and each parameter with
    its guaranteed error (empty where the log was not calibrated)."""
    from .calibrate_norm import PARAM_LABELS
    head = ["log", "status", "verdict", "reason", "delta_sigma_max", "intervals"]
    head += [x for name in PARAM_LABELS[:9] for x in (name, f"{name}_bound")]
    table = []
    for r in rows:
        res = r["result"] or {}
        pars, errs = res.get("parameters") or {}, res.get("guaranteed_error") or {}
        cells = [r["log"], r["status"], r.get("verdict", ""), r.get("reason") or r["message"],
                 _num(res.get("delta_sigma_max")), str(res.get("intervals", ""))]
        cells += [x for name in PARAM_LABELS[:9] for x in (_num(pars.get(name)), _num(errs.get(name)))]
        table.append(cells)
    return head, table


def _num(x):
    return "" if x is None or not np.isfinite(x) else f"{x:.6g}"
