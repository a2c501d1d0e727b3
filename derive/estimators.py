"""Optimal closed-form estimators on a plan, exactly (Theorems 3-4 of 000).

For a = e_nu the Chebyshev polynomial with y = 0 is H_nu itself, so L_nu(0) = max |H_nu| and the
dual lambda = e_nu / L_nu(0) is feasible on the whole continuum. By complementary slackness an
optimal estimator can only use measurements where |H^(p)_nu| reaches L_nu(0), with the sign of
H^(p)_nu there; any such solution of the unbiasedness equations (8) has sum |Psi| = 1/L_nu(0), so it
is optimal. We take the one of smallest support, found in exact rational arithmetic.
"""
from itertools import combinations

import sympy as sp

from .combinations import trig_basis
from .linear import solve_exact


def sup_bound(expr, angles):
    """Upper bound of |expr| on the continuum: sum of |coefficients| of its canonical monomials.

    Exact for the sums of products of sines and cosines met here: each monomial is at most 1.
    """
    return sum((abs(c) for c in trig_basis(expr, angles).values()), sp.Integer(0))


def plan_columns(H, angles, plan_deg):
    """Exact measurement vectors H^(p)(alpha_s, beta_s) on a plan given in degrees."""
    cols = []
    for s, pos in enumerate(plan_deg):
        at = {a: sp.pi * sp.Rational(d, 180) for a, d in zip(angles, pos)}
        for p in range(H.rows):
            cols.append(((s, p), [sp.nsimplify(H[p, nu].subs(at)) for nu in range(H.cols)]))
    return cols


def optimal_estimator(H, angles, cols, nu):
    """Smallest-support optimal estimator of q_nu on the plan: {(position, component): weight}."""
    L = sup_bound(sum(H[p, nu] ** 2 for p in range(H.rows)), angles) and max(
        sup_bound(H[p, nu], angles) for p in range(H.rows))
    cand = [(key, h) for key, h in cols if abs(h[nu]) == L]
    e = [int(i == nu) for i in range(H.cols)]
    for size in range(1, len(cand) + 1):
        for subset in combinations(cand, size):
            signed = [[v * sp.sign(h[nu]) for v in h] for _, h in subset]
            x = solve_exact(signed, e)
            if x is not None and all(v > 0 for v in x):
                return {key: sp.Rational(v) * sp.sign(h[nu]) for (key, h), v in zip(subset, x)}, L
    return None, L


def optimal_estimators(H, angles, plan_deg):
    """Psi[nu] = {(s, p): weight} for every q_nu; raises if some q_nu has no optimal estimator here."""
    cols = plan_columns(H, angles, plan_deg)
    out = []
    for nu in range(H.cols):
        psi, L = optimal_estimator(H, angles, cols, nu)
        if psi is None:
            raise ValueError(f"the plan has no optimal estimator of q{nu + 1} (L = {L})")
        out.append(psi)
    return out
