"""truss_report.cli: the report's command line (postproc/report.py, truss-report): the output
directory, reading -> judging -> page, the staging directory, the PDF, the exit status."""
import multiprocessing
import os
import shutil
import sys
import tempfile
import time
import warnings

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend)

from .argparser import ArgParser  # noqa: E402
from .judging.campaign import JudgeOptions, judge_campaign  # noqa: E402
from .judging.mechanism import compute_margins  # noqa: E402
from .judging.motor_answer import calc_motor_answer, scene_differences, sizing_problem  # noqa: E402
from .judging.stats import CONFIDENCE  # noqa: E402
from .judging.sweep import sweep_frame  # noqa: E402
from .judging.verdict import EXIT_STATUS  # noqa: E402
from .page import pdf  # noqa: E402
from .page.render import Page, find_background_niceness  # noqa: E402
from .page.run_table import write_run_table  # noqa: E402
from .page.sections_design import campaign_report, section_nominal  # noqa: E402
from .page.sections_importance import importance_report  # noqa: E402
from .page.sections_subset import subset_report  # noqa: E402
from .page.sections_sweep import sweep_report  # noqa: E402
from .page.single_run import single_run_report  # noqa: E402
from .reading.campaign import load_campaign  # noqa: E402
from .reading.extras import load_extras  # noqa: E402
from .reading.frame import read_campaign  # noqa: E402
from .reading.importance import Importance, read_importance  # noqa: E402
from .reading.h5file import EXIT_INPUT_ERROR, H5, InputError, file_sha256, open_h5, read_kind  # noqa: E402
from .reading.methods import read_method_groups  # noqa: E402
from .reading.run import load_single_run  # noqa: E402

REPORT_NAME = "report.html"
EXIT_VERDICT = EXIT_STATUS     # by the verdict (judging.verdict; postproc/report.py's docstring)

CSV_NAME = "runs.csv"
PDF_NAME = "report.pdf"


def check_outdir(outdir, force):
    if os.path.exists(outdir):
        if not os.path.isdir(outdir):
            raise InputError(f"{outdir}: exists and is not a directory")
        if os.listdir(outdir) and not force:
            raise InputError(f"{outdir}: directory is not empty; use --force to write into it")


# Text in the figures: 10 pt (9 pt ticks and keys). A figure row is at most 15 inches at 110 dpi
# (1650 px) and shows at about 0.85 of that on a 1400-pixel page: 9 pt is still about 11 px.
FIGURE_STYLE = {"font.size": 10, "axes.titlesize": 10, "axes.labelsize": 10, "legend.fontsize": 9,
                "xtick.labelsize": 9, "ytick.labelsize": 9, "figure.titlesize": 11,
                "axes.formatter.useoffset": False}   # ticks show the values, never "1e-6+145.06"


class Progress:
    """'[report] ...' lines on stderr with the time since the start (silent until the input is
    read and checked: a refused input gets its one error line only)."""

    def __init__(self, quiet=False):
        self.t0, self.quiet, self.clock = time.monotonic(), quiet, time.monotonic

    def __call__(self, what):
        if not self.quiet:
            sys.stderr.write(f"[report] {what} ({self.clock() - self.t0:.1f} s)\n")
            sys.stderr.flush()


def _write_csv(path, out, niceness):
    """Child process: the run table as CSV at `niceness` (exit 1 on any error, said on stderr)."""
    try:
        os.nice(niceness)
        write_run_table(read_campaign(path, columns="all"), out)
    except Exception as e:       # noqa: BLE001 - reported by the parent as a failed CSV
        sys.stderr.write(f"error: {out}: {e}\n")
        os._exit(1)
    os._exit(0)


def start_csv(path, staging, niceness):
    """Writes DIR/runs.csv in a child process while this one draws the report (formatting six
    million numbers is the report's largest single cost). Forked before this process opens the
    HDF5 file (the child opens its own)."""
    proc = multiprocessing.get_context("fork").Process(
        target=_write_csv, args=(path, os.path.join(staging, CSV_NAME), niceness), daemon=True)
    proc.start()
    return proc


def write_pdf(staging, page, progress):
    """DIR/report.pdf from DIR/report.html (page.pdf: A4, page numbers, the figures' PNG files;
    laid out while the page's figures are still being drawn)."""
    progress(f"writing {PDF_NAME}")
    try:
        pdf.write_pdf(os.path.join(staging, REPORT_NAME), os.path.join(staging, PDF_NAME), page.find_size,
                      page.finish)
    except ImportError:
        raise InputError("the PDF needs WeasyPrint (Debian: apt-get install weasyprint); "
                         "--no-pdf writes the HTML only") from None


def read_file(path, kind, sha256):
    """Everything the report shows, read and checked (InputError on a damaged file): (Campaign or
    single run, the rare-event estimate (/importance's or /subset's, or None), /sweep, Extras)."""
    with open_h5(path) as f:
        h5 = H5(f, path)
        try:
            if kind != "campaign":
                return load_single_run(h5, sha256), None, None, None
            c = load_campaign(h5, sha256)
            importance = read_importance(h5)   # a standalone importance campaign: its estimate is the report
            subset, sweep = read_method_groups(h5)
            return c, importance or subset, sweep, load_extras(h5, c)
        except (OSError, RuntimeError) as e:
            raise InputError(f"{path}: damaged or unreadable HDF5 file ({e})") from None


