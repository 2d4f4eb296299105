"""truss_report.page.figures: the campaign report's figures of the outputs' distributions, the lock
timing, the motor margins, the tornado charts and the Sobol' indices (matplotlib)."""
import numpy as np
from matplotlib.ticker import LogLocator, MaxNLocator

from ..reading.schema import LEVELS
from .numbers import fmt, fmt_at



def log_minor_ticks(axis):
    """Minor ticks of a log axis at 2 and 5 times each power of ten: matplotlib's default (2 to 9)
    is a third of a distribution figure's drawing time, for ticks that carry no label."""
    axis.set_minor_locator(LogLocator(subs=(2.0, 5.0)))


def fig_distribution(plt, x, title, u, est, cis, nominal=float("nan"), confidence=0.95, at=None):
    """x sorted, in the display unit u (est, cis and nominal too), values in the key to 10^at."""
    n = len(x)
    unit = f" ({u})" if u != "1" else ""
    # Histogram and exceedance probability (1 - ECDF, log scale: the tail that the design
    # percentiles sit in; the ECDF itself adds nothing the two do not show).
    fig, (a1, a3) = plt.subplots(1, 2, figsize=(13.0, 4.6))
    edges = np.histogram_bin_edges(x, bins="auto")
    if len(edges) > 81:
        edges = np.linspace(x[0], x[-1], 81)
    a1.hist(x, bins=edges, color="C0", alpha=0.8, histtype="stepfilled")   # one polygon, not a bar a bin
    a1.set_ylabel("runs")
    surv = 1.0 - np.arange(1, n + 1) / n
    a3.step(x[:-1], surv[:-1], where="post", color="C0")
    a3.set_yscale("log")
    log_minor_ticks(a3.yaxis)
    a3.set_ylim(min(0.5 / n, 5e-4), 1.5)
    a3.set_ylabel("exceedance probability 1 − ECDF")
    colors = {"p50": "C2", "p95": "C1", "p99": "C3", "p99_865": "C4"}
    for q, name, lab in LEVELS:
        style = dict(color=colors[name], lw=1.1, ls="--")
        a1.axvline(est[name], label=f"{lab} = {fmt_at(est[name], at)}{' ' + u if u != '1' else ''}",
                   **style)
        # The bounds as a segment (it need not contain the estimate for very small n); a bound
        # the sample cannot give is drawn to the sample's extreme.
        ci, level = cis[name], 1.0 - q / 100.0
        lo = ci.lo if np.isfinite(ci.lo) else x[0]
        hi = ci.hi if np.isfinite(ci.hi) else x[-1]
        a3.plot([lo, hi], [level, level], "|-", color=colors[name], lw=1.6, ms=8)
        a3.plot([est[name]], [level], "o", color=colors[name], ms=4,
                label=f"{lab}, {confidence * 100:g} % bounds" + ("" if np.isfinite(ci.lo) and
                                                          np.isfinite(ci.hi) else " (n too small)"))
    if np.isfinite(nominal):
        for ax in (a1, a3):
            ax.axvline(nominal, color="k", lw=1.4, ls="-",
                       label=f"nominal = {fmt_at(nominal, at)}{' ' + u if u != '1' else ''}"
                       if ax is a1 else None)
    for ax in (a1, a3):
        ax.set_xlabel(title + unit)
        ax.grid(True, alpha=0.3)
    # Keys outside the data: the histogram's to its right half is often empty, but not always.
    a1.legend(loc="upper left", bbox_to_anchor=(0.0, -0.2), ncol=2, frameon=False)
    a3.legend(loc="upper left", bbox_to_anchor=(0.0, -0.2), ncol=2, frameon=False)
    fig.suptitle(f"{title}: {n} ok runs with a finite value")
    fig.set_layout_engine("tight")   # applied when drawn
    return fig


def fig_lock_timing(plt, bays, lt, it, u, words, dt_text):
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(15.0, 4.5))
    for ax, s, what in ((a1, lt, f"{words[0]} time"),
                        (a2, it, f"time between successive {words[1]}")):
        ax.fill_between(bays, s["p5"], s["p95"], color="C0", alpha=0.25, step=None,
                        label="5–95 % band")
        ax.plot(bays, s["p50"], "o-", color="C0", ms=3, lw=1.2, label="median")
        ax.set_xlabel("bay index")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_ylabel(f"{what} ({u})")
        ax.grid(True, alpha=0.3)
        ax.legend()
    a1.set_title(f"{words[0]} time per bay")
    a2.set_title(f"time between successive {words[1]}\n({dt_text})")
    fig.set_layout_engine("tight")   # applied when drawn
    return fig


