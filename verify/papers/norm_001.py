"""Checks of the coarse-stand model of 001 (sections 2-6), for `garant verify`."""
from itertools import combinations, product

import numpy as np
import sympy as sp

from garant.derive import published

from ..solve import lp, sphere
from .row import Check

ETA = 1e-9          # dual certificates are proven to |H^T lambda| <= 1 + ETA on the whole sphere


def exact_direction(text):
    return [sp.sympify(x) for x in text.split(",")]


def H_exact(exponents, n):
    return [n[0]**a * n[1]**b * n[2]**c for a, b, c in exponents]


def exact_estimator(exponents, directions, terms):
    """Image a = sum_k x_k H(n_k) and sum |x_k|, exactly (sympy with sqrt(2), sqrt(3))."""
    image = [sp.Integer(0)] * len(exponents)
    for w, k in terms:
        h = H_exact(exponents, directions[k])
        image = [sp.nsimplify(sp.expand(a + w * v)) for a, v in zip(image, h)]
    return image, sum(abs(w) for w, _ in terms)


def estimators(mod):
    """Published (table of 001) and generated estimators: unbiased and with the published error, exactly."""
    pub_dirs = [exact_direction(d) for d in published.DIRECTIONS_001]
    gen_dirs = [exact_direction(d) for d in mod.PLAN_EXACT]
    for nu, name in enumerate(mod.Q_NAMES):
        e = [int(i == nu) for i in range(len(mod.Q_NAMES))]
        want = published.ERRORS_001[nu]
        rows = [("derived", gen_dirs, [(sp.Rational(num, den), k) for k, num, den in mod.ESTIMATOR_TERMS[nu]],
                 "generated/norm.py")]
        if name in published.ESTIMATORS_001:
            rows.insert(0, ("published", pub_dirs, [(sp.Rational(w), k - 1) for w, k in
                                                    published.ESTIMATORS_001[name]], "001, table of section 4"))
        for label, dirs, terms, source in rows:
            image, err = exact_estimator(mod.H_EXPONENTS, dirs, terms)
            ok = image == e and err == want
            yield Check(f"{label} estimator of {name} (exact)", source, f"unbiased, {want}",
                        f"{'unbiased' if image == e else 'BIASED'}, {err}", ok)


def continuum(mod):
    """Optimal errors on the whole sphere: exact estimator (upper) and proven dual certificate (lower)."""
    for nu, name in enumerate(mod.Q_NAMES):
        lam = mod.DUALS[nu]
        ok, boxes, _ = sphere.prove_dual(mod.H_EXPONENTS, lam, eta=ETA)
        upper = sum(abs(sp.Rational(num, den)) for _, num, den in mod.ESTIMATOR_TERMS[nu])
        value = sp.nsimplify(lam[nu])
        yield Check(f"optimal guaranteed error of {name} on the sphere (units of delta_sigma_max)",
                    "001, section 4", str(published.ERRORS_001[nu]),
                    f"{value}/(1+{ETA:g}) <= opt <= {upper} ({boxes} boxes)",
                    ok and value == upper == published.ERRORS_001[nu])


def grid_lp(mod, step=5):
    A = mod.H(sphere.grid(step))
    _, primal = lp.primal(A)
    _, dual = lp.dual(A)
    L, _ = lp.chebyshev(A)
    for nu, name in enumerate(mod.Q_NAMES):
        vals = (primal[nu], dual[nu], 1 / L[nu])
        want = published.ERRORS_001[nu]
        yield Check(f"{name} on a {step} deg sphere grid: primal = dual = 1/L", "001, (3.1)-(3.2), section 4",
                    " = ".join([str(want)] * 3), " = ".join(f"{v:.7f}" for v in vals),
                    bool(np.allclose(vals, want, atol=1e-6)))


def minimal_sets(vectors, e, tol=1e-9):
    """Minimal index sets whose vectors represent e with positive weights (sizes up to all)."""
    found = []
    for k in range(1, len(vectors) + 1):
        for sub in combinations(range(len(vectors)), k):
            if any(set(f) <= set(sub) for f in found):
                continue
            B = vectors[list(sub)].T
            if np.linalg.matrix_rank(B, tol=1e-9) < k:
                continue
            x, *_ = np.linalg.lstsq(B, e, rcond=None)
            if np.abs(B @ x - e).max() < tol and x.min() > tol:
                found.append(sub)
    return found


