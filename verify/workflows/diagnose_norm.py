"""The model-discrepancy test of a static log through the norm relation (2.2) of 001.

Is the calibrated norm model consistent with each interval's own noise (the noise rule), and which effects of
the catalogue (derive/effects.py) make it so? Each effect enters (2.2) through its first-order columns
(n . phi_j(n), phi_j the effect's basis of the generated norm module, derived in derive/norm.py), evaluated at
each still interval's
direction, mid-time and mean temperature (where the log has a temperature column). What the norm relation
cannot tell apart on these orientations is decided exactly, as identifiability is: two effects are
equivalent here when one's columns lie in the span of the base model's and the other's (on the sphere
w_i^3 = g^2 w_i - w_i w_j^2 - w_i w_k^2, so a quadratic scale factor is a case of cross-coupling), and an effect
is unseen when its columns lie in the base model's span (the base parameters absorb it).
The effects named are the fewest that make the data consistent (every interval within its noise bound).
"""
from itertools import combinations

import numpy as np

from ..solve import highs

LARGEST_SET = 3          # effects named together at most
#: Relative to the largest singular value of the unit-norm columns. Columns that differ by rounding and by the
#: curvature within an interval (a warm-up's temperature rate against its temperature: 1e-9) are one space;
#: distinct effects on a log's orientations stand at 1e-2 and above.
RANK_TOL = 1e-6


def rank(rows):
    """The rank of the columns (rows of `rows`, each a column over the intervals) scaled to unit norm."""
    X = np.asarray(rows, float)
    X = X / np.maximum(np.linalg.norm(X, axis=1, keepdims=True), 1e-300)
    sv = np.linalg.svd(X, compute_uv=False)
    return int(np.count_nonzero(sv > RANK_TOL * sv[0])) if sv.size else 0


def columns(mod, n, t_mid, temps, rates=None):
    """({effect: its columns (k, intervals)}, {effect: why skipped}) on these intervals: n . phi_j(n) of the
    generated module's `effect_basis` (first order of (2.2))."""
    cols, skipped = {}, {name: "needs stand angles" for name in mod.STAND_EFFECTS}
    values = {"time_s": t_mid, "temp_c": temps, "temp_rate_c_s": rates}
    for name in mod.EFFECTS:
        need = mod.EFFECT_VARIABLES[name]
        if any(values.get(v) is None for v in need):
            skipped[name] = ("the log has no temperature column" if {"temp_c", "temp_rate_c_s"} & set(need)
                             else f"needs {', '.join(need)}")
            continue
        phi = mod.effect_basis(name, n, t_mid, 20.0 if temps is None else temps, 0.0 if rates is None else rates)
        cols[name] = np.einsum("jik,ik->jk", phi, n)
    return cols, skipped


def equivalence(base, cols):
    """({effect: [the effects these orientations cannot tell from it: beside the base model, one's columns lie in
    the span of the other's (the same space, or one a case of the other)]}, [effects unseen: in the base model's
    span])."""
    r0 = rank(base)
    own = {e: rank(np.vstack([base, c])) for e, c in cols.items()}
    unseen = [e for e in cols if own[e] == r0]
    seen = [e for e in cols if e not in unseen]
    same = {e: [f for f in seen if f != e and rank(np.vstack([base, cols[e], cols[f]])) == max(own[e], own[f])]
            for e in seen}
    return same, unseen


def _alike(named, e, same, tried):
    """The effects the data cannot tell from e here: those whose columns span the same space beside the base
    model, or one nested in the other's, that also make the data consistent in e's place (a nested effect the data
    refute is told apart by them)."""
    out = []
    for f in same:
        key = next((k for k in tried if set(k) == {f if x == e else x for x in named}), None)
        if key is not None and tried[key] <= 1:
            out.append(f)
    return out


def _first_of_kind(best, same, tried, order):
    """The set named: `best` with each effect replaced by the first in catalogue order that spans the same space
    here and fits as well in its place (one name for one explanation, whatever rounding prefers)."""
    named = list(best)
    for k, e in enumerate(best):
        for f in sorted(same[e], key=order.index):
            swap = tuple(sorted(named[:k] + [f] + named[k + 1:], key=order.index))
            if order.index(f) < order.index(e) and tried.get(swap, np.inf) <= 1:
                named[k] = f
                break
    return sorted(named, key=order.index)


