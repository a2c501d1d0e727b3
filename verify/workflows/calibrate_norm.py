"""Calibration of a real accelerometer log through the norm relation (2.2) of 001.

The still intervals give mean raw vectors r_k. The calibration a = M (r - b) (M lower-triangular,
m/s^2 per raw unit) is found by iterating on the exact |f|: calibrate with the current M, b, form
sigma_k and n_k, fit the small corrections q by the Chebyshev (minimax) fit of (2.2) in the
guaranteed sense, fold them into M, b, and repeat until the corrections vanish. The guaranteed error
of each parameter on the directions actually present is the LP (3.1)-(3.2) on those directions, in
units of delta_sigma_max, here set to the minimax residual of the fit (the smallest noise bound the
data allow).
"""
import cvxpy as cp
import numpy as np

from ..errors import DataError
from ..io.report import save_figure
from ..solve import lp

MAX_ITER = 60


def chebyshev_fit(Hk, s):
    """min over q of max_k |s_k - Hk[:, k] . q| (LP): q and the minimax residual."""
    q, t = cp.Variable(Hk.shape[0]), cp.Variable()
    cp.Problem(cp.Minimize(t), [cp.abs(s - Hk.T @ q) <= t]).solve(solver=cp.HIGHS)
    return q.value, float(t.value)


def initial_map(raw, g):
    """Identity for logs already near g in m/s^2; else an axis-aligned ellipsoid fit."""
    norms = np.linalg.norm(raw, axis=1)
    if abs(np.median(norms) / g - 1) < 0.2:
        return np.eye(3), np.zeros(3), "log in m/s^2: starting from the identity"
    mu, scale = raw.mean(axis=0), raw.std(axis=0).max()
    x = (raw - mu) / scale                                   # centred and scaled for conditioning
    X = np.column_stack([x**2, x])
    p, *_ = np.linalg.lstsq(X, np.ones(len(raw)), rcond=None)
    if np.any(p[:3] <= 0):
        raise DataError("the still intervals do not span an ellipsoid; cannot start the fit")
    c = -p[3:] / (2 * p[:3])
    R2 = 1 + np.sum(p[:3] * c**2)
    axes = scale * np.sqrt(R2 / p[:3])
    return np.diag(g / axes), mu + scale * c, "raw units: starting from an axis-aligned ellipsoid fit"


def pendulosity(mod, n, delta):
    """D(n) of (1.3) over g: delta_l n_idx(l) n_l, for directions n (3, K)."""
    return np.array([delta[l] * n[mod.AXES[l] - 1] * n[l] for l in range(3)])


def calibrated(mod, raw, M, b, delta, g):
    f = (raw - b) @ M.T / g                                  # (K, 3), units of g
    n = f.T / np.linalg.norm(f, axis=1)
    return (f.T - pendulosity(mod, n, delta)).T


def sigma_and_n(f):
    r2 = np.sum(f**2, axis=1)
    return (r2 - 1) / (2 * r2), (f / np.sqrt(r2)[:, None]).T


def fit(mod, raw, g, params=9):
    """Iterate the norm relation to convergence: M, b, delta (12 params), residuals, iterations."""
    M, b, note = initial_map(raw, g)
    delta = np.zeros(3)
    for it in range(1, MAX_ITER + 1):
        s, n = sigma_and_n(calibrated(mod, raw, M, b, delta, g))
        q, _ = chebyshev_fit(mod.H(n)[:params], s)
        A = np.array([[q[0], 0, 0], [q[3], q[1], 0], [q[4], q[5], q[2]]])
        b = b + np.linalg.solve(M, g * q[6:9])
        M = np.linalg.solve(np.eye(3) + A, M)
        if params == 12:
            delta = delta + q[9:12]
        if np.abs(q).max() < 1e-12:
            break
    s, n = sigma_and_n(calibrated(mod, raw, M, b, delta, g))
    return dict(M=M, b=b, delta=delta, sigma=s, n=n, iterations=it, note=note)


