"""The lab session's question, which position next: after each measured position, the reachable
position whose addition most reduces the largest ratio guaranteed error / target over the q (the LP
(7)-(8) of 000 on the positions measured so far), "done" when every bound is at its target, and how
many positions are still needed: the one computation `garant next` prints and `garant.next_position`
returns."""
import math
from dataclasses import dataclass

import numpy as np

from ..errors import DataError, opt

#: Relative slack of "at the target": the LP's own tolerance.
AT_TARGET = 1e-7


@dataclass
class Next:
    """Where the session stands and what to measure next. Errors and targets are in the units of each q."""

    model: str
    angles: list                  # the stand's angle names (positions list angles in this order, in degrees)
    names: list                   # what the targets bound: the q's, or the block's parameters (--mount)
    of: str                       # what they are, in words
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
        def finite(v):
            return None if v is None else [None if not np.isfinite(x) else float(x) for x in v]
        return {"model": self.model, "angles": list(self.angles), "names": list(self.names), "of": self.of,
                "sigma": self.sigma,
                "target": [float(t) for t in self.target], "target_source": self.target_source,
                "measured": self.measured, "guaranteed_error_before": finite(self.before), "done": self.done,
                "next": self.position, "guaranteed_error_after": finite(self.after),
                "still_needed": self.still_needed, "still_needed_proven": self.still_needed_proven,
                "candidates": self.candidates}


def errors_on(mod, angles_deg, mounts, C=None):
    """The optimal guaranteed error of each functional c^T q (the rows of C; None: each q) on these
    positions (units of sigma): the LP (7)-(8) of 000 with a = c for those an unbiased estimator exists
    for, inf for the others."""
    m = len(mod.Q_NAMES)
    C = np.eye(m) if C is None else np.asarray(C, float)
    out = np.full(len(C), np.inf)
    if not len(angles_deg):
        return out
    A = _matrix(mod, angles_deg, mounts)
    estimable = np.linalg.norm(A @ (np.linalg.pinv(A) @ C.T) - C.T, axis=0) < 1e-9 * (1 + np.abs(C).sum(axis=1))
    if estimable.any():
        from ..solve import lp
        out[estimable] = lp.primal(A, C[estimable].T)[1]
    return out


def _matrix(mod, angles_deg, mounts):
    """The measurement matrix (m, 3S) of the positions (degrees, with their mountings)."""
    from ..models import H_at
    H = H_at(mod, np.deg2rad(np.asarray(angles_deg, float)), mounts)           # (3, m, S)
    return np.transpose(H, (1, 2, 0)).reshape(len(mod.Q_NAMES), -1)


def rank_still_needed(mod, angles_deg, mounts, C):
    """A lower bound on the positions still needed before every functional (row of C) has an unbiased
    estimator: the dimensions the measured positions lack, rank [A, C^T] - rank A, three at most per position
    (three readings)."""
    A = _matrix(mod, angles_deg, mounts) if len(angles_deg) else np.zeros((len(mod.Q_NAMES), 0))
    rank = (lambda X: int(np.linalg.matrix_rank(X, tol=1e-9 * max(1.0, np.abs(X).max()))) if X.size else 0)  # noqa: E731
    return math.ceil((rank(np.hstack([A, np.asarray(C, float).T])) - rank(A)) / 3)


def block_functionals(mod, model, mount, gamma="lower"):
    """(C, names): the block's parameters in mounting `mount` as functionals of q, the rows of the
    recovery matrix K of (28)-(29) of 000 (biases over g)."""
    from ..models import load_remount
    remount = None if str(model).endswith(".toml") else load_remount(model)
    if remount is None or mount not in remount.MOUNTS:
        raise DataError(f"{opt('mount')} needs a model with the remount formulas (two-axis) and a mounting like "
                        f"+y+z+x; "
                        f"got {mount!r}")
    return remount.recovery_matrix(mount, gamma), list(remount.OUTPUTS)


def target_names(mod, model, mount=None, gamma="lower"):
    """What the targets bound: the q's, or with `mount` the block's parameters the split does not set to zero."""
    if mount is None:
        return list(mod.Q_NAMES)
    C, labels = block_functionals(mod, model, mount, gamma)
    return [n for n, k in zip(labels, np.any(C != 0, axis=1)) if k]