def candidates(mod, nu):
    """Plan directions where the certificate of q_nu touches +-1, with the sign there."""
    p = mod.DUALS[nu] @ mod.H(mod.PLAN.T)
    return [(k, int(np.sign(v))) for k, v in enumerate(p) if abs(abs(v) - 1) < 1e-12]


def minimal_plan(mod, nus):
    """Fewest directions optimal for all q in nus: each must contain a minimal set of every q."""
    per = []
    for nu in nus:
        cand = candidates(mod, nu)
        vecs = np.array([s * mod.H(mod.PLAN[k]) for k, s in cand])
        e = np.eye(len(mod.Q_NAMES))[nu] * mod.DUALS[nu][nu]
        per.append([frozenset(cand[i][0] for i in sub) for sub in minimal_sets(vecs, e)])
    best = min((frozenset().union(*pick) for pick in product(*per)), key=len)
    return sorted(best)


def plans(mod):
    """The minimal optimal plans: 18 directions for the 9 linear parameters; for all 12, against 42."""
    worst = 0.0
    for nu in range(len(mod.Q_NAMES)):
        _, _, touch = sphere.prove_dual(mod.H_EXPONENTS, mod.DUALS[nu], eta=ETA)
        cand = mod.PLAN[[k for k, _ in candidates(mod, nu)]]
        worst = max(worst, sphere.farthest_from(touch, cand))
    yield Check("every near-touching point of the certificates lies next to a plan direction",
                "001, section 4 (Theorem 3 of 000)", "< 0.01 rad", f"{worst:.2e} rad", worst < 0.01)
    lin = minimal_plan(mod, range(9))
    yield Check("fewest directions optimal for the 9 linear parameters", "001, section 4 and (6.1)",
                str(published.DIRECTIONS_COUNT_001["linear"]), str(len(lin)),
                len(lin) == published.DIRECTIONS_COUNT_001["linear"])
    full = minimal_plan(mod, range(12))
    yield Check("fewest directions optimal for all 12 parameters", "001, section 6: 'l = 1..42'",
                f"<= {published.DIRECTIONS_COUNT_001['all']}", f"{len(full)} (fewer than the source's 42)",
                len(full) <= published.DIRECTIONS_COUNT_001["all"])


def worst_remainder(mod, box, seed=0, samples=20000, polish=30):
    """Largest |delta_sigma| found: random vertices of the box and directions, then local ascent."""
    rng = np.random.default_rng(seed)
    mx = np.array([box["k_max"]] * 3 + [box["v_max"]] * 3 + [box["eps_max"]] * 3 + [box["delta_max"]] * 3
                  + [box["dg_max"]] + [box["df_max"]] * 3)
    m = rng.normal(size=(3, samples))
    m /= np.linalg.norm(m, axis=0)
    p = rng.choice([-1.0, 1.0], size=(16, samples)) * mx[:, None]
    r = np.abs(mod.remainder(m, p))
    best = 0.0
    for k in np.argsort(r)[-polish:]:
        mk, pk, val = m[:, k], p[:, k], r[k]
        step = 0.1
        for _ in range(200):
            mt = mk + step * rng.normal(size=3)
            mt /= np.linalg.norm(mt)
            pt = np.clip(pk + step * mx * rng.normal(size=16), -mx, mx)
            vt = abs(mod.remainder(mt, pt))
            if vt > val:
                mk, pk, val = mt, pt, vt
            else:
                step *= 0.97
        best = max(best, val)
    return best


BOXES = {
    "navigation grade": dict(k_max=1e-4, v_max=1e-4, eps_max=1e-4, delta_max=1e-4, df_max=1e-6, dg_max=1e-5),
    "MEMS": dict(k_max=1e-2, v_max=5e-3, eps_max=5e-3, delta_max=1e-3, df_max=1e-4, dg_max=1e-4),
}


def remainder_bounds(mod):
    """The derived bound holds (proof in docs) and is checked against the worst remainder found."""
    for label, box in BOXES.items():
        found = worst_remainder(mod, box)
        ours, pub = mod.remainder_bound(**box), mod.published_bound(**box)
        yield Check(f"remainder bound, {label} box: derived >= worst found", "001, (2.3)-(2.4)",
                    "derived >= found", f"{ours:.3e} >= {found:.3e} (x{ours / found:.2f}); "
                    f"published (2.4) {pub:.3e} (x{pub / found:.2f})", ours >= found)


