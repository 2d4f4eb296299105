"""truss_report.page.figures_run: the figures of one run: the paper's Fig. 4 (hinge trajectory of a
bay in its stage, with the guide rail) and Fig. 5 (drive force and rail pin force against time,
whole run and one bay's stage), and, for a free stack, the frames' heights against time."""
import os

import numpy as np
from matplotlib.colors import Normalize
from matplotlib.ticker import MaxNLocator

def _event_time(run, field, bay):
    """Time of a per-bay event (NaN when absent or not reached)."""
    b = run.bays
    if field not in b:
        return float("nan")
    if "bay" in b:
        idx = np.nonzero(b["bay"] == bay)[0]
        if len(idx) == 0:
            return float("nan")
        return float(b[field][idx[0]])
    return float(b[field][bay - 1]) if len(b[field]) >= bay else float("nan")


def _lock_times(run):
    """All finite lock (retraction: unlock) times; from the bay changes if /bays has none."""
    if "lock_time_s" in run.bays:
        t = run.bays["lock_time_s"]
        return np.sort(t[np.isfinite(t)])
    h = run.history
    change = np.nonzero(np.diff(h["bay"]) != 0)[0]
    return h["t_s"][change + 1]


def _title(run):
    parts = [f"{run.n_bays} bays", f"{run.drive_mode} drive", run.direction]
    if run.stack_mode:
        parts.append(f"{run.stack_mode} stack")
    if run.status:
        parts.append(f"status {run.status}")
    return f"{os.path.basename(run.path)}: " + ", ".join(parts)


def _words(run):
    if run.direction == "retract":
        return {"entry": "rail exit", "lock": "unlock"}
    return {"entry": "rail entry", "lock": "lock"}


def fig4(plt, run, bay):
    h, u = run.history, run.units
    w = _words(run)
    sel = h["bay"] == bay
    x, y, t = h["hinge_x_m"][sel], h["hinge_y_m"][sel], h["t_s"][sel]
    ok = np.isfinite(x) & np.isfinite(y)
    x, y, t = x[ok], y[ok], t[ok]

    xl, yl = run.rail_x, run.rail_y
    cot = 1.0 / np.tan(np.radians(run.rail_beta_deg))

    fig, ax = plt.subplots(figsize=(6.5, 9.5))
    ax.plot(x, y, "-", color="C0", lw=1.8, label=f"hinge of bay {bay}")
    ax.plot(x[0], y[0], "o", color="C2", ms=7, label=f"stage start (t = {t[0]:.3f} s)")
    ax.plot(x[-1], y[-1], "s", color="C3", ms=7,
            label=f"last sample of the stage (t = {t[-1]:.3f} s)")

    # Limits from the trajectory and the rail point, then the rail line across them.
    xs = np.concatenate([x, [0.0, xl]])
    ys = np.concatenate([y, [yl]])
    xmin, xmax = min(0.0, xs.min()), xs.max()
    ymin, ymax = min(0.0, ys.min()), ys.max()
    mx, my = 0.06 * (xmax - xmin or 1.0), 0.06 * (ymax - ymin or 1.0)
    xlim = (xmin - mx, xmax + mx)
    ylim = (ymin - my, ymax + my)
    xr = np.array(xlim)
    ax.plot(xr, yl - cot * (xr - xl), "--", color="0.45", lw=1.2,
            label=rf"guide rail, $\beta$ = {run.rail_beta_deg:g}°")
    ax.plot(xl, yl, "D", color="0.45", ms=5,
            label=f"rail point (x_l, y_l) = ({xl:g}, {yl:g})")

    te = _event_time(run, "entry_time_s", bay)
    if np.isfinite(te) and t[0] <= te <= t[-1]:
        xe, ye = np.interp(te, t, x), np.interp(te, t, y)
        ax.plot(xe, ye, "*", color="C1", ms=14, mec="k", mew=0.6, zorder=5,
                label=f"{w['entry']} (t = {te:.3f} s)\n(x, y) = ({xe:.4f}, {ye:.4f}) m")
    else:
        ax.plot([], [], " ", label=f"no {w['entry']} in this stage")

    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal", adjustable="box")
    ax.xaxis.set_major_locator(MaxNLocator(5))   # the narrow axis: its labels would touch
    ax.set_xlabel(f"hinge radial offset x ({u['hinge_x_m']})")
    ax.set_ylabel(f"hinge height y ({u['hinge_y_m']})")
    ax.grid(True, alpha=0.3)
    # The key below the axes: inside, it hides part of the trajectory or the rail.
    ax.legend(loc="upper left", bbox_to_anchor=(0.0, -0.09), frameon=False)
    ax.set_title(f"Mid-hinge trajectory, bay {bay} stage (cf. paper Fig. 4)\n{_title(run)}")
    fig.set_layout_engine("tight")   # applied when drawn
    return fig


