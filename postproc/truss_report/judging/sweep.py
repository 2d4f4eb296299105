"""truss_report.judging.sweep: the verdict of a design sweep. The file's /sweep/allowable holds the
verdict truss-campaign decided and its reason (the design's own value on the safe or the unsafe side
of the allowable; NOT ASSESSED without an allowable or when an estimate it would rest on is
untrusted: a plateau of the margin, more than 1 % of a value's runs without a usable result). The
report displays it; it does not decide it. It checks it: a PASS or a FAIL the numbers of the file do
not support (a file not written by truss-campaign, or damaged) is shown NOT ASSESSED with why:
  - a PASS or a FAIL needs an allowable that was found and is a number, the design's own value as a
    number, an estimate at some design value, and the side the file's verdict names must be the side
    the own value lies on (safe_side "above": own >= allowable passes); every value swept on the
    allowable's safe side has its upper bound at or below the target (the allowable's definition).
Probabilities (p and its bounds) are clipped to [0, 1]: a lognormal interval's top can pass 1."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..reading.methods import SweepRuns, SweepTable
from .subset import biased_low, count_plateau_levels
from .verdict import FAIL, NOT_ASSESSED, PASS, PHYSICAL_STATUSES

# A design value may have at most this share of its runs without a result; past it, its estimate
# is no evidence of safety (the runs without a result count as safe in it).
NO_RESULT_SHARE = 0.01
PROBABILITY_COLUMNS = ("p", "upper_bound", "lower", "upper")
FILE_VERDICTS = {"PASS": PASS, "FAIL": FAIL, "NOT ASSESSED": NOT_ASSESSED}


def no_result_counts(values: Sequence[float], runs: SweepRuns | None) -> list[int]:
    """Per design value: its runs that gave no result (a status that is neither ok nor an outcome
    of the mechanism, or an ok run whose failure margin is not a number); -1 without the runs."""
    if runs is None:
        return [-1] * len(values)
    names = np.array([runs.status_name.get(int(code), "?") for code in runs.status])
    no_result = ~np.isin(names, ("ok", *PHYSICAL_STATUSES))
    if runs.margin is not None:
        no_result |= (names == "ok") & ~np.isfinite(runs.margin)
    return [int(np.sum(no_result & (runs.value == v))) for v in values]


def sweep_frame(t: SweepTable) -> pd.DataFrame:
    """The per-value table with `plateau_levels` (the levels of the value's subset simulation on a
    plateau of the margin, count_plateau_levels; 0 for the other methods) and `no_result` (its runs
    without a result, no_result_counts), its probabilities clipped to [0, 1]."""
    df = t.table.copy()
    df.attrs = t.table.attrs
    df["plateau_levels"] = [count_plateau_levels(b.tolist()) if b is not None else 0 for b in t.level_thresholds]
    df["no_result"] = no_result_counts(df["value"].tolist(), t.runs)
    for col in PROBABILITY_COLUMNS:
        df[col] = df[col].clip(0.0, 1.0)
    df.attrs["units"]["plateau_levels"] = "1"
    df.attrs["units"]["no_result"] = "1"
    return df


def flat_values(s: pd.DataFrame) -> list[int]:
    """Rows whose subset estimate crossed a plateau of the margin (may be biased low)."""
    return [k for k, n in enumerate(s["plateau_levels"]) if biased_low(int(n))]


@dataclass
class SweepJudgement:
    """The report's verdict of a sweep, the file's, and why they differ: each reason a code and the
    rows it concerns: "not_found" (a verdict without an allowable: status not "found"),
    "allowable_nan", "own_nan", "no_estimate" (every p NaN), "wrong_side" (the verdict names the side
    the own value is not on), "safe_side_above_target" (rows on the safe side whose upper bound
    exceeds the target)."""
    verdict: str
    file_verdict: str
    reasons: list[tuple[str, list[int]]] = field(default_factory=list)


def evidence_reasons(s: pd.DataFrame) -> list[tuple[str, list[int]]]:
    """Why the file's PASS or FAIL is not supported by the numbers it holds (empty: it is)."""
    a, target = s.attrs["allowable"], float(s.attrs["target_probability"])
    if a["status"] != "found":
        return [("not_found", [])]
    res: list[tuple[str, list[int]]] = []
    if not np.any(np.isfinite(s["p"].to_numpy(dtype=float))):
        res.append(("no_estimate", []))
    if not np.isfinite(a["value"]):
        return res + [("allowable_nan", [])]
    above = a["safe_side"] == "above"
    if not np.isfinite(a["own_value"]):
        res.append(("own_nan", []))
    elif (a["own_value"] >= a["value"] if above else a["own_value"] <= a["value"]) != (a["verdict"] == "PASS"):
        res.append(("wrong_side", []))
    x, ub = s["value"].to_numpy(dtype=float), s["upper_bound"].to_numpy(dtype=float)
    safe = (x > a["value"]) if above else (x < a["value"])
    high = [int(k) for k in np.nonzero(safe & (ub > target))[0]]
    if high:
        res.append(("safe_side_above_target", high))
    if a["verdict"] == "PASS":   # truss-campaign never passes on values past NO_RESULT_SHARE
        rows = [k for k, (bad, n) in enumerate(zip(s["no_result"], s["runs"])) if bad > NO_RESULT_SHARE * max(int(n), 1)]
        if rows:
            res.append(("no_result", rows))
    return res


def judge_sweep(s: pd.DataFrame) -> SweepJudgement:
    """The report's verdict of a sweep (s: its table from sweep_frame) with its reasons."""
    file_verdict = str(s.attrs["allowable"]["verdict"])
    if file_verdict == "NOT ASSESSED":
        return SweepJudgement(NOT_ASSESSED, file_verdict)
    reasons = evidence_reasons(s)
    return SweepJudgement(NOT_ASSESSED if reasons else FILE_VERDICTS[file_verdict], file_verdict, reasons)


def sweep_verdict(s: pd.DataFrame) -> str:
    """PASS, FAIL or NOT_ASSESSED of a sweep (its table from sweep_frame)."""
    return judge_sweep(s).verdict


def sweep_reason(s: pd.DataFrame) -> str:
    """The file's reason for its verdict (the allowable's message in a file without one)."""
    a = s.attrs["allowable"]
    return str(a.get("reason", "") or a.get("message", ""))
