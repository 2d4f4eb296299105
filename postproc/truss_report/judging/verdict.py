"""truss_report.judging.verdict: the verdict of a campaign's load report. PASS when nothing fails
and every requirement was assessed; FAIL when the evidence violates a requirement; NOT ASSESSED
when nothing fails but the evidence cannot decide every requirement. Each reason is an item."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..reading.campaign import Campaign
from .design import DesignLoad
from .mechanism import Margins

# Run statuses that are evidence about the mechanism (it stalled, missed the rail, locked up): a
# run with one of them violates a requirement. The others (caps, solver and accuracy flags, bad
# input) say the run gave no evidence: the verdict cannot count it either way.
PHYSICAL_STATUSES = ("rail miss", "stall", "singular configuration")
# What a retraction's drive must do that neither the model nor the file holds: brake the mast (the
# diagonals drive it inwards and the drive's work is negative), hold it at rest anywhere along the
# way, and not be back-driven by it when unpowered (the screw's backward efficiency, a brake or
# detent torque).
RETRACT_NOT_ASSESSED = ("braking", "holding", "back-drive")
FAIL, NOT_ASSESSED, PASS = "fail", "not_assessed", "pass"
VERDICT_WORDS = {PASS: "PASS", FAIL: "FAIL", NOT_ASSESSED: "NOT ASSESSED"}
# Exit status of a written report, by its verdict: 0 PASS (and every report without a verdict: a
# single run, a subset campaign), 3 FAIL, 4 NOT ASSESSED; 1 is left to an unexpected error, 2 to
# bad input.
EXIT_STATUS = {PASS: 0, FAIL: 3, NOT_ASSESSED: 4}


@dataclass
class VerdictItem:
    """One reason of the verdict. `what` says which: "margin" (runs below the required
    motorisation factor: count of `of` runs, `value` the smallest factor), "margin_missing" (no
    resistance or available torque in the file: `name` the note), "margin_undeclared" (the
    campaign declares no motor: `name` the note), "margin_unjudged" (`count` of `of` ok runs
    without a finite resistance or available torque), "status" (count of `of` runs with status
    `name`), "nominal" (the nominal run's status `name`), "too_few" (no upper bound at `level`
    percent from `count` ok runs; it needs `needed`), "load_missing" (`count` of `of` ok runs
    without a finite value of the load `name`), "no_loads" (no load has a finite value in an ok
    run), "retract" (what a retraction's drive must do that the file cannot show: `name` one of
    RETRACT_NOT_ASSESSED), "check" (the consistency check `name` failed)."""
    what: str
    kind: str             # FAIL or NOT_ASSESSED
    name: str = ""
    count: int = 0
    of: int = 0
    needed: int = 0
    level: float = float("nan")
    value: float = float("nan")


def verdict_of(items: Sequence[VerdictItem]) -> str:
    """PASS when no item; FAIL when the evidence violates a requirement (any FAIL item);
    NOT ASSESSED when nothing fails but some requirement cannot be decided from the runs."""
    kinds = {it.kind for it in items}
    return FAIL if FAIL in kinds else NOT_ASSESSED if kinds else PASS


def too_few_items(loads: Sequence[DesignLoad]) -> list[tuple[float, int, int]]:
    """[(level, smallest n, runs needed)] of the levels some load has no upper bound for."""
    res = []
    for i, q in enumerate([lv.level for lv in loads[0].levels] if loads else []):
        short = [d for d in loads if d.levels[i].too_few]
        if short:
            res.append((q, min(d.n for d in short), int(short[0].levels[i].n_needed or 0)))
    return res


def margin_items(m: Margins) -> list[VerdictItem]:
    """The mechanism margins' items: below the factor (FAIL), or not assessed and why."""
    if m.fails:
        return [VerdictItem("margin", FAIL, count=m.n_below, of=m.n, value=m.mf_min)]
    if m.undeclared:
        return [VerdictItem("margin_undeclared", NOT_ASSESSED, name=m.note)]
    if m.missing:
        return [VerdictItem("margin_missing", NOT_ASSESSED, name=m.note)]
    if m.n_unjudged:
        return [VerdictItem("margin_unjudged", NOT_ASSESSED, count=m.n_unjudged, of=m.n + m.n_unjudged)]
    return []


def load_items(loads: Sequence[DesignLoad], n_ok: int) -> list[VerdictItem]:
    """No load with a value (when some run is ok), ok runs without a value of a load, and the
    levels some load has no upper bound for."""
    if not loads:
        return [VerdictItem("no_loads", NOT_ASSESSED)] if n_ok else []
    items = [VerdictItem("load_missing", NOT_ASSESSED, name=d.label, count=d.n_missing, of=d.n + d.n_missing)
             for d in loads if d.n_missing]
    return items + [VerdictItem("too_few", NOT_ASSESSED, count=n, needed=need, level=q)
                    for q, n, need in too_few_items(loads)]


def verdict_items(c: Campaign, m: Margins, failed_checks: Sequence[str], nominal_status: str,
                  loads: Sequence[DesignLoad] = ()) -> list[VerdictItem]:
    """Every requirement that fails (FAIL: a margin below the required factor, a run whose status
    is physical (PHYSICAL_STATUSES), a nominal run that is not ok, a failed consistency check of
    the file) or cannot be decided (NOT_ASSESSED: runs without a result (caps, solver or accuracy
    flags), ok runs without a value, design loads without a bound (too few runs, with the number
    needed), mechanism margins the file has no resistance or motor for, and in a retraction the
    drive's braking, holding and back-drive)."""
    items = margin_items(m)
    for code in sorted(c.status_name):
        name = c.status_name[code]
        k = int(np.sum(c.status == code))
        if name != "ok" and k:
            items.append(VerdictItem("status", FAIL if name in PHYSICAL_STATUSES else NOT_ASSESSED,
                                     name=name, count=k, of=c.n))
    if nominal_status and nominal_status != "ok":
        items.append(VerdictItem("nominal", FAIL if nominal_status in PHYSICAL_STATUSES else NOT_ASSESSED,
                                 name=nominal_status))
    items += load_items(loads, int(np.sum(c.ok)))
    if c.direction == "retract":
        items += [VerdictItem("retract", NOT_ASSESSED, name=what) for what in RETRACT_NOT_ASSESSED]
    for what in failed_checks:
        items.append(VerdictItem("check", FAIL, name=what))
    return items