def _force_panels(plt, run, sel, title, markers):
    h, u = run.history, run.units
    t = h["t_s"][sel]
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(10.0, 6.5))
    a1.plot(t, h["drive_force_N"][sel], color="C0", lw=1.2)
    a2.plot(t, h["pin_force_N"][sel], color="C3", lw=1.2)
    a1.set_ylabel(f"drive force ({u['drive_force_N']})")
    a2.set_ylabel(f"rail pin force ({u['pin_force_N']})")
    a2.set_xlabel(f"time ({u['t_s']})")
    for ax in (a1, a2):
        for tm, style in markers:
            ax.axvline(tm, **style)
        ax.grid(True, alpha=0.3)
    a1.set_title(title)
    fig.set_layout_engine("tight")   # applied when drawn
    return fig, (a1, a2)


def fig5(plt, run):
    h = run.history
    sel = np.ones(len(h["t_s"]), dtype=bool)
    w = _words(run)
    locks = _lock_times(run)
    style = dict(color="C4", lw=0.7, ls="--", alpha=0.35, zorder=0)
    fig, (a1, _) = _force_panels(
        plt, run, sel,
        f"Drive force and rail pin force, whole run (cf. paper Fig. 5)\n{_title(run)}",
        [(tm, style) for tm in locks])
    if len(locks):
        a1.plot([], [], color="C4", lw=0.7, ls="--", alpha=0.6, label=f"{w['lock']} times")
        a1.legend(loc="upper right")
    return fig


def fig5_zoom(plt, run, bay):
    h = run.history
    w = _words(run)
    sel = h["bay"] == bay
    t = h["t_s"][sel]
    markers, labels = [], []
    te = _event_time(run, "entry_time_s", bay)
    tl = _event_time(run, "lock_time_s", bay)
    lo, hi = t.min(), t.max()
    span = hi - lo
    if np.isfinite(te) and lo - 0.05 * span <= te <= hi + 0.05 * span:
        markers.append((te, dict(color="C1", lw=1.0, ls="--", alpha=0.8)))
        labels.append((f"{w['entry']} (t = {te:.3f} s)", dict(color="C1", lw=1.0, ls="--")))
    if np.isfinite(tl) and lo - 0.05 * span <= tl <= hi + 0.05 * span:
        markers.append((tl, dict(color="0.4", lw=1.0, ls=":", alpha=0.8)))
        labels.append((f"{w['lock']} (t = {tl:.3f} s)", dict(color="0.4", lw=1.0, ls=":")))
    fig, (a1, _) = _force_panels(
        plt, run, sel,
        f"Drive force and rail pin force, stage of bay {bay}\n{_title(run)}", markers)
    for text, style in labels:
        a1.plot([], [], label=text, **style)
    if labels:
        a1.legend(loc="best")
    return fig


MAX_FRAME_LINES = 41  # frames drawn by frame_heights (evenly spread over 0..n, top and 0 always)


def frame_lines(n_frames):
    """The frame indices drawn: all of them up to MAX_FRAME_LINES, else an even spread."""
    if n_frames <= MAX_FRAME_LINES:
        return np.arange(n_frames)
    return np.unique(np.round(np.linspace(0, n_frames - 1, MAX_FRAME_LINES)).astype(int))


def fig_frame_heights(plt, run):
    """Heights of the frames against time (free stack: /history/frame_height_m). Top panel: every
    frame (root dark, top light); bottom panel: the lower frames only, each while it is below the
    driven frame (frame k < the running stage's bay), where they move freely by centimetres."""
    h, u = run.history, run.units
    Y = h["frame_height_m"]
    idx = frame_lines(Y.shape[1])
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(10.0, 7.5))
    cmap = plt.get_cmap("viridis")
    below = np.arange(Y.shape[1])[None, :] < h["bay"][:, None]  # frame k below the driven frame
    for k in idx:
        c = cmap(k / max(1, Y.shape[1] - 1))   # the colour bar's scale
        a1.plot(h["t_s"], Y[:, k], lw=0.9, color=c, label=f"frame {k}")
        a2.plot(h["t_s"], np.where(below[:, k], Y[:, k], np.nan), lw=0.9, color=c)
    for ax in (a1, a2):
        for tm in _lock_times(run):
            ax.axvline(tm, color="0.6", lw=0.5, ls=":", zorder=0)
        ax.grid(True, alpha=0.3)
    a2.set_xlabel(f"time ({u['t_s']})")
    a1.set_ylabel(f"frame height ({u['frame_height_m']})")
    a2.set_ylabel(f"lower frames ({u['frame_height_m']})")
    shown = "all frames" if len(idx) == Y.shape[1] else f"{len(idx)} of {Y.shape[1]} frames"
    a1.set_title(f"Frame heights against time ({shown}; dotted: {_words(run)['lock']} times)\n"
                 f"bottom: frames below the driven frame; {_title(run)}")
    # The key: frame index by colour, for any number of frames (a legend of 31 lines would not fit).
    key = plt.cm.ScalarMappable(norm=Normalize(0, Y.shape[1] - 1), cmap=cmap)
    fig.colorbar(key, ax=[a1, a2], label="frame index k (0: root frame)")
    fig.set_layout_engine("constrained")   # applied when drawn (tight cannot place a shared bar)
    return fig
