"""truss_report.judging.structure: margins of safety of the design loads against the allowables the
scene declares in its [structure] table (docs/model-notes.md "Structural margins").

Source: ECSS-E-ST-32-10C Rev.1 (6 March 2009), "Structural factors of safety for spaceflight
hardware": the margin of safety of a load against an allowable is

  MoS = allowable / (FoS x design load) - 1,

FoS the yield factor FOSY against a yield allowable, the ultimate factor FOSU against an ultimate
allowable (scene defaults 1.1 and 1.25: Table 4-1, unmanned spacecraft, metallic parts, verified by
test). The design load is the load report's: the one-sided upper confidence bound of the highest
percentile level of the design-load table (judging.design). One screw carries a third of the drive
force (the three screws are driven together). Per bay: the same bound over the runs' values of
that bay, for the loads the file records per bay.

A load whose allowable is not declared, or whose design load has no bound (too few runs), is NOT
ASSESSED, never PASS; a negative margin FAILs."""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..reading.extras import Extras
from ..reading.h5file import Array, BoolArray
from .design import DesignLoad
from .stats import quantile_ci
from .verdict import VerdictItem

STANDARD = "ECSS-E-ST-32-10C Rev.1 (6 March 2009), Table 4-1"
CONFIRM = ("Confirm the factors against the issue of the standard the contract applies; a structure "
           "verified by analysis alone takes larger ones (FOSY 1.25, FOSU 2 in the same table).")
PASS, FAIL, NOT_ASSESSED = "pass", "fail", "not_assessed"

# The /runs/bays field of a design-load key, where the file records that load per bay.
BAY_FIELDS = {"peak_pin_force_N": "peak_pin_force_N", "peak_drive_force_N": "peak_drive_force_N",
              "peak_latch_energy_J": "latch_energy_J"}
# (allowable stem in [structure], design-load key, share of that load one part carries, part, unit)
LOADS = [
    ("pin_force", "peak_pin_force_N", 1.0, "one rail pin", "N"),
    ("diagonal_tension", "peak_diagonal_tension_N", 1.0, "one diagonal", "N"),
    ("latch_energy", "peak_latch_energy_J", 1.0, "one latch", "J"),
    ("screw_force", "peak_drive_force_N", 1.0 / 3.0, "one of the three screws", "N"),
    ("drive_force", "peak_drive_force_N", 1.0, "the three screws together", "N"),
]
LIMITS = ("yield", "ultimate")


@dataclass
class StructuralMargin:
    stem: str              # "pin_force"
    part: str              # "one rail pin"
    limit: str             # "yield" | "ultimate"
    unit: str
    allowable: float       # NaN: not declared
    factor: float          # FOSY or FOSU
    design_load: float     # NaN: no bound
    bay: int | None = None  # None: the whole run; else the bay (1-based)

    @property
    def margin(self) -> float:
        """MoS = allowable / (FoS x design load) - 1 (NaN when either is missing)."""
        if not (np.isfinite(self.allowable) and np.isfinite(self.design_load)) or self.design_load <= 0:
            return float("nan")
        return float(self.allowable / (self.factor * self.design_load) - 1.0)

    @property
    def status(self) -> str:
        m = self.margin
        return NOT_ASSESSED if not np.isfinite(m) else PASS if m >= 0.0 else FAIL

    @property
    def reason(self) -> str:
        if not np.isfinite(self.allowable):
            return f"no {self.limit} allowable declared ([structure] {self.key})"
        if not np.isfinite(self.design_load):
            return "too few runs for the design load's bound"
        return ""

    @property
    def key(self) -> str:
        return f"{self.stem}_{self.limit}_allowable_{self.unit}"


def read_factors(structure: Mapping[str, Any]) -> tuple[float, float]:
    """(FOSY, FOSU) of the resolved scene's [structure] table."""
    return float(structure.get("yield_factor", 1.1)), float(structure.get("ultimate_factor", 1.25))


def calc_structural_margins(loads: Sequence[DesignLoad], structure: Mapping[str, Any]) -> list[StructuralMargin]:
    """One StructuralMargin per load of LOADS the campaign has and per limit (yield, ultimate)."""
    fos = dict(zip(LIMITS, read_factors(structure)))
    by_key = {d.key: d for d in loads}
    res = []
    for stem, key, share, part, unit in LOADS:
        d = by_key.get(key)
        if d is None:
            continue
        bound = d.levels[-1].bound * share if d.levels else float("nan")
        for limit in LIMITS:
            a = structure.get(f"{stem}_{limit}_allowable_{unit}")
            res.append(StructuralMargin(stem, part, limit, unit, float(a) if a is not None else float("nan"),
                                        fos[limit], bound))
    return res


def calc_bay_margins(e: Extras, ok: BoolArray, level: float, confidence: float,
                     structure: Mapping[str, Any]) -> list[StructuralMargin]:
    """Per bay, for each declared allowable whose load the file records per bay (/runs/bays): the
    design load is the upper bound of that bay's `level`-percentile over the ok runs."""
    fos = dict(zip(LIMITS, read_factors(structure)))
    res = []
    for stem, key, share, part, unit in LOADS:
        field = BAY_FIELDS.get(key, "")
        if field not in e.bays:
            continue
        for limit in LIMITS:
            a = structure.get(f"{stem}_{limit}_allowable_{unit}")
            if a is None:
                continue
            for j in range(e.bays[field].shape[1]):
                v = e.bays[field][ok, j]
                v = np.sort(v[np.isfinite(v)])
                if len(v) == 0 or not np.any(v != 0):
                    continue
                bound = quantile_ci(v, level / 100.0, confidence).hi * share
                res.append(StructuralMargin(stem, part, limit, unit, float(a), fos[limit], bound, bay=j + 1))
    return res


def load_status(margins: Sequence[StructuralMargin], stem: str) -> str:
    """A load is assessed against whichever of its allowables is declared (yield and/or ultimate):
    NOT ASSESSED when none is, or a declared one has no design load; FAIL when one is negative."""
    declared = [m for m in margins if m.stem == stem and np.isfinite(m.allowable)]
    s = {m.status for m in declared}
    return NOT_ASSESSED if not declared or NOT_ASSESSED in s else FAIL if FAIL in s else PASS


def structural_verdict(margins: Sequence[StructuralMargin]) -> str:
    """FAIL if any load fails; NOT ASSESSED if any load is not assessed (or none is listed)."""
    s = {load_status(margins, stem) for stem in dict.fromkeys(m.stem for m in margins)}
    return FAIL if FAIL in s else NOT_ASSESSED if NOT_ASSESSED in s or not margins else PASS


def structure_items(margins: Sequence[StructuralMargin]) -> list[VerdictItem]:
    """The verdict's items of the structural margins: a load with a negative margin FAILs (value:
    its smallest margin); the loads not assessed (no allowable declared, or no design load) make
    one NOT ASSESSED item naming them."""
    stems = list(dict.fromkeys(m.stem for m in margins))
    status = {stem: load_status(margins, stem) for stem in stems}
    items = [VerdictItem("structure", "fail", name=stem,
                         value=min(m.margin for m in margins if m.stem == stem and np.isfinite(m.margin)))
             for stem in stems if status[stem] == FAIL]
    idle = [stem for stem in stems if status[stem] == NOT_ASSESSED]
    if idle:
        items.append(VerdictItem("structure_missing", "not_assessed", name=", ".join(idle), count=len(idle)))
    return items
