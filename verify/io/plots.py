"""Plots people read: residuals against each stand angle (where a pattern shows), legends outside the
data, every panel at its own scale."""
import numpy as np

from .report import save_figure


def _pyplot():
    """matplotlib's pyplot, drawing off-screen, with text drawn as written: a `$...$` in a title (a file
    name) is never read as mathtext, which a hostile name could make recurse without end."""
    import matplotlib
    matplotlib.use("Agg")
    matplotlib.rcParams["text.parse_math"] = False
    import matplotlib.pyplot as plt
    return plt


def residuals_by_angle(angles_deg, names, residual, sigma, path, title):
    """One panel per stand angle: the three residual components (units of sigma) against the angle as
    read, with the +-sigma band."""
    plt = _pyplot()
    r = np.asarray(residual, float) / sigma
    fig, axes = plt.subplots(1, len(names), figsize=(4.2 * len(names), 3.6), squeeze=False)
    for ax, k, name in zip(axes[0], range(len(names)), names):
        for i in range(3):
            ax.plot(angles_deg[:, k], r[:, i], "o", ms=3, color=f"C{i}", label=f"accelerometer {i + 1}")
        ax.axhspan(-1, 1, color="0.85", zorder=0, label="+- sigma")
        ax.set_xlabel(f"{name} as read (deg)")
        ax.set_xticks(range(0, 361, 90))
    axes[0][0].set_ylabel("residual (units of sigma)")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8, bbox_to_anchor=(0.5, 0))
    fig.suptitle(title, fontsize=9)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    save_figure(fig, path)
    plt.close(fig)


def residuals_by_direction(n, residual_ms2, noise_ms2, path, title):
    """The norm residual of each still interval against the direction of gravity in sensor axes
    (elevation and azimuth), with each interval's noise bound."""
    plt = _pyplot()
    n = np.asarray(n, float)
    elevation = np.degrees(np.arcsin(np.clip(n[2], -1, 1)))
    azimuth = np.degrees(np.arctan2(n[1], n[0]))
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for ax, x, label in ((axes[0], elevation, "elevation of n (deg)"), (axes[1], azimuth, "azimuth of n (deg)")):
        ax.errorbar(x, residual_ms2, yerr=noise_ms2, fmt="o", ms=3, color="C0", ecolor="0.6",
                    label="residual, +- the interval's noise bound")
        ax.axhline(0, color="k", lw=0.6)
        ax.set_xlabel(label)
    axes[0].set_ylabel("norm residual (m/s^2)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", fontsize=8, bbox_to_anchor=(0.5, 0))
    fig.suptitle(title, fontsize=9)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    save_figure(fig, path)
    plt.close(fig)