def diagnose(mod, stills, res, params, bounds, t0, temps=None, rates=None, noise_bound="the noise rule"):
    """The diagnosis of a log's norm calibration from its verdict (calibrate_norm.verdict): its fit `res` and its
    worst interval over its own bound `t0` (noise plus the proven remainder): the diagnosis's first line is the
    verdict. The effects are screened to first order in units of each interval's noise bound alone, `bounds`
    (stricter than the verdict's: a set that passes it leaves the remainder its room, and the whole calibration
    checks it, `to_add`): `named`, the fewest effects that make the data consistent so (the smallest worst
    residual among the sets of that size); `equivalent`, per named effect the effects these orientations cannot
    tell from it; `unseen`, the effects the base model absorbs here; `scores`, each set tried with its worst
    residual, size by size. temps: each interval's mean temperature (C), or None; rates: its temperature's rate
    (C/s), or None; `noise_bound`: where the noise bound comes from, in words."""
    s, n = res["sigma"], res["n"]
    t_mid = np.array([(st.start + st.stop) / 2 for st in stills])
    base = mod.H(n)[:params]
    cols, skipped = columns(mod, n, t_mid, None if temps is None else np.asarray(temps, float),
                            None if rates is None else np.asarray(rates, float))
    same, unseen = equivalence(base, cols)
    usable = [e for e in cols if e not in unseen]
    named, after, history, too_many = [], highs.chebyshev_fit(base, s, weights=bounds)[1], [], {}
    for size in range(1, min(LARGEST_SET, len(usable)) + 1 if t0 > 1 else 0):
        tried = {}
        for names in combinations(usable, size):
            need = intervals_needed(mod, params, names)
            if need > len(s):                 # it would saturate the intervals: it fits anything, proves nothing
                too_many[", ".join(names)] = need
                continue
            tried[names] = highs.chebyshev_fit(np.vstack([base] + [cols[c] for c in names]), s, weights=bounds)[1]
        if not tried:
            break
        history.append(tried)
        best = min(tried, key=tried.get)
        after = min(after, tried[best])
        if tried[best] <= 1:
            named = _first_of_kind(best, same, tried, list(mod.EFFECTS))
            break
    return {"noise_bound": noise_bound,
            "consistent_before": bool(t0 <= 1), "max_residual_before": t0,
            "named": named, "first_order": list(named),
            "equivalent": {e: _alike(named, e, same[e], history[-1] if history else {}) for e in named},
            "candidates": {", ".join(k): float(v) for k, v in sorted(history[-1].items(), key=lambda kv: kv[1])
                           if v <= 1} if named else {},
            "too_many_parameters": too_many, "intervals": len(s),
            "unseen": unseen,
            "consistent_after": bool(after <= 1), "max_residual_after": after,
            "scores": [{", ".join(k): float(v) for k, v in h.items()} for h in history], "skipped": skipped}


def intervals_needed(mod, params, names):
    """The still intervals a calibration with the effects `names` needs: its parameters plus three (as
    calibrate_norm's refusal asks)."""
    return params + 3 + sum(len(mod.EFFECTS[x]) for x in names)


def to_add(d, mod, calibrate):
    """The effects to add, checked by the whole calibration: the named set, each set with a named effect swapped
    for one it cannot be told from here, and every other set of that size that makes the data consistent to first
    order, fewest parameters first (on the sphere a quadratic scale factor is a case
    of cross-coupling to first order; the second order may tell them apart), each calibrated by `calibrate(names)`
    (calibrate_norm.run with the extension). Returns (the first set that calibrates, or None; {set: what its
    calibration said})."""
    from ..errors import DataError
    if not d["named"]:
        return None, {}
    sets = [tuple(d["named"])]
    for k, e in enumerate(d["named"]):
        sets += [tuple(d["named"][:k]) + (f,) + tuple(d["named"][k + 1:]) for f in d["equivalent"][e]]
    sets += [tuple(k.split(", ")) for k, v in d["scores"][-1].items() if v <= 1]     # the others of that size too
    sets = sorted(dict.fromkeys(tuple(sorted(x, key=list(mod.EFFECTS).index)) for x in sets),
                  key=lambda x: sum(len(mod.EFFECTS[e]) for e in x))
    checked = {}
    for names in sets:
        key = ",".join(names)
        try:
            out = calibrate(names)
        except DataError as e:
            checked[key] = str(e).split(": ", 1)[-1]
            continue
        checked[key] = "calibrates (consistent, every bound over the information set)" if out["consistent"] else \
            f"refuted: {len(out['disagreements'])} interval(s) beyond their bound with the effects and the remainder"
        if out["consistent"]:
            return list(names), checked
    return None, checked


def settle(d, add, checked):
    """One answer: `named` becomes the set whose whole calibration is consistent (`add`), the first-order choice
    kept as `first_order` (its calibration said why not in `checked`); with none that calibrates, named stays the
    first-order one."""
    d["add"], d["checked"] = add, checked
    if add:
        d["named"] = list(add)
        d["equivalent"] = {e: d["equivalent"].get(e, []) for e in add}
    return d
