"""The lab session's question, which position next: after each measured position, the reachable
position whose addition most reduces the largest ratio guaranteed error / target over the q (the LP
(7)-(8) of 000 on the positions measured so far), "done" when every bound is at its target, and how
many positions are still needed: the one computation `garant next` prints and `garant.next_position`
returns."""
import math
from dataclasses import dataclass

import numpy as np

from ..errors import DataError

#: Relative slack of "at the target": the LP's own tolerance.
AT_TARGET = 1e-7


@dataclass
class Next:
    """Where the session stands and what to measure next. Errors and targets are in the units of each q."""

    model: str
    angles: list                  # the stand's angle names (positions list angles in this order, in degrees)
    q_names: list
    sigma: float
    target: np.ndarray            # per q
    target_source: str
    measured: list                # distinct positions measured: angles in degrees (and mounting)
    before: np.ndarray            # per q: guaranteed error on the measured positions (inf: not estimable yet)
    position: list | None         # the position to measure next (None: done)
    after: np.ndarray | None      # per q: the guaranteed error once it is measured
    still_needed: int             # positions still needed, the suggested one included (0: done)
    still_needed_proven: bool     # the fewest that can reach the target (else a lower bound)
    candidates: int               # reachable positions considered

    @property
    def done(self):
        """Whether every q's guaranteed error is at or below its target."""
        return bool(np.all(self.before <= self.target * (1 + AT_TARGET)))

    def to_dict(self):
        """The result as `garant next --json` writes it (an error not yet finite is null)."""
        finite = (lambda v: None if v is None else [None if not np.isfinite(x) else float(x) for x in v])
        return {"model": self.model, "angles": list(self.angles), "q_names": list(self.q_names), "sigma": self.sigma,
                "target": [float(t) for t in self.target], "target_source": self.target_source,
                "measured": self.measured, "guaranteed_error_before": finite(self.before), "done": self.done,
                "next": self.position, "guaranteed_error_after": finite(self.after),
                "still_needed": self.still_needed, "still_needed_proven": self.still_needed_proven,
                "candidates": self.candidates}


def errors_on(mod, angles_deg, mounts):
    """The optimal guaranteed error of each q on these positions (units of sigma): the LP (7)-(8) of
    000 for the q an unbiased estimator exists for, inf for the others."""
    from ..models import H_at
    from ..solve import lp
    m = len(mod.Q_NAMES)
    out = np.full(m, np.inf)
    if not len(angles_deg):
        return out
    H = H_at(mod, np.deg2rad(np.asarray(angles_deg, float)), mounts)           # (3, m, S)
    A = np.transpose(H, (1, 2, 0)).reshape(m, -1)
    estimable = np.linalg.norm(A @ np.linalg.pinv(A) - np.eye(m), axis=0) < 1e-9   # e_nu in A's column space
    if estimable.any():
        out[estimable] = lp.primal(A, np.eye(m)[:, estimable])[1]
    return out


def next_position(mod, model, angles_deg, mounts, sigma, target=None, grid=None, search_seconds=None,
                  max_candidates=None):
    """The Next of a session whose distinct measured positions are `angles_deg` (N, angles; degrees)
    in mountings `mounts` (N,): target None is sigma times the stand's optimal errors on its reachable
    positions (then the suggestion completes a plan of the fewest positions, which the measured ones
    are part of), a number is one target for every q (units of q)."""
    from ..models import layout
    from ..solve import plans
    from .plan import MAX_CANDIDATES, SEARCH_SECONDS, candidates
    names, mount_names = layout(mod)
    P, M, fixed = _with_measured(*candidates(mod, grid, max_candidates or MAX_CANDIDATES), np.asarray(angles_deg, float).reshape(-1, len(names)),
                                 np.asarray(mounts, int))
    cols = plans.columns(mod, P, M)
    m = len(mod.Q_NAMES)
    lams = [plans.dual_on_grid(cols, nu, False)[0] for nu in range(m)]
    optimal = np.array([float(lam[nu]) for nu, lam in enumerate(lams)])       # units of sigma
    if target is None:
        goal, source = sigma * optimal, "sigma x the stand's optimal errors on its reachable positions"
    else:
        goal, source = np.full(m, float(target)), "--target"
        short = [f"{q} ({sigma * o:.3g})" for q, o in zip(mod.Q_NAMES, optimal) if sigma * o > target * (1 + AT_TARGET)]
        if short:
            raise DataError(f"--target {target:g} is below the stand's optimal error of {', '.join(short)}: no plan "
                            "of its reachable positions reaches it")
    before = sigma * errors_on(mod, P[fixed], M[fixed])
    position = lambda s: [*(float(v) for v in P[s]), *([mount_names[M[s]]] if len(mount_names) > 1 else [])]  # noqa: E731
    common = dict(model=model, angles=list(names), q_names=list(mod.Q_NAMES), sigma=sigma, target=goal, target_source=source,
                  measured=[position(s) for s in fixed], before=before, candidates=len(P))
    if np.all(before <= goal * (1 + AT_TARGET)):
        return Next(**common, position=None, after=None, still_needed=0, still_needed_proven=True)
    if target is None:
        n, found, _, floor = plans.covering_plans(cols, lams, 1, 1.0, search_seconds or SEARCH_SECONDS, fixed)
        pool, needed, proven = [s for s in found[0] if s not in fixed], n - len(fixed), floor is None
    else:
        pool = [s for s in range(len(P)) if s not in fixed]
        deficit = int(np.sum(~np.isfinite(before)))
        needed, proven = max(1, math.ceil(deficit / 3)), False        # each position gives three readings
    best, after = _best(mod, P, M, fixed, pool, sigma, goal)
    return Next(**common, position=position(best), after=after, still_needed=needed, still_needed_proven=proven)


def _with_measured(P, M, measured, mounts):
    """The candidates with the measured positions among them (appended where the grid lacks one), and
    the indices of the measured ones."""
    fixed = []
    for x, k in zip(measured, mounts):
        hit = np.flatnonzero(np.all(np.abs(P - x) < 1e-9, axis=1) & (M == k))
        if not len(hit):
            P, M = np.vstack([P, x[None]]), np.r_[M, k]
            hit = [len(P) - 1]
        if int(hit[0]) not in fixed:
            fixed.append(int(hit[0]))
    return P, M, fixed


def _best(mod, P, M, fixed, pool, sigma, goal):
    """The position of `pool` whose addition leaves the fewest q without an estimator, then the smallest
    largest ratio error / target, then the smallest sum of ratios; and the errors once it is added."""
    best, key, after = None, None, None
    for s in pool:
        idx = [*fixed, s]
        e = sigma * errors_on(mod, P[idx], M[idx])
        r = e / goal
        finite = r[np.isfinite(r)]
        k = (int(np.sum(~np.isfinite(r))), float(finite.max()) if len(finite) else 0.0, float(finite.sum()))
        if key is None or k < key:
            best, key, after = s, k, e
    return best, after