def a_priori(mod, step=10):
    """(5.2)-(5.3): with (5.8) met the tests give 4 delta_sigma_max; with it broken, the prior wins."""
    A = mod.H(sphere.grid(step))
    m, K = A.shape
    qmax_nl = 1e-4
    for dsig in (1e-5, 5e-5):
        qmax = np.array([1e-3] * 3 + [1e-3] * 3 + [1e-3] * 3 + [qmax_nl] * 3)
        errs = []
        for nu in range(9, 12):
            import cvxpy as cp
            xm, x = cp.Variable(m), cp.Variable(K)
            prob = cp.Problem(cp.Minimize(qmax @ cp.abs(xm) + dsig * cp.sum(cp.abs(x))),
                              [xm + A @ x == np.eye(m)[nu]])
            prob.solve(solver=cp.HIGHS)
            errs.append(prob.value)
        holds = 4 * dsig <= qmax_nl
        want = 4 * dsig if holds else qmax_nl
        yield Check(f"a priori (5.2)-(5.3), delta_sigma_max = {dsig:g}, delta_max g = {qmax_nl:g}: "
                    f"(5.8) {'holds' if holds else 'fails'}", "001, section 5",
                    f"{want:.1e} ({'tests' if holds else 'a priori bound'})",
                    ", ".join(f"{v:.3e}" for v in errs), bool(np.allclose(errs, want, rtol=1e-6)))


def _combination_matrix():
    """T of (6.2): sigma* = T sigma over the 18 directions of the table (order of q*)."""
    T = np.zeros((9, 18))
    for i in range(3):
        T[i, 2 * i], T[i, 2 * i + 1] = 0.5, 0.5
        T[6 + i, 2 * i], T[6 + i, 2 * i + 1] = 0.5, -0.5
        T[3 + i, 6 + 4 * i: 10 + 4 * i] = (0.5, -0.5, 0.5, -0.5)
    return T


def cone_error(mod, directions, dsig, dmax):
    """Worst |Delta q*_l| of q^ = F^-1 sigma* ((6.2)-(6.3)) for given directions (3, 18): closed form
    over |delta_sigma| <= dsig and |delta_l g| <= dmax (the error is linear in both)."""
    T = _combination_matrix()
    Hs = mod.H(directions)                       # (12, 18)
    F = T @ Hs[:9].T
    G = np.linalg.solve(F, T)
    return dsig * np.abs(G).sum(axis=1) + dmax * np.abs(G @ Hs[9:].T).sum(axis=1)


def _tilt(n0, phi, rng):
    """Directions at angle phi from n0 (columns), in random azimuths."""
    out = []
    for v in n0.T:
        a = rng.normal(size=3)
        a -= (a @ v) * v
        a /= np.linalg.norm(a)
        out.append(np.cos(phi) * v + np.sin(phi) * a)
    return np.array(out).T


def published_cone_bound(phi, dsig, dmax):
    """(6.6) of 001 for l = 1-3, 7-9 and for l = 4-6."""
    s2 = np.sqrt(2)
    lin = dsig + (phi + 2 * phi**2) * dmax + (6 * phi + 6.5 * phi**2) * dsig + 6 * phi**2 * dmax
    mis = (2 * dsig + (2 * phi + s2 * phi**2) * dmax + (6 * (1 + s2) * phi + (3 + 2 * s2) * phi**2) * dsig
           + 6 * (1 + s2) * phi**2 * dmax)
    return np.array([lin] * 3 + [mis] * 3 + [lin] * 3)


def cone(mod, dsig=1e-5, dmax=1e-4, trials=300, seed=0):
    """(6.1)-(6.6): adversarial search over directions in cones of half-angle phi vs the bound (6.6)."""
    rng = np.random.default_rng(seed)
    n0 = np.array([[float(x) for x in exact_direction(d)] for d in published.DIRECTIONS_001]).T
    for phi in (0.01, 0.05, 0.1):
        worst = np.zeros(9)
        for _ in range(trials):
            worst = np.maximum(worst, cone_error(mod, _tilt(n0, phi * np.sqrt(rng.uniform()), rng), dsig, dmax))
        bound = published_cone_bound(phi, dsig, dmax)
        ratio = (worst / bound).max()
        yield Check(f"cone errors, phi = {phi:g} rad: worst error found / (6.6)", "001, (6.1)-(6.6)",
                    "<= 1", f"{ratio:.3f} (worst lambda*: {worst[0]:.3e}, alpha: {worst[3]:.3e})", ratio <= 1)


def all_groups(mod):
    """Every check group of the coarse-stand model, in report order: (function, args)."""
    return [(estimators, (mod,)), (continuum, (mod,)), (grid_lp, (mod,)), (plans, (mod,)),
            (remainder_bounds, (mod,)), (a_priori, (mod,)), (cone, (mod,))]
