"""Optimal guaranteed errors and a minimal optimal plan of a stand ((7)-(12) of 000; section 4 of 001):
the one computation `garant plan` prints and `garant.plan` returns."""
from dataclasses import dataclass

import numpy as np

from ..errors import DataError, NotExact, opt
from ..defaults import COUNT_SECONDS, MAX_CANDIDATES, SEARCH_SECONDS


@dataclass
class Plan:
    """The plan search of a stand: `search` (solve/plans.PlanSearch) on the candidates, the continuum
    optimum where an angle is continuous, and the preferred minimal plan (indices into the candidates)."""

    model: str
    mod: object
    search: object
    plan: list
    continuum: list | None        # the exchange method's optimum on the continuum, per q (None: detents)
    added: int                    # exchange positions added to the candidates
    grid_step: float | None       # degrees (None: detents or quarter turns)
    search_seconds: float | None = None   # the safety stop of the search for the fewest positions
    search_nodes: int | None = None       # the work allowed for it (branch-and-bound nodes)

    @property
    def finite(self):
        """Whether the stand reaches finitely many positions (detents only): no continuum optimum."""
        return self.continuum is None

    @property
    def multi(self):
        """Whether the stand uses several mountings."""
        return len(self.mod.MOUNTINGS) > 1

    def position(self, s):
        """Candidate s as angles in degrees, and its mounting when the stand has several."""
        from ..models import layout
        mounts = layout(self.mod)[1]
        r = self.search
        return [*(float(v) for v in r.angles_deg[s]), *([mounts[r.mounts[s]]] if self.multi else [])]

    def to_dict(self):
        """The plan as `garant plan --json` writes it."""
        from ..models import layout
        names, mounts = layout(self.mod)
        r = self.search
        on_quarter = all(np.all(np.isclose(r.angles_deg[list(p)] % 90, 0)) for p in r.optimal_plans)
        return {
            "model": self.model, "angles": names, "mountings": mounts, "q_names": list(self.mod.Q_NAMES),
            "definitions": list(self.mod.Q_DEFINITIONS), "guaranteed_errors": list(r.errors),
            "proven_on_continuum": list(r.proven),
            "continuum_errors": None if self.continuum is None else [float(c) for c in self.continuum],
            "reachable_set": "detents" if self.finite else "continuum", "exchange_candidates_added": self.added,
            "guaranteed_errors_exact": r.exact_errors(), "grid_step_deg": self.grid_step, "count_method": r.method,
            "min_positions": r.min_positions, "min_positions_proven": r.floor is None,
            "min_positions_at_least": r.min_positions if r.floor is None else r.floor,
            "optimal_plans_count": len(r.optimal_plans) if r.exhaustive else None,
            "stopped_by_clock": bool(r.clock),
            "optimal_plans_on_quarter_turns": bool(on_quarter),
            "plan": [self.position(s) for s in self.plan],
            "optimal_plans": [[self.position(s) for s in pl] for pl in r.optimal_plans]}




def refuse_variables(mod, model):
    """DataError for a model whose H depends on VARIABLES (an extended model's time or temperature):
    which position comes when, or how warm, is not a choice among positions."""
    variables = tuple(map(str, mod.VARIABLES))
    if variables:
        raise DataError(f"{model}: H depends on {', '.join(variables)} (when or how warm each position is measured), "
                        "which a plan of positions cannot choose: plan with the base model, record "
                        f"{', '.join(variables)} on every row, and estimate with this one", param="model")


