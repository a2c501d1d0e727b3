"""A production line in one process: many logs calibrated through the norm relation (2.2) of 001, on every
core, each unit judged against its specification by its guaranteed intervals.

A unit passes only if every parameter's whole guaranteed interval lies within its limit (a guaranteed
pass), fails if some parameter's whole interval lies outside it, and is undecided otherwise. A log that
proves nothing of the unit (it could not be calibrated, or its data refute the noise bound, so no interval
is guaranteed) is neither: its verdict is retest. Each verdict says why. One bad log is a row of the
summary, never the end of the batch.
"""
import os
import sys

import numpy as np

from ..outcomes import Status, Verdict
from ..errors import DataError

#: What a specification may limit: the parameters of (1.3) of 001 it covers, and their unit.
SPEC_KEYS = {"scale": (("lambda1", "lambda2", "lambda3"), "1"),
             "misalignment": (("alpha", "beta", "gamma"), "rad"),
             "bias": (("eps1/g", "eps2/g", "eps3/g"), "1 (over g)")}


#: The verdicts (outcomes.Verdict), in the order the summary counts them.
PASS, FAIL, UNDECIDED, RETEST = VERDICTS = tuple(Verdict)
#: A log's status in a batch: calibrated and consistent, refuting its noise bound, or not calibrated at all.
CONSISTENT, REFUTED, ERROR = STATUSES = (Status.CONSISTENT, Status.REFUTED, Status.ERROR)


def read_spec(path):
    """A unit's specification: [limits] (|value| <= limit for the whole guaranteed interval) and, optionally,
    [bound_limits] (the guaranteed error itself at most this), each with keys scale, misalignment, bias; and,
    for logs in raw counts, [nominal] sensitivity (counts per g: one number, or one per axis), to which the
    scale is relative, and offset (counts, the reading at zero: the biases are relative to it; default 0)."""
    import tomllib                                   # (here: a calibration without --spec does not load it)
    from ..io import files
    files.regular(path, "the specification", 1_000_000, param="spec")
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, RecursionError) as e:
        raise DataError(f"{path}: not valid TOML ({str(e)[:120]})", param="spec") from None
    out = {}
    for table in ("limits", "bound_limits"):
        given = data.get(table, {})
        if not isinstance(given, dict):
            raise DataError(f"{path}: [{table}] must be a table of scale, misalignment, bias", param="spec")
        for key, value in given.items():
            if key not in SPEC_KEYS:
                raise DataError(f"{path}: [{table}] {key}: unknown; the keys are {', '.join(SPEC_KEYS)}", param="spec")
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < 1:
                raise DataError(f"{path}: [{table}] {key} = {str(value)[:30]} must be a number > 0 and < 1",
                                param="spec")
        out[table] = {k: float(v) for k, v in given.items()}
    nominal = data.get("nominal", {})
    if not isinstance(nominal, dict) or set(nominal) - {"sensitivity", "offset"} or (
            "offset" in nominal and "sensitivity" not in nominal):
        raise DataError(f"{path}: [nominal] holds sensitivity (counts per g) and optionally offset (counts), of a "
                        "log in raw counts", param="spec")
    for key, low in (("sensitivity", 0.0), ("offset", -1e12)):
        if key in nominal:
            S = nominal[key]
            S = [S] * 3 if not isinstance(S, list) else S
            if len(S) != 3 or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not low < v < 1e12
                                  for v in S):
                raise DataError(f"{path}: [nominal] {key} = {str(nominal[key])[:40]} must be a number"
                                + (" > 0 (counts per g)" if key == "sensitivity" else " (counts)")
                                + " or a list of three", param="spec")
            out[key] = [float(v) for v in S]
    unknown = set(data) - {"limits", "bound_limits", "nominal"}
    if unknown or not out["limits"]:
        raise DataError(f"{path}: a specification has [limits] (and optionally [bound_limits] and [nominal]) of "
                        f"{', '.join(SPEC_KEYS)}" + (f"; unknown: {', '.join(sorted(unknown))}" if unknown else ""),
                        param="spec")
    return out


def judge(res, spec):
    """(verdict, reason, nominal): pass, fail or undecided for one calibrated unit against `spec`; retest when
    the log proves nothing of the unit (its data refute the noise bound: no interval is guaranteed). `nominal`:
    for a log in raw counts judged against the spec's [nominal], the parameters and bounds it was judged by
    (`nominal_parameters`), else None."""
    nominal = None
    if not res.get("consistent"):
        where = res.get("disagreements") or []
        return RETEST, ("the log refutes its noise bound" + (
            f" at still interval(s) {', '.join(map(str, where[:8]))}" + (" ..." if len(where) > 8 else "")
            if where else "") + ": no interval is guaranteed, so nothing is proven of the unit; record it again"), None
    pars, errs = res.get("parameters"), res.get("guaranteed_error")
    if not pars:
        counts = res.get("raw_axes_counts")
        if "sensitivity" not in spec or not counts:
            return UNDECIDED, ("a log in raw counts: its parameters are relative to the raw axes; give the nominal "
                                 "sensitivity (counts per g) as [nominal] sensitivity in the spec"), None
        nominal = pars, errs = nominal_parameters(counts, spec["sensitivity"], spec.get("offset", [0.0] * 3))
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
        return FAIL, "; ".join(fails), nominal
    if open_:
        return UNDECIDED, "; ".join(open_), nominal
    return PASS, "every guaranteed interval within its limit", nominal