def guaranteed(mod, n, params, dsig):
    """Guaranteed error of each parameter on the present directions (LP), and the unidentifiable ones."""
    A = mod.H(n)[:params]
    missing = lp.unidentifiable(A)
    if missing:
        return None, missing
    _, err = lp.primal(A)
    return err * dsig, []


def directions_to_add(mod, n, params, within_deg=10.0):
    """Optimal-plan directions farther than within_deg from every direction present."""
    plan = mod.PLAN[:18] if params == 9 else mod.PLAN
    ang = np.degrees(np.arccos(np.clip(plan @ n, -1, 1))).min(axis=1)
    return [(p.tolist(), float(a)) for p, a in zip(plan, ang) if a > within_deg]


def parameters(M_total, b, g):
    """Model parameters of (1.3) relative to the raw axes for a log in m/s^2: lambda, misalignments, eps."""
    P = np.linalg.inv(M_total)
    return np.array([P[0, 0] - 1, P[1, 1] - 1, P[2, 2] - 1, P[1, 0], P[2, 0], P[2, 1], *(b / g)])


PARAM_LABELS = ("lambda1", "lambda2", "lambda3", "alpha", "beta", "gamma", "eps1/g", "eps2/g", "eps3/g",
                "delta1*g", "delta2*g", "delta3*g")


def run(mod, stills, g, params, path, delta_sigma=None):
    """The whole calibration of a log's still intervals: the dictionary the CLI prints and writes."""
    need = params + 3
    if len(stills) < need:
        raise DataError(f"{path}: found only {len(stills)} still interval(s); a {params}-parameter "
                        f"calibration needs at least {need} (record more orientations, or lower --k)")
    raw = np.array([s.mean for s in stills])
    M0, b0, _ = initial_map(raw, g)
    before, _ = sigma_and_n(calibrated(mod, raw, M0, b0, np.zeros(3), g))
    res = fit(mod, raw, g, params)
    fit_residual = float(np.abs(res["sigma"]).max())
    dsig = fit_residual if delta_sigma is None else max(delta_sigma, fit_residual)
    err, missing = guaranteed(mod, res["n"], params, dsig)
    if missing:
        raise DataError(f"{path}: the {len(stills)} orientations cannot identify "
                        f"{', '.join(mod.Q_NAMES[k] for k in missing)}; add orientations")
    plan = mod.PLAN[:18] if params == 9 else mod.PLAN
    _, best = lp.primal(mod.H(plan.T)[:params])
    si = res["note"].startswith("log in m/s^2")
    q = parameters(res["M"], res["b"], g).tolist() + res["delta"].tolist()[: params - 9] if si else None
    return {
        "log": path, "g": g, "params": params, "intervals": len(stills), "iterations": res["iterations"],
        "start": res["note"], "matrix": res["M"].tolist(), "bias": res["b"].tolist(),
        "nonlinearity_delta_g": res["delta"].tolist() if params == 12 else None,
        "delta_sigma_fit": fit_residual, "delta_sigma_max": dsig,
        "delta_sigma_source": ("minimax residual of the fit" if delta_sigma is None else
                               "--delta-sigma" if delta_sigma >= fit_residual else
                               "minimax residual of the fit (larger than --delta-sigma: the data contradict it)"),
        "parameters": None if q is None else dict(zip(PARAM_LABELS, q)),
        "guaranteed_error": dict(zip(PARAM_LABELS, err.tolist())),
        "guaranteed_error_optimal_plan": dict(zip(PARAM_LABELS, (best * dsig).tolist())),
        "directions_to_add": [{"n": d, "nearest_present_deg": a} for d, a in directions_to_add(mod, res["n"], params)],
        "per_interval": [{"start_s": s.start, "stop_s": s.stop, "raw_mean": s.mean.tolist(),
                          "residual_before_ms2": float(g * sb), "residual_after_ms2": float(g * sa)}
                         for s, sb, sa in zip(stills, before, res["sigma"])],
    }


