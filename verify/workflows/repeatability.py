"""Several runs of one sensor at once: is each run's guaranteed bound respected by the others, which
effect explains it when not, and the between-run envelope a user should expect the next run to respect.

Each run is calibrated on its own through the norm relation (2.2) of 001 with the noise rule of
calibrate_norm (never the fit's residual). Two runs agree on a parameter when |a_i - a_j| <= e_i + e_j.
The effect test fits all runs at once around one reference calibration, in units of each interval's
noise bound, with the parameters shared or let free per run as each candidate effect says; the simplest
candidate that makes every run consistent is named. The envelope of a parameter is the hull of the
per-run intervals widened by the largest between-run change seen (ENVELOPE_RULE); it is judged on runs
left out of it.
"""
import itertools

import numpy as np

from ..errors import DataError, opt
from . import calibrate_norm as cn, norm_bounds as nb, norm_noise
from .norm_problem import problem
from ..defaults import MAX_RUNS

#: Candidate effects between runs: (name, physics, which of the 9 parameters move per run, within-run
#: time term). The first (fewest added unknowns) that makes every run consistent is named.
EFFECTS = (
    ("none", "the same sensor in every run", (), False),
    ("bias_drift", "catalogue: f_i += g D_i t, a bias drifting linearly in time within each run (D shared)", (), True),
    ("bias_turn_on", "new: a turn-on bias change per run (eps_i of each run its own)", (6, 7, 8), False),
    ("scale_turn_on", "new: a scale-factor change per run (lambda_i of each run its own; warm-up or temperature)",
     (0, 1, 2), False),
    ("bias_and_scale_turn_on", "new: bias and scale factor of each run their own (a temperature change between runs)",
     (0, 1, 2, 6, 7, 8), False),
)
ENVELOPE_RULE = ("the hull of the per-run intervals [a_r - e_r, a_r + e_r], widened on both sides by the largest "
                 "between-run change seen (max_r a_r - min_r a_r)")


def calibrate_runs(mod, runs, g, params):
    """calibrate_norm.run on each run: (the runs it calibrates, their results (each says whether it is
    consistent), the runs it refuses as [{"log", "reason"}]: a refused run is left out, not fatal)."""
    kept, results, refused = [], [], []
    for r in runs:
        try:
            results.append(cn.run(problem(mod, r.stills, g, params, r.name, quantum=r.quantum)))
            kept.append(r)
        except DataError as e:
            refused.append({"log": r.name, "reason": str(e)})
    return kept, results, refused


def compare(a, e, names):
    """Run-pair x parameter comparisons: inside when |a_i - a_j| <= e_i + e_j. a, e: (R, P)."""
    out = []
    for i, j in itertools.combinations(range(len(a)), 2):
        for p, name in enumerate(names):
            gap = abs(a[i, p] - a[j, p])
            out.append({"runs": [i + 1, j + 1], "parameter": name, "gap": float(gap),
                        "bound": float(e[i, p] + e[j, p]), "inside": bool(gap <= e[i, p] + e[j, p])})
    return out


def envelope(a, e):
    """The envelope of each parameter from runs a, e (R, P): (lo, hi, allowance D)."""
    D = a.max(axis=0) - a.min(axis=0)
    return (a - e).min(axis=0) - D, (a + e).max(axis=0) + D, D


def judged(a, e, names):
    """The envelope judged on runs it was not made from: (1) each run against the envelope of the
    others (leave one out); (2) each run pair against e_i + e_j + D, D from the runs other than i, j."""
    R = len(a)
    loo, pairs = [], []
    if R >= 3:
        for k in range(R):
            lo, hi, _ = envelope(np.delete(a, k, 0), np.delete(e, k, 0))
            loo += [{"run": k + 1, "parameter": n, "inside": bool(lo[p] <= a[k, p] <= hi[p])}
                    for p, n in enumerate(names)]
    if R >= 4:
        for i, j in itertools.combinations(range(R), 2):
            _, _, D = envelope(np.delete(a, [i, j], 0), np.delete(e, [i, j], 0))
            pairs += [{"runs": [i + 1, j + 1], "parameter": n,
                       "inside": bool(abs(a[i, p] - a[j, p]) <= e[i, p] + e[j, p] + D[p])}
                      for p, n in enumerate(names)]
    return loo, pairs


