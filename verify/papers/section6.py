"""Section 6 of 000: what ignoring the stand errors does to the block's optimal estimators.

Setting the stand combinations to zero (q1 = q2 = q3 = 0) removes their columns from H; the problem
then splits into one per accelerometer. Its optimal estimators on the quarter-turn grid are all
found exactly (the minimal sets of `plans`), and each is applied to the full model: the image on the
removed columns is the bias the stand errors put into it.
"""
from dataclasses import dataclass
from fractions import Fraction
from itertools import combinations

import numpy as np

from ..solve import exact, plans


@dataclass(frozen=True)
class Reduced:
    """The reduced estimation problem of section 6 of 000."""

    name: str                 # the block parameter q_nu
    estimators: int           # optimal estimators of the reduced model (minimal sets, quarter grid)
    biased: int               # how many carry stand errors in the full model
    example: str              # bias of one biased estimator, in the stand combinations
    error_reduced: Fraction   # optimal guaranteed error, reduced model (proven, continuum)
    error_full: Fraction      # the same, full model


def analyse(mod, stand_idx):
    """For every block parameter: its reduced-model optimal estimators, and which are biased."""
    m = len(mod.Q_NAMES)
    keep = [k for k in range(m) if k not in stand_idx]

    def H_reduced(alpha, beta):
        return mod.H(alpha, beta)[:, keep]

    cols = exact.integer_columns(mod, plans.QUARTER_DEG)
    reduced_cols = cols[:, :, keep]
    out = []
    for j, nu in enumerate(keep):
        sets = plans.minimal_sets(reduced_cols, j)
        biases = []
        for ms in sets:
            image = [Fraction(0)] * m
            for s, p, w in ms.weights:
                image = [a + w * int(v) for a, v in zip(image, cols[s, p])]
            biases.append({k: image[k] for k in stand_idx if image[k] != 0})
        biased = [b for b in biases if b]
        example = linear(biased[0], mod) if biased else ""
        e_full = [int(i == nu) for i in range(m)]
        e_red = [int(i == j) for i in range(len(keep))]
        out.append(Reduced(
            name=mod.Q_NAMES[nu], estimators=len(sets), biased=len(biased), example=example,
            error_reduced=_closed(exact.dual_lower_bound(mod.H_SUP[:, keep], e_red, e_red),
                                  min(sum(abs(w) for *_, w in ms.weights) for ms in sets)),
            error_full=exact.dual_lower_bound(mod.H_SUP, e_full, e_full)))
    return out


def _closed(lower, upper):
    """The optimum when the proven lower bound meets an exact estimator's error, else None."""
    return lower if lower == upper else None


def linear(coeffs, mod):
    """'-1/2 kappa + (Delta_alpha + alpha_star)' from {q index: coefficient}."""
    out = ""
    for k, c in coeffs.items():
        name = mod.Q_DEFINITIONS[k]
        name = f"({name})" if " " in name else name
        mag = "" if abs(c) == 1 else f"{abs(c)} "
        out += (("-" if c < 0 else "") if not out else (" - " if c < 0 else " + ")) + mag + name
    return out


def per_accelerometer(mod, stand_idx):
    """Without the stand columns, each q involves one accelerometer only: {p: [q names]}."""
    Hs = np.abs(mod.H(np.linspace(0, 6, 7), np.linspace(0, 6, 7)[:, None])).max(axis=(2, 3))   # (3, m)
    return {p + 1: [mod.Q_NAMES[k] for k in range(Hs.shape[1]) if k not in stand_idx and Hs[p, k] > 0]
            for p in range(3)}


def brute_force(mod, stand_idx):
    """{q name: (optimal estimators, biased ones)} of the reduced model, counted a second way: every
    subset of the signed touching measurements of the q's own accelerometer on the quarter grid, in
    exact Fractions, kept when it represents e_nu with positive weights and no smaller subset does."""
    from garant.derive.linear import solve_exact
    P = np.deg2rad(np.array(plans.QUARTER_DEG, float))
    Hq = mod.H(P[:, 0], P[:, 1])                                   # (3, m, 16)
    H = np.rint(Hq).astype(int)
    assert np.abs(Hq - H).max() < 1e-12
    out = {}
    for p, names in per_accelerometer(mod, stand_idx).items():
        own = [mod.Q_NAMES.index(n) for n in names]
        for nu in own:
            touch = [(s, int(np.sign(H[p - 1, nu, s]))) for s in range(H.shape[2]) if abs(H[p - 1, nu, s]) == 1]
            vecs = [[Fraction(sign * H[p - 1, k, s]) for k in own] for s, sign in touch]
            target = [Fraction(int(k == nu)) for k in own]
            found = []
            for size in range(1, len(own) + 1):
                for sub in combinations(range(len(touch)), size):
                    if any(set(f) <= set(sub) for f, _ in found):
                        continue
                    w = solve_exact([vecs[i] for i in sub], target)
                    if w is not None and min(w) > 0:
                        found.append((sub, w))
            biased = sum(any(sum(wi * touch[i][1] * H[p - 1, k, touch[i][0]] for wi, i in zip(w, sub)) != 0
                             for k in stand_idx) for sub, w in found)
            out[mod.Q_NAMES[nu]] = (len(found), biased)
    return out
