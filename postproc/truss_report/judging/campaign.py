"""truss_report.judging.campaign: the judgement of a campaign's load report, computed once from the
file: the design loads, the mechanism margins, the statistics the sections show, the consistency
checks of the file, the rank correlations, and the verdict with its items."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..reading.campaign import Campaign
from ..reading.extras import Extras
from .consistency import Check, consistency_checks
from .correlations import Correlations, InputColumn, input_columns, rank_correlations
from .design import DesignLoad, design_loads
from .mechanism import DEFAULT_INERTIA, DEFAULT_MF, DEFAULT_UNCERTAINTY, Margins, compute_margins
from .runs import LockStats, OutputStats, lock_stats, output_stats, status_counts
from .stats import CONFIDENCE
from .verdict import VerdictItem, verdict_items, verdict_of


@dataclass
class JudgeOptions:
    """The report's options that change a judgement (the command line's)."""
    levels: Sequence[float] = (99.865,)   # percent, ascending
    confidence: float = CONFIDENCE
    motorisation_factor: float = DEFAULT_MF
    uncertainty_factor: float = DEFAULT_UNCERTAINTY
    inertia_factor: float = DEFAULT_INERTIA


@dataclass
class CampaignJudgement:
    loads: list[DesignLoad]
    margins: Margins
    counted: dict[int, int]             # runs per status code
    outputs: dict[str, OutputStats]
    lock: LockStats
    checks: list[Check]
    columns: list[InputColumn]
    correlations: Correlations
    items: list[VerdictItem]
    verdict: str

    @property
    def failed_checks(self) -> list[str]:
        return [ch.what for ch in self.checks if not ch.passed]


def judge_campaign(c: Campaign, e: Extras, opts: JudgeOptions) -> CampaignJudgement:
    loads = design_loads(c, e, opts.levels, opts.confidence)
    m = compute_margins(c, e, opts.motorisation_factor, opts.uncertainty_factor, opts.inertia_factor)
    counted = status_counts(c)
    outputs = output_stats(c, opts.confidence)
    lock = lock_stats(c)
    checks = consistency_checks(c, counted, outputs, lock)
    columns = input_columns(c)
    correlations = rank_correlations(c, columns) if c.dispersions else {}
    items = verdict_items(c, m, [ch.what for ch in checks if not ch.passed], e.nominal_status, loads)
    return CampaignJudgement(loads, m, counted, outputs, lock, checks, columns, correlations, items,
                             verdict_of(items))