def read_other(path, kind, data, rare, sweep):
    """The file of --compare-with, read and checked against this one: a load report pairs with a
    motor-sizing sweep of the same mast and a motor-sizing sweep with a load report's campaign
    (judging.motor_answer). Returns (load-report Campaign, its Extras, sweep Campaign, sweep table);
    InputError naming the file when they cannot be paired."""
    if kind != "campaign" or (rare is not None and sweep is None):
        raise InputError(f"{path}: --compare-with pairs a load report with a motor-sizing sweep; this report "
                         "(a single run, a subset or an importance-sampling campaign) states no stall torque")
    sha256 = file_sha256(path) if os.path.isfile(path) else ""
    with open_h5(path) as f:
        other_kind = read_kind(H5(f, path))
    if other_kind != "campaign":
        raise InputError(f"{path}: --compare-with needs a campaign file, not a {other_kind.replace('_', ' ')} file")
    c, o_rare, o_sweep, e = read_file(path, other_kind, sha256)
    if sweep is not None:
        if o_sweep is not None or o_rare is not None:
            raise InputError(f"{path}: --compare-with of a sweep needs a load report's campaign (Monte Carlo or "
                             "Latin hypercube runs, no [sweep], no subset or importance sampling)")
        load, load_e, sizing, s = c, e, data, sweep_frame(sweep)
    else:
        if o_sweep is None:
            raise InputError(f"{path}: --compare-with of a load report needs a motor-sizing sweep (a [sweep] of "
                             "drive.stall_torque_Nm); this file has no /sweep")
        load, load_e, sizing, s = data, None, c, sweep_frame(o_sweep)
    problem = sizing_problem(s)
    if problem:
        raise InputError(f"{sizing.path}: not a motor-sizing sweep: {problem}")
    diffs, _ = scene_differences(load, sizing, str(s.attrs["variable"]))
    if diffs:
        shown = "; ".join(f"{k} = {a!r} in {os.path.basename(load.path)}, {b!r} in {os.path.basename(sizing.path)}"
                          for k, a, b in diffs[:4])
        raise InputError(f"{path}: not the same mast as {data.path}: the base scenes differ in {len(diffs)} "
                         f"key(s): {shown}")
    return load, load_e, sizing, s


def render(page, kind, data, rare, sweep, extras, opts, other=None):
    """The Report of what read_file gave: judged, then drawn (rare: the rare-event estimate, an
    Importance or a subset simulation's; other: read_other's, or None)."""
    replaced = any(v is not None for v in (opts.motorisation_factor, opts.uncertainty_factor, opts.inertia_factor))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        if kind != "campaign":
            return single_run_report(page, data)
        if sweep is not None:  # runs of one campaign per design value: no design loads
            s, answer = sweep_frame(sweep), None
            if other is not None:
                load, load_e = other[0], other[1]
                m = compute_margins(load, load_e, opts.motorisation_factor, opts.uncertainty_factor,
                                    opts.inertia_factor, opts.levels[-1], opts.confidence)
                answer = calc_motor_answer(load, m, data, s, replaced)
            return sweep_report(page, data, s, opts.revision, section_nominal(page, extras), answer)
        if isinstance(rare, Importance):  # draws of a density moved to the failure: no design loads
            return importance_report(data, rare, opts.revision, section_nominal(page, extras))
        if rare is not None:  # subset simulation's levels: the runs are not draws, no design loads
            return subset_report(page, data, rare, opts.revision, section_nominal(page, extras))
        j = judge_campaign(data, extras, JudgeOptions(opts.levels, opts.confidence, opts.motorisation_factor,
                                                      opts.uncertainty_factor, opts.inertia_factor))
        answer = calc_motor_answer(data, j.margins, other[2], other[3], replaced) if other is not None else None
        return campaign_report(page, data, extras, j, opts, answer)


