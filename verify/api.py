"""The notebook API: a few functions with the same content as the commands' JSON (docs/api.md).

Each returns a result object (verify/io/results.py): a dict of the command's JSON fields, also reachable
as attributes, with numpy arrays, `to_dict()`, `to_json()` and a short repr; errors are raised as
DataError.
"""
from __future__ import annotations

import os
from typing import Optional, Sequence

from . import models, options
from .errors import DataError
from .io import results
from .io.recordings import FORMATS
from .workflows import jobs


#: The API's arguments renamed (old name -> new): the old one is taken for a release, with a DeprecationWarning.
RENAMED = {"temperature": "thermal_degree", "fmt": "format"}


def _api(fn):
    """The API's form of a job: each argument checked by the rule the job declares beside it (`fn.constraints`,
    options.constraints: the same checks as the command's option types), a DataError's options named as the API's
    arguments (`imu=`: errors.opt), and the input files the result came from remembered, so that
    `result.to_json(path)` never writes over one of them."""
    import functools
    import inspect
    import warnings
    signature, rules = inspect.signature(fn), fn.constraints

    @functools.wraps(fn)
    def call(*args, **kwargs):
        for old, new in RENAMED.items():
            if old in kwargs and new in rules:
                warnings.warn(f"{fn.__name__}: {old}= is now {new}= (the old name goes in a later release)",
                              DeprecationWarning, stacklevel=2)
                kwargs.setdefault(new, kwargs.pop(old))
        bound = signature.bind(*args, **kwargs)
        for name, value in bound.arguments.items():
            bound.arguments[name] = options.check(name, value, rules[name])
        from threadpoolctl import threadpool_limits
        try:
            with threadpool_limits(limits=1):        # one BLAS thread, as the command: the same bounds on any machine
                out = fn(*bound.args, **bound.kwargs)
        except DataError as e:
            raise DataError(e.render("api"), param=e.param) from None
        if isinstance(out, results.Result):
            out._inputs = tuple(str(v) for v in bound.arguments.values()
                               if isinstance(v, (str, os.PathLike)) and os.path.isfile(v))
        return out
    return call


@_api
@options.constraints(model=options.model, grid=options.positive, count_seconds=options.positive,
                    max_candidates=options.positive_int, search_seconds=options.positive,
                    search_nodes=options.positive_int, count_nodes=options.count)
def plan(model: str, *, grid: Optional[float] = None, count_seconds: Optional[float] = None,
         max_candidates: Optional[int] = None, search_seconds: Optional[float] = None,
         search_nodes: Optional[int] = None, count_nodes: Optional[int] = None) -> results.Plan:
    """Optimal guaranteed errors (units of sigma), the minimal optimal plans and the preferred one, exactly
    as `garant plan --model MODEL --json` (workflows/plan.py does both); `norm` gives the orientations of 001.
    `max_candidates` bounds the size of the search, `search_nodes` and `count_nodes` its work (the same plan
    on every machine; `count_nodes=0`: the plan alone, the others not counted), `search_seconds` and
    `count_seconds` are its safety stops (None: the command's defaults)."""
    from .workflows.plan import COUNT_SECONDS, MAX_CANDIDATES, SEARCH_SECONDS, norm_plan, plan as search_plan
    mod = models.load(model)
    if models.kind(model) == "norm":
        return results.Plan(norm_plan(mod))
    return results.Plan(search_plan(mod, model, grid, count_seconds or COUNT_SECONDS, max_candidates or MAX_CANDIDATES,
                                    search_seconds or SEARCH_SECONDS, search_nodes=search_nodes,
                                    count_nodes=count_nodes).to_dict())


@_api
@options.constraints(logs=options.by_the_job("batch.calibrate_many"), g=options.gravity, g_uncertainty=options.small,
                    delta_sigma=options.noise, params=options.one_of(9, 12), format=options.one_of(*FORMATS),
                    sensor=options.sensor, imu=options.imu, rate=options.rate,
                    window=options.positive,
                    k=options.positive, min_still=options.positive, jobs=options.positive_int, spec=options.path)
def calibrate_many(logs: Sequence, *, g: Optional[float] = None, g_uncertainty: Optional[float] = None,
                   delta_sigma: Optional[float] = None, params: int = 9, format: Optional[str] = None,
                   sensor: Optional[str] = None, imu: Optional[int] = None, rate: Optional[float] = None,
                   window: float = 1.0, k: float = 10.0, min_still: float = 2.0, jobs: Optional[int] = None,
                   spec: Optional[str] = None) -> list:
    """Many logs calibrated as `calibrate_norm`, in one process pool (`jobs`, default every core; the same
    results whatever it is), as `garant calibrate-norm LOG... --out DIR`: a list of rows, one per log in
    order, each {"log", "status" (consistent, refuted or error), "message", "result" (the calibration's
    dictionary, or None)} and, with `spec` (a SPEC.toml path: [limits] and [bound_limits] of scale,
    misalignment, bias, and [nominal] sensitivity for logs in raw counts), "verdict" (pass: every guaranteed
    interval within its limit; fail: one wholly outside; undecided; retest: the log could not be calibrated or
    refutes its noise bound, so it proves nothing of the unit) and "reason", and for a log in raw counts judged
    against [nominal] "nominal" (the parameters and bounds relative to it). A log that cannot be calibrated is
    its row, never the end of the batch."""
    from .workflows import batch
    if not isinstance(logs, (list, tuple)) or not logs:
        raise DataError("logs: a list of log paths or arrays", param="logs")
    return batch.calibrate_many(logs, jobs, batch.read_spec(spec) if spec else None, None, g=g, params=params,
                                format=format, sensor=sensor, imu=imu, window=window, k=k, min_still=min_still,
                                delta_sigma=delta_sigma, g_uncertainty=g_uncertainty, rate=rate)


#: The jobs, as the commands run them (workflows/jobs.py: the same functions, the same keyword-only options).
estimate = _api(jobs.estimate)
calibrate_norm = _api(jobs.calibrate_norm)
next_position = _api(jobs.next_position)
diagnose = _api(jobs.diagnose)
apply = _api(jobs.apply)
budget = _api(jobs.budget)
