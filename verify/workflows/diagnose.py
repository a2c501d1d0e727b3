"""`garant diagnose`: find where the model and the data disagree, name the missing effect, add it.

1. The verdict of `estimate` on the current model (the exact model's minimax fit, linearised there, the
   remainder proven a posteriori under the premises): with noise bounded by sigma the fit must come
   within sigma plus that remainder; the positions that do not are reported.
2. Each catalogue effect is added to the model symbolically (derive/effects.py, cached); an effect
   that leaves the rank of this plan's measurement matrix unchanged is zero or fully absorbed here
   (the plan is blind to it). The others are scored by the minimax residual of the extended fit, made
   at the same point (Study.relinearise).
3. select() names the fewest effects that make the model consistent (forward, all small sets, backward);
   alternatives that do so in a chosen effect's place are reported as indistinguishable, with the
   positions that would separate them.
4. The chosen effects are estimated with guaranteed bounds (the LP on these positions), the extended
   model's module is written, and the residuals before and after are shown against +-sigma.
"""
import itertools

import numpy as np

from ..errors import DataError
from ..models import reachable_grid
from ..solve import highs, lp
from . import guarantee
from .estimate import check_residual_size


def chebyshev_fit(A, z, rb=None):
    """min over q of max_k (|z_k - a_k^T q| - rb_k) (HiGHS; rb the proven remainder, 0 when not given):
    q, that minimax, the residual vector. With noise bounded by sigma it is <= sigma for the true model."""
    return highs.chebyshev_fit(A, z, slack=rb)


class Study:
    """The data and the model family: measurement matrices of extended models, cached."""

    def __init__(self, base_model, mod, positions, g):
        from garant.derive import effects as cat
        self.cat, self.base_model, self.mod = cat, base_model, mod
        self.angles = positions.radians
        self.mounts = positions.mounts
        self.extra = positions.extra
        kw = {} if self.mounts is None else {"mount": self.mounts}
        self.z = mod.residual(*self.angles, positions.f.T, g, **kw).T.reshape(-1)
        self.columns = {v: np.asarray(positions.extra[v], float) for v in ("time_s", "temp_c")
                        if v in positions.extra}
        self._cache = {}

    def available(self):
        """Applicable effects, and those skipped for a missing column."""
        ok, skipped = [], {}
        for name in self.cat.applicable(self.base_model):
            need = {str(v) for v in self.cat.extend(self.base_model, [name]).variables}
            missing = need - set(self.columns)
            if missing:
                skipped[name] = f"needs column {', '.join(sorted(missing))}"
                continue
            from garant.derive.derivation import derive
            from garant.derive.description import Unobservable
            try:                                     # the stand may not see some of its parameters at all
                derive(self.model([name]))
            except Unobservable as e:
                skipped[name] = f"this stand cannot observe it ({e.why})"
                continue
            ok.append(name)
        return ok, skipped

    def model(self, names):
        """The base model extended by the named catalogue effects."""
        return self.cat.extend(self.base_model, names)

    def relinearise(self, lin, A0):
        """Fit at the exact-model fit `lin` (guarantee.linearise), as `estimate` does: the residuals become
        z - z0 + A^T q0 (the curvature of the base model at the fit removed) and, in every extended matrix,
        the base combinations' rows A0 are replaced by the relinearised A (mapped through the extended
        combinations: exactly where the effect keeps the base q's, (4) of 000, as most do)."""
        self._dA = lin.A - A0
        self.z_fit = self.z - lin.z0 + lin.A.T @ lin.q0
        # how far the unit's errors move a reading's row of H, relative to the row: an effect's own rows
        # stay at zero errors, so its part of a fit is off by about this fraction of itself
        col = np.abs(A0).sum(axis=0)
        self.shift = float(np.max(np.abs(self._dA).sum(axis=0)[col > 0] / col[col > 0], initial=0.0))

    def A_fit(self, names):
        """The extended measurement matrix at the fit (relinearise): A(names) with the base part moved."""
        A = self.A(names)
        if not names:
            return A + self._dA
        from garant.derive.derivation import derive
        R0 = np.asarray(derive(self.base_model).ident.R, float)
        R = np.asarray(derive(self.model(names)).ident.R, float)
        T = np.hstack([R0, np.zeros((R0.shape[0], R.shape[1] - R0.shape[1]))]) @ np.linalg.pinv(R)   # q_base = T q_ext
        return A + T.T @ self._dA

    def H(self, names, angles=None, columns=None, mounts=None):
        """H of the extended model at positions, (3, m, N): rows of each position's mounting."""
        key = tuple(sorted(names, key=list(self.cat.CATALOGUE).index))
        if key not in self._cache:
            from garant.derive.derivation import numeric_H
            self._cache[key] = numeric_H(self.model(key))
        ext = self.model(key)
        if angles is None:
            angles, mounts = self.angles, self.mounts
        columns = self.columns if columns is None else columns
        Hs = self._cache[key](*angles, *[columns[str(v)] for v in ext.variables])     # (3 x mounts, m, N)
        if mounts is None:
            return Hs[:3]
        idx = 3 * np.asarray(mounts)[None, :] + np.arange(3)[:, None]                 # (3, N)
        return np.take_along_axis(Hs, idx[:, None, :], axis=0)

    def A(self, names, angles=None, columns=None, mounts=None):
        """The measurement matrix (m x 3N) of the base model with the named effects."""
        Hs = self.H(names, angles, columns, mounts)
        return np.transpose(Hs, (1, 2, 0)).reshape(Hs.shape[1], -1)


