"""Identifiability as a service: identical linear dependence of basis functions (003, (9)-(16)).

A model gives a residual V of the measured functions (a constraint, or the linearised residual of a
stand). Its basis functions are the partial derivatives of V with respect to the error parameters:
dV/df_i for an additive error c_i of f_i, and f_i dV/df_i for a multiplicative one theta_i. The
parameters are estimable together iff these functions are linearly independent along the data;
an identical relation sum a_k phi_k = 0 (on the constraint) names a direction no data can see.
Relations are found exactly: the functions are written in canonical form (trigonometric monomials
reduced by sin^2 + cos^2 = 1, polynomials reduced modulo the constraint) and the null space of
their coefficient matrix is computed in rational arithmetic.
"""
from dataclasses import dataclass

import sympy as sp

from .combinations import reduce_squares


@dataclass(frozen=True)
class Relation:
    """An identity sum a_k phi_k = 0 among basis functions: a direction no data can see."""

    coefficients: tuple          # a_k, one per basis function
    names: tuple                 # names of the basis functions

    def expr(self):
        """The relation as a SymPy expression in the basis functions' names."""
        return sum((a * sp.Symbol(n) for a, n in zip(self.coefficients, self.names)), sp.Integer(0))

    def text(self):
        """The relation as text, '... = 0'."""
        return f"{sp.sstr(self.expr())} = 0"


def _normalise(v):
    """Clear denominators, then choose the sign that makes most numeric coefficients positive."""
    v = [sp.nsimplify(sp.together(x)) for x in v]
    den = sp.lcm([sp.fraction(x)[1] for x in v])
    v = [sp.expand(sp.cancel(x * den)) for x in v]
    g = sp.gcd_list([x for x in v if x != 0])
    v = [sp.expand(sp.cancel(x / g)) for x in v]
    score = sum(1 if x.is_Number and x > 0 else -1 if x.is_Number and x < 0 else 0 for x in v)
    return tuple(-x for x in v) if score < 0 else tuple(v)


def basis_functions(V, measured, multiplicative=True):
    """(name, function) pairs: dV/df_i (additive c_i) and f_i dV/df_i (multiplicative theta_i)."""
    out = [(f"phi[c_{f}]", sp.diff(V, f)) for f in measured]
    if multiplicative:
        out += [(f"phi[theta_{f}]", f * sp.diff(V, f)) for f in measured]
    return out


def canonical(expr, trig, solve_for=None):
    """Canonical form: trig functions of the angles as c/s symbols modulo c^2 + s^2 = 1, and the
    constraint used to eliminate `solve_for` = (symbol, expression)."""
    if solve_for is not None:
        expr = expr.subs(*solve_for)
    cs = {}
    for a in trig:
        c, s = sp.Symbol(f"cos_{a}"), sp.Symbol(f"sin_{a}")
        expr = expr.subs({sp.cos(a): c, sp.sin(a): s})
        cs[a] = (c, s)
    expr = sp.expand(expr)
    if cs:
        gens = sorted(expr.free_symbols, key=str)
        order = [s for _, s in cs.values()] + [g for g in gens if g not in {s for _, s in cs.values()}]
        expr = reduce_squares(sp.Poly(expr, *order), [(s, 1 - c**2) for c, s in cs.values()]).as_expr()
    return sp.expand(expr)


def relations(functions, variables, trig=(), solve_for=None, constants=()):
    """Identical linear relations among functions of `variables` (constants allowed in coefficients)."""
    names = [n for n, _ in functions]
    forms = [canonical(f, trig, solve_for) for _, f in functions]
    gens = sorted({g for f in forms for g in f.free_symbols if g not in set(constants)}, key=str)
    polys = [sp.Poly(f, *gens) if gens else sp.Poly(f, sp.Dummy()) for f in forms]
    monoms = sorted({m for p in polys for m in p.monoms()})
    M = sp.Matrix([[p.as_dict().get(m, 0) for p in polys] for m in monoms])
    return [Relation(_normalise(list(v)), tuple(names)) for v in M.nullspace()]


def degenerate_trajectories(functions, free, trig=(), solve_for=None, constants=()):
    """Trajectories on which independent functions become dependent: each free variable held
    constant in turn (a new constant symbol), with the relations that appear there."""
    base = len(relations(functions, free, trig, solve_for, constants))
    out = []
    for v in free:
        k = sp.Symbol(f"{v}_0")
        held = [(n, f.subs(v, k)) for n, f in functions]
        sf = None if solve_for is None else (solve_for[0], solve_for[1].subs(v, k))
        tr = [t for t in trig if t != v]
        rel = relations(held, [x for x in free if x != v], tr, sf, tuple(constants) + (k,))
        if len(rel) > base:
            out.append((f"{v} = const", rel))
    return out


def vector_functions(J, names):
    """Columns of a 3 x n linearised residual as scalar functions tagged by component (E1, E2, E3)."""
    tags = sp.symbols(f"E1:{J.rows + 1}")
    return [(f"phi[{n}]", sum((J[p, k] * tags[p] for p in range(J.rows)), sp.Integer(0)))
            for k, n in enumerate(names)], tags


def confounded_groups(rel):
    """Parameters linked through relations (connected components); parameters in none are alone."""
    groups = []
    for r in rel:
        members = {n[4:-1] for a, n in zip(r.coefficients, r.names) if a != 0}
        touching = [g for g in groups if g & members]
        for g in touching:
            members |= g
            groups.remove(g)
        groups.append(members)
    return [sorted(g) for g in groups]


def explain_stand(d):
    """Relations among the columns of dz/dp of a stand (why the combinations (4) are what they are)."""
    funcs, tags = vector_functions(d.J, d.names)
    rel = relations(funcs, [*d.angles, *tags], trig=list(d.angles))
    return rel, confounded_groups(rel)


def example(name):
    """The examples of 003: (residual V, measured functions, trig angles, constraint, constants, free)."""
    x, y, d, a, R, al = sp.symbols("x y d a R alpha", real=True)
    if name == "003-example1":
        return dict(V=d**2 - (x - a)**2 - y**2, measured=[x, y, d], trig=[], constants=(a,),
                    solve_for=(d**2, (x - a)**2 + y**2), free=[x, y],
                    title="003 Example 1: x, y and the distance d to A(a, 0)")
    if name == "003-example2":
        return dict(V=x - R * sp.cos(al), measured=[x, R, al], trig=[al], constants=(),
                    solve_for=(x, R * sp.cos(al)), free=[R, al],
                    title="003 Example 2: x, radius R and angle alpha")
    raise ValueError(name)


def analyse_example(name, multiplicative=True):
    """Basis functions, relations, and degenerate trajectories of a 003 example."""
    ex = example(name)
    funcs = basis_functions(ex["V"], ex["measured"], multiplicative)
    rel = relations(funcs, ex["measured"], ex["trig"], ex["solve_for"], ex["constants"])
    degenerate = degenerate_trajectories(funcs, ex["free"], ex["trig"], ex["solve_for"], ex["constants"])
    return dict(title=ex["title"], V=ex["V"], functions=funcs, relations=rel,
                groups=confounded_groups(rel), degenerate=degenerate)
