"""Results of the notebook API as objects: a dict whose keys are also attributes (like scipy's
OptimizeResult), numpy arrays kept as arrays, `to_dict()` / `to_json()` for files, a short `repr` and an
HTML table in notebooks. Each kind's FIELDS are its JSON schema's properties with their meanings (docs/schemas/,
the one home of every field; docs/fields.md lists them)."""
from __future__ import annotations

import json

import numpy as np

from ..outcomes import Status
from . import files, schemas
from .report import json_value, write_text


def _short(v, width=72):
    """A one-line summary of a value: arrays by shape, long lists by length, numbers to 6 digits."""
    if isinstance(v, np.ndarray):
        return f"array{v.shape}" if v.size > 6 else np.array2string(v, precision=6, separator=", ")
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, dict):
        text = "{" + ", ".join(f"{k}: {_short(x, 20)}" for k, x in v.items()) + "}"
        return text if len(text) <= width else f"dict of {len(v)}: {', '.join(map(str, list(v)[:4]))}, ..."
    if isinstance(v, (list, tuple)) and len(v) > 6:
        return f"{type(v).__name__} of {len(v)}"
    text = repr(v)
    return text if len(text) <= width else text[:width - 3] + "..."


class _Schema:
    """FIELDS of a result kind: the properties of its schema, docs/schemas/NAME.schema.json, with their meanings."""

    def __init__(self, name):
        self.name = name

    def __get__(self, obj, kind=None):
        return schemas.fields(self.name)


class Result(dict):
    """A result: its keys are also attributes; FIELDS documents them (name: meaning and unit)."""

    FIELDS = {}
    #: status -> message: what each status means, in a line (every result has a status; scipy's habit).
    STATUSES = {Status.DONE: "the job ran"}
    #: The input files the result was computed from (set by the API): `to_json` never writes over one.
    _inputs = ()

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(f"{type(self).__name__} has no field {name!r}; "
                                 f"it has {', '.join(self.keys())}") from None

    @property
    def status(self) -> Status:
        """What came out, in a word (a key of STATUSES; outcomes.Status): consistent, refuted, done, ..."""
        return Status.DONE

    @property
    def message(self) -> str:
        """The status in a line."""
        return self.STATUSES[self.status]

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(self.keys()))

    def to_dict(self) -> dict:
        """Plain JSON types only: arrays as lists (what the command's --json file holds)."""
        return json.loads(json.dumps(self, default=json_value))

    def to_json(self, path: str | None = None) -> str | None:
        """The JSON text, or written to `path` (atomically) when given."""
        text = json.dumps(self, default=json_value, indent=1) + "\n"
        if path is None:
            return text
        files.check_inputs(self._inputs)
        try:
            files.check_outputs([(path, "the JSON output", "file")])
            write_text(path, text)
        finally:
            files.check_inputs([])
        return None

    def table(self, *fields: str) -> str:
        """The fields that hold one value per name (q, guaranteed_error, units, ... of an estimate) side by side, a
        row per name, as text; `fields` picks them (default every such field, in FIELDS order)."""
        order = fields or [k for k in self.FIELDS if k in self] + [k for k in self.keys() if k not in self.FIELDS]
        per_name = [k for k in order if isinstance(self.get(k), dict) and self[k]
                    and not any(isinstance(v, (dict, list, np.ndarray)) for v in self[k].values())]
        if not per_name:
            return ""
        names = list(self[per_name[0]])
        cols = [k for k in per_name if list(self[k]) == names]
        rows = [["name", *cols]] + [[str(n)] + [v if isinstance(v, str) else _short(v, 40)
                                                 for v in (self[k][n] for k in cols)] for n in names]
        widths = [max(len(r[i]) for r in rows) for i in range(len(cols) + 1)]
        return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows) + "\n"

    def __repr__(self):
        keys = [k for k in self.FIELDS if k in self] + [k for k in self.keys() if k not in self.FIELDS]
        return f"{type(self).__name__}(\n" + "".join(f"  {k}: {_short(self[k])}\n" for k in keys) + ")"

    def _repr_html_(self):
        from html import escape
        keys = [k for k in self.FIELDS if k in self] + [k for k in self.keys() if k not in self.FIELDS]
        rows = "".join(f"<tr><td><code>{escape(k)}</code></td><td>{escape(_short(self[k]))}</td>"
                       f"<td>{escape(self.FIELDS.get(k, ''))}</td></tr>" for k in keys)
        return f"<table><caption>{type(self).__name__}</caption>{rows}</table>"