def norm_residuals(result, log, path):
    """PNG of a norm calibration at a glance: the raw log's three axes against time with the still intervals
    shaded and numbered (what the calibration used), then the norm residual of each interval before (the
    starting map) and after, against the interval's number and against time, each at its own scale, with
    the noise bound band after. `log`: (t, raw) of the log, drawn from at most 20,000 samples."""
    plt = _pyplot()
    rows = result["per_interval"]
    k = np.arange(1, len(rows) + 1)
    g = result["g"]
    t, raw = log
    step = max(1, len(t) // 20_000)
    fig = plt.figure(figsize=(12, 7.5))
    top = fig.add_subplot(2, 1, 1)
    for i, name in enumerate("xyz"):
        top.plot(t[::step], raw[::step, i], lw=0.6, color=f"C{i}", label=f"raw {name}")
    lo, hi = float(np.min(raw[::step])), float(np.max(raw[::step]))
    for n, r in enumerate(rows, 1):
        top.axvspan(r["start_s"], r["stop_s"], color="0.5", alpha=0.18, lw=0)
        top.text(0.5 * (r["start_s"] + r["stop_s"]), hi + 0.02 * (hi - lo), str(n), ha="center", va="bottom",
                 fontsize=7)
    top.set_xlabel("time (s)")
    top.set_ylabel(f"raw ({result['raw_unit']})")
    top.set_title(f"the log and its {len(rows)} still intervals (shaded, numbered as below)", fontsize=9)
    top.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7)
    a0, a1, a2 = (fig.add_subplot(2, 3, 4 + i) for i in range(3))
    before, after = [r["residual_before_ms2"] for r in rows], [r["residual_after_ms2"] for r in rows]
    mid = [0.5 * (r["start_s"] + r["stop_s"]) for r in rows]
    band = g * (result["delta_sigma_max"] + result["remainder_bound"])
    a0.plot(k, before, "o", color="C3")
    a0.set_title("before (starting map)", fontsize=9)
    for ax, x, label in ((a1, k, "still interval"), (a2, mid, "time (s)")):
        ax.plot(x, after, "s", color="C0")
        ax.plot(x, [g * r["noise_rule"] for r in rows], "_", color="C2", label="noise rule of each interval")
        ax.plot(x, [-g * r["noise_rule"] for r in rows], "_", color="C2")
        ax.axhspan(-band, band, color="C0", alpha=0.12, label=f"+- (delta_sigma_max + remainder) g = {band:.2e} m/s^2")
        ax.set_xlabel(label)
    a1.set_title(f"after ({result['params']}-parameter calibration): "
                 + ("consistent" if result["consistent"] else "INCONSISTENT"), fontsize=9)
    a2.set_title("after, against time (a drift shows here)", fontsize=9)
    a0.set_xlabel("still interval")
    for ax in (a0, a1, a2):
        ax.axhline(0, color="k", lw=0.6)
    a0.set_ylabel("(|a|^2 - g^2) / (2 |a|^2) x g   (m/s^2)")
    fig.legend(*a1.get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8)
    fig.suptitle(f"{result['log'].rsplit('/', 1)[-1]}: the log, and the norm residual per still interval", fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    save_figure(fig, path)
    plt.close(fig)


def diagnosis(res, path, title):
    """Residuals of the minimax fit before and after the effects are added, each panel at its own
    scale, against the position (three components each), with +-sigma and the proven remainder."""
    plt = _pyplot()
    s = res["sigma"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    added = "with " + (", ".join(res["effects"]) if res["effects"] else "no effect added")
    for ax, key, colour, label in ((axes[0], "residual_before", "C3", "current model"),
                                   (axes[1], "residual_after", "C0", added)):
        r = np.array(res[key]).reshape(-1) / s
        ax.plot(np.arange(r.size) / 3, r, "o", ms=3, color=colour)
        ax.axhspan(-1, 1, color="0.85", zorder=0, label="+- sigma")
        ax.axhline(1 + res["remainder_bound"] / s, color="k", lw=0.8, ls=":", label="+ the largest proven remainder")
        ax.axhline(-1 - res["remainder_bound"] / s, color="k", lw=0.8, ls=":")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("position (three components each)")
    axes[0].set_ylabel("minimax-fit residual (units of sigma)")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    save_figure(fig, path)
    plt.close(fig)


def repeatability(results, path):
    """PNG: each parameter per run with its guaranteed bound, and the envelope band; one colour per
    sensor when several are given (results: {label: run() output})."""
    plt = _pyplot()
    first = next(iter(results.values()))
    names = first["parameters"]
    cols = 3
    fig, axes = plt.subplots((len(names) + cols - 1) // cols, cols, figsize=(12, 3 * ((len(names) + 2) // cols)))
    for p, (name, ax) in enumerate(zip(names, axes.flat)):
        for c, (label, res) in enumerate(results.items()):
            if "envelope" not in res:
                continue
            a = np.array([r["parameters"][name] for r in res["runs"]])
            e = np.array([r["guaranteed_error"][name] for r in res["runs"]])
            ref = res["envelope"][name]
            mid = (ref["lo"] + ref["hi"]) / 2
            x = np.arange(1, len(a) + 1) + 0.08 * c
            ax.errorbar(x, a - mid, e, fmt="o", ms=3, color=f"C{c % 10}", label=label)
            ax.hlines([ref["lo"] - mid, ref["hi"] - mid], x[0] - 0.2, x[-1] + 0.2, colors=f"C{c % 10}",
                      linestyles="dashed", lw=0.8)
        ax.set_title(f"{name} (minus the envelope centre)", fontsize=9)
        ax.set_xlabel("run")
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 8), fontsize=8)
    fig.suptitle("per-run estimate with its guaranteed bound; dashed: the between-run envelope "
                 "(units as the parameter: 1, rad, or 1 over g)", fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.96))
    save_figure(fig, path)
    plt.close(fig)


