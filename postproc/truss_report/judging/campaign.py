"""truss_report.judging.campaign: the judgement of a campaign's load report, computed once from the
file: the design loads, the mechanism margins, the statistics the sections show, the consistency
checks of the file, the rank correlations, and the verdict with its items."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..reading.campaign import Campaign
from ..reading.extras import Extras
from .bays import BayTable, TorqueChart, calc_bay_table, calc_torque_chart
from .consistency import Check, consistency_checks
from .correlations import Correlations, InputColumn, input_columns, rank_correlations
from .design import DesignLoad, design_loads
from .mechanism import Margins, compute_margins
from .runs import LockStats, OutputStats, lock_stats, output_stats, status_counts
from ..reading.h5file import scene_table
from .stats import CONFIDENCE
from .structure import StructuralMargin, calc_bay_margins, calc_structural_margins, structure_items
from .verdict import VerdictItem, verdict_items, verdict_of


@dataclass
class JudgeOptions:
    """The report's options that change a judgement (the command line's)."""
    levels: Sequence[float] = (99.865,)   # percent, ascending
    confidence: float = CONFIDENCE
    motorisation_factor: float | None = None   # None: the scene's [motorisation] factors
    uncertainty_factor: float | None = None
    inertia_factor: float | None = None


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
    structure: list[StructuralMargin]       # per load and limit
    structure_bays: list[StructuralMargin]  # per bay, for the loads the file records per bay
    bay_table: BayTable                     # per-bay design values (lock time, latch energy, ...)
    torque_chart: TorqueChart | None        # the motorisation chart's torques (velocity drive)

    @property
    def failed_checks(self) -> list[str]:
        return [ch.what for ch in self.checks if not ch.passed]


def judge_campaign(c: Campaign, e: Extras, opts: JudgeOptions) -> CampaignJudgement:
    loads = design_loads(c, e, opts.levels, opts.confidence)
    m = compute_margins(c, e, opts.motorisation_factor, opts.uncertainty_factor, opts.inertia_factor,
                        opts.levels[-1], opts.confidence)
    counted = status_counts(c)
    outputs = output_stats(c, opts.confidence)
    lock = lock_stats(c)
    checks = consistency_checks(c, counted, outputs, lock)
    columns = input_columns(c)
    correlations = rank_correlations(c, columns) if c.dispersions else {}
    items = verdict_items(c, m, [ch.what for ch in checks if not ch.passed], e.nominal_status, loads)
    declared = scene_table(c.base_scene, "structure")
    structure = calc_structural_margins(loads, declared)
    bays = calc_bay_margins(e, c.ok, opts.levels[-1], opts.confidence, declared)
    items += structure_items(structure)
    return CampaignJudgement(loads, m, counted, outputs, lock, checks, columns, correlations, items,
                             verdict_of(items), structure, bays,
                             calc_bay_table(e, c.ok, opts.levels[-1], opts.confidence), calc_torque_chart(c, e))
