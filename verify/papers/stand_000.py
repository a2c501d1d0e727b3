"""Checks of the two-axis stand of 000 for `garant verify`: closed forms, continuum optimum, plans,
Tables 1-2, additivity, remount (25)-(29), realised plans (20)-(24), section 6."""
from fractions import Fraction
from itertools import product

import numpy as np

from garant.derive import published

from ..solve import exact, lp, plans
from ..workflows import nearby
from . import physics_000, section6
from .row import Check
GRID_STEP_DEG = 15


def _e(nu, m):
    return [int(i == nu) for i in range(m)]


def closed_forms(mod):
    """Published (section 4.3 of 000) and derived estimators: unbiased and sum |Psi| = 1, exactly."""
    m = len(mod.Q_NAMES)
    for nu, name in enumerate(mod.Q_NAMES):
        for label, terms, source in (
                ("published", exact.terms_from_published(published.ESTIMATORS_000[name]),
                 "000, section 4.3"),
                ("derived", exact.terms_from_generated(mod, nu), "generated/two_axis.py")):
            unbiased = exact.unbiased_image(mod.H, terms) == _e(nu, m)
            err = exact.l1(terms)
            yield Check(f"{label} estimator of {name}: unbiased, sum|Psi| (exact)", source,
                        "unbiased, 1", f"{'unbiased' if unbiased else 'BIASED'}, {err}",
                        unbiased and err == 1)


def continuum_optimum(mod):
    """Optimal guaranteed error of every q_nu on the whole square, proven: primal = dual bound = 1."""
    m = len(mod.Q_NAMES)
    for nu, name in enumerate(mod.Q_NAMES):
        upper = exact.l1(exact.terms_from_generated(mod, nu))
        lower = exact.dual_lower_bound(mod.H_SUP, _e(nu, m), _e(nu, m))
        yield Check(f"optimal guaranteed error of {name} on the continuum (units of sigma)",
                    "000, section 4: sigma for every q_nu", "1",
                    f"{lower} <= opt <= {upper}", lower == upper == 1)


def grid_lp(mod, step=GRID_STEP_DEG):
    """Primal (7)-(8) = dual (9)-(10) = 1/L_nu (12) on a grid of the square (Theorem 3)."""
    g = np.deg2rad(np.arange(0, 360, step))
    A = lp.measurement_matrix(mod.H, np.array([(a, b) for a in g for b in g]))
    _, primal = lp.primal(A)
    _, dual = lp.dual(A)
    L, _ = lp.chebyshev(A)
    for nu, name in enumerate(mod.Q_NAMES):
        vals = (primal[nu], dual[nu], 1 / L[nu])
        yield Check(f"{name} on the {step} deg grid: primal = dual = 1/L", "000, (7)-(12), Theorem 3",
                    "1 = 1 = 1", " = ".join(f"{v:.9f}" for v in vals),
                    bool(np.allclose(vals, 1, atol=1e-7)))


def _same_sets(found, listed):
    return {frozenset(s) for s in found} == {frozenset(s) for s in listed}


