"""truss_report.page.figures_motor: the motorisation chart: the resistive torque at the screws per
bay over the runs (P50, the top level, min-max band, nominal) with the motor's torque at the screws
after derating and losses drawn over it (judging.bays.TorqueChart)."""
import numpy as np

from ..judging.stats import percentile


def bay_envelope(v, level):
    """(P50, P{level}, min, max) of each column's finite values (NaN where none)."""
    out = np.full((4, v.shape[1]), np.nan)
    for j in range(v.shape[1]):
        col = v[:, j][np.isfinite(v[:, j])]
        if len(col):
            out[:, j] = percentile(col, 50), percentile(col, level), col.min(), col.max()
    return out


def fig_motor_torque(plt, chart, level, lab, factor):
    """The chart; torques shown in `lab` (value / factor)."""
    nb = int(np.max(np.nonzero(np.any(np.isfinite(chart.resist), axis=0))[0])) + 1
    bays = np.arange(1, nb + 1)
    p50, ptop, lo, hi = bay_envelope(chart.resist[:, :nb], level) / factor
    fig, ax = plt.subplots(figsize=(9.0, 4.4))
    ax.fill_between(bays, lo, hi, color="C0", alpha=0.15, label="resistive torque: min–max over the runs")
    ax.plot(bays, p50, "o-", ms=3, color="C0", label="resistive torque: P50")
    ax.plot(bays, ptop, "s-", ms=3, color="C3", label=f"resistive torque: P{level:g}")
    if chart.nominal is not None:
        ax.plot(bays, chart.nominal[:nb] / factor, "k--", lw=1, label="resistive torque: nominal run")
    avail = chart.available[np.isfinite(chart.available)]
    if len(avail):
        ax.axhline(percentile(avail, 50) / factor, color="C2", lw=1.6,
                   label="motor at the screws, after derating and losses: P50")
        low = 100.0 - level
        if np.ptp(avail) > 0:
            ax.axhline(percentile(avail, low) / factor, color="C2", lw=1.2, ls=":",
                       label=f"motor at the screws, after derating and losses: P{low:g}")
    ax.set_xlabel("bay (its stage of the stroke)")
    ax.set_ylabel(f"torque at the screws ({lab})")
    ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    fig.set_layout_engine("tight", rect=(0, 0.2, 1, 1))
    handles, names = ax.get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=2, frameon=False, fontsize="small")
    return fig