def plan(mod, model, grid=None, count_seconds=COUNT_SECONDS, max_candidates=MAX_CANDIDATES,
         search_seconds=SEARCH_SECONDS, progress=None, certify=False, search_nodes=None, count_nodes=None):
    """The Plan of a stand model: candidates every `grid` degrees (default: detents or quarter turns), and
    on a stand with a continuous angle the exchange method's positions added when the candidates miss
    the continuum optimum. A grid of more than `max_candidates` positions (times mountings) is refused
    before any work; the search for the fewest positions keeps its best plan after `search_nodes`
    branch-and-bound nodes, and counts the plans of that size within `count_nodes` (None: the defaults of
    solve/highs.py); the seconds are a safety stop.
    `progress(text)`, when given, hears the size of a search beyond the bit masks before it starts.
    With `certify`, a stand whose H is not exact at the candidates (no certificate can be written) is
    refused before the search."""
    from ..models import layout
    from ..proof import build
    from ..solve import continuum, plans
    refuse_variables(mod, model)
    names, mounts = layout(mod)
    P, M = candidates(mod, grid, max_candidates)
    if certify:
        from ..solve import exact
        try:
            exact.exact_columns(mod, P, M)                  # every candidate: a detent off 15 degrees is in P too
        except NotExact as e:
            raise DataError(f"{opt('certificates')}: {e}") from None
    from ..solve import highs
    work = dict(count_seconds=count_seconds, search_seconds=search_seconds, search_nodes=search_nodes,
                count_nodes=count_nodes)
    if progress is not None and len(P) > plans.BITMASK_LIMIT:
        progress(f"{len(P)} candidate positions, {len(mod.Q_NAMES)} combinations: the fewest positions by a "
                 f"mixed-integer program (up to {search_nodes or highs.SEARCH_NODES:,} nodes, then "
                 f"{highs.COUNT_NODES if count_nodes is None else count_nodes:,} counting)")
    first = plans.optimal_errors(mod, P, M)          # each q's optimal error on the candidates, before any search
    n = len(names)
    ranges = mod.ANGLE_RANGES_DEG
    detents = mod.ANGLE_DETENTS_DEG
    cont, added, r = None, 0, None
    if not all(len(d) for d in detents):    # the continuum of reachable angles: the exchange method there
        sol = continuum.exchange(build.stacked_H(mod), n, np.eye(len(mod.Q_NAMES)), ranges_deg=ranges)
        cont = sol.values
        if any(e > c + 1e-7 for e, c in zip(first.errors, cont)):   # the exchange positions become candidates
            r, added = _with_exchange(mod, P, M, sol, ranges, detents, len(mounts), work)
    if r is None:
        r = plans.search(mod, P, M, **work, optimal=first)
    return Plan(model, mod, r, _preferred_plan(mod, r), None if cont is None else list(cont), added, grid,
                search_seconds, search_nodes or highs.SEARCH_NODES)


def _with_exchange(mod, P, M, sol, ranges, detents, k, work):
    """The search with the exchange method's positions as candidates: exact ones (multiples of 15 degrees)
    first, then all, until the candidates reach the continuum optimum (each set's errors looked at before
    the one search). (search, added), or (None, 0) when the exchange adds no position."""
    from ..solve import plans
    X = _snap(np.rad2deg(sol.positions), ranges, detents)
    base = P[M == 0]
    new_all = [x for x in X if not np.any(np.all(np.isclose(base, x), axis=1))]
    exact = [x for x in new_all if np.all(x % 15 == 0)]
    chosen, added, optimal = None, 0, None
    for new in ([exact, new_all] if exact and len(exact) < len(new_all) else [new_all]):
        if not new:
            continue
        P2 = np.vstack([base, np.array(new)])
        chosen, added = (np.tile(P2, (k, 1)), np.repeat(np.arange(k), len(P2))), len(new)
        optimal = plans.optimal_errors(mod, *chosen)
        if all(e <= c + 1e-7 for e, c in zip(optimal.errors, sol.values)):
            break
    return (None, 0) if chosen is None else (plans.search(mod, *chosen, **work, optimal=optimal), added)


def _snap(X, ranges, detents, step=15.0, tol=1e-6):
    """Exchange positions (degrees): onto multiples of 15 degrees where within tol (then exact), within
    the range of each angle; positions a stand cannot take are dropped."""
    from ..models import unreachable
    k = np.round(X / step) * step
    X = np.where(np.abs(X - k) < tol, k, X) % 360
    return [x for x in X if unreachable(ranges, detents, x[None]) is None]


