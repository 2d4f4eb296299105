"""truss_report.design: the design-load table (nominal, mean, percentiles, one-sided
distribution-free upper confidence bounds, ratio to nominal) of the loads, impulses included,
each with its definition; readable units.

One-sided upper bound of the p-quantile xi_p from n independent runs: the order statistic
x_(k) with k the smallest rank such that P(x_(k) >= xi_p) >= confidence. x_(k) >= xi_p holds
exactly when at most k - 1 runs fall below xi_p, and that count is Binomial(n, p), so
P(x_(k) >= xi_p) = sum_{i=0}^{k-1} C(n, i) p^i (1 - p)^(n - i) = F_Binom(k - 1; n, p).
No such k <= n exists when 1 - p^n < confidence (n below ln(1 - confidence) / ln p)."""
from dataclasses import dataclass

import numpy as np

from .stats import percentile

# (key, label, source, definition). source: "runs" = a /runs column; "bays_max" = the largest
# over the bays of a /runs/bays field (per run).
LOADS = [
    ("peak_drive_force_N", "peak drive force", "runs",
     "smooth part of the force on the driven frame, total (all drive units); impulses excluded"),
    ("peak_drive_torque_Nm", "peak drive (screw) torque", "runs",
     "screw torque of the smooth drive force, total; impulses excluded"),
    ("peak_pin_force_N", "peak rail pin force", "runs",
     "smooth rail normal force on one pin; the rail-entry impulse excluded"),
    ("peak_diagonal_tension_N", "peak diagonal tension", "runs",
     "tension in one diagonal of the deploying bay, smooth part"),
    ("peak_latch_energy_J", "peak latch energy", "runs",
     "strut radial kinetic energy lost at one latch (paid at one unlock in retraction), "
     "largest over the bays"),
    ("start_drive_impulse_Ns", "start drive impulse", "runs",
     "impulse, total: the drive impulse that starts the driven part from rest (velocity mode)"),
    ("entry_impulse_Ns", "rail-entry impulse per pin", "bays_max",
     "impulse on one pin when a bay's pins enter the rail, largest over the bays"),
    ("entry_drive_impulse_Ns", "rail-entry drive impulse", "bays_max",
     "impulse, total: drive impulse at a rail entry (exit), largest over the bays (velocity mode)"),
    ("landing_impulse_Ns", "landing impulse", "bays_max",
     "impulse, total: stack impulse on the lower frame at rail exit (retraction), largest over "
     "the bays"),
    ("unlock_impulse_Ns", "unlock impulse per pin", "bays_max",
     "impulse on one pin when a bay unlocks (retraction): the rail gives the hinge its radial "
     "speed; largest over the bays"),
    ("drive_work_impulses_J", "drive work of the impulses", "runs",
     "work of the start, rail-entry and unlock drive impulses, summed over the run"),
    ("deploy_time_s", "deployment time", "runs", "time of the last lock (end of retraction)"),
]

IMPULSE_KEYS = {"start_drive_impulse_Ns", "entry_impulse_Ns", "entry_drive_impulse_Ns",
                "landing_impulse_Ns", "unlock_impulse_Ns", "drive_work_impulses_J"}

# Readable units: base unit -> [(label, factor)] in increasing order of size.
PREFIXES = {"N": [("mN", 1e-3), ("N", 1.0)], "Nm": [("µN m", 1e-6), ("mN m", 1e-3), ("N m", 1.0)],
            "J": [("µJ", 1e-6), ("mJ", 1e-3), ("J", 1.0)],
            "Ns": [("mN s", 1e-3), ("N s", 1.0)], "s": [("s", 1.0)]}


def readable_unit(unit, magnitude):
    """(label, factor): value / factor is shown in `label`, chosen so that |magnitude| / factor
    is at least 1 when a prefix allows (the largest prefix not above the magnitude)."""
    opts = PREFIXES.get(unit)
    if not opts:
        return unit, 1.0
    best = opts[0]
    for lab, f in opts:
        if np.isfinite(magnitude) and abs(magnitude) >= f:
            best = (lab, f)
    return best


def upper_bound_rank(n, p, confidence):
    """Smallest rank k (1-based) with F_Binom(k - 1; n, p) >= confidence, or None if k > n."""
    from scipy.stats import binom
    if n < 1:
        return None
    cdf = binom.cdf(np.arange(n), n, p)       # F(k - 1) for k = 1 .. n
    hit = np.nonzero(cdf >= confidence)[0]
    return int(hit[0]) + 1 if len(hit) else None


def runs_needed_for_bound(p, confidence):
    """Smallest n that has an upper bound: 1 - p^n >= confidence."""
    n = max(1, int(np.floor(np.log(1.0 - confidence) / np.log(p))))
    while 1.0 - p ** n < confidence:
        n += 1
    while n > 1 and 1.0 - p ** (n - 1) >= confidence:
        n -= 1
    return n


@dataclass
class LevelValue:
    level: float          # percent
    estimate: float       # type-7 percentile
    bound: float          # one-sided upper confidence bound (NaN if the sample is too small)
    rank: int             # its rank k (None if none)
    n_needed: int         # runs a bound needs (when rank is None)


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
    max: float
    levels: list          # LevelValue per requested level

    @property
    def ratio(self):
        """Highest-level percentile / nominal."""
        top = self.levels[-1].estimate
        return top / self.nominal if self.nominal not in (0.0,) and np.isfinite(self.nominal) \
            else float("nan")


def load_values(c, e, key, source):
    """Per-run values of a load (None if the file does not have it) and its nominal value."""
    if source == "runs":
        x = c.outputs.get(key, e.runs.get(key))
        nom = e.nominal.get(key, np.nan) if e.nominal else np.nan
        unit = c.units.get(key, e.units.get(key))
    else:
        if key not in e.bays:
            return None, np.nan, None
        with np.errstate(all="ignore"):
            b = e.bays[key]
            x = np.where(np.all(np.isnan(b), axis=1), np.nan,
                         np.nanmax(np.where(np.isnan(b), -np.inf, b), axis=1))
        nb = e.nominal["bays"].get(key) if e.nominal else None
        nom = float(np.max(nb[np.isfinite(nb)])) if nb is not None and np.any(np.isfinite(nb)) \
            else np.nan
        unit = e.units[key]
    return x, nom, unit


def design_loads(c, e, levels, confidence):
    """The DesignLoad of every load the file has with a finite nonzero value in some ok run."""
    res = []
    for key, label, source, definition in LOADS:
        x, nom, unit = load_values(c, e, key, source)
        if x is None:
            continue
        v = np.sort(x[c.ok & np.isfinite(x)])
        if len(v) == 0 or not np.any(v != 0):
            continue
        lv = []
        for q in levels:
            k = upper_bound_rank(len(v), q / 100.0, confidence)
            lv.append(LevelValue(q, percentile(v, q), float(v[k - 1]) if k else float("nan"), k,
                                 None if k else runs_needed_for_bound(q / 100.0, confidence)))
        res.append(DesignLoad(key, label, definition, unit, key in IMPULSE_KEYS, len(v), nom,
                              float(np.mean(v)), float(v[-1]), lv))
    return res
