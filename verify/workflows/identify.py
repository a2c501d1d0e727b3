"""`garant identify`: what a model can estimate, what it confounds, and what a plan cannot separate."""
import numpy as np

from ..errors import DataError, opt
from ..io.positions import read_plan
from ..solve import lp



def plan_blind_spots(mod, positions_deg, mounts=None):
    """q combinations the plan cannot see: the null space of the plan's measurement matrix in q."""
    key = np.round(np.asarray(positions_deg, float), 6)
    if mounts is not None:
        key = np.column_stack([key, mounts])
    distinct = np.unique(key, axis=0)                                      # repeats add nothing
    P, m = (distinct[:, :-1], distinct[:, -1].astype(int)) if mounts is not None else (distinct, None)
    A = lp.measurement_matrix(mod if m is not None else mod.H, np.deg2rad(P), m)
    out = []
    for v in rref(lp.blind_directions(A)):
        out.append(" ".join(f"{c:+.3g}*{n}" for c, n in zip(v, mod.Q_NAMES) if c))
    return lp.unidentifiable(A), out


def rref(B, tol=1e-9):
    """Reduced row-echelon form of the rows of B (a canonical basis of their span)."""
    B = np.array(B, float)
    r = 0
    for c in range(B.shape[1] if B.size else 0):
        if r == len(B):
            break
        p = r + int(np.argmax(np.abs(B[r:, c])))
        if abs(B[p, c]) < tol:
            continue
        B[[r, p]] = B[[p, r]]
        B[r] /= B[r, c]
        for i in range(len(B)):
            if i != r:
                B[i] -= B[i, c] * B[r]
        r += 1
    B[np.abs(B) < tol] = 0
    return B[:r]


def report(model, plan_path=None):
    """Lines of text and a JSON-able dict for a model (and a plan)."""
    from garant.derive import identifiability as I
    if model not in ("003-example1", "003-example2"):            # a stand: built-in or a STAND.toml
        from garant.derive.derivation import derive

        from .. import models
        mod = models.load(model)
        rel, groups = I.explain_stand(derive(models.stand_model(model)))
        res = {"model": model, "estimable": [f"{q} = {d}" for q, d in zip(mod.Q_NAMES, mod.Q_DEFINITIONS)],
               "relations": [r.text() for r in rel], "confounded_groups": groups}
        if plan_path:
            names, mounts = models.layout(mod)
            P, m = read_plan(plan_path, names, mounts if len(mounts) > 1 else None)
            missing, blind = plan_blind_spots(mod, P, m)
            res["plan"] = {"path": plan_path,
                           "not_identifiable": [f"{mod.Q_NAMES[k]} = {mod.Q_DEFINITIONS[k]}" for k in missing],
                           "invisible_combinations": blind}
        return res
    if model in ("003-example1", "003-example2"):
        if plan_path:
            raise DataError(f"{opt('plan')} applies to stand models, not to {model}")
        out = I.analyse_example(model)
        return {"model": model, "title": out["title"], "V": str(out["V"]),
                "basis_functions": [f"{n} = {f}" for n, f in out["functions"]],
                "relations": [r.text() for r in out["relations"]], "confounded_groups": out["groups"],
                "degenerate_trajectories": [{"trajectory": t, "relations": [r.text() for r in rel]}
                                            for t, rel in out["degenerate"]]}
