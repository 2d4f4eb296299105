"""truss_report.mechanism: mechanism margins in the form of the ECSS mechanisms standard.

ECSS-E-ST-33-01C, clause 4.7.5.2 (motorisation factor, deployment and actuation mechanisms):
the available (minimum) driving torque must exceed the resistive torque, each resistive
contribution multiplied by its uncertainty factor, by the motorisation factor, 2 by default
(the value this report uses for the design and qualification of a deployment mechanism). The
simulated resistive torque here is inertial and elastic (diagonals, hinge springs) in one
number: the report applies ONE uncertainty factor to it, by default 1.2 (the standard's factor
for spring / elastic resistances, the larger of the two kinds the model holds; 1.1 for inertia).
The model is frictionless: friction, hysteresis, harness and adhesion, whose factor in the
standard is 3, are not in it and must be added by the user. Both factors are report options
(--motorisation-factor, --uncertainty-factor).

  MF = T_available / (k_u T_resistive),  torque margin TM = MF - 1,  required MF >= MF_req.

Velocity drive: T_resistive = the run's peak drive (screw) torque, T_available = the scene's
motor at the prescribed screw speed (/runs/motor_torque_at_speed_Nm, the simulator's motor law).
The motor that would be needed: the torque MF_req k_u T_design at the prescribed speed, and the
stall torque giving it on the linear line T_s (1 - omega / omega_0) with the scene's no-load
speed, T_design the largest peak torque over the ok runs.
Motor drive: the peak torque equals the stall torque (the motor starts from rest), so the
resistive torque is not in the file; the runs that stall are the motor's failures."""
from dataclasses import dataclass

import numpy as np

from .stats import clopper_pearson

ECSS_CLAUSE = "ECSS-E-ST-33-01C (6 March 2009), clause 4.7.5.2, motorisation factor"
DEFAULT_MF = 2.0
DEFAULT_UNCERTAINTY = 1.2


@dataclass
class Margins:
    mode: str
    mf_required: float
    k_uncertainty: float
    n: int = 0                    # runs considered
    mf: np.ndarray = None         # per considered run
    mf_min: float = float("nan")
    mf_nominal: float = float("nan")
    n_below: int = 0
    p_below_ci: tuple = (float("nan"), float("nan"))
    t_design: float = float("nan")       # largest peak torque, Nm
    t_needed_at_speed: float = float("nan")
    stall_needed: float = float("nan")
    stall_scene: float = float("nan")
    no_load_speed: float = float("nan")
    omega: float = float("nan")
    note: str = ""

    @property
    def fails(self):
        return self.n > 0 and self.n_below > 0


def compute_margins(c, e, mf_required=DEFAULT_MF, k_uncertainty=DEFAULT_UNCERTAINTY):
    m = Margins(c.attrs["drive_mode"], mf_required, k_uncertainty)
    drive = c.base_scene.get("drive") or {}
    m.stall_scene = float(drive.get("stall_torque_Nm", np.nan))
    m.no_load_speed = float(drive.get("no_load_speed_rad_per_s", np.nan))
    if m.mode != "velocity":
        m.note = ("motor drive: the peak torque is the motor's own stall torque, the resistive "
                  "torque is not in the file; see the stalls" if m.mode == "motor" else
                  "torque drive: no motor")
        return m
    if c.motor_torque_at_speed is None:
        m.note = "the file has no /runs/motor_torque_at_speed_Nm"
        return m
    t = c.outputs["peak_drive_torque_Nm"]
    avail = c.motor_torque_at_speed
    sel = c.ok & np.isfinite(t) & np.isfinite(avail) & (t > 0)
    m.n = int(sel.sum())
    if m.n == 0:
        m.note = "no ok run with a finite positive peak torque"
        return m
    m.mf = avail[sel] / (k_uncertainty * t[sel])
    m.mf_min = float(np.min(m.mf))
    m.n_below = int(np.sum(m.mf < mf_required))
    m.p_below_ci = clopper_pearson(m.n_below, m.n)
    if e.nominal and e.nominal.get("peak_drive_torque_Nm", 0) > 0:
        m.mf_nominal = e.nominal["motor_torque_at_speed_Nm"] / (
            k_uncertainty * e.nominal["peak_drive_torque_Nm"])
    m.t_design = float(np.max(t[sel]))
    m.t_needed_at_speed = mf_required * k_uncertainty * m.t_design
    m.omega = 2.0 * np.pi * float(drive["speed_m_per_s"]) / float(drive["screw_lead_m"])
    frac = 1.0 - m.omega / m.no_load_speed
    m.stall_needed = m.t_needed_at_speed / frac if frac > 0 else float("inf")
    return m
