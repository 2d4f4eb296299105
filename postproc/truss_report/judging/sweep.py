"""truss_report.judging.sweep: the verdict of a design sweep. The file's /sweep/allowable holds the
verdict C++ decided (the design's own value on the safe or the unsafe side of the allowable, or no
allowable in the swept range); the report overrides it in one place, plateau_override: a PASS
resting on an estimate that may be biased low (a plateau of the margin) is NOT ASSESSED."""
from __future__ import annotations

from collections.abc import Sequence

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


def plateau_override(file_verdict: str, flat: Sequence[int]) -> str:
    """The report's one override of the file's verdict: a PASS with a value whose estimate may be
    biased low is NOT_ASSESSED (an estimate below the true p moves the allowable to the unsafe
    side); a FAIL stays a FAIL. Returns PASS, FAIL or NOT_ASSESSED."""
    if file_verdict == "PASS" and flat:
        return NOT_ASSESSED
    return PASS if file_verdict == "PASS" else FAIL if file_verdict == "FAIL" else NOT_ASSESSED


def sweep_verdict(s: pd.DataFrame) -> str:
    """PASS, FAIL or NOT_ASSESSED of a sweep (its table from sweep_frame)."""
    return plateau_override(str(s.attrs["allowable"].get("verdict", "")), flat_values(s))
