"""Checks of 003 for `garant verify`: the trace identity, the limits (6)-(7), Monte Carlo."""
import numpy as np
import sympy as sp

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
    """Identical linear dependence (003, (9)-(16)) found by the service, and the two-axis stand."""
    from garant.derive import identifiability as I
    from garant.derive.derivation import derive
    from garant.derive.builtin import TWO_AXIS_MODEL
    ex1 = I.analyse_example("003-example1")
    got = [r.text() for r in ex1["relations"]]
    want = "-a*phi[c_x] + phi[theta_d] + phi[theta_x] + phi[theta_y] = 0"
    yield Check("003 Example 1: basis dependent, with the printed relation", "003, Example 1",
                "phi2 + phi4 - a phi3 + phi6 = 0", "; ".join(got), got == [want])
    ex2 = I.analyse_example("003-example2", multiplicative=False)
    degenerate = [t for t, _ in ex2["degenerate"]]
    yield Check("003 Example 2, additive errors: independent, degenerate when alpha = const",
                "003, Example 2", "no relation; alpha = const degenerate",
                f"{len(ex2['relations'])} relations; degenerate on {', '.join(degenerate)}",
                not ex2["relations"] and "alpha = const" in degenerate)
    full = [r.text() for r in I.analyse_example("003-example2")["relations"]]
    yield Check("003 Example 2, additive and multiplicative: the printed claim 'independent'",
                "003, Example 2 (claim corrected: V is homogeneous in x, R)",
                "phi[theta_R] + phi[theta_x] = 0", "; ".join(full),
                full == ["phi[theta_R] + phi[theta_x] = 0"])
    rel, groups = I.explain_stand(derive(TWO_AXIS_MODEL))
    yield Check("two-axis stand: relations among the 21 basis functions = 21 - 15", "000, (4)",
                "6 relations, 5 confounded groups", f"{len(rel)} relations, {len(groups)} groups",
                len(rel) == 6 and len(groups) == 5)


def all_groups():
    return [(examples, ()), (trace_identity, ()), (limits, ()), (monte_carlo, ())]
