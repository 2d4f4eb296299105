#!/usr/bin/python3
"""Frame heights of a free-stack run: /history/frame_height_m and its figure.

Usage: test_frame_heights.py --sim TRUSS_SIM --root REPO_ROOT --scratch DIR

Runs truss-sim on a 4-bay free stack (paper_free_slack) and a 2-bay held stack, then checks
1. the dataset: shape (samples, n + 1), units m; its driven and lower columns equal the 1-D
   datasets y_driven_m / y_lower_m (written from the phase point, the frame heights from the state
   through another function); frames above the driven one sit 2 l_s apart (locked); frame 0 rests
   at 0 until bay 1's stage; a held-stack file has no such dataset;
2. the figure: the lines of truss_report.page.figures_run.fig_frame_heights are the file's columns, read here with
   h5py directly (top panel every frame, bottom panel each frame while below the driven frame);
3. run_figures.py writes frame_heights.png for the free run and not for the held one, and the
   single-run report (report.py) shows it.
Exit 0 when every check passes; one line per failed check otherwise.
"""
import argparse
import os
import subprocess
import sys

import h5py
import numpy as np

fails = []


def check(ok, what):
    print(("ok:   " if ok else "FAIL: ") + what)
    if not ok:
        fails.append(what)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--sim", required=True)
    p.add_argument("--root", required=True)
    p.add_argument("--scratch", required=True)
    a = p.parse_args()
    os.makedirs(a.scratch, exist_ok=True)
    free = os.path.join(a.scratch, "free4.h5")
    held = os.path.join(a.scratch, "held2.h5")
    scenes = os.path.join(a.root, "campaigns", "scenes")
    subprocess.run([a.sim, os.path.join(scenes, "paper_free_slack.toml"), "--set", "mast.n_bays=4",
                    "--set", "run.output_step_s=0.01", "-o", free, "--force"], check=True, capture_output=True)
    subprocess.run([a.sim, os.path.join(scenes, "table1.toml"), "--set", "mast.n_bays=2",
                    "--set", "run.output_step_s=0.01", "-o", held, "--force"], check=True, capture_output=True)

    # 1. The dataset against the file's other datasets.
    n, l_s = 4, 0.18
    with h5py.File(free, "r") as f:
        h = f["history"]
        Y = h["frame_height_m"][()]
        units = h["frame_height_m"].attrs["units"]
        bay = h["bay"][()]
        yd, yl, t = h["y_driven_m"][()], h["y_lower_m"][()], h["t_s"][()]
    units = units.decode() if isinstance(units, bytes) else units
    rows = np.arange(len(t))
    check(Y.shape == (len(t), n + 1), f"frame_height_m shape {Y.shape} == ({len(t)}, {n + 1})")
    check(units == "m", "frame_height_m units m")
    check(np.all(np.isfinite(Y)), "frame heights finite")
    # Same values by two routes (PhasePoint vs the state): equal to rounding of one addition.
    check(np.max(np.abs(Y[rows, bay] - yd)) < 1e-12, "driven column == y_driven_m")
    check(np.max(np.abs(Y[rows, bay - 1] - yl)) < 1e-12, "lower column == y_lower_m")
    above = np.arange(n + 1)[None, :] > bay[:, None]
    gaps = np.diff(Y, axis=1)  # gaps[:, k-1] = y_k - y_{k-1}
    locked = above[:, 1:]
    check(np.max(np.abs(gaps[locked] - 2 * l_s)) < 1e-12, "locked frames 2 l_s apart")
    check(np.all(Y[bay > 1, 0] == 0.0), "frame 0 on the floor before bay 1's stage")
    check(Y[-1, 0] > 0.1, "frame 0 lifted by bay 1's rail at the end")
    with h5py.File(held, "r") as f:
        check("frame_height_m" not in f["history"], "held stack: no frame_height_m")

    # 2. The figure's lines are the file's columns.
    sys.path.insert(0, os.path.join(a.root, "postproc"))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from truss_report.page.figures_run import fig_frame_heights
    from truss_report.reading.run import load_run
    run = load_run(free)
    fig = fig_frame_heights(plt, run)
    top, bottom = fig.axes[0], fig.axes[1]
    check([ln.get_label() for ln in top.lines[:n + 1]] == [f"frame {k}" for k in range(n + 1)],
          "top panel: one line per frame, frames 0..n first (then the lock markers)")
    ok_top = all(np.array_equal(top.lines[k].get_xdata(), t) and np.array_equal(top.lines[k].get_ydata(), Y[:, k])
                 for k in range(n + 1))
    check(ok_top, "top panel: frame k's line is column k of the file")
    ok_bottom = True
    for k in range(n + 1):
        yb = np.asarray(bottom.lines[k].get_ydata(), dtype=float)
        shown = k < bay
        ok_bottom &= np.array_equal(yb[shown], Y[shown, k]) and bool(np.all(np.isnan(yb[~shown])))
    check(ok_bottom, "bottom panel: frame k shown exactly while k < bay")
    check("m" in top.get_ylabel() and "s" in bottom.get_xlabel(), "axes carry units")
    # The key: a colour bar of the frame index whose colour at k is frame k's line colour.
    bars = [ax for ax in fig.axes[2:] if "frame index" in ax.get_ylabel()]
    cmap = plt.get_cmap("viridis")
    colours = all(np.allclose(matplotlib.colors.to_rgba(top.lines[k].get_color()), cmap(k / n))
                  for k in range(n + 1))
    check(len(bars) == 1 and colours, "key: a colour bar of the frame index, frame k's line in its colour")
    plt.close(fig)

    # 3. Command line and report.
    out = os.path.join(a.scratch, "figs_free")
    r = subprocess.run([sys.executable, os.path.join(a.root, "postproc", "run_figures.py"), free, "-o", out, "--force"],
                       capture_output=True, text=True)
    png = os.path.join(out, "frame_heights.png")
    check(r.returncode == 0 and os.path.exists(png) and open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n",
          "run_figures.py writes frame_heights.png for the free stack")
    out_h = os.path.join(a.scratch, "figs_held")
    r = subprocess.run([sys.executable, os.path.join(a.root, "postproc", "run_figures.py"), held, "-o", out_h, "--force"],
                       capture_output=True, text=True)
    check(r.returncode == 0 and not os.path.exists(os.path.join(out_h, "frame_heights.png")),
          "run_figures.py: no frame_heights.png for the held stack")
    rep = os.path.join(a.scratch, "report_free")
    r = subprocess.run([sys.executable, os.path.join(a.root, "postproc", "report.py"), free, "-o", rep, "--force"],
                       capture_output=True, text=True)
    html = ""
    for name in os.listdir(rep) if os.path.isdir(rep) else []:
        if name.endswith(".html"):
            html += open(os.path.join(rep, name)).read()
    check(r.returncode == 0 and 'src="frame_heights.png"' in html and os.path.exists(os.path.join(rep, "frame_heights.png")),
          "single-run report shows frame_heights.png")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