def printed_bounds(res, labels):
    """(bounds, floor): the bounds `garant estimate` printed (its result `res`, consistent) in the order of
    `labels`, the q's or with --mount the block's parameters of (28)-(29) of 000 (biases over g), nan for one it
    has not; floor, the part of each that the premises alone set (no readings reduce it: Delta_g/g, Delta_beta
    and the split's second order), 0 for the q's."""
    if labels and labels[0] in res["guaranteed_error"]:
        return np.array([res["guaranteed_error"].get(n, np.nan) for n in labels], float), np.zeros(len(labels))
    g = res["g"]

    def pick(bound):
        out = []
        for n in labels:
            if n in bound and not isinstance(bound[n], list):
                out.append(bound[n])
            elif n.startswith("bias"):
                out.append(bound["bias"][int(n[-1]) - 1] / g)
            elif n.startswith("Gamma"):
                out.append(bound["Gamma"][int(n[-2]) - 1][int(n[-1]) - 1])
            elif n.startswith("theta_k"):
                out.append(bound["theta_k"][int(n[-1]) - 1])
            else:
                out.append(np.nan)
        return np.array(out, float)
    return pick(res.get("physical_bound", {})), np.nan_to_num(pick(res.get("physical_bound_premises", {})))


#: The default target is sigma x the stand's optimal errors, widened by this much: room for the estimate's
#: own bound, the model linearised where the unit is (H moves by the size of its errors: a MEMS-size unit's
#: scale errors of 2e-2 move a minimal plan's bounds by 1.5-3.6 % at the noise's worst signs) plus the remainder.
TARGET_SLACK = 0.05


def next_position(mod, model, angles_deg, mounts, sigma, target=None, grid=None, search_seconds=None,
                  max_candidates=None, mount=None, gamma="lower", printed=None, floor=None, candidates=None):
    """The Next of a session whose distinct measured positions are `angles_deg` (N, angles; degrees)
    in mountings `mounts` (N,): target None is sigma times the stand's optimal errors on its reachable
    positions (then, for the q's, the suggestion completes a plan of the fewest positions, which the
    measured ones are part of), a number is one target for every q (units of q). With `mount` the targets
    bound the block's parameters in that mounting ((28)-(29) of 000) instead of the q's. `printed`: the
    bounds `estimate` prints on the readings so far (`printed_bounds`), where it gives them: "done" is
    decided on them (remainder included, linearised where the unit is), not on the plan's nominal H; the
    default target then holds TARGET_SLACK for that and `floor`, what the premises alone set. `candidates`: what
    `sized` gave the caller for these positions (else it is made here)."""
    from ..models import layout
    from ..solve import plans
    from .plan import SEARCH_SECONDS, refuse_variables
    refuse_variables(mod, model)
    names, mount_names = layout(mod)
    P, M, fixed = candidates or sized(mod, angles_deg, mounts, grid, max_candidates)   # (sized by the caller)
    m = len(mod.Q_NAMES)
    if mount is None:
        C, labels, of = None, list(mod.Q_NAMES), "the combinations q of (4) of 000"
        cols = plans.columns(mod, P, M)
        lams = [plans.dual_on_grid(cols, nu, False)[0] for nu in range(m)]
        optimal = np.array([float(lam[nu]) for nu, lam in enumerate(lams)])       # units of sigma
    else:
        C, labels = block_functionals(mod, model, mount, gamma)
        keep = np.any(C != 0, axis=1)              # an entry the split sets to zero is no target (`target_names`)
        C, labels = C[keep], [n for n, k in zip(labels, keep) if k]
        of = f"the block's parameters in mounting {mount}, (28)-(29) of 000 (biases over g)"
        optimal = errors_on(mod, P, M, C)
        if not np.all(np.isfinite(optimal)):
            raise DataError(f"{opt('mount')} {mount}: this stand does not separate "
                            + ", ".join(n for n, o in zip(labels, optimal) if not np.isfinite(o)))
    if target is None and printed is None:
        goal, source = sigma * optimal, "sigma x the stand's optimal errors on its reachable positions"
    elif target is None:
        goal = sigma * optimal * (1 + TARGET_SLACK) + (0.0 if floor is None else floor)
        source = (f"sigma x the stand's optimal errors on its reachable positions, +{TARGET_SLACK:.0%} for the "
                  f"estimate "
                  "linearised where the unit is" + (", plus what the premises alone set (estimate's bound)"
                                                     if floor is not None and np.any(floor > 0) else ""))
    else:
        goal, source = np.full(len(labels), float(target)), "--target"
        short = [f"{q} ({sigma * o:.3g})" for q, o in zip(labels, optimal) if sigma * o > target * (1 + AT_TARGET)]
        if short:
            raise DataError(f"{opt('target')} {target:g} is below the stand's optimal error of {', '.join(short)}: no "
                            f"plan "
                            "of its reachable positions reaches it")
    before = sigma * errors_on(mod, P[fixed], M[fixed], C)
    nominal_done = bool(np.all(before <= goal * (1 + AT_TARGET)))
    if printed is not None:                       # what estimate prints where it has a bound
        before = np.where(np.isfinite(printed), printed, before)
    position = lambda s: [*(float(v) for v in P[s]), *([mount_names[M[s]]] if len(mount_names) > 1 else [])]  # noqa: E731
    common = dict(model=model, angles=list(names), names=labels, of=of, sigma=sigma, target=goal, target_source=source,
                  measured=[position(s) for s in fixed], before=before, candidates=len(P))
    if np.all(before <= goal * (1 + AT_TARGET)):
        return Next(**common, position=None, after=None, still_needed=0, still_needed_proven=True)
    if target is None and mount is None and not nominal_done:
        n, found, _, floor, _ = plans.covering_plans(cols, lams, 1, 1.0, search_seconds or SEARCH_SECONDS, fixed)
        pool, needed, proven = [s for s in found[0] if s not in fixed], n - len(fixed), floor is None
    else:                                         # (nominal_done: the plan would be, what estimate prints is not)
        pool = []
    if not pool:                                  # (or the plan is measured, and what estimate prints is not there)
        pool = [s for s in range(len(P)) if s not in fixed]
        needed = max(1, rank_still_needed(mod, P[fixed], M[fixed], np.eye(m) if C is None else C))
        proven = False
    if not pool:
        raise DataError(f"all {len(P)} candidate positions are measured and the guaranteed errors are still above the "
                        f"target (a repeat does not lower a guaranteed bound): give a finer {opt('grid')}, or a larger "
                        f"{opt('target')}")
    best, after = _best(mod, P, M, fixed, pool, sigma, goal, C)
    return Next(**common, position=position(best), after=after, still_needed=needed, still_needed_proven=proven)


