"""truss_report: the statistical load report of a truss-campaign results file, and the report of
a single run (postproc/report.py is its command line).

Modules:
    constants          reported outputs, percentile levels, limits
    h5read             reading and checking the HDF5 files (campaign and single run)
    stats              percentiles, order-statistic intervals, Clopper-Pearson, Spearman, checks
    page               HTML building: numbers with data-key, tables, the page, CSS
    figures            matplotlib figures
    sections_campaign  campaign, status, failures, dispersions, loads, lock timing sections
    sections_margins   margins, sensitivity, histories, consistency checks; the campaign report
    sections_sweep     a design sweep's report (/sweep): p against the design value, the allowable
    single_run         the single-run report (paper Fig. 4 and 5)
    cli                output directory handling, build(), main()
"""
import os
import sys

# run_figures.py (paper figures, HDF5 text helpers) lives beside this package.
_HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if _HERE not in sys.path:
    sys.path.insert(0, _HERE)


def read_campaign(path):
    """A campaign file as a pandas DataFrame (truss_report.dataframe.read_campaign); a design
    sweep's per-value table (read_sweep) in df.attrs["sweep"]."""
    from .dataframe import read_campaign as _read
    from .sections_sweep import read_sweep as _sweep
    df = _read(path)
    sweep = _sweep(path)
    if sweep is not None:
        df.attrs["sweep"] = sweep
    return df


def read_sweep(path):
    """A design sweep's /sweep as a pandas DataFrame, one row per design value, the allowable in
    df.attrs["allowable"] (truss_report.sections_sweep.read_sweep); None without a sweep."""
    from .sections_sweep import read_sweep as _read
    return _read(path)
