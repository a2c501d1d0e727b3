"""Guaranteed estimation on the unit sphere (001): grids, dual certificates proven on the sphere.

A dual certificate is a vector lambda with |H(n)^T lambda| <= 1 for every unit n; then every unbiased
estimator of a^T q has guaranteed error >= a^T lambda (weak duality), and an exact estimator with
sum |x| = a^T lambda is optimal on the continuum. `prove_dual` checks |H^T lambda| <= 1 + eta on the
whole sphere by branch and bound over the six faces of the cube (n = v / |v|), with rigorous interval
arithmetic in the mean-value form (`interval.py`).
"""
from itertools import combinations, product

import numpy as np

from .interval import Grad, Iv, mean_value_enclosure, variables

# Faces of the cube: n = sign * (v permuted) / |v| with v = (1, s, t).
FACES = [(axis, sign) for axis in range(3) for sign in (1, -1)]


def grid(step_deg=5):
    """Unit directions on a latitude-longitude grid (poles once), shape (3, K)."""
    out = []
    for th in np.deg2rad(np.arange(0, 180 + 1e-9, step_deg)):
        phis = [0.0] if th in (0.0, np.pi) or abs(th - np.pi) < 1e-12 else np.deg2rad(np.arange(0, 360, step_deg))
        for ph in phis:
            out.append((np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)))
    return np.array(out).T


def _face_direction(axis, sign, s, t):
    """n = v/|v| on cube faces as Grad objects (components in order 1, 2, 3); axis and sign are one
    face's, or arrays giving each box its face."""
    r = (s * s + t * t + 1.0).sqrt().recip()
    if np.ndim(axis) == 0:
        others = [k for k in range(3) if k != axis]
        comps = [None] * 3
        comps[axis] = r * float(sign)
        comps[others[0]], comps[others[1]] = s * r, t * r
        return comps
    options = [r * np.asarray(sign, float), s * r, t * r]
    # component k is the face's own axis (option 0), else the lower (s) or the higher (t) of the others
    return [_pick(options, np.where(axis == k, 0, np.where(k < 3 - axis - k, 1, 2))) for k in range(3)]


def _pick(options, code):
    """The Grad whose entries are those of options[code] box by box."""
    def iv(xs):
        return Iv(np.choose(code, [np.broadcast_to(x.lo, code.shape) for x in xs]),
                  np.choose(code, [np.broadcast_to(x.hi, code.shape) for x in xs]))
    return Grad(iv([o.v for o in options]), [iv([o.d[i] for o in options]) for i in range(len(options[0].d))])


def polynomial(exponents, lam):
    """p(n) = sum_nu lam_nu n^exponents_nu, a function of Grad components."""
    return _terms_function([(float(c), e) for c, e in zip(lam, exponents) if c != 0])


def _terms_function(terms):

    def p(n):
        total = None
        for c, (a, b, d) in terms:
            term = None
            for comp, k in zip(n, (a, b, d)):
                for _ in range(k):
                    term = comp if term is None else term * comp
            term = (n[0] * 0.0 + c) if term is None else term * c
            total = term if total is None else total + term
        return total
    return p


def prove_terms(terms, eta=1e-9):
    """prove_dual for a polynomial given as [(coefficient, (a, b, c))] terms n1^a n2^b n3^c."""
    return prove_dual(None, None, eta=eta, p=_terms_function(terms))


def prove_dual(exponents, lam, eta=1e-9, max_boxes=2_000_000, start=8, locate=1e-3, p=None):
    """Prove |p(n)| <= 1 + eta on the sphere; returns (proven, boxes evaluated, near-touching boxes).

    Boxes where |p| may exceed 1 - 1e-6 are split further down to width `locate`, so the returned
    near-touching boxes locate the touching set to that size.
    """
    p = p or polynomial(exponents, lam)
    evaluated, touching = 0, []
    edges = np.linspace(-1, 1, start + 1)
    s0, t0 = (g.ravel() for g in np.meshgrid(edges[:-1], edges[:-1], indexing="ij"))
    axis = np.repeat([a for a, _ in FACES], s0.size)            # every face at once, box by box
    sign = np.repeat([g for _, g in FACES], s0.size)
    s_lo, t_lo = np.tile(s0, len(FACES)), np.tile(t0, len(FACES))
    w = np.full(s_lo.shape, 2.0 / start)
    while s_lo.size:
        evaluated += s_lo.size
        if evaluated > max_boxes:
            return False, evaluated, touching

        def f(s, t, axis=axis, sign=sign):
            return p(_face_direction(axis, sign, s, t))
        enc = mean_value_enclosure(f, s_lo, s_lo + w, t_lo, t_lo + w)
        cs, ct = s_lo + w / 2, t_lo + w / 2
        at_centre = f(*variables(cs, cs, ct, ct)).v
        if np.any(np.minimum(np.abs(at_centre.lo), np.abs(at_centre.hi)) > 1 + eta):
            return False, evaluated, touching              # a point where |p| > 1 + eta: disproved
        bad = enc.mag() > 1 + eta
        near = (enc.mag() > 1 - 1e-6) & ~bad
        for k in np.flatnonzero(near & (w <= locate)):
            touching.append((int(axis[k]), int(sign[k]), s_lo[k], t_lo[k], w[k]))
        if np.any(bad & (w < 1e-7)):
            return False, evaluated, touching
        split = bad | (near & (w > locate))
        s_lo, t_lo, w, axis, sign = s_lo[split], t_lo[split], w[split] / 2, axis[split], sign[split]
        s_lo, t_lo = (np.concatenate([s_lo, s_lo + w, s_lo, s_lo + w]),
                      np.concatenate([t_lo, t_lo, t_lo + w, t_lo + w]))
        w, axis, sign = (np.concatenate([x] * 4) for x in (w, axis, sign))
    return True, evaluated, touching


def farthest_from(touching, candidates):
    """Largest angle (rad) from a near-touching box (|p| may exceed 1 - 1e-6 there) to the nearest
    candidate direction: every point where the certificate nearly touches lies within it."""
    worst = 0.0
    for axis, sign, s, t, w in touching:
        corners = []
        for ds in (0, w):
            for dt in (0, w):
                v = np.empty(3)
                others = [k for k in range(3) if k != axis]
                v[axis], v[others[0]], v[others[1]] = sign, s + ds, t + dt
                corners.append(v / np.linalg.norm(v))
        corners = np.array(corners)
        near = min(np.arccos(np.clip(corners @ c, -1, 1)).max() for c in candidates)
        worst = max(worst, near)
    return worst


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
        per.append([frozenset(cand[i][0] for i in sub) for sub in minimal_sets(vecs, e)] if cand else [])
    if not all(per):
        return None                                   # some q has no optimal estimator on these directions
    best = min((frozenset().union(*pick) for pick in product(*per)), key=len)
    return sorted(best)
