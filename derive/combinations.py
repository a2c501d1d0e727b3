"""Identifiable combinations q ((4) of 000) from the coefficient structure of the linearised residual.

Each entry of dz/dp is a trigonometric polynomial in the read angles. Written in the canonical basis
cos^k(x) sin^e(x) (e in {0, 1}, from sin^2 = 1 - cos^2), the map p -> z(., .) becomes an exact
rational matrix M whose rows are (component, basis function). Its row space is the space of
identifiable functionals; the reduced row-echelon form in the model's preferred order of parameters
is the canonical choice of q, and its null space lists what no plan can separate.
"""
from dataclasses import dataclass

import sympy as sp


def trig_basis(expr, angles, others=()):
    """Split a trigonometric polynomial into {canonical monomial: rational coefficient}.

    `others` are further variables (time, temperature) taken as plain polynomial generators; an
    absolute value |e| is a function of its own (it is no trigonometric polynomial), keyed by the
    canonical form of e."""
    cs = {a: (sp.Symbol(f"c_{a}"), sp.Symbol(f"s_{a}")) for a in angles}
    trig = {f(a): v for a, pair in cs.items() for f, v in zip((sp.cos, sp.sin), pair)}
    absolutes = {}      # |e| -> a generator of its own, and back
    for k, node in enumerate(sorted(expr.atoms(sp.Abs), key=sp.default_sort_key)):
        absolutes[node] = sp.Symbol(f"abs_{k}")
        absolutes[absolutes[node]] = node
    # xreplace: the nodes cos(a), sin(a), |e| swapped as they stand (subs would try algebra first)
    poly = sp.expand(expr.xreplace({k: v for k, v in absolutes.items() if isinstance(k, sp.Abs)}).xreplace(trig))
    gens = [v for pair in cs.values() for v in pair] + list(others) + [
        v for k, v in absolutes.items() if isinstance(k, sp.Abs)]
    if poly.free_symbols - set(gens):
        raise ValueError(f"not a trigonometric polynomial in the angles: {expr}")
    rem = reduce_squares(sp.Poly(poly, *gens), [(s, 1 - c**2) for c, s in cs.values()])
    back = {v: f(a) for a, pair in cs.items() for f, v in zip((sp.cos, sp.sin), pair)}
    back.update({v: k for k, v in absolutes.items() if isinstance(k, sp.Abs)})
    out = {}
    for monom, coeff in rem.terms():
        term = sp.Mul(*[back.get(g, g)**k for g, k in zip(gens, monom)])
        out[term] = coeff if coeff.is_Rational else _radical(coeff)
    return out


def reduce_squares(poly, rules):
    """The normal form of the Poly `poly` modulo x^2 - r for each rule (x, r): every x^e written
    x^(e mod 2) r^(e div 2), where no r holds any rule's x (sin_a^2 -> 1 - cos_a^2; m3^2 -> 1 - m1^2 - m2^2 on
    the unit sphere). The rules' leading terms x^2 (lex, each x first) are pairwise coprime, so they are a
    Groebner basis and this is the remainder sp.reduced gives, without its general division."""
    for x, r in rules:
        i = poly.gens.index(x)
        if poly.degree(x) < 2:                       # nothing to rewrite (most entries of a Jacobian)
            continue
        r = sp.Poly(r, *poly.gens, domain=poly.domain)
        groups = {}                                  # x^(2h + b) t -> (h: {x^b t: coefficient})
        for monom, coeff in poly.rep.terms():
            m = list(monom)
            h, m[i] = divmod(m[i], 2)
            groups.setdefault(h, {})[tuple(m)] = coeff
        poly = sum((sp.Poly.from_dict(part, *poly.gens, domain=poly.domain) * r**h
                    for h, part in sorted(groups.items())), sp.Poly(0, *poly.gens, domain=poly.domain))
    return poly


def harmonic_degree(J, angle, angles):
    """The highest harmonic of `angle` in J: the largest power of cos and sin of it in one monomial
    of J's trigonometric basis (its entries are trigonometric polynomials of that degree in it)."""
    trig = (sp.cos(angle), sp.sin(angle))
    return max((sum(term.as_powers_dict().get(f, 0) for f in trig)
                for entry in J for term in trig_basis(entry, angles)), default=0)