def fig_motor(plt, torque, stall_t, ok_t, stalled, nominal, u):
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(15.0, 4.5))
    both = stall_t[ok_t | stalled]
    edges = np.histogram_bin_edges(both[np.isfinite(both)], bins="auto")
    edges = edges if len(edges) <= 61 else np.linspace(edges[0], edges[-1], 61)
    a1.hist([stall_t[ok_t], stall_t[stalled]], bins=edges, stacked=True, color=["C0", "C3"],
            label=[f"ok runs ({int(ok_t.sum())})", f"stalled runs ({int(stalled.sum())})"])
    a1.axvline(nominal, color="k", ls="--", lw=1, label=f"base scene {fmt(nominal)} {u}")
    a1.set_xlabel(f"stall torque of the run ({u})")
    a1.set_ylabel("runs")
    a1.legend()
    a2.plot(stall_t[ok_t], torque[ok_t], ".", ms=3, color="C0", label="ok runs")
    a2.plot(stall_t[stalled], torque[stalled], "x", ms=4, color="C3",
            label="stalled runs (peak before the stall)")
    lim = np.array([np.nanmin(both), np.nanmax(both)])
    a2.plot(lim, lim, "k--", lw=1, label="peak torque = stall torque")
    a2.set_xlabel(f"stall torque of the run ({u})")
    a2.set_ylabel(f"peak drive torque ({u})")
    a2.legend()
    for ax in (a1, a2):
        ax.grid(True, alpha=0.3)
    fig.set_layout_engine("tight")   # applied when drawn
    return fig


def fig_tornado(plt, ranked, aggregate, title, band):
    labels = [lab for lab, _, _ in ranked][::-1]
    vals = np.array([r for _, r, _ in ranked][::-1])
    fig, ax = plt.subplots(figsize=(7.4, 0.32 * len(labels) + 1.4))
    colors = ["C3" if v > 0 else "C0" for v in vals]
    bars = ax.barh(range(len(vals)), vals, color=colors, alpha=0.85)
    for bar, lab in zip(bars, labels):
        if lab in aggregate:
            bar.set_hatch("///")
            bar.set_edgecolor("k")
    ax.axvspan(-band, band, color="0.8", alpha=0.6, zorder=0)
    ax.axvline(0, color="k", lw=0.8)
    ax.set_yticks(range(len(vals)))
    ax.set_yticklabels(labels)
    ax.set_xlim(-1.05, 1.05)
    ax.set_xlabel("Spearman ρ (1)")
    for i, v in enumerate(vals):
        ax.text(v, i, f" {v:+.3f} ".replace("-0.000", "0.000").replace("+0.000", "0.000"), va="center", ha="left" if v > 0 else "right", fontsize=8)
    ax.set_title(f"{title}: top {len(vals)} inputs by |ρ|")
    ax.grid(True, axis="x", alpha=0.3)
    fig.set_layout_engine("tight")   # applied when drawn
    return fig


def fig_sobol(plt, factors, outs):
    G = len(factors)
    ncol = 3
    nrow = -(-len(outs) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(15.0, 3.2 + 0.25 * G + 3.0 * (nrow - 1)),
                             squeeze=False)
    y = np.arange(G)
    for ax, (key, so) in zip(axes.ravel(), outs.items()):
        o = so.indices
        for k, dy, color, label in (("first_order", 0.2, "C0", "first order S1"),
                                    ("total", -0.2, "C1", "total ST")):
            ok = np.isfinite(o[k])            # NaN: undefined (e.g. an output that never varies)
            ax.barh(y[ok] + dy, o[k][ok], 0.4, color=color, label=label)
            ok &= np.isfinite(o[k + "_lo"]) & np.isfinite(o[k + "_hi"])
            ax.hlines(y[ok] + dy, o[k + "_lo"][ok], o[k + "_hi"][ok], color="k", lw=1.2)
        ax.set_yticks(y)
        ax.set_yticklabels(factors)
        ax.set_ylim(G - 0.5, -0.5)
        undefined = not np.all(np.isfinite(o["first_order"]) & np.isfinite(o["total"]))
        ax.set_title(key + (" (some indices undefined: NaN)" if undefined else ""))
        ax.set_xlabel("Sobol' index (1); black: CI")
        ax.grid(True, axis="x", alpha=0.3)
    axes.ravel()[0].legend()
    for ax in axes.ravel()[len(outs):]:
        ax.set_visible(False)
    fig.set_layout_engine("tight")   # applied when drawn
    return fig


def fig_velocity_margin(plt, torque, a_min, a_max, u, at=None):
    """Histogram of the ok runs' peak drive torque (display unit u, resolution 10^at) against the
    smallest torque the scene's motor gives at the prescribed speed (a_min; a_max the largest)."""
    fig, ax = plt.subplots(figsize=(10.0, 4.2))
    ax.hist(torque, bins=60, color="C0", histtype="stepfilled", label=f"peak drive torque, {len(torque)} ok runs")
    ax.axvline(a_min, color="C3", ls="--", lw=1.2,
               label=f"available at the prescribed speed: {fmt_at(a_min, at)} {u}"
               + (f" (smallest; largest {fmt_at(a_max, at)} {u})" if a_max > a_min else ""))
    ax.set_xlabel(f"drive torque, the three screws together ({u})")
    ax.set_ylabel("runs")
    ax.legend(loc="upper left", bbox_to_anchor=(0.0, -0.18), ncol=2, frameon=False)
    ax.grid(True, alpha=0.3)
    fig.set_layout_engine("tight")   # applied when drawn
    return fig