def rank(A):
    """The numerical rank of A (singular values above 1e-9 of the largest)."""
    s = np.linalg.svd(A, compute_uv=False)
    return int((s > 1e-9 * s.max()).sum())


def separating_positions(study, chosen, alt1, alt2, step=30, top=3):
    """Positions (every mounting) where the two alternative extended fits predict most differently."""
    stand = study.base_model.stand.angles          # only positions the stand can take (detents, ranges)
    grid = np.deg2rad(reachable_grid([a.range_deg for a in stand], [a.detents_deg for a in stand], step)).T
    mounts = None
    if study.mounts is not None:
        nm = len(study.base_model.mountings)
        mounts = np.repeat(np.arange(nm), grid.shape[1])
        grid = np.tile(grid, nm)
    cols = {k: np.full(grid.shape[1], np.mean(v)) for k, v in study.columns.items()}
    preds = []
    for alt in (alt1, alt2):
        q, _, _ = chebyshev_fit(study.A_fit(chosen + [alt]), study.z_fit)
        preds.append(np.einsum("pns,n->sp", study.H(chosen + [alt], tuple(grid), cols, mounts), q))
    diff = np.abs(preds[0] - preds[1]).max(axis=1)
    best = np.argsort(diff)[::-1][:top]
    names = [a.name for a in study.base_model.stand.angles]
    return [{**{f"{a}_deg": float(np.rad2deg(grid[i, k])) for i, a in enumerate(names)},
             **({"mount": study.base_model.mountings[mounts[k]]} if mounts is not None else {}),
             "predicted_difference": float(diff[k])} for k in best]


