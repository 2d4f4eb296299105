#!/usr/bin/python3
"""Figures of one simulated run: the paper's Fig. 4 and Fig. 5.

Usage:
    /usr/bin/python3 postproc/run_figures.py RUN.h5 -o OUTDIR [--bay N] [--force]

RUN.h5 is a single-run file written by `truss-sim -o RUN.h5` (schema_version 1) with time
histories (`run.output_step_s > 0`). Writes into OUTDIR (created if needed):

    fig4_hinge_trajectory_bay<N>.png  mid-hinge trajectory of bay N in its stage (paper Fig. 4),
                                      with the guide-rail line and the rail entry point
    fig5_drive_and_pin_force.png      drive force and rail pin force over the whole run
                                      (paper Fig. 5), lock times as faint vertical lines
    fig5_bay<N>_zoom.png              the same two quantities in the stage of bay N
    frame_heights.png                 free stack only (/history/frame_height_m): the heights of
                                      the frames against time, the lower frames included

N defaults to the top bay (n_bays), the one the paper plots. The paths written are printed,
one per line. Any problem with the input (missing file, not HDF5, wrong schema_version, no
/history, --bay out of range, an existing PNG without --force) prints one line starting with
`error:` on stderr, exits with code 2 and writes nothing.

Needs numpy, h5py and matplotlib (Debian: python3-numpy python3-h5py python3-matplotlib) and
Python >= 3.11 (tomllib).
"""
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend)
import numpy as np  # noqa: E402

from truss_report.argparser import ArgParser  # noqa: E402
from truss_report.page.figures_run import fig4, fig5, fig5_zoom, fig_frame_heights  # noqa: E402
from truss_report.reading.h5file import EXIT_INPUT_ERROR, InputError  # noqa: E402
from truss_report.reading.run import load_run  # noqa: E402


def main(argv=None):
    p = ArgParser(
        prog="run_figures.py",
        description="Paper Fig. 4 and Fig. 5 from a single-run truss-sim HDF5 file.")
    p.add_argument("run", metavar="RUN.h5", help="single-run file from `truss-sim -o RUN.h5`")
    p.add_argument("-o", "--outdir", required=True, metavar="OUTDIR",
                   help="directory for the PNGs (created if needed)")
    p.add_argument("--bay", type=int, default=None, metavar="N",
                   help="bay for the trajectory and the zoom (default: the top bay, n_bays)")
    p.add_argument("--force", action="store_true", help="overwrite existing PNGs")
    args = p.parse_args(argv)

    try:
        run = load_run(args.run)
        n = run.n_bays
        bay = n if args.bay is None else args.bay
        if not 1 <= bay <= n:
            raise InputError(f"--bay {bay} is out of range: the run has bays 1..{n}")
        if not np.any(run.history["bay"] == bay):
            raise InputError(
                f"/history has no samples of bay {bay}'s stage (the run did not reach it"
                + (f"; status {run.status}" if run.status else "") + ")")
        h = run.history
        sel = h["bay"] == bay
        if not np.any(np.isfinite(h["hinge_x_m"][sel]) & np.isfinite(h["hinge_y_m"][sel])):
            raise InputError(f"/history has no finite hinge position in bay {bay}'s stage")

        outdir = args.outdir
        if os.path.exists(outdir) and not os.path.isdir(outdir):
            raise InputError(f"output path {outdir} exists and is not a directory")
        names = [f"fig4_hinge_trajectory_bay{bay}.png",
                 "fig5_drive_and_pin_force.png",
                 f"fig5_bay{bay}_zoom.png"]
        if "frame_height_m" in h:
            names.append("frame_heights.png")
        targets = [os.path.join(outdir, nm) for nm in names]
        if not args.force:
            for tpath in targets:
                if os.path.exists(tpath):
                    raise InputError(f"{tpath} exists; use --force to overwrite")
    except InputError as e:
        sys.stderr.write(f"error: {e}\n")
        return EXIT_INPUT_ERROR

    figs = [fig4(plt, run, bay), fig5(plt, run), fig5_zoom(plt, run, bay)]
    if "frame_height_m" in run.history:
        figs.append(fig_frame_heights(plt, run))

    # Render every figure to a temporary file first, then move all into place: a failure
    # while rendering leaves no partial set of PNGs behind.
    os.makedirs(outdir, exist_ok=True)
    temps = []
    try:
        for fig, tpath in zip(figs, targets):
            tmp = os.path.join(outdir, f".{os.path.basename(tpath)}.{os.getpid()}.tmp")
            temps.append(tmp)
            fig.savefig(tmp, format="png", dpi=130)
            plt.close(fig)
        for tmp, tpath in zip(temps, targets):
            os.replace(tmp, tpath)
    finally:
        for tmp in temps:
            if os.path.exists(tmp):
                os.remove(tmp)
    for tpath in targets:
        print(tpath)
    return 0


if __name__ == "__main__":
    sys.exit(main())
