"""Building optimality certificates for the models of the project (checked by check.py).

Two-axis stand: the derived closed-form estimators and the duals e_nu. Coarse stand of 001: the
derived estimators on the 30 directions and the Chebyshev polynomials of section 4. Other stands:
the exchange solution on the continuum, made exact (rational or surd duals, exact primals on the
quarter turns or on multiples of pi/24).
"""
import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import sympy as sp

from .check import as_exact, feasible, make
from ..models import kind
from .reference import MODELS, reference


def _angle(deg):
    return sp.sstr(sp.pi * sp.Rational(str(deg)) / 180)


def for_stand(key):
    """Certificates of every optimal value of a built-in stand (derive/stands/KEY.toml)."""
    from garant.derive.builtin import MODELS as BUILTIN
    from garant.derive.derivation import derive

    from .. import models
    d = derive(BUILTIN[key])
    mod = models.load(key.replace("_", "-"))
    H, domain, _ = reference(key)
    names = domain["names"]
    rows = [[sp.sstr(e) for e in row] for row in H]
    m = d.ident.H.cols
    out = []
    if len(mod.ESTIMATOR_TERMS):       # derived closed forms with the duals e_nu
        for nu in range(m):
            primal = [([_angle(v) for v in mod.PLAN_DEG[s]], p, Fraction(num, den))
                      for s, p, num, den in mod.ESTIMATOR_TERMS[nu]]
            out.append((mod.Q_NAMES[nu], [int(i == nu) for i in range(m)], primal,
                        [int(i == nu) for i in range(m)]))
    else:
        out = _continuum_certificates(mod, d, rows, names, m)
    return [make(key, f"optimal guaranteed error of {q} = {mod.Q_DEFINITIONS[mod.Q_NAMES.index(q)]} on "
                 f"the whole box of angles", domain, rows, a, sum(abs(w) for _, _, w in primal), primal, lam)
            for q, a, primal, lam in out]


def stacked_H(mod):
    """H of a stand module with all mountings stacked as rows: (3 x mountings, m, ...)."""
    if len(mod.MOUNTINGS) == 1:
        return mod.H
    return lambda *a: np.concatenate([mod.H(*a, mount=k) for k in range(len(mod.MOUNTINGS))], axis=0)


def _continuum_certificates(mod, d, rows, names, m, step=sp.pi / 24):
    """Exact certificates from the exchange solution. The primal: the exact grid estimator when the
    continuum value equals the quarter-turn one, else an exact solve on the exchange positions
    (snapped to multiples of pi/24). The dual: the exchange dual, rationalised, or made exact by
    complementary slackness; the checker decides whether it holds."""
    from ..solve import continuum, exact, lp, plans
    H = stacked_H(mod)
    sol = continuum.exchange(H, len(names), np.eye(m))
    r = plans.search(mod, count_limit=1)                 # one plan is enough here: no count
    cols_grid = exact.integer_columns(mod, r.angles_deg, r.mounts)
    k = np.rint(sol.positions / float(step))
    keep = np.all(np.abs(sol.positions - k * float(step)) < 1e-7, axis=1)
    X, K = sol.positions[keep], k[keep].astype(int)
    Phi, _ = lp.primal(lp.measurement_matrix(H, X))
    syms = [sp.Symbol(n, real=True) for n in names]
    R = d.ident.H.rows
    out = []
    for nu in range(m):
        a = [int(i == nu) for i in range(m)]
        if abs(sol.values[nu] - r.errors[nu]) < 1e-7:
            lam_g, sets = plans.dual_on_grid(cols_grid, nu)
            weights = sets[0].weights if sets else exact_primal(cols_grid, nu, lam_g)
            if weights is None:
                continue
            primal = [([_angle(v) for v in r.angles_deg[s_]], 3 * int(r.mounts[s_]) + p, w) for s_, p, w in weights]
        else:
            primal = _snapped_primal(d, syms, X, K, Phi[:, nu], nu, step, R)
            if primal is None:
                continue
        value = sum((abs(as_exact(w)) for _, _, w in primal), sp.Integer(0))
        Hs = [list(d.ident.H.row(i)) for i in range(R)]
        dom = {"kind": "angles", "names": names, "ranges": [["0", "2*pi"]] * len(names)}
        for lam in _dual_candidates(sol.lam[:, nu], primal, d, syms, R, step):
            if (sp.simplify(sum(x * y for x, y in zip(a, lam)) - value) == 0
                    and feasible(Hs, lam, dom, syms, max_boxes=100_000)[0]):
                out.append((mod.Q_NAMES[nu], a, primal, lam))
                break
    return out


