"""truss_report.judging.runs: the statistics of the runs that the campaign report's sections show:
the outcome of the runs (counts by status, failed runs grouped by message), each output's
distribution (type-7 percentiles and their bounds), the lock timing per bay, the rail-miss
probability, and the bare torque balance of the drive against its motor."""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..reading.campaign import Campaign
from ..reading.h5file import Array
from ..reading.schema import LEVELS, OUTPUTS
from .stats import (QuantileCI, band_stats, clopper_pearson, column_stats, lock_intervals, lock_order,
                    percentile, quantile_ci)

# Motor margin: a peak torque counts as exceeding the stall torque above stall x (1 + this).
# A motor starts from rest at its stall torque, so peak = stall up to rounding in every run.
TORQUE_RTOL = 1e-9

Mask = np.ndarray[Any, np.dtype[np.bool_]]


def status_counts(c: Campaign) -> dict[int, int]:
    """Runs per status code, counted in /runs/status (every code of the enum)."""
    return {k: int(np.sum(c.status == k)) for k in sorted(c.status_name)}


def message_template(msg: str) -> str:
    """A failure message with its numbers replaced by #, to group messages that differ only
    in the numbers (times, heights, bay indices)."""
    return re.sub(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?", "#", msg)


def failure_groups(c: Campaign) -> list[tuple[str, str, list[int]]]:
    """[(status, message template, run indices)] of the failed runs, the largest group first."""
    groups: dict[tuple[str, str], list[int]] = {}
    for i in np.nonzero(~c.ok)[0]:
        groups.setdefault((c.status_name[int(c.status[i])], message_template(c.messages[i])),
                          []).append(int(i))
    return [(s, t, runs) for (s, t), runs in sorted(groups.items(), key=lambda kv: -len(kv[1]))]


@dataclass
class OutputStats:
    """One output over the ok runs with a finite value: the sorted values, their /stats fields,
    and per reported level (LEVELS' names) the estimate and its bounds (empty without values)."""
    key: str
    x: Array
    mine: dict[str, float]
    est: dict[str, float] = field(default_factory=dict)
    cis: dict[str, QuantileCI] = field(default_factory=dict)


def output_stats(c: Campaign, confidence: float) -> dict[str, OutputStats]:
    res = {}
    for key in OUTPUTS:
        x = np.sort(c.outputs[key][c.ok & np.isfinite(c.outputs[key])])
        o = OutputStats(key, x, column_stats(x))
        if len(x):
            o.cis = {name: quantile_ci(x, q / 100.0, confidence) for q, name, _ in LEVELS}
            o.est = {name: percentile(x, q) for q, name, _ in LEVELS}
        res[key] = o
    return res


@dataclass
class LockStats:
    """Lock (retraction: unlock) times per bay over the ok runs: the order in which the bays
    lock, the intervals between successive locks (with their definition), count, P5, P50, P95."""
    order: str
    interval_text: str
    times: dict[str, Array]
    intervals: dict[str, Array]


def lock_stats(c: Campaign) -> LockStats:
    lock_ok = c.lock[c.ok]
    order = lock_order(lock_ok)
    dt, dt_text = lock_intervals(lock_ok, order)
    return LockStats(order, dt_text, band_stats(lock_ok), band_stats(dt))


@dataclass
class RailMiss:
    """Free stack: runs whose pin never reached the rail, with the exact 95 % interval of their
    share and the closest approach's min, P5, P50, P95 and max over them."""
    n: int
    k: int
    lo: float
    hi: float
    approach: dict[str, float]


def rail_miss(c: Campaign) -> RailMiss | None:
    """None unless the file has rail-miss runs and the closest-approach column."""
    miss = c.status_mask("rail miss")
    k = int(miss.sum())
    if k == 0 or c.rail_approach is None:
        return None
    lo, hi = clopper_pearson(k, c.n)
    x = c.rail_approach[miss & np.isfinite(c.rail_approach)]
    approach = ({name: percentile(x, q) for name, q in
                 (("min", 0), ("p05", 5), ("median", 50), ("p95", 95), ("max", 100))} if len(x) else {})
    return RailMiss(c.n, k, lo, hi, approach)


@dataclass
class MotorExceedance:
    """Motor drive: runs whose peak torque exceeds their stall torque (stalled runs count as
    exceedances), over the ok runs with a finite peak torque and the stalled runs."""
    ok_t: Mask            # ok runs with a finite peak and stall torque
    stalled: Mask
    n_considered: int
    n_ok_exceed: int
    k: int
    lo: float
    hi: float
    utilisation_max: float  # largest peak / stall torque of an ok run
    n_other_failures: int


def motor_exceedance(c: Campaign) -> MotorExceedance | None:
    """None when no run is ok or stalled."""
    assert c.stall_torque is not None
    stalled = c.status_mask("stall")
    torque, stall_t = c.outputs["peak_drive_torque_Nm"], c.stall_torque
    ok_t = c.ok & np.isfinite(torque) & np.isfinite(stall_t)
    ok_exceed = ok_t & (torque > stall_t * (1.0 + TORQUE_RTOL))
    n_cons = int(ok_t.sum() + stalled.sum())
    if n_cons == 0:
        return None
    k = int(ok_exceed.sum() + stalled.sum())
    lo, hi = clopper_pearson(k, n_cons)
    util = torque[ok_t] / stall_t[ok_t]
    return MotorExceedance(ok_t, stalled, n_cons, int(ok_exceed.sum()), k, lo, hi,
                           float(np.max(util)) if len(util) else float("nan"),
                           int(np.sum(~c.ok & ~stalled)))


@dataclass
class VelocityExceedance:
    """Velocity drive: ok runs whose peak torque exceeds what the scene's motor gives at the
    prescribed speed (the file's /runs/motor_torque_at_speed_Nm)."""
    considered: Mask
    k: int
    lo: float
    hi: float
    omega: float          # screw speed 2 pi v / h, rad/s
    ratio_min: float      # available / peak torque
    ratio_p50: float
    avail_min: float
    avail_max: float

    @property
    def n_considered(self) -> int:
        return int(self.considered.sum())


def velocity_exceedance(c: Campaign) -> VelocityExceedance | None:
    """None when no ok run has a finite peak torque and available torque."""
    assert c.motor_torque_at_speed is not None
    torque, avail = c.outputs["peak_drive_torque_Nm"], c.motor_torque_at_speed
    considered = c.ok & np.isfinite(torque) & np.isfinite(avail)
    n_cons = int(considered.sum())
    if n_cons == 0:
        return None
    k = int((considered & (torque > avail)).sum())
    lo, hi = clopper_pearson(k, n_cons)
    omega = 2.0 * np.pi * float(c.drive["speed_m_per_s"]) / float(c.drive["screw_lead_m"])
    ratio = avail[considered] / torque[considered]
    return VelocityExceedance(considered, k, lo, hi, omega, float(np.min(ratio)),
                              float(np.percentile(ratio, 50)), float(np.min(avail[considered])),
                              float(np.max(avail[considered])))
