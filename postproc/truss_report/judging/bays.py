"""truss_report.judging.bays: per-bay design values and the motorisation chart's torques.

Per-bay design values: for lock time, latch energy, rail pin force and rail-entry impulse (the
/runs/bays fields), per bay the top design-load level's percentile over the ok runs with a value
(type 7, judging.stats.percentile) and its one-sided distribution-free upper confidence bound
(judging.stats.quantile_ci: the design loads' bound).

The motorisation chart (velocity drive, where the motion is prescribed and the drive force is what
the mast resists with): per run and bay the resistive torque at the screws, the peak drive torque of
the bay's stage M_s = F_peak h / (2 pi) (/runs/bays/peak_drive_force_N; the three screws together),
against the torque the motor delivers to the screws after derating and losses,
N eta_g eta_s (T_available - T_L) (docs/model-notes.md "Drive train": T_available the derated motor
at the prescribed speed, /runs/motorisation_available_torque_Nm; T_L the declared friction, detent,
hysteresis and harness torques at the motor shaft), constant along the stroke at constant speed.
Drive-train keys are per run when a campaign disperses them, else the base scene's."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..reading.campaign import Campaign
from ..reading.extras import Extras
from ..reading.h5file import Array, BoolArray, IntArray
from .mechanism import AVAILABLE
from .stats import percentile, quantile_ci

FIELDS = ("lock_time_s", "latch_energy_J", "peak_pin_force_N", "entry_impulse_Ns")
LOSS_KEYS = ("friction_torque_Nm", "detent_torque_Nm", "hysteresis_torque_Nm", "harness_torque_Nm")


@dataclass
class BayTable:
    level: float                      # percent
    confidence: float
    n_bays: int
    fields: list[str] = field(default_factory=list)
    units: dict[str, str] = field(default_factory=dict)
    estimate: dict[str, Array] = field(default_factory=dict)   # per field, per bay (NaN: no value)
    bound: dict[str, Array] = field(default_factory=dict)      # NaN: no value or too few runs
    n: dict[str, IntArray] = field(default_factory=dict)       # ok runs with a value
    n_needed: int = 0                                           # runs a bound needs


def calc_bay_table(e: Extras, ok: BoolArray, level: float, confidence: float) -> BayTable:
    """The per-bay design values of FIELDS the file has with a finite nonzero value in some ok run."""
    present = [f for f in FIELDS if f in e.bays and np.any(np.isfinite(e.bays[f][ok]) & (e.bays[f][ok] != 0))]
    nb = max((int(np.max(np.nonzero(np.any(np.isfinite(e.bays[f][ok]), axis=0))[0])) + 1 for f in present),
             default=0)
    t = BayTable(level, confidence, nb, present, {f: e.units[f] for f in present})
    for f in present:
        est, hi, n = np.full(nb, np.nan), np.full(nb, np.nan), np.zeros(nb, dtype=np.int64)
        for j in range(nb):
            v = e.bays[f][ok, j]
            v = np.sort(v[np.isfinite(v)])
            n[j] = len(v)
            if len(v):
                ci = quantile_ci(v, level / 100.0, confidence)
                est[j], hi[j] = percentile(v, level), ci.hi
                t.n_needed = max(t.n_needed, int(ci.n_needed_hi or 0))
        t.estimate[f], t.bound[f], t.n[f] = est, hi, n
    return t


def drive_per_run(c: Campaign, key: str, default: float) -> Array:
    """The [drive] key's value in every run: its per-run draws when dispersed, else the base scene's."""
    for d in c.dispersions:
        if d.key == f"drive.{key}" and d.per == "run":
            return np.asarray(d.values, dtype=float)
    return np.full(c.n, float(c.drive.get(key, default)))


@dataclass
class TorqueChart:
    resist: Array        # ok runs x bays: peak drive torque of each bay's stage at the screws, N m
    available: Array     # ok runs: the motor's torque at the screws after derating and losses, N m
    nominal: Array | None = None   # the nominal run's resist per bay


def calc_torque_chart(c: Campaign, e: Extras) -> TorqueChart | None:
    """The chart's torques (None: not a velocity drive, or the file lacks the columns)."""
    if c.drive_mode != "velocity" or "peak_drive_force_N" not in e.bays or AVAILABLE not in e.runs:
        return None
    lead = drive_per_run(c, "screw_lead_m", np.nan)
    train = (drive_per_run(c, "gear_ratio", 1.0) * drive_per_run(c, "gear_efficiency", 1.0)
             * drive_per_run(c, "screw_efficiency", 1.0))
    losses = sum((drive_per_run(c, k, 0.0) for k in LOSS_KEYS), np.zeros(c.n))
    ok = c.ok
    resist = e.bays["peak_drive_force_N"][ok] * (lead[ok] / (2.0 * np.pi))[:, None]
    available = train[ok] * (e.runs[AVAILABLE][ok] - losses[ok])
    nominal = None
    if e.nominal is not None and "peak_drive_force_N" in e.nominal_bays:
        nominal = e.nominal_bays["peak_drive_force_N"] * float(c.drive.get("screw_lead_m", np.nan)) / (2.0 * np.pi)
    if not np.any(np.isfinite(resist)):
        return None
    return TorqueChart(resist, available, nominal)
