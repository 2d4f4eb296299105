"""truss_report.judging.mechanism: mechanism margins in the form of the ECSS mechanisms standard.

Source: ECSS-E-ST-33-01C (6 March 2009), "Space engineering - Mechanisms", clause 4.7.5.3.1
"Motorization factors" and its Table 4-2 (uncertainty factors of the resistance contributors);
later issues (Rev.1 2017, Rev.2 2019) may number or set them differently, so the report tells the
user to confirm the factors against the issue in their contract (ECSS_CONFIRM). The clause: the
components of resistance are multiplied by the minimum uncertainty factors of Table 4-2 (theoretical column: inertia I 1.1, spring S 1.2, motor magnetic
losses H_M 1.5, friction F_R 3, hysteresis H_Y 3, others/harness H_A 3, adhesion H_D 3; measured
column 1.1, 1.2, 1.2, 1.5, 1.5, 1.5, 3), and the minimum actuation torque is

  T_min = 2 (1.1 I + 1.2 S + 1.5 H_M + 3 F_R + 3 H_Y + 3 H_A + 3 H_D) + 1.25 T_D + T_L

with I the inertial torque of an accelerated reference frame (a spinning spacecraft), T_D the
inertial resistance torque "to accelerate the inertia" under the acceleration the customer
specifies (or deduces from speed or time requirements), T_L a deliverable output torque; the
actuation torque T must be >= T_min over the full range of travel (4.7.5.3.2 b), and the kinetic
energy of the moving parts must not be counted on to meet the motorisation factor (4.7.5.3.1 f).
The factor 3 of the friction-like terms is that of Table 4-2.

This rigid, frictionless model has two of these resistances (the others are zero in it, and the
report says they must be added by the user):
  S   = /runs/peak_static_drive_torque_Nm: the torque at the screws that holds the mast at rest in
        each configuration of its path, (h / 2 pi) dU/dy_m, U the diagonals' strain energy (spring;
        the free stack: with the deploying bay in its configuration, the frames below at rest);
  T_D = /runs/peak_inertial_drive_torque_Nm: drive torque minus S, the torque that accelerates the
        mast (velocity drive: its prescribed motion is the acceleration requirement).
Both are peaks over the run; they need not occur at the same instant, so S and T_D at their peaks
bound the torque at every instant from above: the report's T_min is conservative.

  velocity drive: T_min = MF (k_S S) + k_D T_D, T_available = the scene's motor at the prescribed
                  screw speed (/runs/motor_torque_at_speed_Nm; the speed is constant over travel);
  motor drive:    T_min = MF (k_S S), T_D = 0 (no acceleration is specified: the motor's own
                  acceleration of the mast is not a requirement), T_available = the stall torque
                  (per run when dispersed): the torque the motor gives wherever the mast holds it.
  achieved motorisation factor MF_ach = (T_available - k_D T_D) / (k_S S) (>= MF required;
  infinite when S <= 0, as in retraction, where the diagonals help), torque margin
  T_available / T_min - 1 (>= 0); a run fails when T_available < T_min. Runs with T_min = 0 (no
  resistance at all) are not counted.
MF (2), k_S (1.2) and k_D (1.25) are report options (--motorisation-factor, --uncertainty-factor,
--inertia-factor)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..reading.campaign import Campaign
from ..reading.extras import Extras
from ..reading.h5file import Array
from .stats import clopper_pearson

ECSS_CLAUSE = ("ECSS-E-ST-33-01C (6 March 2009), Space engineering – Mechanisms, clause 4.7.5.3.1 "
               "“Motorization factors” and Table 4-2 (uncertainty factors)")
ECSS_SHORT = "ECSS-E-ST-33-01C, clause 4.7.5.3.1 and Table 4-2"
ECSS_CONFIRM = ("Confirm the factors and the clause against the issue of the standard your "
                "contract applies (later issues: Rev.1 of 15 February 2017, Rev.2 of 1 March "
                "2019); set them with --motorisation-factor, --uncertainty-factor and "
                "--inertia-factor.")
DEFAULT_MF = 2.0
DEFAULT_UNCERTAINTY = 1.2     # Table 4-2, spring (S), theoretical and measured
DEFAULT_INERTIA = 1.25        # clause 4.7.5.3.1 equation, inertial resistance T_D
STATIC = "peak_static_drive_torque_Nm"
INERTIAL = "peak_inertial_drive_torque_Nm"


@dataclass
class Margins:
    mode: str
    mf_required: float
    k_uncertainty: float          # k_S, on the spring resistance
    k_inertia: float = DEFAULT_INERTIA
    n: int = 0                    # runs considered
    mf: Array | None = None       # achieved MF per considered run
    mf_min: float = float("nan")
    tm_min: float = float("nan")  # smallest torque margin T_available / T_min - 1
    mf_nominal: float = float("nan")
    n_below: int = 0
    p_below_ci: tuple[float, float] = (float("nan"), float("nan"))
    s_design: float = float("nan")       # largest spring resistance S over the runs, Nm
    d_design: float = float("nan")       # largest inertial resistance T_D, Nm
    t_min_design: float = float("nan")   # largest T_min, Nm
    t_avail_min: float = float("nan")
    stall_needed: float = float("nan")
    stall_scene: float = float("nan")
    no_load_speed: float = float("nan")
    omega: float = float("nan")
    note: str = ""
    missing: bool = False         # the file holds no resistance to judge (not assessed)

    @property
    def fails(self) -> bool:
        return self.n > 0 and self.n_below > 0


def screw_speed(drive: dict[str, Any]) -> float:
    """Screw speed omega = 2 pi v / h (rad/s) of a velocity drive (NaN without v or h)."""
    try:
        return 2.0 * np.pi * float(drive["speed_m_per_s"]) / float(drive["screw_lead_m"])
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return float("nan")


def available_at_speed(c: Campaign, drive: dict[str, Any]) -> float:
    """Smallest torque the scene's motor gives at the prescribed screw speed: the file's
    /runs/motor_torque_at_speed_Nm over the runs where finite, else the motor's line
    T_s (1 - omega / omega_0) of the base scene."""
    a = c.motor_torque_at_speed
    if a is not None and np.any(np.isfinite(a)):
        return float(np.nanmin(a))
    try:
        return float(drive["stall_torque_Nm"]) * (1.0 - screw_speed(drive)
                                                  / float(drive["no_load_speed_rad_per_s"]))
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return float("nan")


def _required(m: Margins, s: Array, d: Array) -> Array:
    """T_min per run from the spring and inertial resistances (T_D = 0 in motor mode)."""
    return m.mf_required * m.k_uncertainty * s + m.k_inertia * d


def _resistances(e: Extras, m: Margins) -> tuple[Array, Array] | None:
    s, d = e.runs.get(STATIC), e.runs.get(INERTIAL)
    if s is None or d is None:
        m.note, m.missing = f"the file has no /runs/{STATIC}", True
        return None
    d = np.maximum(d, 0.0) if m.mode == "velocity" else np.zeros_like(d)
    return s, d


def compute_margins(c: Campaign, e: Extras, mf_required: float = DEFAULT_MF,
                    k_uncertainty: float = DEFAULT_UNCERTAINTY,
                    k_inertia: float = DEFAULT_INERTIA) -> Margins:
    m = Margins(c.drive_mode, mf_required, k_uncertainty, k_inertia)
    drive = c.drive
    avail: Array | None
    m.stall_scene = float(drive.get("stall_torque_Nm", np.nan))
    m.no_load_speed = float(drive.get("no_load_speed_rad_per_s", np.nan))
    if m.mode == "velocity":
        if c.motor_torque_at_speed is None:
            m.note = "the file has no /runs/motor_torque_at_speed_Nm"
            return m
        avail = c.motor_torque_at_speed
        m.omega = screw_speed(drive)   # also when no margin can be computed
    elif m.mode == "motor":
        avail = c.stall_torque
    else:
        m.note = "torque drive: no motor"
        return m
    resistances = _resistances(e, m)
    if resistances is None or avail is None:   # a motor drive always has its stall torque
        return m
    s, d = resistances
    sel = c.ok & np.isfinite(s) & np.isfinite(d) & np.isfinite(avail)
    if not np.any(sel):
        m.note = ("no ok run has a finite static resistance and available torque "
                  f"(/runs/{STATIC} holds none for this campaign)")
        m.missing = True
        return m
    s, d, t_av = np.maximum(s[sel], 0.0), d[sel], avail[sel]   # S <= 0: the springs help
    t_min = _required(m, s, d)
    m.n = int(np.sum(t_min > 0))
    if m.n == 0:
        m.note = ("no ok run has a resistance to overcome: the diagonals drive the mast and the "
                  "drive only brakes it (as in retraction); its braking torque is the peak drive "
                  "torque of the design loads")
        return m
    s, d, t_av, t_min = s[t_min > 0], d[t_min > 0], t_av[t_min > 0], t_min[t_min > 0]
    with np.errstate(divide="ignore"):
        m.mf = np.where(s > 0, (t_av - k_inertia * d) / (k_uncertainty * s),
                        np.where(t_av >= k_inertia * d, np.inf, -np.inf))
    m.mf_min = float(np.min(m.mf))
    m.tm_min = float(np.min(t_av / t_min - 1.0))
    m.n_below = int(np.sum(t_av < t_min))
    m.p_below_ci = clopper_pearson(m.n_below, m.n)
    m.s_design, m.d_design = float(np.max(s)), float(np.max(d))
    m.t_min_design = float(np.max(t_min))
    m.t_avail_min = float(np.min(t_av))
    if e.nominal is not None and e.nominal.get(STATIC, 0) > 0 and m.mode in ("velocity", "motor"):
        nd = max(e.nominal[INERTIAL], 0.0) if m.mode == "velocity" else 0.0
        na = e.nominal["motor_torque_at_speed_Nm"] if m.mode == "velocity" else m.stall_scene
        m.mf_nominal = (na - k_inertia * nd) / (k_uncertainty * e.nominal[STATIC])
    if m.mode == "velocity":
        frac = 1.0 - m.omega / m.no_load_speed
        m.stall_needed = m.t_min_design / frac if frac > 0 else float("inf")
    else:
        m.stall_needed = m.t_min_design
    return m
