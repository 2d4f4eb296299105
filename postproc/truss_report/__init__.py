"""truss_report: the statistical load report of a truss-campaign results file, and the report of
a single run (postproc/report.py is its command line), in three layers, each importing only the
ones before it:

    reading   typed readers of the HDF5 files (h5file, run, campaign, extras, methods, frame)
    judging   statistics, design loads, mechanism margins, consistency checks, verdicts
    page      sections, figures, units on the page, HTML, the run table as CSV

cli (the command line: reading -> judging -> page, the PDF) and argparser sit on top.

    from truss_report import read_campaign, read_sweep
"""
from collections.abc import Sequence

import pandas as pd

from .judging.sweep import sweep_frame
from .reading.frame import read_campaign as _read_campaign
from .reading.methods import read_sweep_table

__all__ = ["read_campaign", "read_sweep"]


def read_campaign(path: str, columns: str | Sequence[str] | None = None) -> pd.DataFrame:
    """A campaign file as a pandas DataFrame, one row per run: the per-run columns, and the per-bay
    ones named in `columns` (or all with columns="all"; truss_report.reading.frame.read_campaign);
    a design sweep's per-value table (read_sweep) in df.attrs["sweep"]."""
    df = _read_campaign(path, columns)
    sweep = read_sweep(path)
    if sweep is not None:
        df.attrs["sweep"] = sweep
    return df


def read_sweep(path: str) -> pd.DataFrame | None:
    """A design sweep's /sweep as a pandas DataFrame, one row per design value: value (the design
    value), p, cov, upper_bound (one-sided, at the confidence), lower and upper (two-sided
    interval), runs, failures (Monte Carlo's count; -1 for subset simulation), master_seed (of the
    value's standalone campaign), index (the design value's index k: /sweep/inner/<k>), refinement
    (True for a value the refinement placed inside the bracket of the listed values' allowable),
    status, message, plateau_levels (subset simulation's levels on a plateau of the margin; 0 for
    the other methods). df.attrs: the /sweep attributes (variable, target_probability, confidence,
    inner_method, failure event; the design variable's unit as design_units), "units" per column,
    and "allowable" (a dict: status, value, estimate, lower, upper, own_value, safe_side, verdict,
    message, method). None when the file has no /sweep."""
    t = read_sweep_table(path)
    return sweep_frame(t) if t is not None else None