@dataclass(frozen=True)
class Identification:
    """Result of the rank analysis: rows of (4), the functions of (3), the unseparable directions."""

    parameters: tuple[str, ...]      # physical parameters, in the model's own order
    leading: tuple[str, ...]         # leading (pivot) parameter of each q
    R: sp.Matrix                     # q = R p: the combinations (4), rows q_1..q_m
    H: sp.Matrix                     # 3 x m: z^(p) = H[p, :] q at first order, (2)-(3)
    null_space: tuple[sp.Matrix, ...]  # directions dp with R dp = 0, one per free parameter
    free: tuple[str, ...]            # parameters that appear only inside combinations


def _radical(x):
    """An algebraic number in its plain form: denominators rationalised, expanded ((2 - sqrt(3))/(sqrt(3) - 1)
    is (sqrt(3) - 1)/2). Without it, H of a stand with 120-degree detents grows integers of 650,000 digits."""
    return sp.expand(sp.radsimp(x))


def _rref(M):
    """M.rref() in the number field of M's entries (QQ, or QQ adjoined the radicals of tilted axes and detents):
    exact field arithmetic, not SymPy's zero test by minimal polynomials, which on an axis such as
    [999983, 999979, 999961] beside another tilted one did not finish in 120 s."""
    from sympy.polys.matrices import DomainMatrix
    dM = DomainMatrix.from_list_sympy(M.rows, M.cols, M.tolist(), extension=True)
    if not dM.domain.is_Field:
        dM = dM.to_field()
    rref, pivots = dM.rref()
    return rref.to_Matrix().applyfunc(_radical), tuple(pivots)


def identify(J, names, preferred, angles, others=(), positions=None):
    """Rank analysis of J (3 x n, trig entries): combinations q, linearised H, null space.

    With `positions` (the finite set a stand with detents can reach: dicts angle -> exact value), the
    combinations are those of J at those positions, and H = J R^T (R R^T)^-1, which equals J's
    coordinates in q at every reachable position (J there lies in the row space of R)."""
    index = [names.index(n) for n in preferred]
    rows, keys = [], []
    if positions is None:
        for p in range(J.rows):
            parts = [trig_basis(J[p, k], angles, others) for k in range(J.cols)]
            for term in sorted({t for d in parts for t in d}, key=sp.default_sort_key):
                keys.append((p, term))
                rows.append([parts[k].get(term, 0) for k in index])
    else:                            # positions may fix only some angles: the others stay a trig basis
        rest = [a for a in angles if a not in positions[0]]
        for at in positions:
            for p in range(J.rows):
                values = [sp.nsimplify(sp.expand_trig(J[p, k].subs(at))) for k in index]
                if not rest:
                    rows.append(values)
                    continue
                parts = [trig_basis(v, rest) for v in values]
                rows.extend([d.get(t, 0) for d in parts]
                            for t in sorted({t for d in parts for t in d}, key=sp.default_sort_key))
    M = sp.Matrix(rows)
    rref, pivots = _rref(M)
    rank = len(pivots)
    R_pref = rref[:rank, :]
    if positions is not None:        # detents such as 120 degrees: radicals, denominators rationalised
        R_pref = R_pref.applyfunc(_radical)
    if positions is None:
        B = M.extract(list(range(M.rows)), list(pivots))
        H = sp.zeros(J.rows, rank)
        for (p, term), row in zip(keys, B.tolist()):
            for nu in range(rank):
                H[p, nu] += row[nu] * term
    else:
        Rp = R_pref.extract(list(range(rank)), [index.index(k) for k in range(len(names))])
        H = (J * Rp.T * (Rp * Rp.T).inv().applyfunc(_radical)).applyfunc(sp.expand)
    back = [index.index(k) for k in range(len(names))]
    R = R_pref.extract(list(range(rank)), back)
    free = [k for k in range(len(preferred)) if k not in pivots]
    null = []
    for f in free:
        v = sp.zeros(len(names), 1)
        v[index[f]] = 1
        for r, pc in enumerate(pivots):
            v[index[pc]] = -R_pref[r, f]
        null.append(v)
    return Identification(
        parameters=tuple(names), leading=tuple(preferred[k] for k in pivots), R=R, H=H,
        null_space=tuple(null), free=tuple(preferred[k] for k in free))
