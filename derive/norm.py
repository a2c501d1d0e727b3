"""The coarse stand of 001: the norm relation (2.2), its exact remainder, and a proven bound.

Everything is normalised by the measured gravity g: F = f/g, and the block model (1.3) reads
F = c (E + A) m + e + c^2 D(m) + u,  c = g0/g = 1 - Delta_g/g,
with m the true direction of -gravity in block axes (|m| = 1), A lower-triangular
[[lambda1,0,0],[alpha,lambda2,0],[beta,gamma,lambda3]], e = eps/g, D(m)_l = (delta_l g) m_idx(l) m_l
(pendulosity, idx = (i, j, k) with idx(l) != l) and u = delta_f/g the noise.
"""
from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from .combinations import reduce_squares

SQ2, SQ3 = sp.sqrt(2), sp.sqrt(3)


@dataclass(frozen=True)
class NormModel:
    """The 001 block on a coarse stand; `axes` = (i, j, k) of B(w) in (1.3)."""

    axes: tuple[int, int, int] = (2, 3, 1)
    source: str = "001, (1.3), (2.2)-(2.4)"

    def __post_init__(self):
        if any(a == k + 1 for k, a in enumerate(self.axes)) or not set(self.axes) <= {1, 2, 3}:
            raise ValueError(f"pendulosity axes (i, j, k) need i != 1, j != 2, k != 3, got {self.axes}")


Q_NAMES = ("lambda1_star", "lambda2_star", "lambda3_star", "alpha", "beta", "gamma",
           "eps1_over_g", "eps2_over_g", "eps3_over_g", "delta1_g", "delta2_g", "delta3_g")
Q_LATEX = (r"\lambda_1^*", r"\lambda_2^*", r"\lambda_3^*", r"\alpha", r"\beta", r"\gamma",
           r"\varepsilon_1/g", r"\varepsilon_2/g", r"\varepsilon_3/g", r"\delta_1 g", r"\delta_2 g",
           r"\delta_3 g")
PARAMS = sp.symbols("lambda1 lambda2 lambda3 alpha beta gamma e1 e2 e3 d1 d2 d3 dg u1 u2 u3", real=True)
PARAM_UNITS = ("1",) * 3 + ("rad",) * 3 + ("1",) * 10
PARAM_MEANINGS = (
    "scale-factor error 1", "scale-factor error 2", "scale-factor error 3",
    "misalignment alpha", "misalignment beta", "misalignment gamma",
    "bias 1 over g", "bias 2 over g", "bias 3 over g",
    "nonlinearity delta1 times g", "nonlinearity delta2 times g", "nonlinearity delta3 times g",
    "relative gravity error Delta_g/g", "noise 1 over g", "noise 2 over g", "noise 3 over g")
m_sym = sp.symbols("m1:4", real=True)
n_sym = sp.symbols("n1:4", real=True)


def block(model):
    """A, the bias, the nonlinearity coefficients, Delta_g/g and the noise of (1.3) of 001, as symbols."""
    lam1, lam2, lam3, al, be, ga, e1, e2, e3, d1, d2, d3, dg, u1, u2, u3 = PARAMS
    A = sp.Matrix([[lam1, 0, 0], [al, lam2, 0], [be, ga, lam3]])
    return A, sp.Matrix([e1, e2, e3]), (d1, d2, d3), dg, sp.Matrix([u1, u2, u3])


def pendulosity(model, v, d):
    """D(v)_l = d_l v_idx(l) v_l: the B(w) w term of (1.3) over g, for a unit-scaled v."""
    return sp.Matrix([d[k] * v[model.axes[k] - 1] * v[k] for k in range(3)])


def readings(model):
    """Exact F = f/g of (1.3) for true direction m: c (E + A) m + e + c^2 D(m) + u."""
    A, e, d, dg, u = block(model)
    m = sp.Matrix(m_sym)
    c = 1 - dg
    return c * (sp.eye(3) + A) * m + e + c**2 * pendulosity(model, m, d) + u


def sigma(F):
    """The measured quantity of (2.2), as the derivation decides: (|f|^2 - g^2) / (2 |f|^2)."""
    r2 = sum(x**2 for x in F)
    return (r2 - 1) / (2 * r2)