def realised_plan(s, path):
    """PNG: guaranteed error (units of sigma) against the position error, (23) vs the LP optimum: the rows
    of nearby.sweep (miss in degrees, (23) mean and worst, LP mean and worst)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    ax.plot(s[:, 0], s[:, 2], "o-", color="C1", label="estimator (23), worst of 20 plans")
    ax.plot(s[:, 0], s[:, 1], "o--", color="C1", alpha=0.6, label="estimator (23), mean")
    ax.plot(s[:, 0], s[:, 4], "s-", color="C0", label="LP optimum on the realised plan, worst")
    ax.plot(s[:, 0], s[:, 3], "s--", color="C0", alpha=0.6, label="LP optimum, mean")
    ax.axhline(1, color="k", lw=0.8)
    ax.set_xlabel("position error: each angle uniform in [-d, d], d in degrees")
    ax.set_ylabel("max over q of the guaranteed error (units of sigma)")
    ax.set_title("Two-axis stand, optimal 10-position plan set with errors\n"
                 "(reusing the exact-plan estimators: biased, guaranteed error infinite)", fontsize=9)
    fig.legend(*ax.get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8)
    fig.tight_layout(rect=(0, 0.14, 1, 1))
    save_figure(fig, path)
    plt.close(fig)


def _face(u):
    """The block face nearest to pointing up along u: '+x' ... '-z'."""
    k = int(np.argmax(np.abs(u)))
    return ("+" if u[k] > 0 else "-") + "xyz"[k]


def plan_directions(U, path, title):
    """PNG: the up-direction in block axes at each position of a plan (U: (S, 3) unit vectors, in the
    plan's order), as arrows on the unit sphere and on the two hemispheres seen from outside (equal-area),
    each labelled with its number and the face of the block nearest to pointing up."""
    plt = _pyplot()
    U = np.asarray(U, float)
    groups = {}                                        # positions with one up-direction share a label
    for k, u in enumerate(U, 1):
        groups.setdefault(tuple(np.round(u, 6) + 0.0), []).append(str(k))
    fig = plt.figure(figsize=(13, 4.4))
    ax = fig.add_subplot(1, 3, 1, projection="3d")
    a, b = np.meshgrid(np.linspace(0, 2 * np.pi, 37), np.linspace(0, np.pi, 19))
    ax.plot_wireframe(np.cos(a) * np.sin(b), np.sin(a) * np.sin(b), np.cos(b), color="0.85", lw=0.4)
    ax.quiver(0, 0, 0, U[:, 0], U[:, 1], U[:, 2], color="C0", arrow_length_ratio=0.08, lw=1.2)
    for u, ks in groups.items():
        ax.text(*(1.15 * np.array(u)), ",".join(ks), fontsize=7)
    ax.set_xlabel("block x")
    ax.set_ylabel("block y")
    ax.set_zlabel("block z")
    ax.set_box_aspect((1, 1, 1))
    ax.set_title("up-direction at each position", fontsize=9)
    for panel, sign, name in ((2, 1, "upper half (z >= 0), seen from +z"), (3, -1, "lower half (z < 0), seen from -z")):
        h = fig.add_subplot(1, 3, panel)
        h.add_patch(plt.Circle((0, 0), 1, fill=False, color="0.5"))
        for u, ks in groups.items():
            u = np.array(u)
            if (u[2] < 0) != (sign < 0):
                continue
            r = np.sqrt(max(0.0, 1 - sign * u[2]))               # equal-area: radius sqrt(1 - cos(polar angle))
            xy = np.array([u[0], sign * u[1]])
            xy = r * xy / (np.linalg.norm(xy) or 1.0)
            h.plot(*xy, "o", color="C0", ms=5)
            h.annotate(f"{','.join(ks)}: {_face(u)} up", xy, xytext=(4, 4), textcoords="offset points", fontsize=7)
        h.set_xlim(-1.3, 1.3)
        h.set_ylim(-1.3, 1.3)
        h.set_aspect("equal")
        h.set_xlabel("block x")
        h.set_ylabel("block y" if sign > 0 else "block -y (seen from below)")
        h.set_title(name, fontsize=9)
    fig.suptitle(title + " (number: position; face: the block face nearest to pointing up)", fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.94))
    save_figure(fig, path)
    plt.close(fig)


def bounds_before_after(q_names, before, after, target, path, title):
    """PNG: each q's guaranteed error over its target before the next position and after it (log scale),
    the target at 1; a q without an estimator yet drawn at the top, hatched; `after` None: no next position
    (done, or the data refute sigma), the errors now alone."""
    plt = _pyplot()
    t = np.asarray(target, float)
    bars = ([(-0.2, before, "C3", "now"), (0.2, after, "C0", "after the next position")] if after
            else [(0, before, "C3", "now")])
    ratios = [np.asarray([np.inf if v is None else v for v in x], float) / t for _, x, _, _ in bars]
    finite = np.concatenate([r[np.isfinite(r)] for r in ratios])
    top = 2 * max(finite.max() if finite.size else 1.0, 1.0)
    fig, ax = plt.subplots(figsize=(max(6, 0.55 * len(q_names)), 4))
    x = np.arange(len(q_names))
    for (shift, _, colour, label), r in zip(bars, ratios):
        none = ~np.isfinite(r)
        if (~none).any():
            ax.bar(x[~none] + shift, r[~none], 0.4, color=colour, label=label)
        if none.any():
            ax.bar(x[none] + shift, top, 0.4, color="none", edgecolor=colour, hatch="//",
                   label=f"{label}: no estimator yet")
    ax.axhline(1, color="k", lw=1, label="target")
    ax.set_yscale("log")
    ax.set_xticks(x, q_names, rotation=60, fontsize=8)
    ax.set_ylabel("guaranteed error / target")
    ax.set_title(title, fontsize=9)
    fig.legend(*ax.get_legend_handles_labels(), loc="lower center", ncol=3, fontsize=7)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    save_figure(fig, path)
    plt.close(fig)


def thermal(res, path, title):
    """One panel per q with a temperature polynomial: q(T) - q(T0) over the range with its guaranteed band
    (the one bound over the range), and the estimate with its own bound at each chamber temperature."""
    plt = _pyplot()
    th = res["thermal"]
    names = list(th["q"])
    t0, (lo, hi) = th["t0_c"], th["range_c"]
    cols = min(4, len(names))
    rows = -(-len(names) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.4 * cols, 2.6 * rows), squeeze=False)
    T = np.linspace(lo, hi, 200)
    for ax, name in zip(axes.flat, names):
        c = np.asarray(th["q"][name])
        unit = res["units"][name]
        scale, label = (1e6, "ppm") if unit == "1" and not res["definitions"][name].startswith("bias") else \
            (1e3, "mg") if res["definitions"][name].startswith("bias") else (1e3, f"m{unit}")
        q = sum(ck * (T - t0) ** k for k, ck in enumerate(c)) - c[0]
        b = th["bound"][name]
        ax.fill_between(T, scale * (q - b), scale * (q + b), color="C0", alpha=0.25, label="guaranteed band")
        ax.plot(T, scale * q, color="C0", lw=1.2, label="estimate")
        pts = th["at_temperature"][name]
        ax.errorbar([p["temp_c"] for p in pts], [scale * (p["q"] - c[0]) for p in pts],
                    yerr=[scale * p["bound"] for p in pts], fmt="o", ms=3, color="C3", capsize=2,
                    label="at a chamber temperature")
        ax.set_title(f"{name} = {res['definitions'][name]}", fontsize=8)
        ax.set_xlabel("T (C)", fontsize=8)
        ax.set_ylabel(f"q(T) - q({t0} C) ({label})", fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, bbox_to_anchor=(0.5, 0))
    fig.suptitle(title, fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    save_figure(fig, path)
    plt.close(fig)
