"""Other mountings of the block, (25)-(29) of 000, derived from the base model.

A mounting is an exact turn Q of the block (signed permutation, det Q = 1), with v_block = Q v_table:
row i of Q is block axis i in table axes. Substituting (26)-(27) into the base residual, the base
estimates q recover the block's physical errors:
(28) kappa = q1, Delta_alpha + alpha_star = q2, epsilon = q3, Delta_f0 = g Q (q_bias1, q_bias2, q_bias3);
(29) Gamma + hat(theta^k) = Q G(q) Q^-1 + D(Delta_g, Delta_beta) with D = Q (E Delta_g/g - N Delta_beta) Q^-1,
where G(q) places each q at the block error it leads ((4) of 000) and D is what q cannot see.
Everything here is found from the base identification, not typed in.
"""
from dataclasses import dataclass
from itertools import permutations, product

import sympy as sp

from .rotations import hat

AXES = "xyz"


def mountings():
    """The 24 proper mountings: {name: Q}. '+y+z+x' puts block axis 1 along table +y, 2 along +z, 3 along +x."""
    out = {}
    for perm in permutations(range(3)):
        for signs in product((1, -1), repeat=3):
            Q = sp.zeros(3, 3)
            for i, (j, s) in enumerate(zip(perm, signs)):
                Q[i, j] = s
            if Q.det() == 1:
                out["".join(f"{'+' if s > 0 else '-'}{AXES[j]}" for j, s in zip(perm, signs))] = Q
    return out


@dataclass(frozen=True)
class Remount:
    """The remount formulas (26)-(29) of 000 for one stand: G(q), the bias and stand q, and the rest D."""

    G: sp.Matrix            # 3 x 3 of q symbols: G[i, j] = q whose leading parameter is Gamma_ij
    bias: tuple             # q index (0-based) whose leading parameter is bias_i
    stand: dict             # name -> (q index, definition) for the stand combinations kept in (28)
    D: sp.Matrix            # Gamma + hat(theta) - G(q), in table axes: depends only on unseparable params
    q: tuple                # q symbols


def derive_remount(d):
    """(26)-(29) from a derivation of the base model: the layout G, the unseen part D, the stand part."""
    ident = d.ident
    q = sp.symbols(f"q1:{ident.R.rows + 1}")
    lead = {name: k for k, name in enumerate(ident.leading)}
    G = sp.Matrix(3, 3, lambda i, j: q[lead[f"Gamma{i + 1}{j + 1}"]])
    syms = [p.symbol for p in d.model.parameters]
    q_of_p = ident.R * sp.Matrix(syms)
    s = d.model.symbols
    Gamma = sp.Matrix(3, 3, lambda i, j: s[f"Gamma{i + 1}{j + 1}"])
    theta = hat([s[n] for n in d.model.stand.theta])
    D = sp.expand(Gamma + theta - G.subs(dict(zip(q, q_of_p))))
    unseen = set(ident.free) - set(d.model.stand.theta)
    if not {x.name for x in D.free_symbols} <= unseen:
        extra = sorted({x.name for x in D.free_symbols} - {str(u) for u in unseen})
        raise ValueError(f"Gamma + hat(theta) - G(q) depends on {', '.join(extra)}")
    stand = {n: (lead[n], sum(c * x for c, x in zip(ident.R.row(lead[n]), syms)))
             for n in ident.leading if n in {p.name for p in d.model.stand.parameters}}
    return Remount(G=G, bias=tuple(lead[f"bias{i}"] for i in range(1, 4)), stand=stand, D=D, q=q)


def physical(r, Q):
    """(28)-(29) for mounting Q: Gamma + hat(theta^k) with and without D, and Delta_f0 / g."""
    return Q * r.G * Q.T, Q * r.D * Q.T, Q * sp.Matrix([r.q[k] for k in r.bias])


def substitution_holds(d, Q):
    """(26)-(27) checked symbolically: the base model with Gamma' = Q^-1 Gamma Q, Delta_f0' = Q^-1 Delta_f0,
    hat(theta') = Q^-1 hat(theta^k) Q gives Q^-1 times the residual of the mounted block, to first order."""
    s = d.model.symbols
    Gk = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"Gk{i + 1}{j + 1}"))
    bk = sp.Matrix(sp.symbols("bk1:4"))
    tk = sp.Matrix(sp.symbols("tk1:4"))
    sub = {s[f"Gamma{i + 1}{j + 1}"]: (Q.T * Gk * Q)[i, j] for i in range(3) for j in range(3)}
    sub.update({s[f"bias{i + 1}"]: (Q.T * bk)[i] for i in range(3)})
    sub.update({s[n]: (Q.T * tk)[i] for i, n in enumerate(d.model.stand.theta)})
    syms = [p.symbol for p in d.model.parameters]
    z_base = (d.J * sp.Matrix(syms)).subs(sub, simultaneous=True)
    # Mounted block, first order: z_b = (Gk - E dg) Q u + Q hat(theta') u... written directly:
    u = d.up_nominal[0]
    stand_only = d.J * sp.Matrix([x if p.name in {q.name for q in d.model.stand.parameters}
                                  and p.name not in d.model.stand.theta else 0
                                  for x, p in zip(syms, d.model.parameters)])
    z_block = Gk * Q * u + hat(list(tk)) * Q * u + bk + Q * stand_only
    return sp.expand(Q.T * z_block - z_base) == sp.zeros(3, 1)
