"""Checks of 003 for `garant verify`: the trace identity, the limits (6)-(7), Monte Carlo."""
import re

import numpy as np
import sympy as sp

from garant.derive import published

from ..workflows import redundancy as rd
from .row import Check

SIGMA2 = sp.Integer(1)


def trace_identity():
    """trace(B_C^-1) = N (r - q)/sigma^2 exactly, for random rational geometries (003, (5))."""
    rng = np.random.default_rng(0)
    for r, q, N in ((3, 1, 3), (3, 2, 4), (4, 2, 3), (5, 3, 3)):
        got = [(rd.covariance_4(rd.random_rational_geometry(r, q, N, rng), SIGMA2).inv()).trace()
               for _ in range(3)]
        yield Check(f"trace(B_C^-1) for 3 random geometries, r={r}, q={q}, N={N} (exact)", "003, (5)",
                    f"N (r - q) = {N * (r - q)}", ", ".join(map(str, got)),
                    all(g == N * (r - q) for g in got))


def limits():
    """Balanced geometries reach (6) exactly; random ones never go below sigma^2/N (7)."""
    for r, q in ((3, 1), (4, 2), (5, 2)):
        blocks = rd.balanced_geometry(r, q)
        N = len(blocks)
        B = rd.covariance_4(blocks, SIGMA2)
        want = sp.Rational(r, N * (r - q))
        ok = B == sp.eye(r) * want
        yield Check(f"balanced geometry r={r}, q={q}, N={N}: each variance (exact, sigma=1)", "003, (6)",
                    f"sigma^2/N r/(r-q) = {want}", f"diag {sorted(set(B.diagonal()))}, off-diagonal 0: {ok}", ok)
    rng = np.random.default_rng(1)
    worst = min(min(rd.covariance_4(rd.random_rational_geometry(r, q, N, rng), SIGMA2).diagonal()) * N
                for r, q, N in ((3, 1, 3), (4, 2, 3), (4, 1, 4)) for _ in range(4))
    yield Check("smallest variance x N over 12 random geometries (exact, sigma=1)", "003, (7)",
                ">= sigma^2 = 1", str(worst), worst >= 1)
    for r, q, N in ((3, 1, 3), (4, 2, 3)):
        tr = min(rd.covariance_4(rd.random_rational_geometry(r, q, N, rng), SIGMA2).trace() for _ in range(4))
        bound = sp.Rational(r * r, N * (r - q))
        yield Check(f"trace(B_C) of random geometries r={r}, q={q}, N={N} vs the minimum (6)", "003, (6)",
                    f">= r^2 sigma^2/(N(r-q)) = {bound}", str(tr), tr >= bound)


def monte_carlo(runs=20000, N=40, sigma=0.01):
    """ML estimate (3): its covariance equals (4), and Monte Carlo variances fall in a 99.9% interval."""
    rng = np.random.default_rng(2)
    lo, hi = rd.chi2_interval(runs - 1, 0.999)
    f0 = rd.example2_trajectory(N)
    D, P = rd.example2_blocks(f0)
    cases = [("003 Example 2 (x, R, alpha)", D, P, f0, np.array([0.05, -0.03, 0.002]),
              lambda f: (f[..., 0] - f[..., 1] * np.cos(f[..., 2]))[..., None])]
    ft, Dt, Pt = rd.trilateration(N)
    Dstack = np.stack(Dt)                                                        # (N, 1, 3)
    cases.append(("trilateration, 3 ranges to a moving point", Dt, Pt, ft, np.array([0.02, -0.01, 0.03]),
                  lambda f: np.einsum("ikr,nir->nik", Dstack, f - ft)))
    for name, D, P, f0, c, resid in cases:
        cov3 = rd.ml_estimate_3(D, [np.zeros(Di.shape[0]) for Di in D], sigma**2)[1]
        cov4 = rd.covariance_4(P, sigma**2)
        ratio = np.diag(rd.monte_carlo(D, f0, c, sigma, runs, rng, resid)) / np.diag(cov4)
        ok = np.allclose(cov3, cov4, rtol=1e-9, atol=1e-15) and np.all((ratio > lo) & (ratio < hi))
        floor = (np.diag(cov4) * N / sigma**2).min()
        yield Check(f"{name}, N={N}, {runs} runs: covariance of (3) = (4); Monte Carlo / (4) per c_i",
                    "003, (3)-(4), (7)", f"in [{lo:.3f}, {hi:.3f}] (99.9%), and var >= sigma^2/N",
                    " ".join(f"{x:.3f}" for x in ratio) + f"; min var x N/sigma^2 = {floor:.2f}",
                    bool(ok and floor >= 1))