def plot(result, path):
    """PNG of the norm residual per still interval, before and after calibration."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = result["per_interval"]
    k = np.arange(1, len(rows) + 1)
    before = [r["residual_before_ms2"] for r in rows]
    after = [r["residual_after_ms2"] for r in rows]
    band = result["g"] * result["delta_sigma_fit"]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(k, before, "o", color="C3", label="before (starting map)")
    ax.plot(k, after, "s", color="C0", label=f"after ({result['params']}-parameter calibration)")
    ax.axhspan(-band, band, color="C0", alpha=0.15, label=f"+- delta_sigma_fit g = {band:.2e} m/s^2")
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel("still interval")
    ax.set_ylabel("(|a|^2 - g^2) / (2 |a|^2) x g   (m/s^2)")
    ax.set_title(f"{result['log'].rsplit('/', 1)[-1]}: norm residual per still interval", fontsize=9)
    if max(map(abs, before)) > 50 * band:
        ax.set_yscale("symlog", linthresh=band)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def weighted_fit(Hk, s, bounds):
    """min over q of max_k |s_k - Hk[:, k] . q| / bounds_k (LP): the fit in units of each noise bound."""
    q, t = cp.Variable(Hk.shape[0]), cp.Variable()
    cp.Problem(cp.Minimize(t), [cp.abs(s - Hk.T @ q) <= t * bounds]).solve(solver=cp.HIGHS)
    return q.value, float(t.value)


def diagnose_norm(mod, stills, res, g, params, k_se=3.0):
    """The model-discrepancy test on a real log: is the calibrated norm model consistent with each
    interval's own noise (k_se standard errors of its mean), and which catalogue effect helps?"""
    import sympy as sp
    from garant.derive.effects import CATALOGUE
    from garant.derive.norm import NormModel, effect_columns, n_sym
    s, n = res["sigma"], res["n"]
    se = np.array([np.linalg.norm(res["M"] @ st.std_error) for st in stills]) / g   # units of g
    bounds = k_se * se
    t_mid = np.array([(st.start + st.stop) / 2 for st in stills])
    base = mod.H(n)[:params]
    _, t0 = weighted_fit(base, s, bounds)
    cols, skipped = {}, {}
    for name in CATALOGUE:
        out = effect_columns(NormModel(mod.AXES), name)
        if out is None:
            skipped[name] = "needs stand angles"
            continue
        names, exprs = out
        if any(sym.name == "temp_c" for e in exprs for sym in e.free_symbols):
            skipped[name] = "the log has no temperature"
            continue
        f = sp.lambdify([*n_sym, sp.Symbol("time_s", real=True)], exprs, "numpy")
        cols[name] = np.array([np.broadcast_to(v, t_mid.shape) for v in f(*n, t_mid)], float)
    chosen, score, history, tied = [], t0, [], []
    while score > 1 and len(chosen) < len(cols):
        scores = {e: weighted_fit(np.vstack([base] + [cols[c] for c in chosen + [e]]), s, bounds)[1]
                  for e in cols if e not in chosen}
        best = min(scores, key=scores.get)
        history.append(scores)
        if scores[best] >= score * 0.95:
            break
        ties = [e for e, v in scores.items() if e != best and v <= scores[best] + 0.02]
        if ties and scores[best] <= 1:
            tied.append([best] + ties)
        chosen.append(best)
        score = scores[best]
    return {"noise_bound": f"{k_se:g} standard errors of each interval's mean",
            "indistinguishable": tied,
            "consistent_before": bool(t0 <= 1), "max_residual_before": t0, "effects": chosen,
            "consistent_after": bool(score <= 1), "max_residual_after": score,
            "scores": [{k: float(v) for k, v in h.items()} for h in history], "skipped": skipped}
