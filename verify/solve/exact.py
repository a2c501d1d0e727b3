"""Exact (rational) checks of estimators, and continuum bounds that are proofs, not samples.

- unbiasedness (8)/(24) of 000: sum_k Psi_k H_k = a, in Fraction arithmetic, with H at quarter-turn
  positions taken as the exact integers cos/sin are there;
- guaranteed error of an estimator: sum_k |Psi_k| (times sigma), exactly;
- a lower bound of the continuum optimum from a dual vector lambda (weak duality, (9)-(10)):
  a^T lambda / max_p sup |H^(p)T lambda|, with the sup bounded by the triangle inequality over the
  proven entry bounds H_SUP. Primal value = this bound closes the optimum on the continuum.
"""
import weakref
from fractions import Fraction

import numpy as np

from ..errors import NotExact
from ..models import H_at


def exact_columns(mod, angles_deg, mounts=None):
    """H^(p) at grid positions exactly, shape (S, 3, m): integers where H is integer there (int64),
    else elements of Q(sqrt2, sqrt3) (field.QF, object array) from the stand's symbolic H, on grids of
    multiples of 15 degrees. ValueError, saying why, when neither holds."""
    try:
        return integer_columns(mod, angles_deg, mounts)
    except ValueError:
        pass
    f, m, cache = _evaluator(mod)
    P = np.atleast_2d(np.asarray(angles_deg, float))
    mounts = np.zeros(len(P), int) if mounts is None else np.asarray(mounts)
    out = np.empty((len(P), 3, m), dtype=object)
    check = np.empty((len(P), 3, m))
    for s, (deg, k) in enumerate(zip(P, mounts)):
        key = tuple(deg)
        if key not in cache:
            try:
                vals = f(key)
            except ValueError as e:
                raise NotExact(f"H is not exact on these positions ({e}); exact plan search takes grids of "
                                 "multiples of 15 degrees and wedges of multiples of 15 degrees") from None
            cache[key] = vals, np.array([float(v) for v in vals])
        vals, approx = cache[key]
        for p in range(3):
            rows = slice((3 * int(k) + p) * m, (3 * int(k) + p + 1) * m)
            out[s, p], check[s, p] = vals[rows], approx[rows]
    want = np.moveaxis(H_at(mod, np.deg2rad(P), mounts), -1, 0)
    if np.abs(check - want).max() > 1e-9:
        raise AssertionError("the exact H disagrees with the generated H")
    return out


_EVALUATORS = weakref.WeakKeyDictionary()      # module -> (exact H of a position, m, its values so far)


def _evaluator(mod):
    """(f, m, values): f gives the stand's symbolic H exactly at a position (degrees), m its columns, and
    `values` the positions evaluated so far, exact and as floats (kept with the module: a search evaluates
    the same ones again)."""
    if mod not in _EVALUATORS:
        from ..models import symbolic_H
        from .field import evaluator
        H, symbols = symbolic_H(mod)
        try:
            f = evaluator(list(H), symbols)
        except ValueError as e:
            raise NotExact(f"H is not exact in Q(sqrt2, sqrt3) ({e}); exact plan search takes axes and wedges "
                             "whose components lie there, e.g. [0, 1, 1]") from None
        _EVALUATORS[mod] = (f, H.cols, {})
    return _EVALUATORS[mod]


def integer_columns(mod, angles_deg, mounts=None):
    """H^(p) at grid positions as exact integers, shape (S, 3, m); fails if not integer."""
    if callable(mod):                                  # an H function of the angles
        P = np.deg2rad(np.atleast_2d(np.asarray(angles_deg, float)))
        Hs = mod(*[P[:, i] for i in range(P.shape[1])])
    else:
        Hs = H_at(mod, np.deg2rad(np.asarray(angles_deg, float)), mounts)
    Hs = np.moveaxis(Hs, -1, 0)
    rounded = np.rint(Hs)
    if np.abs(Hs - rounded).max() > 1e-12:
        raise ValueError("H is not integer on these positions; exact plan search needs a grid where it is")
    return rounded.astype(np.int64)


def terms_from_published(terms):
    """[(weight str, p 1..3, alpha deg, beta deg)] -> [(Fraction, p 0..2, (alpha, beta))]."""
    return [(Fraction(w), p - 1, (a, b)) for w, p, a, b in terms]


def terms_from_generated(mod, nu):
    """A generated module's estimator terms as exact fractions per (position, component)."""
    return [(Fraction(num, den), p, tuple(int(v) for v in mod.PLAN_DEG[s]))
            for s, p, num, den in mod.ESTIMATOR_TERMS[nu]]


def unbiased_image(H, terms):
    """sum_k Psi_k H^(p_k)(position_k), exactly: a list of Fractions (the a of the estimator)."""
    positions = sorted({pos for _, _, pos in terms})
    cols = integer_columns(H, positions)            # H: a model's H function of the angles
    out = [Fraction(0)] * cols.shape[2]
    for w, p, pos in terms:
        h = cols[positions.index(pos), p]
        out = [o + w * int(v) for o, v in zip(out, h)]
    return out


def l1(terms):
    """Guaranteed error of the estimator in units of sigma: sum |Psi|, exactly."""
    return sum((abs(w) for w, _, _ in terms), Fraction(0))


def dual_lower_bound(H_sup, a, lam):
    """a^T lambda / max_p sum_nu |lambda_nu| H_SUP[p, nu]: a proven lower bound of the optimum."""
    a, lam = [Fraction(x) for x in a], [Fraction(x) for x in lam]
    worst = max(sum(abs(y) * Fraction(int(s)) for y, s in zip(lam, row)) for row in np.asarray(H_sup))
    return sum(x * y for x, y in zip(a, lam)) / worst
