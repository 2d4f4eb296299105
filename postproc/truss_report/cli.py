"""truss_report.cli: see the package docstring (postproc/truss_report/__init__.py)."""
import os
import shutil
import sys
import tempfile
import warnings

import run_figures as rf
from run_figures import InputError
from .constants import CONFIDENCE, EXIT_INPUT_ERROR, REPORT_NAME
from .extras import load_extras
from .h5read import H5, file_sha256, load_campaign, load_single_run, read_kind
from .mechanism import DEFAULT_INERTIA, DEFAULT_MF, DEFAULT_UNCERTAINTY
from .page import Page
from .sections_design import campaign_report
from .single_run import single_run_report

CSV_NAME = "runs.csv"


def check_outdir(outdir, force):
    if os.path.exists(outdir):
        if not os.path.isdir(outdir):
            raise InputError(f"{outdir}: exists and is not a directory")
        if os.listdir(outdir) and not force:
            raise InputError(f"{outdir}: directory is not empty; use --force to write into it")


def build(path, outdir, force, opts=None):
    """Validate, then render into a staging directory beside OUTDIR and move the files in."""
    opts = opts or parse_args([path, "-o", outdir])
    check_outdir(outdir, force)
    sha256 = file_sha256(path) if os.path.isfile(path) else ""
    with rf.open_h5(path) as f:
        h5 = H5(f, path)
        try:
            kind = read_kind(h5)
            data = load_campaign(h5, sha256) if kind == "campaign" else load_single_run(h5, sha256)
            extras = load_extras(h5, data) if kind == "campaign" else None
        except (OSError, RuntimeError) as e:
            raise InputError(f"{path}: damaged or unreadable HDF5 file ({e})") from None

        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        parent = os.path.dirname(os.path.abspath(outdir))
        os.makedirs(parent, exist_ok=True)
        staging = tempfile.mkdtemp(prefix=f".{os.path.basename(outdir)}.", dir=parent)
        try:
            page = Page(staging, plt)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                text = (campaign_report(page, data, extras, opts) if kind == "campaign"
                        else single_run_report(page, data))
            if kind == "campaign" and opts.csv:
                from .dataframe import read_campaign, write_tabular
                write_tabular(read_campaign(path), os.path.join(staging, CSV_NAME))
                page.files.append(CSV_NAME)
            with open(os.path.join(staging, REPORT_NAME), "w", encoding="utf-8") as fh:
                fh.write(text)
            os.makedirs(outdir, exist_ok=True)
            for name in page.files + [REPORT_NAME]:   # report.html last
                os.replace(os.path.join(staging, name), os.path.join(outdir, name))
        finally:
            shutil.rmtree(staging, ignore_errors=True)
    return os.path.join(outdir, REPORT_NAME)


def parse_args(argv=None):
    p = rf._Parser(prog="truss-report",
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
    p.add_argument("--motorisation-factor", type=float, default=DEFAULT_MF, metavar="MF",
                   help="required motorisation factor (ECSS-E-ST-33-01C clause 4.7.5.3.1; "
                        f"default {DEFAULT_MF})")
    p.add_argument("--uncertainty-factor", type=float, default=DEFAULT_UNCERTAINTY, metavar="K",
                   help="uncertainty factor on the simulated spring resistance (default "
                        f"{DEFAULT_UNCERTAINTY}: Table 4-2 of the standard, spring)")
    p.add_argument("--inertia-factor", type=float, default=DEFAULT_INERTIA, metavar="KD",
                   help="factor on the inertial resistance torque T_D, velocity drive (default "
                        f"{DEFAULT_INERTIA}: clause 4.7.5.3.1)")
    p.add_argument("--revision", default="draft", help="revision shown in the sign-off block")
    p.add_argument("--csv", action="store_true",
                   help=f"also write DIR/{CSV_NAME}: the run table, Dakota-style tabular (campaigns)")
    a = p.parse_args(argv)
    if not 0.0 < a.confidence < 1.0:
        p.error(f"--confidence {a.confidence}: must be between 0 and 1 (exclusive)")
    try:
        a.levels = sorted(float(v) for v in a.levels.split(","))
    except ValueError:
        p.error(f"--levels {a.levels}: not a comma-separated list of numbers")
    if not all(0.0 < v < 100.0 for v in a.levels):
        p.error(f"--levels: every level must be between 0 and 100 (exclusive), got {a.levels}")
    if not (a.motorisation_factor > 0 and a.uncertainty_factor > 0 and a.inertia_factor > 0):
        p.error("--motorisation-factor, --uncertainty-factor and --inertia-factor must be positive")
    return a


def main(argv=None):
    args = parse_args(argv)
    try:
        print(build(args.results, args.outdir, args.force, args))
    except InputError as e:
        sys.stderr.write(f"error: {e}\n")
        return EXIT_INPUT_ERROR
    return 0