class Plan(Result):
    """`garant.plan`: the optimal guaranteed errors and a minimal optimal plan (`garant plan --json`)."""

    FIELDS = _Schema("plan")


class Estimate(Result):
    """`garant.estimate`: the verdict, q and guaranteed errors (`garant estimate --json`)."""

    FIELDS = _Schema("estimate")

    STATUSES = {Status.CONSISTENT: "the readings fit sigma within the premises: q, the bounds and the calibration "
                                   "hold",
                Status.REFUTED: "the readings refute sigma (or a premise): no bound is given",
                Status.PREMISE_REFUTED: "the readings put some q beyond what its parameters' stated bounds allow: no "
                                   "bound is guaranteed (premises_refuted names them)"}

    @property
    def status(self):
        """consistent, refuted or premise refuted."""
        if not self["consistent"]:
            return Status.REFUTED
        return Status.PREMISE_REFUTED if self.get("premises_refuted") else Status.CONSISTENT

    @property
    def names(self):
        """The q's names, in the model's order (empty when the data refute sigma)."""
        return tuple(self.get("q", {}))

    def array(self, field: str = "q") -> np.ndarray:
        """A per-q field (q, guaranteed_error, guaranteed_error_linear, ...) as a numpy array in `names`' order."""
        values = self[field] if field in self else None
        if not isinstance(values, dict) or set(values) != set(self.names):
            raise KeyError(f"{field!r} is not a per-q field of this result")
        return np.array([values[n] for n in self.names], float)


class NormCalibration(Result):
    """`garant.calibrate_norm`: a log calibrated through the norm relation (2.2) of 001."""

    FIELDS = _Schema("calibrate-norm")
    STATUSES = {Status.CONSISTENT: "the still intervals fit the noise bound: M, b and their bounds hold",
                Status.REFUTED: "the still intervals refute the noise bound: no bound is given"}

    @property
    def status(self):
        """consistent or refuted."""
        return Status.CONSISTENT if self["consistent"] else Status.REFUTED


class Diagnosis(Result):
    """`garant.diagnose`: where the model and the data disagree, and the effect that closes the gap."""

    FIELDS = _Schema("diagnose")
    STATUSES = {Status.CONSISTENT: "the model fits the data within sigma as it is",
                Status.EXPLAINED: "the effects named close the gap",
                Status.UNEXPLAINED: "no effect of the catalogue closes the gap"}
    #: Not a field (not in the JSON): the extended models of the study, what `diagnose.write_module` needs to
    #: write the module of the effects named (`garant diagnose --report`).
    study = None

    @property
    def status(self):
        """consistent (as it is), explained (by the effects named) or unexplained."""
        if self["consistent_before"]:
            return Status.CONSISTENT
        return Status.EXPLAINED if self.get("consistent_after") else Status.UNEXPLAINED


class Budget(Result):
    """`garant budget --json`: what a calibration guarantees downstream, over the information set."""

    FIELDS = _Schema("budget")


class Correction(Result):
    """`garant.apply`: a corrected log. Unpacks as (t, a, bound) too."""

    FIELDS = {"t": "time, s", "a": "corrected specific force (N, 3), m/s^2",
              "bound": "worst-case error of each component (N, 3), m/s^2",
              "outside": "samples of this piece dropped as outside the calibration's temperature range"}

    def __iter__(self):
        return iter((self["t"], self["a"], self["bound"]))


class NextPosition(Result):
    """`garant next --json`: where a calibration session stands and the position to measure next."""

    FIELDS = _Schema("next")
    STATUSES = {Status.DONE: "every guaranteed error is at or below its target",
                Status.MEASURE: "measure the position `next`",
                Status.REFUTED: "the readings so far refute sigma or a premise: find the cause before measuring more"}

    @property
    def status(self):
        """done, measure or refuted."""
        if self.get("consistent") is False or self.get("premises_refuted"):
            return Status.REFUTED
        return Status.DONE if self["done"] else Status.MEASURE