def _snapped_primal(d, syms, X, K, phi, nu, step, R):
    """Exact weights on the exchange positions carrying the LP estimator of q_nu."""
    m = d.ident.H.cols
    support = [j for j in np.argsort(-np.abs(phi)) if abs(phi[j]) > 1e-9]
    chosen, cols = [], []
    for j in support:
        at = {s: ki * step for s, ki in zip(syms, K[j // R])}
        col = sp.Matrix([as_exact(d.ident.H[j % R, c].subs(at)) for c in range(m)])
        if sp.Matrix.hstack(*(cols + [col])).rank() == len(cols) + 1:
            chosen, cols = chosen + [j], cols + [col]
    try:
        w, free = sp.Matrix.hstack(*cols).gauss_jordan_solve(sp.Matrix([int(i == nu) for i in range(m)]))
    except ValueError:
        return None
    if free:
        return None
    return [([sp.sstr(ki * step) for ki in K[j // R]], j % R, sp.nsimplify(sp.radsimp(wi)))
            for j, wi in zip(chosen, w)]


def _dual_candidates(lam, primal, d, syms, R, step):
    """Exact versions of a float dual: small rationals, rationals, with surds of 2 and 3, then by
    complementary slackness (the checker decides which, if any, holds)."""
    for den in (12, 1000):
        yield [sp.Rational(str(round(v, 9))).limit_denominator(den) if abs(v) > 1e-6 else sp.Integer(0)
               for v in lam]
    yield [sp.nsimplify(v, [sp.sqrt(2), sp.sqrt(3)], tolerance=1e-8) if abs(v) > 1e-9 else sp.Integer(0) for v in lam]
    cols, signs = [], []
    for at, row, w in primal:
        sub = {s: sp.sympify(x) for s, x in zip(syms, at)}
        cols.append([as_exact(d.ident.H[row, c].subs(sub)) for c in range(d.ident.H.cols)])
        signs.append(1 if as_exact(w) > 0 else -1)
    yield from exact_duals(lam, cols, signs)


def exact_duals(lam, cols, signs):
    """lambda made exact by complementary slackness: on its support J, the active constraints
    h_k . lambda = sign_k of the primal's measurements, solved exactly; free parameters left by them
    are set to simple exact numbers near the float dual (looser and looser), one candidate each."""
    J = [i for i, v in enumerate(lam) if abs(v) > 1e-6]
    M = sp.Matrix([[c[i] for i in J] for c in cols])
    try:
        x, free = M.gauss_jordan_solve(sp.Matrix([int(s) for s in signs]))
    except ValueError:
        return
    taus = list(free)
    for tol in (1e-9, 1e-6, 1e-3):
        fix = {}
        for t in taus:
            i = next(k for k, v in enumerate(x) if v == t)
            fix[t] = sp.nsimplify(lam[J[i]], [sp.sqrt(2), sp.sqrt(3)], tolerance=tol)
        out = [sp.Integer(0)] * len(lam)
        for i, v in zip(J, x.subs(fix)):
            out[i] = sp.nsimplify(sp.radsimp(v))
        yield out


def exact_primal(cols, nu, lam):
    """An exact optimal estimator on the grid: a vertex of {w >= 0 : sum w sign H = e_nu} among the
    measurements where the dual touches (any such w is optimal), made exact in rationals."""
    import cvxpy as cp

    from garant.derive.linear import solve_exact

    from ..errors import LPFailed
    from ..solve import lp
    from ..solve.plans import touching
    cand, signs = touching(cols, lam)
    V = np.array([cols[s, p] * g for (s, p), g in zip(cand, signs)], float)
    w = cp.Variable(len(cand), nonneg=True)
    prob = cp.Problem(cp.Minimize(0), [V.T @ w == np.eye(V.shape[1])[nu]])
    try:
        lp.optimal(prob, "exact primal support")
    except LPFailed:
        return None
    support = [k for k in np.argsort(-w.value) if w.value[k] > 1e-9]
    chosen = []
    for k in support:                                       # an independent subset carrying e_nu
        trial = chosen + [k]
        if np.linalg.matrix_rank(V[trial]) == len(trial):
            chosen = trial
    e = [int(i == nu) for i in range(V.shape[1])]
    x = solve_exact([V[k].astype(int) for k in chosen], e)
    if x is None or min(x) < 0:
        return None
    return [(cand[k][0], cand[k][1], xi * signs[k]) for k, xi in zip(chosen, x) if xi != 0]


def for_norm():
    """Certificates of the twelve optimal values of 001 on the unit sphere."""
    from garant.generated import norm as mod
    H, domain, _ = reference("norm")
    rows = [[sp.sstr(e) for e in row] for row in H]
    out = []
    for nu, q in enumerate(mod.Q_NAMES):
        primal = [([x.strip() for x in mod.PLAN_EXACT[k].split(",")], 0, Fraction(num, den))
                  for k, num, den in mod.ESTIMATOR_TERMS[nu]]
        lam = [int(v) for v in mod.DUALS[nu]]
        a = [int(i == nu) for i in range(len(mod.Q_NAMES))]
        out.append(make("norm", f"optimal guaranteed error of {q} on the unit sphere (units of "
                        "delta_sigma_max)", domain, rows, a, sum(abs(w) for _, _, w in primal), primal, lam))
    return out


def for_model(name):
    """Every certificate of a built-in model (its q's optimal errors on its plan)."""
    return for_norm() if kind(name) == "norm" else for_stand(MODELS[name])


def file_name(cert):
    """The file name a certificate is written under."""
    q = cert["claim"].split(" of ", 1)[1].split(" ", 1)[0]
    return f"{cert['model'].replace('_', '-')}_{q}.json"


def for_plan(mod, model, r, plan, grid_step=None):
    """Certificates that the plan (grid indices of the search r) is optimal for each q on the
    positions it was chosen from: the exact dual of the search, an exact estimator inside the plan.
    Only where the dual is exact; returns [(q name, certificate)]."""
    import hashlib
    from pathlib import Path

    from ..models import symbolic_H
    from ..solve import exact, field, plans
    H, _ = symbolic_H(mod)
    names = list(mod.ANGLES)
    distinct = sorted({tuple(float(v) for v in a) for a in r.angles_deg})
    domain = {"kind": "positions", "names": names, "positions": [[_angle(v) for v in p] for p in distinct]}
    if not all(mod.ANGLE_DETENTS_DEG):    # the grid the candidates come from
        domain["grid_step_deg"] = sp.sstr(sp.Rational(str(grid_step or 90)))
    rows = [[sp.sstr(e) for e in H.row(i)] for i in range(H.rows)]
    sub = exact.exact_columns(mod, r.angles_deg[list(plan)], r.mounts[list(plan)])
    out = []
    for nu, lam in enumerate(r.duals):
        if not plans.is_exact(lam):
            continue
        weights = plans.estimator_in(sub, nu, lam)
        if not weights:
            continue
        def to_sympy(x):
            return x.sympy() if isinstance(x, field.QF) else as_exact(x)
        primal = [([_angle(v) for v in r.angles_deg[plan[s_]]], 3 * int(r.mounts[plan[s_]]) + p, to_sympy(w))
                  for s_, p, w in weights]
        lam_x = [to_sympy(v) for v in lam]
        a = [int(i == nu) for i in range(len(lam))]
        value = sum((abs(w) for _, _, w in primal), sp.Integer(0))
        q = mod.Q_NAMES[nu]
        cert = make(model, f"optimal guaranteed error of {q} = {mod.Q_DEFINITIONS[nu]} on the {len(distinct)} "
                    "candidate positions of the plan search", domain, rows, a, value, primal, lam_x)
        if str(model).endswith(".toml"):
            cert["model_sha256"] = hashlib.sha256(Path(model).read_bytes()).hexdigest()
        out.append((q, cert))
    return out


#: The certificates of the built-in models, built once and committed: `garant verify` re-checks these
#: (the check is the proof; building is a search that takes seconds). `python -m verify.proof` rebuilds
#: them, `--check` fails on any difference, and tests/solve/test_certificates.py does the same.
COMMITTED = Path(__file__).resolve().parent / "certificates"


def committed(name, q_names):
    """[(q, the committed certificate of q, or None when there is none)] of a built-in model."""
    from . import check
    return [(q, check.read(COMMITTED / f"{name}_{q}.json") if (COMMITTED / f"{name}_{q}.json").is_file() else None)
            for q in q_names]


def built():
    """{file name: JSON text} of every built-in model's certificates, built now."""
    from .reference import MODELS
    return {file_name(c): json.dumps(c, indent=1) + "\n" for name in MODELS for c in for_model(name)}

