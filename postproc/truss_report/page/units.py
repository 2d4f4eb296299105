"""truss_report.page.units: the unit each quantity is shown in (one per quantity for the whole
report, with an SI prefix chosen from its largest typical value); values stay in SI in data-value."""
from collections.abc import Sequence

import numpy as np

from ..judging.design import DesignLoad

# Readable units: base unit -> [(label, factor)] in increasing order of size.
PREFIXES = {"N": [("mN", 1e-3), ("N", 1.0)], "Nm": [("µN m", 1e-6), ("mN m", 1e-3), ("N m", 1.0)],
            "J": [("µJ", 1e-6), ("mJ", 1e-3), ("J", 1.0)],
            "Ns": [("mN s", 1e-3), ("N s", 1.0)], "s": [("s", 1.0)],
            "m": [("mm", 1e-3), ("m", 1.0)], "kg": [("g", 1e-3), ("kg", 1.0)]}


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


class DisplayUnits:
    """One display unit per quantity for the whole report: the design table, section 2, the
    margins, the plots and the terminal summary show a load in the same unit (chosen once, from
    its largest typical value). Related quantities share their load's unit: the per-bay fields,
    and every torque of the margins (the drive torque's)."""
    ALIASES = {"latch_energy_J": "peak_latch_energy_J",
               "peak_static_drive_torque_Nm": "peak_drive_torque_Nm",
               "peak_inertial_drive_torque_Nm": "peak_drive_torque_Nm",
               "motor_torque_at_speed_Nm": "peak_drive_torque_Nm",
               "drive.stall_torque_Nm": "peak_drive_torque_Nm", "torque": "peak_drive_torque_Nm"}

    def __init__(self):
        self.chosen = {}

    def choose(self, key, unit, magnitude):
        self.chosen.setdefault(key, readable_unit(unit, magnitude))

    def get(self, key, unit, values=None):
        """(label, factor) of `key`; a key not chosen yet gets one from `values` (and keeps it)."""
        key = self.ALIASES.get(key, key)
        if key not in self.chosen:
            v = np.asarray(values if values is not None else [], dtype=float)
            v = v[np.isfinite(v)]
            self.choose(key, unit, float(np.max(np.abs(v))) if len(v) else float("nan"))
        return self.chosen[key]




def choose_load_units(units, loads: Sequence[DesignLoad]):
    """Each design load's display unit, from the larger of its nominal and its top percentile
    (its largest value when no level is reported)."""
    for d in loads:
        top = abs(d.levels[-1].estimate) if d.levels else abs(d.max)
        units.choose(d.key, d.unit, max(abs(d.nominal) if np.isfinite(d.nominal) else 0.0, top))