def build(path, outdir, force, opts=None, progress=None):
    """Validate, then render into a staging directory beside OUTDIR and move the files in.
    Returns (path of report.html, the verdict's lines for the terminal: empty for a single run,
    the verdict: "pass", "fail", "not_assessed", or None for a report without one)."""
    opts = opts or parse_args([path, "-o", outdir])
    progress = progress or Progress(quiet=True)
    check_outdir(outdir, force)
    sha256 = file_sha256(path) if os.path.isfile(path) else ""
    with open_h5(path) as f:
        kind = read_kind(H5(f, path))
    parent = os.path.dirname(os.path.abspath(outdir))
    os.makedirs(parent, exist_ok=True)
    staging = tempfile.mkdtemp(prefix=f".{os.path.basename(outdir)}.", dir=parent)
    # The children yield to a main chain of its own length, the PDF's (before the first child:
    # the machine's load, not the report's).
    niceness = find_background_niceness() if opts.pdf else 0
    csv = start_csv(path, staging, niceness) if kind == "campaign" and opts.csv else None
    try:
        data, rare, sweep, extras = read_file(path, kind, sha256)
        other = read_other(opts.compare_with, kind, data, rare, sweep) if opts.compare_with else None
        progress(f"{path}: {kind.replace('_', ' ')}"
                 + (f", {data.n} runs" if kind == "campaign" else "") + ", read and checked"
                 + (f"; writing {CSV_NAME} beside" if csv else ""))
        plt.rcParams.update(FIGURE_STYLE)
        page = Page(staging, plt, progress, niceness)
        report = render(page, kind, data, rare, sweep, extras, opts, other)
        with open(os.path.join(staging, REPORT_NAME), "w", encoding="utf-8") as fh:
            fh.write(report.html)
        if opts.pdf:   # laid out while the figures are drawn
            write_pdf(staging, page, progress)
            page.files.append(PDF_NAME)
        page.finish()
        if csv is not None:
            csv.join()
            if csv.exitcode != 0:
                raise RuntimeError(f"writing {CSV_NAME} failed (exit {csv.exitcode})")
            page.files.append(CSV_NAME)
        os.makedirs(outdir, exist_ok=True)
        for name in page.files + [REPORT_NAME]:   # report.html last
            os.replace(os.path.join(staging, name), os.path.join(outdir, name))
    finally:
        if csv is not None and csv.is_alive():
            csv.terminate()
        shutil.rmtree(staging, ignore_errors=True)
    return os.path.join(outdir, REPORT_NAME), report.summary, report.verdict


def parse_args(argv=None):
    p = ArgParser(prog="truss-report",
                   description="Load report (HTML + PNG) of a truss-campaign file, with the "
                               "verdict and the design loads on top, or the report of a "
                               "truss-sim single-run file.")
    p.add_argument("results", metavar="RESULTS.h5", help="campaign or single-run HDF5 file")
    p.add_argument("-o", "--outdir", required=True, metavar="DIR",
                   help="output directory: new or empty, unless --force")
    p.add_argument("--force", action="store_true",
                   help="write into a non-empty DIR, replacing files of the same names")
    p.add_argument("--confidence", type=float, default=CONFIDENCE, metavar="C",
                   help=f"confidence of the one-sided upper bounds, 0 < C < 1 (default {CONFIDENCE})")
    p.add_argument("--levels", default="99.865", metavar="P[,P...]",
                   help="percentile levels of the design-load table, in percent, 0 < P < 100 "
                        "(default 99.865: the one-sided 3-sigma level)")
    p.add_argument("--motorisation-factor", type=float, default=None, metavar="MF",
                   help="required motorisation factor (ECSS-E-ST-33-01C clause 4.7.5.3.1; default: the "
                        "scene's motorisation.factor, with which the simulator computed the check)")
    p.add_argument("--uncertainty-factor", type=float, default=None, metavar="K",
                   help="uncertainty factor on the spring resistance (default: the scene's "
                        "motorisation.spring_factor)")
    p.add_argument("--inertia-factor", type=float, default=None, metavar="KD",
                   help="factor on the inertial resistance torque T_D, velocity drive (default: the "
                        "scene's motorisation.inertia_factor)")
    p.add_argument("--compare-with", metavar="OTHER.h5", default=None,
                   help="the other campaign of the motor answer: for a load report the motor-sizing sweep's file, "
                        "for a motor-sizing sweep a load report's campaign file, of the same mast; both stall "
                        "torques are shown with which one governs")
    p.add_argument("--revision", default="draft", help="revision shown in the sign-off block")
    p.add_argument("--csv", action="store_true",
                   help=f"also write DIR/{CSV_NAME}: the run table, one row per run (campaigns)")
    p.add_argument("--no-pdf", dest="pdf", action="store_false",
                   help=f"do not write DIR/{PDF_NAME} (the report for signature, A4, numbered pages)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress lines on stderr (errors and the verdict are still printed)")
    a = p.parse_args(argv)
    if not 0.0 < a.confidence < 1.0:
        p.error(f"--confidence {a.confidence}: must be between 0 and 1 (exclusive)")
    try:
        a.levels = sorted(float(v) for v in a.levels.split(","))
    except ValueError:
        p.error(f"--levels {a.levels}: not a comma-separated list of numbers")
    if not all(0.0 < v < 100.0 for v in a.levels):
        p.error(f"--levels: every level must be between 0 and 100 (exclusive), got {a.levels}")
    if any(v is not None and not v > 0 for v in (a.motorisation_factor, a.uncertainty_factor, a.inertia_factor)):
        p.error("--motorisation-factor, --uncertainty-factor and --inertia-factor must be positive")
    return a


def main(argv=None):
    args = parse_args(argv)
    progress = Progress(quiet=args.quiet)
    try:
        report, summary, verdict = build(args.results, args.outdir, args.force, args, progress)
    except InputError as e:
        sys.stderr.write(f"error: {e}\n")
        return EXIT_INPUT_ERROR
    progress(f"written: {report}")
    for line in summary:
        print(line)
    print(report)
    return EXIT_VERDICT.get(verdict, 0)