def sigma_as_printed(F):
    """(2.2) as transcribed, |f|^2 - g^2/|f|^2 (in units of g): four times the linear part, see the docs."""
    r2 = sum(x**2 for x in F)
    return r2 - 1 / r2


def H(model, n=n_sym):
    """H(n) of (2.2): (n1^2, n2^2, n3^2, n1 n2, n1 n3, n2 n3, n1, n2, n3, n1^2 n_i, n2^2 n_j, n3^2 n_k)."""
    n1, n2, n3 = n
    i, j, k = (n[a - 1] for a in model.axes)
    return sp.Matrix([n1**2, n2**2, n3**2, n1 * n2, n1 * n3, n2 * n3, n1, n2, n3,
                      n1**2 * i, n2**2 * j, n3**2 * k])


def q_of_params():
    """q of (2.2) from the physical parameters: lambda_i* = lambda_i - Delta_g/g."""
    lam1, lam2, lam3, al, be, ga, e1, e2, e3, d1, d2, d3, dg, *_ = PARAMS
    return sp.Matrix([lam1 - dg, lam2 - dg, lam3 - dg, al, be, ga, e1, e2, e3, d1, d2, d3])


def first_order(expr):
    """Linear part of expr in all parameters: sum_p p d(expr)/dp at p = 0, taken as d/de expr(e p) at
    e = 0 (one derivative instead of one per parameter)."""
    e = sp.Dummy("e")
    return sp.expand(sp.diff(expr.xreplace({p: e * p for p in PARAMS}), e).subs(e, 0))


def on_sphere(expr):
    """Numerator of a rational function of m reduced modulo |m|^2 = 1: 0 iff it vanishes on the sphere
    (denominators here are powers of |m|^2, never 0 there)."""
    m1, m2, m3 = m_sym
    num, _ = sp.fraction(sp.together(expr))
    num = sp.expand(num)
    rest = sorted((x for x in num.free_symbols if x not in m_sym), key=str)
    return sp.expand(reduce_squares(sp.Poly(num, m3, m1, m2, *rest), [(m3, 1 - m1**2 - m2**2)]).as_expr())


@lru_cache(maxsize=None)
def first_order_checks(model):
    """(linear part of sigma) - H(m)^T q - m.u, and (linear part of the printed sigma) - 4 (H(m)^T q + m.u).

    Both are 0 on the sphere: the printed form is four times the linear relation, the derived one is it.
    """
    F = readings(model)
    m = sp.Matrix(m_sym)
    *_, u = block(model)
    target = (H(model, m_sym).T * q_of_params())[0] + (m.T * u)[0]
    ours = on_sphere(first_order(sigma(F)) - target)
    printed = on_sphere(first_order(sigma_as_printed(F)) - 4 * target)
    return ours, printed


# The bound: symbols for the a priori maxima of (1.2), (1.4), (2.1); K is ||A_max|| (spectral norm).
K, kmax, vmax, emax, dmax, fmax, Gmax = sp.symbols(
    "K k_max v_max eps_max delta_max df_max dg_max", nonnegative=True)


def remainder_bound():
    """A bound of |delta_sigma(n)| on the whole sphere that provably holds; proof in docs/norm_001.md.

    delta_sigma = rho1 - h^2 (3/2 + h)/(1 + h)^2 exactly, h = |F| - 1, with
    rho1 = -r n^T A n - c (|n - m|^2/2 + n^T A (n - m)) + (c^2 n.D(m) - n.D(n)) + n.u;
    each piece is bounded with |a| = |F - m| <= a_max, |n - m| <= sqrt2 a_max / (1 - a_max),
    |D(v)| <= delta_max g / sqrt2 on the unit sphere, |D(m) - D(n)| <= sqrt2 delta_max g |n - m|.
    """
    B, parts = remainder_bound_parts()
    return B.subs(A_MAX, parts[A_MAX]).subs(parts)


A_MAX, DN_MAX = sp.symbols("a_max Delta_n_max", positive=True)
LATEX_NAMES = {K: "K", emax: r"\varepsilon_{\max}", dmax: r"\delta_{\max}", fmax: r"\delta f_{\max}",
               Gmax: r"\Delta g_{\max}", A_MAX: r"a_{\max}", DN_MAX: r"\Delta n_{\max}"}


