"""truss_report.cli: see the package docstring (postproc/truss_report/__init__.py)."""
import os
import shutil
import sys
import tempfile
import warnings

import run_figures as rf
from run_figures import InputError
from .constants import EXIT_INPUT_ERROR, REPORT_NAME
from .h5read import H5, file_sha256, load_campaign, load_single_run, read_kind
from .page import Page
from .sections_margins import campaign_report
from .single_run import single_run_report


def check_outdir(outdir, force):
    if os.path.exists(outdir):
        if not os.path.isdir(outdir):
            raise InputError(f"{outdir}: exists and is not a directory")
        if os.listdir(outdir) and not force:
            raise InputError(f"{outdir}: directory is not empty; use --force to write into it")


def build(path, outdir, force):
    """Validate, then render into a staging directory beside OUTDIR and move the files in."""
    check_outdir(outdir, force)
    sha256 = file_sha256(path) if os.path.isfile(path) else ""
    with rf.open_h5(path) as f:
        h5 = H5(f, path)
        try:
            kind = read_kind(h5)
            data = load_campaign(h5, sha256) if kind == "campaign" else load_single_run(h5, sha256)
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
                text = (campaign_report(page, data) if kind == "campaign"
                        else single_run_report(page, data))
            with open(os.path.join(staging, REPORT_NAME), "w", encoding="utf-8") as fh:
                fh.write(text)
            os.makedirs(outdir, exist_ok=True)
            for name in page.files + [REPORT_NAME]:   # report.html last
                os.replace(os.path.join(staging, name), os.path.join(outdir, name))
        finally:
            shutil.rmtree(staging, ignore_errors=True)
    return os.path.join(outdir, REPORT_NAME)


def main(argv=None):
    p = rf._Parser(prog="report.py",
                   description="Statistical load report (HTML + PNG) of a truss-campaign file, "
                               "or the report of a truss-sim single-run file.")
    p.add_argument("results", metavar="RESULTS.h5", help="campaign or single-run HDF5 file")
    p.add_argument("-o", "--outdir", required=True, metavar="DIR",
                   help="output directory: new or empty, unless --force")
    p.add_argument("--force", action="store_true",
                   help="write into a non-empty DIR, replacing files of the same names")
    args = p.parse_args(argv)
    try:
        print(build(args.results, args.outdir, args.force))
    except InputError as e:
        sys.stderr.write(f"error: {e}\n")
        return EXIT_INPUT_ERROR
    return 0
