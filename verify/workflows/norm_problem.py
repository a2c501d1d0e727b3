"""What a norm calibration of 001 is computed from, decided once (`NormProblem`), and what its verdict found
(`NormVerdict`): the records the orchestrator (calibrate_norm.run) passes between its steps, as the estimate path
passes its Positions and premises.

The problem is built once from a log's still intervals (jobs.calibrate_norm, the batch, the API): the interval
means, g, the unit of the raw readings (m/s^2 or counts: decided here and nowhere else), the quantum, the
parameter count, the catalogue effects and the misalignment premise. Nothing downstream recomputes them.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Optional

import numpy as np

from ..io.recordings import raw_unit


@dataclass(frozen=True, eq=False)
class NormProblem:
    """A norm calibration's inputs. `raw` (K, 3): each still interval's mean, raw units; `si`: the log is in m/s^2
    (else counts); `delta_sigma`: a stated noise bound (units of g) or None for the noise rule; `ext`: the catalogue
    effects (norm_effects.Extension) or None; `premise`: {misalignment: bound, rad} (--bound) or None; `temps`,
    `rates`: each interval's mean temperature (C) and its rate (C/s), or None."""

    mod: Any
    path: str
    stills: tuple
    raw: np.ndarray
    g: float
    params: int = 9
    si: bool = True
    quantum: float = 0.0
    delta_sigma: Optional[float] = None
    ext: Any = None
    premise: Optional[dict] = None
    temps: Optional[np.ndarray] = None
    rates: Optional[np.ndarray] = None

    @property
    def raw_unit(self):
        """"m/s^2" or "count", as files and messages say it."""
        return "m/s^2" if self.si else "count"

    @property
    def stated(self):
        """The noise bound is stated (--delta-sigma), not the noise rule's."""
        return self.delta_sigma is not None

    def base(self):
        """The same problem without catalogue effects: the 9- or 12-parameter model the diagnosis starts from."""
        return replace(self, ext=None)

    def with_effects(self, ext):
        """The same problem with the catalogue effects `ext` (norm_effects.Extension) added."""
        return replace(self, ext=ext, premise=None)


def problem(mod, stills, g, params=9, path="log", delta_sigma=None, quantum=0.0, ext=None, premise=None,
            temps=None, rates=None):
    """The NormProblem of a log's still intervals: their means, and the raw unit decided from them and g."""
    stills = tuple(stills)
    raw = np.array([s.mean for s in stills], float).reshape(-1, 3)
    raw.flags.writeable = False
    return NormProblem(mod, str(path), stills, raw, float(g), int(params), raw_unit(raw, g) == "m/s^2",
                       float(quantum), delta_sigma, ext, premise, temps, rates)


@dataclass(eq=False)
class NormVerdict:
    """What the verdict of a norm calibration found and the bounds are computed from. `res`: the fit
    (calibrate_norm.fit); `rule`: each interval's noise rule; `noise`: each interval's noise bound as the bound
    uses it (units of g); `nu`: the bound of each calibrated mean's error (the remainder's); `dsig`, `source`: the
    noise bound printed and where it comes from; `err`: the LP estimator's errors (noise only); `rb`: the remainder
    (the largest interval's); `bnd`: each interval's bound (noise plus its remainder, units of sigma); `worst`: the
    weighted minimax residual in units of `bnd` (within 1: consistent); `cap`: the misalignment premise carried
    to q (inf where none); `held`: the q it holds; `info`: (lo, hi) of q over the information set; `box`: the
    premise box of the per-interval remainder (or None); `exact`: (A, bnd, shift, ext) with catalogue effects;
    `discrepancy`: with effects, the base model's and the extended one's worst residuals in noise-rule units."""

    res: dict
    rule: np.ndarray
    noise: np.ndarray
    nu: np.ndarray
    dsig: float
    source: str
    err: np.ndarray
    rb: float = 0.0
    bnd: np.ndarray = None
    worst: float = np.inf
    cap: Optional[np.ndarray] = None
    held: Optional[list] = None
    info: Optional[tuple] = None
    box: Optional[np.ndarray] = None
    exact: Optional[tuple] = None
    discrepancy: Optional[list] = None

    @property
    def consistent(self):
        """Some correction of the relation, with its proven remainder, meets every interval's own bound."""
        return bool(self.worst <= 1.0)