def effect_test(mod, runs, ref, g, params):
    """Fit every run at once with the exact norm relation, each candidate of EFFECTS in turn: shared
    parameters, those the effect moves free per run, iterated from the reference calibration `ref` (a
    calibrate_norm.fit of the first run) until the corrections vanish, the minimax taken in units of each
    interval's noise bound. Its worst exact residual in those units (consistent when <= 1) and the
    per-run changes it finds. Exact residuals: no linearisation remainder enters the verdict."""
    raw = [np.array([st.mean for st in run.stills]) for run in runs]
    mid = [np.array([(st.start + st.stop) / 2 for st in run.stills]) for run in runs]
    timed_ok = all(np.all(np.isfinite(m)) for m in mid)
    t = [m - np.mean(m) if timed_ok else None for m in mid]
    R, out = len(runs), []
    for name, physics, free, timed in EFFECTS:
        if timed and not timed_ok:
            out.append({"effect": name, "physics": physics, "skipped": "the runs have no time (give --rate for "
                        "a means file with start_sample, stop_sample)"})
            continue
        Ms, bs, D = [ref["M"].copy() for _ in runs], [ref["b"].copy() for _ in runs], np.zeros(3)
        for _ in range(cn.MAX_ITER):
            H, s, bounds, run_of = [], [], [], []
            for r in range(R):
                drift = np.outer(t[r], np.linalg.solve(Ms[r], g * D)) if timed else 0.0
                sig, n = cn.sigma_and_n(cn.calibrated(mod, raw[r] - drift, Ms[r], bs[r], np.zeros(3), g))
                H.append(mod.H(n)[:params])
                s.append(sig)
                bounds.append(norm_noise.noise_rule(runs[r].stills, Ms[r], n, g, runs[r].quantum))
                run_of.append(np.full(len(sig), r))
            H, s, bounds, run_of = np.hstack(H), np.concatenate(s), np.concatenate(bounds), np.concatenate(run_of)
            cols = [H] + [H[list(free)] * (run_of == r) for r in range(1, R)] + ([H[6:9] * np.concatenate(t)]
                                                                                  if timed else [])
            q, score, _ = cn.highs.chebyshev_fit(np.vstack(cols), s, weights=bounds)
            for r in range(R):
                q_r = q[:params].copy()
                if r and free:
                    q_r[list(free)] += q[params + (r - 1) * len(free): params + r * len(free)]
                Ms[r], bs[r], _ = nb.fold(Ms[r], bs[r], np.zeros(3), q_r, g)
            if timed:
                D = D + q[-3:]
            if np.abs(q).max() < 1e-12:
                break
        worst = float(np.max(np.abs(s) / bounds))
        p0 = nb.parameters(Ms[0], bs[0], g)
        changes = {f"run {r + 1} - run 1": {nb.PARAM_LABELS[p]: float(v) for p, v in
                                            zip(free, (nb.parameters(Ms[r], bs[r], g) - p0)[list(free)])}
                   for r in range(1, R)} if free else {}
        out.append({"effect": name, "physics": physics, "parameters_per_run": [nb.PARAM_LABELS[p] for p in free],
                    "worst_in_noise_units": worst, "consistent": bool(worst <= 1), "changes": changes,
                    **({"drift_per_s": (D).tolist()} if timed else {})})
    return out




def run(mod, runs, g, params=9, max_runs=MAX_RUNS):
    """The whole repeatability study of one sensor's runs: the dictionary the CLI prints and writes.
    More than `max_runs` usable runs are refused before any fit."""
    refused = [{"log": r.name, "reason": r.refused} for r in runs if getattr(r, "refused", None)]
    runs = [r for r in runs if not getattr(r, "refused", None)]
    if len(runs) > max_runs:
        raise DataError(f"{len(runs):,} runs, over the limit of {max_runs} (the effect test fits every run at once "
                        f"and grows with the square of their number): compare fewer runs, or raise {opt('max_runs')}")
    runs, results, more = calibrate_runs(mod, runs, g, params)
    refused += more
    if len(runs) < 2:
        raise DataError("repeatability needs at least two usable runs (several logs, or a means file with a run "
                        "column)" + (f"; left out: {'; '.join(x['log'] + ': ' + x['reason'] for x in refused)}"
                                     if refused else ""), param="logs")
    names = list(nb.PARAM_LABELS[:params])
    bad = [r.name for r, res in zip(runs, results) if not res["consistent"]]
    per_run = [{"run": k + 1, "log": r.name, "consistent": res["consistent"],
                "delta_sigma_max": res["delta_sigma_max"], "minimax_residual": res["minimax_residual"],
                "parameters": res.get("parameters"), "guaranteed_error": res.get("guaranteed_error"),
                "premises": res["premises"]}
               for k, (r, res) in enumerate(zip(runs, results))]
    out = {"runs": per_run, "refused_runs": refused, "parameters": names, "envelope_rule": ENVELOPE_RULE,
           "comparison_rule": "runs i and j agree on a parameter when |a_i - a_j| <= e_i + e_j"}
    if bad:
        out["inconsistent_runs"] = bad
        return out
    if any(res.get("parameters") is None for res in results):
        raise DataError("repeatability compares parameters of logs in m/s^2; give logs in m/s^2 "
                        "(or a means file)", param="logs")
    a = np.array([[res["parameters"][n] for n in names] for res in results])
    e = np.array([[res["guaranteed_error"][n] for n in names] for res in results])
    comps = compare(a, e, names)
    lo, hi, D = envelope(a, e)
    loo, pairs_env = judged(a, e, names)
    ref = cn.fit(problem(mod, runs[0].stills, g, params))
    effects = effect_test(mod, runs, ref, g, params)
    named = next((x for x in effects if x.get("consistent")), None)
    moved = set(named["parameters_per_run"]) | ({"eps1/g", "eps2/g", "eps3/g"} if named["effect"] == "bias_drift"
                                                 else set()) if named else set()
    for c in comps:
        if not c["inside"]:
            c["explained_by"] = named["effect"] if named and c["parameter"] in moved else None
    frac = lambda xs: float(np.mean([x["inside"] for x in xs])) if xs else None      # noqa: E731
    out.update({
        "comparisons": comps, "coverage_per_run_bounds": frac(comps),
        "envelope": {n: {"lo": float(lo[p]), "hi": float(hi[p]), "between_run_allowance": float(D[p])}
                     for p, n in enumerate(names)},
        "coverage_with_envelope_pairs": frac(pairs_env), "coverage_with_envelope_leave_one_out": frac(loo),
        "envelope_judged": {"leave_one_out": loo, "pairs": pairs_env},
        "effects": effects, "named_effect": named["effect"] if named else None,
        "also_consistent": [x["effect"] for x in effects if x.get("consistent") and x is not named],
        "unexplained": [c for c in comps if not c["inside"] and not c.get("explained_by")],
    })
    return out