def plan_checks(mod, search=None):
    """Minimal plan, count of optimal plans, Tables 1 and 2 of 000 (exact search on the quarter grid)."""
    r = search or plans.search(mod, np.array(plans.QUARTER_DEG, float))
    yield Check("minimal number of positions optimal for all 15 q (quarter-turn grid)",
                "000, section 4.3: fewer than 10 cannot be optimal", str(published.MIN_POSITIONS_000),
                str(r.min_positions), r.min_positions == published.MIN_POSITIONS_000)
    n = len(r.optimal_plans)
    table2 = int(np.prod([len(alts) for _, alts in published.TABLE2_000]))
    yield Check("number of optimal 10-position plans on the quarter-turn grid (16 positions, exact count)",
                "000, section 4.3 ('at least 64') and Table 2 (one set of each row)",
                f"{table2} (product of the alternatives of Table 2; the paper: >= {published.AT_LEAST_PLANS_000})",
                str(n), n == table2 and n >= published.AT_LEAST_PLANS_000)
    for name, listed in published.TABLE1_000.items():
        nu = mod.Q_NAMES.index(name)
        found = [r.plan_deg(ms.positions) for ms in r.minimal[nu]]
        yield Check(f"Table 1: necessary position sets of {name}", "000, Table 1",
                    f"{len(listed)} sets as printed", f"{len(found)} sets",
                    _same_sets([map(tuple, f) for f in found], listed))
    for group, alternatives in published.TABLE2_000:
        ok = all(r.is_optimal_for(mod.Q_NAMES.index(q), [plans.QUARTER_DEG.index(p) for p in alt])
                 for q in group for alt in alternatives)
        yield Check(f"Table 2: each set of group {','.join(group)} is optimal for all of it",
                    "000, Table 2", "optimal", "optimal" if ok else "NOT optimal", ok)
    combos = {frozenset().union(*(frozenset(plans.QUARTER_DEG.index(p) for p in alt) for alt in pick))
              for pick in product(*(alts for _, alts in published.TABLE2_000))}
    same = combos == {frozenset(pl) for pl in r.optimal_plans}
    yield Check("optimal 10-position plans = one set of each row of Table 2", "000, Table 2",
                f"{len(combos)} combinations", f"{n} plans, {'same' if same else 'different'} sets", same)
    starred = tuple(sorted(plans.QUARTER_DEG.index(p) for p in published.PLAN_000))
    yield Check("starred plan of Table 2 is among the optimal 10-position plans", "000, Table 2",
                "yes", "yes" if starred in r.optimal_plans else "no", starred in r.optimal_plans)


def additivity(mod):
    """Gamma_ij + Gamma_ji: the sum of the optimal estimators is optimal (000, section 4.3)."""
    m = len(mod.Q_NAMES)
    A = lp.measurement_matrix(mod.H, np.deg2rad(np.asarray(mod.PLAN_DEG, float)))
    for i, j in ((6, 9), (4, 12), (8, 13)):
        a = np.array(_e(i - 1, m)) + np.array(_e(j - 1, m))
        terms = (exact.terms_from_published(published.ESTIMATORS_000[f"q{i}"])
                 + exact.terms_from_published(published.ESTIMATORS_000[f"q{j}"]))
        summed = {}
        for w, p, pos in terms:
            summed[(p, pos)] = summed.get((p, pos), Fraction(0)) + w
        err = sum(abs(w) for w in summed.values())
        lower = exact.dual_lower_bound(mod.H_SUP, a, a)
        _, val = lp.primal(A, a)
        ok = bool(lower == err and abs(val[0] - float(err)) < 1e-7)
        yield Check(f"q{i} + q{j}: sum of optimal estimators is optimal", "000, section 4.3",
                    f"LP = exact = dual bound = {err}", f"{val[0]:.9f}, {err}, {lower}", ok)


