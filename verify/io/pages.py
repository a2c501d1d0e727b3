"""The report pages (--report, a batch's index.html): what each holds, as sections io/report.py writes as Markdown
and one self-contained HTML page. The commands pass the results and print what was written."""
from pathlib import Path

from . import files, report

UNITS = {"lambda": "1", "alpha": "rad", "beta": "rad", "gamma": "rad", "eps": "1 (over g)", "delta": "1 (x g)"}


def unit(k):
    """A norm parameter's SI unit: 1, rad, 1 (over g), 1 (x g)."""
    return next(u for p, u in UNITS.items() if k.startswith(p))


def side(k, x):
    """A parameter's value in ppm, mrad or mg, one unit per kind (the nonlinearity as it is)."""
    return report.human(x, "1" if k.startswith(("lambda", "eps")) else unit(k), bias=k.startswith("eps"),
                        fixed=True) if not k.startswith("delta") else f"{x:+.4g} {unit(k)}"


def discrepancy(res):
    """The worst residual without and with the effects added (--effect), in units of each interval's noise rule."""
    d = res["model_discrepancy"]
    return (f"worst residual in units of {d['units']}: {d['max_residual_before']:.2f} without the effects "
            f"({'consistent' if d['max_residual_before'] <= 1 else 'INCONSISTENT'}) -> {d['max_residual_after']:.2f} "
            f"with {', '.join(res['effect_names'])}")


def batch_sections(rows, stems, spec, spec_path, said, labels, spec_keys):
    """The batch page's sections: the summary, the specification's limits with their units, each unit's verdict
    (coloured) linking to its calibration file, and each unit's parameters of (1.3) of 001 with their guaranteed
    errors in ppm, mrad or mg (summary.csv holds the same in SI, for programs). `labels`: the parameters' names,
    `spec_keys`: each limit's parameters (workflows/batch.py)."""
    sections = [("Summary", said)]
    if spec:
        unit = {"scale": "ppm", "misalignment": "mrad", "bias": "mg"}
        factor = {"scale": 1e6, "misalignment": 1e3, "bias": 1e3}
        sections.append((f"The specification ({spec_path}): a unit passes when every parameter's whole guaranteed "
                         "interval lies within its limit (and its guaranteed error within its bound limit)",
                         report.Table(("kind", "parameters", "limit on the value, either sign",
                                       "limit on the guaranteed error"), [
                             (kind, ", ".join(spec_keys[kind][0]),
                              *(f"{spec[t][kind] * factor[kind]:g} {unit[kind]}" if kind in spec.get(t, {}) else "none"
                                for t in ("limits", "bound_limits"))) for kind in spec_keys])))
    sections.append(("Each unit: its verdict and its calibration file", report.Table(
        ("log", "status", "verdict", "reason", "noise bound (units of g)", "still intervals", "calibration file"),
        [(r["log"], r["status"], report.Verdict(r.get("verdict", "")), r.get("reason") or r["message"] or "",
          f"{r['result']['delta_sigma_max']:.3g}" if r["result"] else "", str((r["result"] or {}).get("intervals", "")),
          report.Link(r["file"], r["file"]) if r.get("file") else "") for r in rows])))
    cells = []
    for stem, r in zip(stems, rows):
        res = r["result"] or {}
        pars, errs = r.get("nominal") or (res.get("parameters") or {}, res.get("guaranteed_error") or {})
        cells.append((stem, *(f"{side(k, pars[k])} ± {side(k, errs[k]).lstrip('+')}".replace(
            f" {unit_of(k)} ±", " ±") if k in pars and k in errs else "" for k in labels)))
    sections.append(("Each unit's parameters of (1.3) of 001: estimate ± guaranteed error over its information set",
                     report.Table(("unit", *(f"{k} ({unit_of(k)})" for k in labels)), cells)))
    return sections


def unit_of(k):
    """The unit a parameter is shown in on the batch page: the one `side` writes it in (ppm, mrad or mg)."""
    return side(k, 1.0).split(" ", 1)[1]


