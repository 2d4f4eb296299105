"""truss_report.judging.design: the design-load table (nominal, mean, percentiles, one-sided
distribution-free upper confidence bounds, ratio to nominal) of the loads, impulses included,
each with its definition; readable units.

One-sided upper bound of the p-quantile xi_p from n independent runs: the order statistic
x_(k) with k the smallest rank such that P(x_(k) >= xi_p) >= confidence. x_(k) >= xi_p holds
exactly when at most k - 1 runs fall below xi_p, and that count is Binomial(n, p), so
P(x_(k) >= xi_p) = sum_{i=0}^{k-1} C(n, i) p^i (1 - p)^(n - i) = F_Binom(k - 1; n, p).
No such k <= n exists when 1 - p^n < confidence (n below ln(1 - confidence) / ln p)."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..reading.campaign import Campaign
from ..reading.extras import Extras
from ..reading.h5file import Array
from .stats import percentile, quantile_ci

# The same datasets name other events in a retraction.
RETRACT_LABELS = {"deploy_time_s": "retraction time", "peak_latch_energy_J": "peak unlock energy"}

# (key, label, source, definition when deploying, definition when retracting). source: "runs" =
# a /runs column; "bays_max" = the largest over the bays of a /runs/bays field (per run). A load
# whose file column holds no finite nonzero value (an impulse of the other direction or drive
# mode) is left out of the table.
TOTAL = "total of the three screws, = one motor driving them 1:1; one screw carries a third"
LOADS = [
    ("peak_drive_force_N", "peak drive force", "runs",
     "smooth part of the axial force on the driven frame, total of the three screws; impulses "
     "excluded", None),
    ("peak_drive_torque_Nm", "peak drive torque", "runs",
     f"screw torque of that force ({TOTAL}); impulses excluded", None),
    ("peak_pin_force_N", "peak rail pin force", "runs",
     "smooth rail normal force on one pin; the rail-entry impulse excluded",
     "smooth rail normal force on one pin; the unlock and rail-exit impulses excluded"),
    ("peak_diagonal_tension_N", "peak diagonal tension", "runs",
     "tension in one diagonal of the deploying bay, smooth part",
     "tension in one diagonal of the retracting bay, smooth part"),
    ("peak_latch_energy_J", "peak latch energy", "runs",
     "strut radial kinetic energy lost at one latch, largest over the bays",
     "strut radial kinetic energy given at one unlock (paid by the drive), largest over the bays"),
    ("start_drive_impulse_Ns", "start drive impulse", "runs",
     "impulse, total: the drive impulse that starts the driven part from rest (velocity drive)",
     None),
    ("entry_impulse_Ns", "rail-entry impulse per pin", "bays_max",
     "impulse on one pin when a bay's pins enter the rail, largest over the bays", None),
    ("entry_drive_impulse_Ns", "rail-entry drive impulse", "bays_max",
     "impulse, total: drive impulse at a rail entry, largest over the bays (velocity drive)",
     "impulse, total: drive impulse at a rail exit, largest over the bays (velocity drive)"),
    ("landing_impulse_Ns", "landing impulse", "bays_max", None,
     "impulse, total: stack impulse on the lower frame at rail exit, largest over the bays"),
    ("unlock_impulse_Ns", "unlock impulse per pin", "bays_max", None,
     "impulse on one pin when a bay unlocks: the rail gives the hinge its radial speed; largest "
     "over the bays"),
    ("drive_work_impulses_J", "drive work of the impulses", "runs",
     "work of the start and rail-entry drive impulses, summed over the run",
     "work of the start, rail-exit and unlock drive impulses, summed over the run"),
    ("deploy_time_s", "deployment time", "runs", "time of the last lock (bay 1 locks)", None),
]

RETRACT_DEFINITIONS = {"deploy_time_s": "time at which frame n lands on the stack: the end of "
                                        "the retraction (the file's deploy_time_s)"}


def load_text(key: str, label: str, deploy_def: str | None, retract_def: str | None,
              direction: str) -> tuple[str, str | None]:
    """(label, definition) of a load for this direction; None for a load it does not have."""
    if direction == "retract":
        definition = RETRACT_DEFINITIONS.get(key, retract_def or deploy_def)
        return RETRACT_LABELS.get(key, label), definition
    return (label, deploy_def) if deploy_def else (label, None)


IMPULSE_KEYS = {"start_drive_impulse_Ns", "entry_impulse_Ns", "entry_drive_impulse_Ns",
                "landing_impulse_Ns", "unlock_impulse_Ns", "drive_work_impulses_J"}

@dataclass
class LevelValue:
    level: float          # percent
    estimate: float       # type-7 percentile
    bound: float          # one-sided upper confidence bound (NaN if the sample is too small)
    rank: int | None      # its rank k (None if none)
    n_needed: int | None  # runs a bound needs (when rank is None)

    @property
    def too_few(self) -> bool:
        return self.rank is None


@dataclass
class DesignLoad:
    key: str
    label: str
    definition: str
    unit: str
    impulse: bool
    n: int                # ok runs with a finite value
    nominal: float
    mean: float
    min: float
    max: float
    levels: list[LevelValue]   # per requested level

    @property
    def nominal_below_runs(self) -> bool:
        """The nominal lies below every dispersed run (a peak over dispersed bays, see
        design_table_html)."""
        return bool(np.isfinite(self.nominal) and self.nominal < self.min)

    @property
    def ratio(self) -> float:
        """Highest-level percentile / nominal."""
        top = self.levels[-1].estimate
        return top / self.nominal if self.nominal not in (0.0,) and np.isfinite(self.nominal) \
            else float("nan")


def load_values(c: Campaign, e: Extras, key: str,
                source: str) -> tuple[Array | None, float, str | None]:
    """Per-run values of a load (None if the file does not have it) and its nominal value."""
    if source == "runs":
        x = c.outputs.get(key, e.runs.get(key))
        nom = e.nominal_value(key)
        unit = c.units.get(key, e.units.get(key))
    else:
        if key not in e.bays:
            return None, np.nan, None
        with np.errstate(all="ignore"):
            b = e.bays[key]
            x = np.where(np.all(np.isnan(b), axis=1), np.nan,
                         np.nanmax(np.where(np.isnan(b), -np.inf, b), axis=1))
        nb = e.nominal_bays.get(key) if e.nominal is not None else None
        nom = float(np.max(nb[np.isfinite(nb)])) if nb is not None and np.any(np.isfinite(nb)) \
            else np.nan
        unit = e.units[key]
    return x, nom, unit


def design_loads(c: Campaign, e: Extras, levels: Sequence[float], confidence: float) -> list[DesignLoad]:
    """The DesignLoad of every load the file has with a finite nonzero value in some ok run, with
    its label and definition for the campaign's direction."""
    res = []
    for key, label, source, deploy_def, retract_def in LOADS:
        label, definition = load_text(key, label, deploy_def, retract_def, c.direction)
        x, nom, unit = load_values(c, e, key, source)
        if x is None or definition is None or unit is None:
            continue
        v = np.sort(x[c.ok & np.isfinite(x)])
        if len(v) == 0 or not np.any(v != 0):
            continue
        lv = []
        for q in levels:
            ci = quantile_ci(v, q / 100.0, confidence)
            lv.append(LevelValue(q, percentile(v, q), ci.hi, ci.s, ci.n_needed_hi))
        res.append(DesignLoad(key, label, definition, unit, key in IMPULSE_KEYS, len(v), nom,
                              float(np.mean(v)), float(v[0]), float(v[-1]), lv))
    return res