def sized(mod, angles_deg, mounts, grid=None, max_candidates=None):
    """The candidates (P, M) with the distinct measured positions among them and the indices of those
    (`_with_measured`), refused in one line when they are more than `max_candidates`: measured positions off
    the grid are candidates too, and the search grows with them. Cheap: called before any estimate."""
    from ..models import layout
    from .plan import MAX_CANDIDATES, candidates
    limit = max_candidates or MAX_CANDIDATES
    measured = np.asarray(angles_deg, float).reshape(-1, len(layout(mod)[0]))
    P, M, fixed = _with_measured(*candidates(mod, grid, limit), measured, np.asarray(mounts, int))
    if len(P) > limit:
        raise DataError(f"{len(fixed):,} distinct measured positions and the {len(P) - len(fixed):,} other candidates "
                        f"make {len(P):,} candidate positions, more than {opt('max_candidates')} {limit:,}: the "
                        "search for the next one grows with them; give a larger --max-candidates, or ask "
                        "`garant estimate` (the bounds on these readings)", param="max_candidates")
    return P, M, fixed


def _with_measured(P, M, measured, mounts):
    """The candidates with the measured positions among them (appended where the grid lacks one), and
    the indices of the measured ones (a position matches a candidate to 1e-7 degree: one look-up per distinct
    position, repeats joined first)."""
    def key(x, k):
        return (*np.round(np.asarray(x, float), 7).tolist(), int(k))
    index = {}
    for i, (x, k) in enumerate(zip(P, M)):
        index.setdefault(key(x, k), i)
    rows = np.column_stack([np.round(np.asarray(measured, float), 7), np.asarray(mounts, float)])
    order = np.lexsort(rows.T[::-1])                                    # stable: a group's first row leads it
    first = np.sort(order[np.r_[True, np.any(rows[order[1:]] != rows[order[:-1]], axis=1)]]) if len(rows) else order
    fixed, seen, extra = [], set(), []
    for x, k in zip(measured[first], np.asarray(mounts)[first]):       # each distinct position once, in order
        hit = index.get(key(x, k))
        if hit is None:
            hit = index[key(x, k)] = len(P) + len(extra)
            extra.append((x, k))
        if hit not in seen:
            seen.add(hit)
            fixed.append(hit)
    if extra:
        P = np.vstack([P, np.array([x for x, _ in extra], float)])
        M = np.r_[M, np.array([k for _, k in extra], M.dtype if len(M) else int)]
    return P, M, fixed


def _best(mod, P, M, fixed, pool, sigma, goal, C=None):
    """The position of `pool` whose addition leaves the fewest q without an estimator, then the smallest
    largest ratio error / target, then the smallest sum of ratios; and the errors once it is added."""
    best, key, after = None, None, None
    for s in pool:
        idx = [*fixed, s]
        e = sigma * errors_on(mod, P[idx], M[idx], C)
        r = e / goal
        finite = r[np.isfinite(r)]
        k = (int(np.sum(~np.isfinite(r))), float(finite.max()) if len(finite) else 0.0, float(finite.sum()))
        if key is None or k < key:
            best, key, after = s, k, e
    return best, after