def remainder_bound_parts():
    """The bound in terms of a_max >= |F - m| and Delta_n_max >= |n - m|, and those two."""
    a = (1 + Gmax) * K + Gmax + SQ3 * emax + (1 + Gmax)**2 * dmax / SQ2 + SQ3 * fmax
    B = (Gmax * K + (2 * Gmax + Gmax**2) * dmax / SQ2 + SQ2 * dmax * DN_MAX + SQ3 * fmax
         + (1 + Gmax) * (DN_MAX**2 / 2 + K * DN_MAX) + A_MAX**2 * (sp.Rational(3, 2) + A_MAX) / (1 - A_MAX)**2)
    return B, {A_MAX: a, DN_MAX: SQ2 * A_MAX / (1 - A_MAX)}


def published_bound():
    """(2.4) of 001 as printed, with the unbalanced last brace read as a product (see docs)."""
    half = (3 * K**2 + 8 * K * dmax + 5 * dmax**2 + 3 * emax**2 + 4 * emax * K + 6 * emax * dmax
            + 2 * SQ3 * fmax + 2 * K * fmax + 4 * fmax * dmax + 3 * fmax**2 + Gmax**2) / 2
    return half + (SQ3 * emax + dmax / SQ2 + Gmax) * (K + dmax / 2 + SQ3 * (emax + fmax + Gmax))


def second_order_terms(expr):
    """Coefficients of the Taylor expansion of a bound to second order in the maxima."""
    t = sp.Dummy("t")
    small = (K, emax, dmax, fmax, Gmax)
    f = expr.subs({s: t * s for s in small})      # f(0) + f'(0) + f''(0)/2: the terms of order 0 to 2
    d1 = sp.diff(f, t)
    poly = sp.expand(f.subs(t, 0) + d1.subs(t, 0) + sp.diff(d1, t).subs(t, 0) / 2)
    return sp.Poly(poly, *small).as_dict(), small


# The optimal plan: the 18 directions of the table of 001 and the 12 of the nonlinearity coefficients.
def plan(model):
    """Directions (exact) and their role; the nonlinearity ones follow from the dual certificates."""
    e = [sp.Matrix([int(i == j) for j in range(3)]) for i in range(3)]
    dirs = []
    for i in range(3):
        dirs += [e[i], -e[i]]
    for a, b in ((0, 1), (0, 2), (1, 2)):
        for s1, s2 in ((1, 1), (1, -1), (-1, -1), (-1, 1)):
            dirs.append((s1 * e[a] + s2 * e[b]) / SQ2)
    for k, i in enumerate(model.axes):          # delta_k: n_k^2 n_i, touching points n_k^2 = 3/4
        for s1, s2 in ((1, 1), (-1, 1), (1, -1), (-1, -1)):
            dirs.append(s1 * SQ3 / 2 * e[k] + s2 * e[i - 1] / 2)
    return dirs


def duals(model):
    """Optimal dual vectors lambda (Chebyshev polynomials of 001, section 4), one per q."""
    out = []
    for nu in range(12):
        lam = [0] * 12
        if nu in (3, 4, 5):
            lam[nu] = 2
        elif nu >= 9:
            lam[nu], lam[6 + model.axes[nu - 9] - 1] = 4, -1
        else:
            lam[nu] = 1
        out.append(lam)
    return out


def touching(lam, cols):
    """Indices and signs of the plan directions where |H(n)^T lambda| reaches 1, `cols` their exact H(n) (entries
    in the field of sqrt 2 and sqrt 3, so each value comes out of expand in its canonical form, +-1 included)."""
    out = []
    for k, h in enumerate(cols):
        v = sp.expand(sum((c * w for c, w in zip(h, lam) if w), sp.Integer(0)))
        if abs(v) == 1:
            out.append((k, int(sp.sign(v))))
    return out


