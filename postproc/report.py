#!/usr/bin/python3
"""Statistical load report of a truss-campaign results file, or the report of a single run.

Usage:
    /usr/bin/python3 postproc/report.py RESULTS.h5 -o DIR [--force]

RESULTS.h5 is a campaign file (`truss-campaign -o RESULTS.h5`, kind "campaign") or a single-run
file (`truss-sim -o RUN.h5`, kind "single_run"), schema_version 1 (docs/hdf5-schema.md). Writes
DIR/report.html, one self-contained HTML page, with its PNG figures beside it (relative links).
DIR must be new or empty unless --force is given (then files of the same names are replaced,
other files are left alone). The path of the report is printed.

DIR/report.pdf is the same report for signature (A4, numbered pages; WeasyPrint; --no-pdf skips it).
Both begin with the document block: campaign, tool version, date, the results file's name and
SHA-256, the verdict.

Exit codes: 0 report written, verdict PASS (or a report without a verdict: a single run, a
subset campaign); 3 report written, verdict FAIL (the evidence violates a requirement); 4 report
written, verdict NOT ASSESSED (nothing fails, but the runs cannot decide every requirement, e.g.
too few runs for the design level); 2 bad input (not an HDF5 file, damaged or truncated file, wrong
kind or schema_version, a missing or malformed required dataset, an output directory that is
not empty): one line `error: FILE: what is wrong` on stderr and nothing written.

Every number in a table carries `data-key` (a stable name) and `data-value` (the float64 value,
Python repr) attributes; the visible text is rounded. docs/report.md describes the content and
the statistical methods.

The code is the package truss_report/ beside this file (reading -> judging -> page).

Needs numpy, scipy, h5py, matplotlib and WeasyPrint (Debian: python3-numpy python3-scipy
python3-h5py python3-matplotlib weasyprint) and Python >= 3.11.
"""
import sys

from truss_report.cli import main  # the package beside this file

if __name__ == "__main__":
    sys.exit(main())
