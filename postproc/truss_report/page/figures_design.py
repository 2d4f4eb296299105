"""truss_report.page.figures_design: per-bay envelopes, where the peaks occur, top inputs against each
load, and the convergence of the percentile estimates and Sobol' indices with the run count."""
import numpy as np

from ..judging.sobol import sobol_estimates, usable_blocks
from ..judging.stats import min_runs_for_bound, percentile, quantile_ci
from .figures import log_minor_ticks
from .numbers import readable_unit


def input_axis(col):
    """(axis label, values) of an input column for a plot: a relative deviation in %, a length
    in mm, a mass in g (when the values are that small), else the file's unit."""
    if col.relative:
        key, per = col.label[:-1].split(" (mean over ")
        return f"{key}: mean relative\ndeviation over {per} (%)", 100.0 * col.values
    finite = col.values[np.isfinite(col.values)]
    lab, f = readable_unit(col.units, float(np.max(np.abs(finite))) if len(finite) else np.nan)
    return (col.label + (f" ({lab})" if lab != "1" else ""), col.values / f)


def panel_grid(plt, n, width=5.0, height=3.8, ncol_max=3):
    """A figure of n panels, at most ncol_max a row (a 15-inch row at 110 dpi is shown at about
    0.85 of its size on the page, so that 9-10 pt text stays readable), extra axes hidden."""
    ncol = min(n, ncol_max)
    nrow = -(-n // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(width * ncol, height * nrow), squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    return fig, axes.ravel()[:n]


def fig_envelopes(plt, fields, ok, nominal_bays, units, top_level):
    """fields: [(field, label, n x nb array)]: P50 and P{top} per bay, min-max band, nominal.
    units: field -> (display unit, factor)."""
    fig, axes = panel_grid(plt, len(fields))
    for ax, (key, label, b) in zip(axes, fields):
        v = b[ok]
        bays = np.arange(1, v.shape[1] + 1)
        p50, ptop, lo, hi = (np.full(len(bays), np.nan) for _ in range(4))
        for j in range(len(bays)):
            col = v[:, j][np.isfinite(v[:, j])]
            if len(col):
                p50[j], ptop[j] = percentile(col, 50), percentile(col, top_level)
                lo[j], hi[j] = col.min(), col.max()
        lab, f = units[key]
        ax.fill_between(bays, lo / f, hi / f, color="C0", alpha=0.15, label="min–max")
        ax.plot(bays, p50 / f, "o-", ms=3, color="C0", label="P50")
        ax.plot(bays, ptop / f, "s-", ms=3, color="C3", label=f"P{top_level:g}")
        if nominal_bays is not None and key in nominal_bays:
            ax.plot(bays, nominal_bays[key][:len(bays)] / f, "k--", lw=1, label="nominal")
        ax.set_xlabel("bay")
        ax.set_ylabel(f"{label} ({lab})")
        ax.grid(True, alpha=0.3)
    # One key for all panels, below them: inside a panel it hides the band.
    handles, names = axes[0].get_legend_handles_labels()
    fig.set_layout_engine("tight", rect=(0, 0.08 / max(1, len(axes) // 3 + 1), 1, 1))
    fig.legend(handles, names, loc="lower center", ncol=len(names), frameon=False)
    return fig


def fig_peak_location(plt, items, units):
    """items: [(label, bay array, time array, value array, key)]: bay counts and value vs time."""
    fig, axes = plt.subplots(2, len(items), figsize=(6.0 * len(items), 7.0), squeeze=False)
    for j, (label, bay, t, v, key) in enumerate(items):
        sel = np.isfinite(bay) & np.isfinite(t) & np.isfinite(v)
        bays = bay[sel].astype(int)
        if not len(bays):
            continue
        u, counts = np.unique(bays, return_counts=True)
        axes[0, j].bar(u, counts, color="C0")
        axes[0, j].set_xlabel("bay where the peak occurs")
        axes[0, j].set_ylabel("runs")
        axes[0, j].set_title(label)
        lab, f = units[key]
        sc = axes[1, j].scatter(t[sel], v[sel] / f, c=bays, s=5, cmap="viridis")
        fig.colorbar(sc, ax=axes[1, j], label="bay")
        axes[1, j].set_xlabel("time of the peak (s)")
        axes[1, j].set_ylabel(f"{label} ({lab})")
        for ax in axes[:, j]:
            ax.grid(True, alpha=0.3)
    fig.set_layout_engine("tight")   # applied when drawn
    return fig


def fig_scatter(plt, rows, nominal):
    """rows: [(load label, (unit, factor), y, [(axis label, x already in its axis unit)])];
    nominal: {load label: value}. At most 4,000 points a panel (every run up to that; a random
    but fixed subset beyond: the cloud's shape, not its count, is what the panel shows)."""
    ncol = max(len(r[3]) for r in rows)
    fig, axes = plt.subplots(len(rows), ncol, figsize=(5.0 * ncol, 3.4 * len(rows)),
                             squeeze=False)
    for i, (label, (lab, f), y, inputs) in enumerate(rows):
        for j in range(ncol):
            ax = axes[i, j]
            if j >= len(inputs):
                ax.set_visible(False)
                continue
            name, x = inputs[j]
            sel = np.nonzero(np.isfinite(x) & np.isfinite(y))[0]
            if len(sel) > 4000:
                sel = np.sort(np.random.default_rng(1).choice(sel, 4000, replace=False))
            ax.plot(x[sel], y[sel] / f, ".", ms=2.5, color="C0", alpha=0.5,
                    label=f"ok runs{' (4000 shown)' if len(sel) == 4000 else ''}")
            if np.isfinite(nominal.get(label, np.nan)):
                ax.axhline(nominal[label] / f, color="k", ls="--", lw=0.9, label="nominal")
            ax.set_xlabel(name)
            ax.set_ylabel(f"{label} ({lab})")
            ax.grid(True, alpha=0.3)
    handles, names = axes[0, 0].get_legend_handles_labels()
    fig.set_layout_engine("tight", rect=(0, 0.02, 1, 1))
    fig.legend(handles, names, loc="lower center", ncol=len(names), frameon=False)
    return fig


def convergence_points(n):
    """Run counts at which estimates are shown: about 12 per decade from 20 up to n."""
    if n < 20:
        return np.array([n])
    m = np.unique(np.round(np.logspace(np.log10(20), np.log10(n), 25)).astype(int))
    return m[m <= n]


def fig_convergence(plt, series, levels, confidence):
    """series: [(label, (unit, factor), values in run order (ok and finite only))]: each
    level's estimate over the first m runs with its one-sided bounds (both at `confidence`)."""
    fig, axes = panel_grid(plt, len(series))
    for ax, (label, (lab, f), x) in zip(axes, series):
        ms = convergence_points(len(x))
        for c_i, q in enumerate(levels):
            est, lo, hi = [], [], []
            for m in ms:
                s = np.sort(x[:m])
                ci = quantile_ci(s, q / 100.0, confidence)
                est.append(percentile(s, q))
                lo.append(ci.lo)
                hi.append(ci.hi)
            col = f"C{c_i}"
            ax.plot(ms, np.array(est) / f, "-", color=col, label=f"P{q:g}")
            ax.fill_between(ms, np.array(lo) / f, np.array(hi) / f, color=col, alpha=0.2,
                            label=f"P{q:g}: one-sided {confidence * 100:g} % bounds")
        need = min_runs_for_bound(levels[-1] / 100.0, 1.0 - confidence, "hi")
        if need <= len(x):
            ax.axvline(need, color="0.4", ls=":", lw=1.0,
                       label=f"runs an upper bound of P{levels[-1]:g} needs ({need})")
        ax.set_xscale("log")
        log_minor_ticks(ax.xaxis)
        ax.set_xlabel("runs")
        ax.set_ylabel(f"{label} ({lab})")
        ax.grid(True, alpha=0.3)
    handles, names = axes[0].get_legend_handles_labels()
    fig.set_layout_engine("tight", rect=(0, 0.1 / (len(axes) // 3 + 1), 1, 1))
    fig.legend(handles, names, loc="lower center", ncol=len(names), frameon=False)
    return fig


def fig_sobol_convergence(plt, series, G, factors, confidence, n_boot=200):
    """series: [(label, y over all runs, ok mask)]: S1 and ST against the number of blocks, with
    a percentile bootstrap interval over blocks (seeded: the figure is reproducible)."""
    rng = np.random.default_rng(12345)
    fig, axes = plt.subplots(1, len(series), figsize=(4.8 * len(series), 3.8), squeeze=False)
    a = (1.0 - confidence) / 2.0
    for ax, (label, y, ok) in zip(axes[0], series):
        fA, fB, fAB = usable_blocks(y, ok, G)
        ms = convergence_points(len(fA)) if len(fA) >= 20 else np.array([len(fA)])
        for g in range(G):
            est, lo, hi = [], [], []
            for m in ms:
                s1, st = sobol_estimates(fA[:m], fB[:m], fAB[:m])
                boot = []
                for _ in range(n_boot):
                    i = rng.integers(0, m, m)
                    boot.append(sobol_estimates(fA[i], fB[i], fAB[i])[1][g])
                est.append(st[g])
                lo.append(np.quantile(boot, a))
                hi.append(np.quantile(boot, 1 - a))
            ax.plot(ms, est, "-", color=f"C{g % 10}", label=factors[g])
            ax.fill_between(ms, lo, hi, color=f"C{g % 10}", alpha=0.15)
        ax.set_xscale("log")
        ax.set_xlabel("Saltelli blocks used")
        ax.set_ylabel("total Sobol' index ST (1)")
        ax.set_title(label)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.set_layout_engine("tight")   # applied when drawn
    return fig
