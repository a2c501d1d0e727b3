"""Plots people read: residuals against each stand angle (where a pattern shows), legends outside the
data, every panel at its own scale."""
import numpy as np

from ..io.report import save_figure


def residuals_by_angle(angles_deg, names, residual, sigma, path, title):
    """One panel per stand angle: the three residual components (units of sigma) against the angle as
    read, with the +-sigma band."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
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
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
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