def candidates(mod, step=None, limit=MAX_CANDIDATES):
    """The candidate positions (degrees, (S, angles)) and mountings (S,) of a search: every `step` degrees
    that the stand can take, in every mounting (at most `limit` in all), or without a step its detents
    or quarter turns."""
    if step is None:
        from ..solve import plans
        detents = mod.ANGLE_DETENTS_DEG
        if all(len(d) for d in detents):              # every angle on detents: their product, sized before it is made
            from ..models import layout
            count = int(np.prod([len(d) for d in detents])) * len(layout(mod)[1])
            if count > limit:
                raise DataError(f"the stand's detents give {count:,} candidate positions (" + " x ".join(
                                str(len(d)) for d in detents) + (f" in {len(layout(mod)[1])} mountings" if
                                                                 len(layout(mod)[1]) > 1 else "")
                                + f"), more than {opt('max_candidates')} {limit:,}: give a coarser {opt('grid')} "
                                "STEP, or a larger --max-candidates", param="max_candidates")
        return plans.grid(mod)
    if 360 % step:
        raise DataError(f"{opt('grid')} {step:g}: give a step that divides 360 degrees")
    from ..models import layout, reachable_grid
    k = len(layout(mod)[1])
    P = reachable_grid(mod.ANGLE_RANGES_DEG,
                       mod.ANGLE_DETENTS_DEG, step, limit=max(limit // k, 1),
                       what=f"--grid {step:g}" + (f" (in each of {k} mountings)" if k > 1 else ""),
                       raise_with="--max-candidates")
    return np.tile(P, (k, 1)), np.repeat(np.arange(k), len(P))


def _preferred_plan(mod, r):
    """The model's own plan (PLAN_DEG) when it is among the optimal ones, else the first found."""
    own = mod.PLAN_DEG
    if len(own):
        idx = tuple(sorted(int(np.flatnonzero(np.all(r.angles_deg == p, axis=1))[0]) for p in own))
        if idx in r.optimal_plans:
            return [int(np.flatnonzero(np.all(r.angles_deg == p, axis=1))[0]) for p in own]
    return list(r.optimal_plans[0])


def norm_plan(mod):
    """The coarse stand of 001: optimal errors on the sphere (units of delta_sigma_max) and the fewest
    orientations optimal for the 9 linear parameters and for all 12 (unit vectors, -gravity in sensor
    axes), as a dictionary (the JSON of `garant plan --model norm`)."""
    from ..solve import lp
    from ..solve.sphere import minimal_plan
    _, errors = lp.primal(mod.H(mod.PLAN.T))
    plans = {k: minimal_plan(mod, range(k)) for k in (9, 12)}
    return {"model": "norm", "q_names": list(mod.Q_NAMES), "guaranteed_errors": [float(e) for e in errors],
            "min_positions": {"9": len(plans[9]), "12": len(plans[12])},
            "directions": {str(k): [mod.PLAN[i].tolist() for i in idx] for k, idx in plans.items()},
            "directions_exact": {str(k): [mod.PLAN_EXACT[i] for i in idx] for k, idx in plans.items()}}


def route(res):
    """The plan's positions in the order of least total stand time, from the motion the stand's
    description states (per angle speed_deg_s and acceleration_deg_s2; settle_s, remount_s), or without
    speeds in the order of least largest angle turned in one move: a dictionary (`plan --json`'s
    "route")."""
    from ..models import layout, stand_model
    from ..solve import route as rt
    try:
        stand = stand_model(res.model).stand
        angles = stand.angles
        motion = rt.Motion(tuple(a.speed_deg_s for a in angles), tuple(a.acceleration_deg_s2 for a in angles),
                           stand.settle_s or 0.0, stand.remount_s or 0.0)
    except DataError:                                          # a generated module: no description to read
        motion = rt.Motion((None,) * len(res.mod.ANGLES), (None,) * len(res.mod.ANGLES))
        stand = None
    r = res.search
    P, M = r.angles_deg[res.plan], r.mounts[res.plan]
    ranges = res.mod.ANGLE_RANGES_DEG
    C = rt.costs(P, M, ranges, motion)
    order, method, bound = rt.order(C, bottleneck=not motion.timed)
    moves = [0.0] + [float(C[a, b]) for a, b in zip(order, order[1:])]
    turned = rt.travel(P, ranges)
    notes = []
    if motion.timed and res.multi and stand is not None and stand.remount_s is None:
        notes.append("the description states no remount_s: a change of mounting is counted as no time")
    if motion.timed and any(a is None for a in motion.acceleration):
        notes.append("an angle without acceleration_deg_s2 is taken to reach its speed at once")
    total = float(sum(moves))
    return {"objective": "total stand time, s" if motion.timed else "largest angle turned in one move, degrees",
            "method": method, "positions": [res.position(res.plan[k]) for k in order],
            "turned_deg": [[0.0] * len(res.mod.ANGLES)] + [turned[a, b].tolist() for a, b in zip(order, order[1:])],
            "move": moves, "arrive_s": list(np.cumsum(moves)) if motion.timed else None,
            "total": total if motion.timed else max(moves), "lower_bound": bound,
            "gap": None if bound is None or not bound else total / bound - 1, "notes": notes,
            "layout": layout(res.mod)[0]}