def remount_round_trip(mod, remount, size=1e-6):
    """(28)-(29) recover the block errors of every mounting, both Gamma conventions, from readings
    simulated by the paper's own chain in numpy (physics_000.py), estimated with the generated H on
    the quarter-turn grid: exact up to the second-order remainder (errors of size 1e-6)."""
    rng = np.random.default_rng(0)
    P = np.deg2rad(np.array(plans.QUARTER_DEG, float))
    A = lp.measurement_matrix(mod.H, P)
    worst = 0.0
    for name, Q in remount.MOUNTS.items():
        for gamma in ("lower", "symmetric"):
            stand = dict(zip(physics_000.STAND, rng.uniform(-size, size, 6)))
            G = rng.uniform(-size, size, (3, 3))
            G = np.tril(G) if gamma == "lower" else (G + G.T) / 2
            b, th = rng.uniform(-size, size, 3), rng.uniform(-size, size, 3)
            z = np.concatenate([physics_000.residual_table_axes(a, be, physics_000.readings_over_g(
                a, be, stand, Q, G, b, th), Q) for a, be in P])
            q = np.linalg.lstsq(A.T, z, rcond=None)[0]
            got = remount.recovery_matrix(name, gamma) @ q + remount.neglected(
                name, stand["Delta_g"], stand["Delta_beta"], gamma)
            want = np.concatenate([[stand["kappa"], stand["Delta_alpha"] + stand["alpha_star"], stand["epsilon"]],
                                   b, G.ravel(), th])
            worst = max(worst, float(np.abs(got - want).max()) / size)
    yield Check("remount (28)-(29): 24 mountings x 2 Gamma conventions recover the block errors",
                "000, (25)-(29); readings from the paper's chain (verify/papers/physics_000.py)",
                "< 1e-4 of the error size (second order)", f"{worst:.1e}", worst < 1e-4)


#: docs/mountings_and_realised_plans.md: at a 1-degree miss the worst guaranteed error over 20 random
#: realisations is about 1.05 sigma for (23) and 1.03 sigma for the LP optimum on the same positions.
DOCS_REALISED_1DEG = (1.05, 1.03)


def realised_plan(mod):
    """(23)-(24) of 000 on the optimal plan missed by 1 degree: the figures the docs quote."""
    _, _, worst23, _, worst_lp = nearby.sweep(mod, [1.0])[0]
    got = (round(float(worst23), 2), round(float(worst_lp), 2))
    yield Check("(23) and the LP optimum on the optimal plan missed by 1 deg (worst of 20 realisations)",
                "000, (20)-(24); docs/mountings_and_realised_plans.md",
                f"{DOCS_REALISED_1DEG[0]} and {DOCS_REALISED_1DEG[1]} sigma",
                f"{worst23:.4f} and {worst_lp:.4f} sigma", got == DOCS_REALISED_1DEG)


def ignoring_the_stand(mod, remount):
    """Section 6 of 000: reduced-model optimal estimators, their stand bias, and equal optimal errors,
    each compared with an independent value: counts by brute force over the quarter grid
    (section6.brute_force), the full-model optimum closed by the exact estimator of the module."""
    stand_idx = [k for _, k, _ in remount.STAND]
    rows = section6.analyse(mod, stand_idx)
    brute = section6.brute_force(mod, stand_idx)
    for r in rows:
        nu = mod.Q_NAMES.index(r.name)
        full_upper = exact.l1(exact.terms_from_generated(mod, nu))
        n, nb = brute[r.name]
        ok = (r.estimators, r.biased) == (n, nb) and r.error_reduced == 1 and r.error_full == full_upper == 1
        yield Check(f"ignoring the stand: optimal estimators of {r.name} biased by stand errors",
                    "000, section 6", f"{nb}/{n} biased (brute force); errors 1 = 1 (exact estimators)",
                    f"{r.biased}/{r.estimators} biased; reduced {r.error_reduced}, full {r.error_full} <= "
                    f"{full_upper}" + (f"; e.g. {r.example}" if r.example else ""), ok)
    total = sum(r.estimators for r in rows), sum(r.biased for r in rows)
    yield Check("ignoring the stand: some optimal estimators are biased, others are not",
                "000, section 6 ('some of their optimal estimators are then biased')", "0 < biased < all",
                f"{total[1]} biased of {total[0]}", 0 < total[1] < total[0])


def all_groups(mod, remount):
    """Every check group of the two-axis model, in report order: (function, args)."""
    return [(closed_forms, (mod,)), (continuum_optimum, (mod,)), (grid_lp, (mod,)),
            (plan_checks, (mod,)), (additivity, (mod,)), (remount_round_trip, (mod, remount)),
            (realised_plan, (mod,)), (ignoring_the_stand, (mod, remount))]