def diagnose(base_model, mod, positions, sigma, premises):
    """The discrepancy workflow, on the fit `estimate` makes: the exact model linearised at its minimax
    fit, the proven remainder a posteriori around it (workflows/guarantee.py, under `premises`), so the
    threshold stays near sigma for MEMS-size units too. The current model is consistent when `estimate`'s
    verdict says so; an extended model when its minimax residual less that remainder is at most sigma."""
    study = Study(base_model, mod, positions, premises.g)
    check_residual_size(study.z.reshape(-1, 3), positions.path)
    A0 = study.A([])
    if rank(A0) < A0.shape[0]:
        raise DataError(f"{positions.path}: these positions cannot identify the current model; "
                        f"see `garant identify --plan`", param="data")
    lin = guarantee.linearise(mod, positions, study.z, A0, premises)
    before = guarantee.verdict(lin, study.z, sigma, lp.primal(lin.A)[0].T)
    rb = before.remainder
    study.relinearise(lin, A0)
    t0, r0 = before.minimax_less_remainder, before.residual
    candidates, skipped = study.available()
    base_rank = rank(A0)
    blind = [e for e in candidates if rank(study.A([e])) == base_rank]
    usable = [e for e in candidates if e not in blind]
    # an extended model is consistent within sigma plus the allowance for its effects' rows taken at zero
    # errors: at most the relative shift of H times what the effects explain (the misfit plus the noise)
    limit = sigma + study.shift * (t0 + sigma)
    chosen, history, indistinguishable = ([], [], []) if before.consistent else select(study, usable, rb, limit, t0)
    separate = []
    for group in indistinguishable:
        others = [e for e in chosen if e != group[0]]
        separate += [{"effects": [group[0], t], "positions": separating_positions(study, others, group[0], t)}
                     for t in group[1:]]
    A1 = study.A_fit(chosen)
    _, t1, r1 = chebyshev_fit(A1, study.z_fit, rb)
    estimates = effect_estimates(study, chosen, A1, limit + rb) if chosen else {}
    names = [a.name for a in base_model.stand.angles]
    excess = [{"position": int(k // 3), "component": int(k % 3) + 1,
               **{f"{a}_deg": float(positions.angles_deg[k // 3, i]) for i, a in enumerate(names)},
               "residual": float(r0[k]), "remainder": float(rb[k]),
               "excess_over_sigma": float(abs(r0[k]) - rb[k] - sigma)}
              for k in before.disagree]
    return {
        "sigma": sigma, "premises": premises.to_dict(), "remainder_bound": float(rb.max()),
        "consistent_before": before.consistent, "max_residual_before": t0, "disagreements": excess, "effects": chosen,
        "indistinguishable": indistinguishable, "separating_positions": separate,
        "consistent_after": bool(t1 <= limit), "max_residual_after": t1, "estimates": estimates,
        "effect_allowance": limit - sigma,
        "blind_to": blind, "skipped": skipped, "history": history,
        "residual_before": r0.reshape(-1, 3).tolist(), "residual_after": r1.reshape(-1, 3).tolist(),
        "_study": study,
    }


#: The most effects named at once: the fewest that explain the data are searched among all sets up to this size.
MAX_EFFECTS = 3


def select(study, usable, rb, sigma, t0):
    """For a current model the data refute (minimax residual t0), the fewest effects that make it
    consistent: minimax residual less the remainder rb at most `sigma` (the limit diagnose passes).
    Forward selection adds the effect that lowers the minimax residual most, at least one, until the
    model is consistent; if those steps stall, every set of up to MAX_EFFECTS is tried; then each effect
    named is tried without (backward: one the data do not need is dropped). Returns (chosen, history of
    scores, groups of effects that explain the data equally well): a group lists the chosen effect first,
    then each alternative that, put in its place, also makes the model consistent (the data cannot tell
    them apart under the noise bound)."""
    memo = {}

    def score(names):
        key = frozenset(names)
        if key not in memo:
            memo[key] = chebyshev_fit(study.A_fit(sorted(key, key=usable.index)), study.z_fit, rb)[1]
        return memo[key]
    chosen, current, history = [], t0, []          # the current model is refuted: at least one effect
    while (current > sigma or not chosen) and len(chosen) < len(usable):
        scores = {e: score(chosen + [e]) for e in usable if e not in chosen}
        best = min(scores, key=scores.get)
        if scores[best] >= current * (1 - 1e-6):
            break
        history.append({"step": len(chosen) + 1, "scores": scores})
        chosen.append(best)
        current = scores[best]
    if current > sigma:                     # forward steps stalled: the fewest of all small sets, if any
        for k in range(len(chosen) + 1, min(MAX_EFFECTS, len(usable)) + 1):
            fits = [(score(list(c)), list(c)) for c in itertools.combinations(usable, k)]
            best_score, best_set = min(fits)
            if best_score <= sigma:
                chosen, current = best_set, best_score
                history.append({"step": "all sets of " + str(k), "scores": {"+".join(c): v for v, c in fits}})
                break
    for e in list(chosen):                  # backward: drop an effect the others explain the data without
        if len(chosen) > 1:
            without = [x for x in chosen if x != e]
            if score(without) <= max(sigma, current):
                chosen = without
    groups = []
    if current <= sigma:
        for e in chosen:
            rest = [x for x in chosen if x != e]
            alternatives = [a for a in usable if a not in chosen and score(rest + [a]) <= sigma]
            if alternatives:
                groups.append([e] + alternatives)
    return chosen, history, groups


def effect_estimates(study, chosen, A, noise):
    """Each effect parameter: the q it leads in the extended model, its value and guaranteed bound
    (noise: the bound of each residual component: sigma, the allowance for the effects' rows taken at zero
    errors, and the proven remainder of the base model)."""
    from garant.derive.derivation import derive
    d = derive(study.model(chosen))
    blind = set(lp.unidentifiable(A))                   # combinations this plan cannot estimate
    seen = [k for k in range(A.shape[0]) if k not in blind]
    Phi = np.zeros((A.shape[1], A.shape[0]))
    Phi[:, seen] = lp.primal(A, np.eye(A.shape[0])[:, seen])[0]
    err = np.abs(Phi.T) @ noise
    q = Phi.T @ study.z_fit
    names = [p.name for p in d.model.parameters]
    out = {}
    for e in chosen:
        for p in study.cat.CATALOGUE[e].params:
            if p.name in d.ident.leading and d.ident.leading.index(p.name) in seen:
                k = d.ident.leading.index(p.name)
                row = d.ident.R.row(k)
                definition = " ".join(f"{'+' if c > 0 else '-'}{'' if abs(c) == 1 else abs(c)}{n}"
                                      for c, n in zip(row, names) if c != 0).lstrip("+")
                out[p.name] = {"value": float(q[k]), "bound": float(err[k]), "unit": p.unit,
                               "q": definition}
    return out


def write_module(study, chosen, directory):
    """The extended model's generated module and report, written to `directory`."""
    from garant.derive import codegen

    from ..io import report
    return report.write_files(codegen.model_files(study.model(chosen), str(directory), str(directory)))