def nominal_parameters(counts, S, offset):
    """The parameters of (1.3) of 001 and their guaranteed errors for a log in raw counts, relative to the
    nominal sensitivity S (counts per g, per axis) and zero offset (counts): lambda_i = S_ii / S_i - 1, the
    misalignments S_ij / S_i (i the row's axis), eps_i/g = (b_i - offset_i) / S_i; each exactly linear in the
    raw-axes parameters, so each interval is theirs divided by S_i."""
    sens, err = counts["sensitivity"], counts["error"]
    rows = {"lambda1": ("S11", 0, 1.0), "lambda2": ("S22", 1, 1.0), "lambda3": ("S33", 2, 1.0),
            "alpha": ("S21", 1, 0.0), "beta": ("S31", 2, 0.0), "gamma": ("S32", 2, 0.0),
            "eps1/g": ("b1", 0, 0.0), "eps2/g": ("b2", 1, 0.0), "eps3/g": ("b3", 2, 0.0)}
    pars = {n: (sens[c] - (offset[i] if c[0] == "b" else 0.0)) / S[i] - one for n, (c, i, one) in rows.items()}
    errs = {n: err[c] / S[i] * (1 + 1e-12) for n, (c, i, _) in rows.items()}
    return pars, errs


def _in_memory(log):
    """Whether a log is data (an array or a DataFrame) rather than a path."""
    return not isinstance(log, (str, os.PathLike))


def _one(job):
    """One log: the calibration's result, or the one-line error (run in a worker process)."""
    path, kwargs = job
    from .jobs import calibrate_norm
    try:
        return dict(calibrate_norm(path, **kwargs)), None
    except DataError as e:
        return None, str(e).replace("log: ", "", 1) if _in_memory(path) else str(e)
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
    work = [(p if _in_memory(p) else str(p), kwargs) for p in paths]
    jobs = max(1, min(jobs or cores(), len(work)))
    if jobs == 1:
        outcomes = []
        for k, w in enumerate(work, 1):
            outcomes.append(_one(w))
            if progress:
                progress(k, len(work))
    else:                                            # (the pool's modules loaded only here: 10 ms of a log's run)
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor
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
    for k, ((path, _), (res, error)) in enumerate(zip(work, outcomes), 1):
        status = ERROR if res is None else (CONSISTENT if res["consistent"] else REFUTED)
        row = {"log": f"log {k} (in memory)" if _in_memory(path) else path, "status": status,
               "message": error or "", "result": res}
        if spec is not None:
            row["verdict"], row["reason"], nominal = ((RETEST, f"not calibrated: {error}", None) if res is None
                                                      else judge(res, spec))
            if nominal is not None:
                row["nominal"] = nominal
        rows.append(row)
    return rows


def stems(paths):
    """A file name stem for each log, unique in the batch: a repeated stem gets _2, _3, ..., past any stem the
    batch already holds (a/u.txt, b/u.txt, c/u_2.txt give u, u_3, u_2)."""
    base = [os.path.splitext(os.path.basename(str(p)))[0] or "log" for p in paths]
    taken, out = set(), [None] * len(base)
    for k, stem in enumerate(base):               # a log keeps its own stem where no earlier log has it
        if stem not in taken:
            taken.add(stem)
            out[k] = stem
    for k, stem in enumerate(base):
        if out[k] is None:
            n = 2
            while f"{stem}_{n}" in taken or f"{stem}_{n}" in base:
                n += 1
            out[k] = f"{stem}_{n}"
            taken.add(out[k])
    return out


def summary_rows(rows):
    """The summary table: per log its status, verdict, noise bound, still intervals, each parameter with its
    guaranteed error (empty where the log was not calibrated; a log in raw counts relative to the spec's
    [nominal]) and the name of its calibration file."""
    from .norm_bounds import PARAM_LABELS
    head = ["log", "status", "verdict", "reason", "delta_sigma_max", "intervals"]
    head += [x for name in PARAM_LABELS[:9] for x in (name, f"{name}_bound")] + ["calibration_file"]
    table = []
    for r in rows:
        res = r["result"] or {}
        pars, errs = r.get("nominal") or (res.get("parameters") or {}, res.get("guaranteed_error") or {})
        cells = [r["log"], r["status"], r.get("verdict", ""), r.get("reason") or r["message"],
                 _num(res.get("delta_sigma_max")), str(res.get("intervals", ""))]
        cells += [x for name in PARAM_LABELS[:9] for x in (_num(pars.get(name)), _num(errs.get(name)))]
        cells.append(r.get("file", ""))
        table.append(cells)
    return head, table


def _num(x):
    return "" if x is None or not np.isfinite(x) else f"{x:.6g}"