def norm(res, folder, log, log_data, command, downstream=tuple):
    """The norm calibration's page (calibrate-norm --report) in `folder`: the verdict, the premises a line each, M
    and b by entry, the parameters with their guaranteed errors in SI and in ppm, mrad or mg, the effects, the
    sections `downstream()` gives (the budget, cli/budget.py: called once the plots are written, so that a folder
    that cannot take them is said before that work) and the plots of the log (`log_data`: its t, raw) and of each
    interval's residual. Returns the page's path."""
    import numpy as np

    from . import plots
    folder = files.make_folder(folder, param="report")
    plots.norm_residuals(res, log_data, folder / "residuals.png")
    rows = res["per_interval"]
    M, b = np.array(res["matrix"]), np.array(res["bias"])
    plots.residuals_by_direction(np.array([r["direction"] for r in rows]).T, [r["residual_after_ms2"] for r in rows],
                                 [res["g"] * r["noise_rule"] for r in rows],
                                 folder / "directions.png", f"{log}: residual against the direction of gravity")
    verdict = (("**consistent**: every still interval's reading fits the model of (2.2) of 001 within its own noise "
                "bound, so the calibration below holds for this unit with the guaranteed errors shown, as long as "
                "the premises (next) hold" if res["consistent"] else
                "**INCONSISTENT**: no correction of the model meets every still interval's own bound, so the data "
                "refute the noise bound or the model; no bound is given and no calibration should be used")
               + f". The worst interval is {res['worst_over_bound']:.3f} of its own bound (noise plus the proven "
               f"remainder) at the fit minimax in those units; noise bound at most {res['delta_sigma_max']:.3e} "
               f"({res['delta_sigma_source']}), proven remainder {res['remainder_bound']:.1e} (units of g)")
    if "model_discrepancy" in res:
        verdict += ". The " + discrepancy(res)
    axes = ("x", "y", "z")
    sections = [("Verdict", verdict), ("Premises: what must hold for the bounds to hold",
                                       report.Bullets(report.clauses(res["premises"]["statement"]))),
                ("Calibration a = M (raw - b)", report.Table(
                    ("row", "M_i1 (m/s^2 per raw unit)", "M_i2 (m/s^2 per raw unit)", "M_i3 (m/s^2 per raw unit)",
                     "b_i (raw units)"),
                    [(axes[i], *(f"{v:+.6e}" for v in M[i]), f"{b[i]:+.6e}") for i in range(3)]))]
    if res["consistent"]:
        pars = res.get("parameters") or {}
        sections.append(("Parameters of (1.3) of 001 and their guaranteed errors", report.Table(
            ("parameter", "unit", "estimate", "guaranteed error (over the information set)",
             "estimate (ppm, mrad or mg)", "guaranteed error (ppm, mrad or mg)",
             "a priori (these orientations, any data within the noise bound)",
             "on the optimal plan (the 18 orientations of 001's plan, the same noise)"),
            [(k, unit(k), f"{pars[k]:+.4e}" if k in pars else "(raw units)", f"{v:.3e}",
              side(k, pars[k]) if k in pars else "", side(k, v).lstrip("+"),
              f"{res['guaranteed_error_a_priori'][k]:.3e}", f"{res['guaranteed_error_optimal_plan'][k]:.3e}")
             for k, v in res["guaranteed_error"].items()])))
        sections.append(("How to read the parameters",
                         "A guaranteed error is the largest distance, over every set of parameters that fits every "
                         "interval within its noise bound, from the estimate: the truth lies within it when the "
                         "premises hold. The a-priori column is what these orientations guarantee for any data; the "
                         "optimal plan's is what the best set of orientations would give with the same noise, so a "
                         "large ratio between the two says more orientations would pay."))
    if res.get("effects"):
        ref = res["effect_reference"]
        sections.append((f"Effects added to the reading (over g; time from {ref['time_s']:g} s of the log, temperature "
                         f"from {ref['temp_c']:g} C), guaranteed errors over the same information set", report.Table(
            ("effect", "parameter", "estimate", "guaranteed error", "a priori", "unit"),
            [(name, p, f"{v['estimate']:+.4e}", f"{v['guaranteed_error']:.3e}", f"{v['guaranteed_error_a_priori']:.3e}",
              v["unit"]) for name, e in res["effects"].items() for p, v in e["parameters"].items()])))
    sections += [*downstream(), ("The log, its still intervals, and the residual of each",
                                 report.Image("residuals.png")),
                 ("Residual against the direction of gravity", report.Image("directions.png"))]
    return report.write_page(folder, f"Norm calibration: {log}", command, sections, [log])


def estimate(res, angles, q_names, sigma, data, model, plot, folder, command, downstream=tuple):
    """estimate's residual plot (`plot`) and page (`folder`, --report): the verdict, the premises, q with the
    guaranteed error's linear and remainder parts, the sections `downstream()` gives (as `norm`'s), the
    residuals against each stand angle. Returns the page's path, or None without a folder."""
    import numpy as np

    from . import plots
    title = f"{data}: residuals of the minimax fit, " + ("consistent" if res["consistent"] else "INCONSISTENT")
    targets = [p for p in (plot, folder and str(Path(folder) / "residuals.png")) if p]
    if folder:
        files.make_folder(folder, param="report")
    for path in targets:
        plots.residuals_by_angle(np.array(res["positions_deg"]), list(angles), res["residual_minimax"],
                                 sigma, path, title)
    if not folder:
        return None
    verdict = (f"**consistent** with sigma = {sigma:g}: minimax residual of the exact model "
               f"{res['minimax_residual']:.3e}, proven remainder left after absorption into q <= "
               f"{res['remainder_left_bound']:.2e}"
               if res["consistent"] else
               f"**INCONSISTENT**: the data refute sigma = {sigma:g}; they support sigma >= "
               f"{res['sigma_min_supported']:.3g}. No bound is given.")
    sections = [("Verdict", verdict), ("Premises", " ".join(filter(None, (res["premises"]["statement"] + ".",
                                                                res["premises"]["meaning"]))))]
    if res["consistent"]:
        sections.append(("Estimates (guaranteed error = linear + remainder)", report.Table(
            ("q", "definition", "estimate", "guaranteed error", "linear", "remainder", "unit"),
            [(q, res["definitions"][q], f"{res['q'][q]:+.6e}", f"{res['guaranteed_error'][q]:.3e}",
              f"{res['guaranteed_error_linear'][q]:.3e}", f"{res['guaranteed_error_remainder'][q]:.1e}",
              res["units"][q]) for q in q_names])))
    sections += [*downstream(), ("Residuals against each stand angle", report.Image("residuals.png"))]
    return report.write_page(folder, f"Estimate: {data}", command, sections,
                             [data, *([model] if str(model).endswith(".toml") else [])])