def estimators(model):
    """Smallest-support optimal estimator of each q on the plan, exactly: {direction index: weight}.

    Complementary slackness with the dual certificates `duals`: only directions where the
    Chebyshev polynomial touches +-1 are used, with its sign; any nonnegative solution there of the
    unbiasedness equations (3.2) has sum |x| = a^T lambda, the optimum.
    """
    from itertools import combinations

    import numpy as np
    dirs = plan(model)
    cols = {k: H(model, list(n)) for k, n in enumerate(dirs)}
    approx = {k: np.array([float(v) for v in c]) for k, c in cols.items()}
    out = []
    for nu, lam in enumerate(duals(model)):
        cand = touching(lam, list(cols.values()))
        e = sp.Matrix([int(i == nu) for i in range(12)])
        target = np.eye(12)[nu]
        found = None
        for size in range(1, len(cand) + 1):
            for subset in combinations(cand, size):
                # in floats first (a subset that fails there cannot hold exactly); then exactly
                A = np.column_stack([s * approx[k] for k, s in subset])
                x, *_ = np.linalg.lstsq(A, target, rcond=None)
                if np.abs(A @ x - target).max() > 1e-9 or np.any(x <= 1e-12) or np.linalg.matrix_rank(A) < size:
                    continue
                A = sp.Matrix.hstack(*[s * cols[k] for k, s in subset])
                try:
                    x, params = A.gauss_jordan_solve(e)
                except ValueError:
                    continue
                x = x.applyfunc(sp.nsimplify)
                if not params and all(v > 0 for v in x):
                    found = {k: s * v for (k, s), v in zip(subset, x)}
                    break
            if found:
                break
        if found is None:
            raise ValueError(f"no optimal estimator of {Q_NAMES[nu]} on the plan")
        out.append(found)
    return out


def effect_basis(name):
    """A catalogue effect's addition to the reading over g, term(w) = sum_j theta_j phi_j(w, time_s, temp_c), as
    the basis (phi_1, ..., phi_P), each a 3-vector in the true specific force over g, w = (n1, n2, n3), and the
    symbols time_s, temp_c, temp_rate_c_s; or None when the effect has no meaning without a stand (encoder
    harmonics need stand angles). Returns (parameter names, [phi_j as 3 expressions])."""
    from .effects import CATALOGUE, LOG_EFFECTS
    e = {**CATALOGUE, **LOG_EFFECTS}[name]
    if e.term is None:
        return None
    syms = {p.name: p.symbol for p in e.params}
    term = e.term(sp.Matrix(n_sym), syms)
    return [p.name for p in e.params], [[sp.expand(v) for v in term.diff(p.symbol)] for p in e.params]


#: The variables beside w an effect's term reads, in the order of EFFECT_TERMS' exponents: the row's time (s), its
#: temperature above the reference (C) and the temperature's rate (C/s).
EFFECT_VARIABLES = ("time_s", "temp_c", "temp_rate_c_s")


def effect_terms(name):
    """A catalogue effect's basis as data: (parameter names, terms), each term (j, i, numerator, denominator,
    w exponents, |w| exponents, variable exponents) one monomial c w^a |w|^b v^e of phi_j's entry i, with
    v = (time_s, temp_c - T0, temp_rate_c_s) (EFFECT_VARIABLES, T0 the reference temperature of derive/effects.py)
    and c rational; their sum is `effect_basis` exactly (anything else stops generation). None for an effect that
    needs a stand."""
    from .effects import VARIABLE_DEFAULTS
    out = effect_basis(name)
    if out is None:
        return None
    names, basis = out
    absolute = [sp.Symbol(f"abs_{v.name}", real=True) for v in n_sym]
    variables = [sp.Symbol(v, real=True) for v in EFFECT_VARIABLES]
    shift = {variables[1]: variables[1] + sp.Rational(VARIABLE_DEFAULTS["temp_c"])}
    terms = []
    for j, phi in enumerate(basis):
        for i, entry in enumerate(phi):
            expr = sp.expand(entry.xreplace({sp.Abs(v): a for v, a in zip(n_sym, absolute)}).xreplace(shift))
            gens = (*n_sym, *absolute, *variables)
            poly = sp.Poly(expr, *gens)
            if expr.free_symbols - set(gens) or not all(c.is_Rational for c in poly.coeffs()):
                raise ValueError(f"effect {name}: entry {entry} is not a polynomial in w, |w| and "
                                 f"{', '.join(EFFECT_VARIABLES)} with rational coefficients")
            terms += [(j, i, int(c.p), int(c.q), monom[:3], monom[3:6], monom[6:])
                      for monom, c in sorted(poly.terms()) if c != 0]
    return names, terms
