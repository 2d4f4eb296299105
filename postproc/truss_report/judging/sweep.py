"""truss_report.judging.sweep: the verdict of a design sweep. The file's /sweep/allowable holds the
verdict truss-campaign decided and its reason (the design's own value on the safe or the unsafe side
of the allowable; NOT ASSESSED without an allowable or when an estimate it would rest on is
untrusted: a plateau of the margin, too many unusable runs); the report displays it, it does not
decide it."""
from __future__ import annotations

import pandas as pd

from ..reading.methods import SweepTable
from .subset import biased_low, count_plateau_levels
from .verdict import FAIL, NOT_ASSESSED, PASS


def sweep_frame(t: SweepTable) -> pd.DataFrame:
    """The per-value table with `plateau_levels`: the levels of the value's subset simulation on a
    plateau of the margin (count_plateau_levels; 0 for the other methods)."""
    df = t.table.copy()
    df.attrs = t.table.attrs
    df["plateau_levels"] = [count_plateau_levels(b.tolist()) if b is not None else 0 for b in t.level_thresholds]
    df.attrs["units"]["plateau_levels"] = "1"
    return df


def flat_values(s: pd.DataFrame) -> list[int]:
    """Rows whose subset estimate crossed a plateau of the margin (may be biased low)."""
    return [k for k, n in enumerate(s["plateau_levels"]) if biased_low(int(n))]


def sweep_verdict(s: pd.DataFrame) -> str:
    """PASS, FAIL or NOT_ASSESSED of a sweep (its table from sweep_frame): the file's."""
    v = str(s.attrs["allowable"].get("verdict", ""))
    return PASS if v == "PASS" else FAIL if v == "FAIL" else NOT_ASSESSED


def sweep_reason(s: pd.DataFrame) -> str:
    """The file's reason for its verdict (the allowable's message in a file without one)."""
    a = s.attrs["allowable"]
    return str(a.get("reason", "") or a.get("message", ""))