def examples():
    """Identical linear dependence (003, (9)-(16)): each relation the service finds is backed by an
    exact identity derived here, and compared with the paper's (or the paper's (4) of 000)."""
    from garant.derive import identifiability as I
    from garant.derive.builtin import TWO_AXIS_MODEL
    from garant.derive.derivation import derive
    x, y, d, a, R, al = sp.symbols("x y d a R alpha", real=True)
    V1 = d**2 - (x - a)**2 - y**2
    printed = -a * sp.diff(V1, x) + x * sp.diff(V1, x) + y * sp.diff(V1, y) + d * sp.diff(V1, d)   # = 2 V
    identity = sp.expand(printed.subs(d**2, (x - a)**2 + y**2))
    got = [r.text() for r in I.analyse_example("003-example1")["relations"]]
    want = "-a*phi[c_x] + phi[theta_d] + phi[theta_x] + phi[theta_y] = 0"
    yield Check("003 Example 1: the printed relation is an identity on the constraint, and the only one found",
                "003, Example 1: phi2 + phi4 - a phi3 + phi6 = 0",
                "identity 0; service: that relation alone", f"identity {identity}; service: {'; '.join(got)}",
                identity == 0 and got == [want])
    ex2 = I.analyse_example("003-example2", multiplicative=False)
    degenerate = [t for t, _ in ex2["degenerate"]]
    yield Check("003 Example 2, additive errors: independent, degenerate when alpha = const",
                "003, Example 2", "no relation; alpha = const degenerate",
                f"{len(ex2['relations'])} relations; degenerate on {', '.join(degenerate)}",
                not ex2["relations"] and "alpha = const" in degenerate)
    V2 = x - R * sp.cos(al)
    euler = sp.simplify((x * sp.diff(V2, x) + R * sp.diff(V2, R)).subs(x, R * sp.cos(al)))
    full = [r.text() for r in I.analyse_example("003-example2")["relations"]]
    yield Check("003 Example 2, additive and multiplicative: theta_x + theta_R = 0 (Euler: V homogeneous "
                "in x, R), so not 'independent' as printed", "003, Example 2 (claim corrected)",
                "x V_x + R V_R = V = 0 on the constraint; service: that relation alone",
                f"x V_x + R V_R = {euler}; service: {'; '.join(full)}",
                euler == 0 and full == ["phi[theta_R] + phi[theta_x] = 0"])
    d = derive(TWO_AXIS_MODEL)
    rel, groups = I.explain_stand(d)
    names = list(d.names)
    null = all(sp.simplify(d.J * sp.Matrix([r.coefficients[r.names.index(f"phi[{n}]")] for n in names]))
               == sp.zeros(d.J.rows, 1) for r in rel)
    want_rel = len(names) - len(published.Q_000)
    want_groups = _groups_of(published.Q_000, names)
    got_groups = sorted(sorted(g) for g in groups)
    yield Check("two-axis stand: relations among the basis functions, each J r = 0 exactly",
                "000, (4): 21 parameters, 15 combinations, their shared parameters",
                f"{want_rel} relations, groups {want_groups}",
                f"{len(rel)} relations ({'all J r = 0' if null else 'NOT in the null space'}), groups {got_groups}",
                null and len(rel) == want_rel and got_groups == want_groups)


def _groups_of(combinations, names):
    """Parameters linked by the printed combinations (4) (connected components), with more than one member."""
    groups = []
    for text in combinations:
        members = set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", text)) & set(names)
        for g in [g for g in groups if g & members]:
            members |= g
            groups.remove(g)
        groups.append(members)
    return sorted(sorted(g) for g in groups if len(g) > 1)


def all_groups():
    """The check groups of 003, as `garant verify` runs them."""
    return [(examples, ()), (trace_identity, ()), (limits, ()), (monte_carlo, ())]
