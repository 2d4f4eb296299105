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

The model's dynamics give two of these resistances; the drive train's losses (F_R, H_M, H_Y, H_A)
are the scene's [drive] torques:
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
The simulator computes the check per run with the drive train's losses and the factors of the
scene's [motorisation] table (/runs/motorisation_required_torque_Nm, _available_torque_Nm,
_stall_torque_Nm; docs/model-notes.md "Motorisation check"):
  T_min = MF (k_S S_m + L) + k_D T_D,m,  S_m = S / (N eta_g eta_s), T_D,m likewise (velocity drive),
L the factored loss torques at the motor shaft. The report reads those columns; MF, k_S and k_D are
the scene's unless the report's options (--motorisation-factor, --uncertainty-factor,
--inertia-factor) replace them, in which case T_min is rebuilt from the same columns with L
recovered from the file's T_min. The achieved factor is MF_ach = (T_available - k_D T_D,m) /
(k_S S_m + L). The stall torque needed is a statistical statement, never a sample maximum: the
one-sided upper confidence bound of the top design-load level's percentile of the per-run stall
torque that meets the factors exactly (stall torque x T_min / T_available)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..reading.campaign import Campaign
from ..reading.extras import Extras
from ..reading.h5file import Array, BoolArray
from ..reading.h5file import scene_table
from .stats import CONFIDENCE, clopper_pearson, quantile_ci

ECSS_CLAUSE = ("ECSS-E-ST-33-01C (6 March 2009), Space engineering – Mechanisms, clause 4.7.5.3.1 "
               "“Motorization factors” and Table 4-2 (uncertainty factors)")
ECSS_SHORT = "ECSS-E-ST-33-01C, clause 4.7.5.3.1 and Table 4-2"
ECSS_CONFIRM = ("Confirm the factors and the clause against the issue of the standard your "
                "contract applies (later issues: Rev.1 of 15 February 2017, Rev.2 of 1 March "
                "2019); set them in the scene's [motorisation] table.")
DEFAULT_MF = 2.0
DEFAULT_UNCERTAINTY = 1.2     # Table 4-2, spring (S), theoretical and measured
DEFAULT_INERTIA = 1.25        # clause 4.7.5.3.1 equation, inertial resistance T_D
STATIC = "peak_static_drive_torque_Nm"
INERTIAL = "peak_inertial_drive_torque_Nm"
REQUIRED = "motorisation_required_torque_Nm"
AVAILABLE = "motorisation_available_torque_Nm"


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
    stall_needed: float = float("nan")   # upper bound of the needed stall torque's percentile
    stall_level: float = 99.865           # percent, of that percentile
    stall_confidence: float = CONFIDENCE
    stall_n_needed: int = 0               # runs the bound needs when it has none
    losses: Array | None = None           # L per considered run (factored losses at the motor), Nm
    stall_scene: float = float("nan")
    no_load_speed: float = float("nan")
    omega: float = float("nan")
    note: str = ""
    missing: bool = False         # the file holds no resistance to judge (not assessed)
    undeclared: bool = False      # the campaign declares no motor: nothing available to judge
    n_unjudged: int = 0           # ok runs without a finite resistance or available torque

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


def scene_factors(c: Campaign) -> tuple[float, float, float]:
    """(MF, k_S, k_D) of the resolved scene's [motorisation] table (the defaults without one)."""
    t = scene_table(c.base_scene, "motorisation")
    return (float(t.get("factor", DEFAULT_MF)), float(t.get("spring_factor", DEFAULT_UNCERTAINTY)),
            float(t.get("inertia_factor", DEFAULT_INERTIA)))


def train_factor(c: Campaign) -> float:
    """N eta_g eta_s of the scene's drive train: a screw torque over it is the motor's."""
    d = c.drive
    return (float(d.get("gear_ratio", 1.0)) * float(d.get("gear_efficiency", 1.0))
            * float(d.get("screw_efficiency", 1.0)))


def _required(m: Margins, s: Array, d: Array, t_file: Array | None, scene: tuple[float, float, float]) -> Array:
    """T_min per run at the motor shaft (s, d: the resistances referred to the motor; T_D = 0 in
    motor mode). From the file's T_min, L = (T_min - k_D0 d) / MF0 - k_S0 s (the factored losses,
    0 without a drive train), rebuilt with the report's factors; without that column L = 0."""
    mf0, ks0, kd0 = scene
    m.losses = (t_file - kd0 * d) / mf0 - ks0 * s if t_file is not None else np.zeros_like(s)
    return m.mf_required * (m.k_uncertainty * s + m.losses) + m.k_inertia * d


def _resistances(e: Extras, m: Margins) -> tuple[Array, Array] | None:
    s, d = e.runs.get(STATIC), e.runs.get(INERTIAL)
    if s is None or d is None:
        m.note, m.missing = f"the file has no /runs/{STATIC}", True
        return None
    d = np.maximum(d, 0.0) if m.mode == "velocity" else np.zeros_like(d)
    return s, d


def compute_margins(c: Campaign, e: Extras, mf_required: float | None = None,
                    k_uncertainty: float | None = None, k_inertia: float | None = None,
                    level: float = 99.865, confidence: float = CONFIDENCE) -> Margins:
    """The margins of the campaign's runs (factors: the scene's, unless given). Without a declared
    motor (c.motor_declared_by == "") the required side (S, T_D, T_min) and the stall torque needed
    are computed and the available side left NaN (m.undeclared)."""
    scene = scene_factors(c)
    m = Margins(c.drive_mode, mf_required if mf_required is not None else scene[0],
                k_uncertainty if k_uncertainty is not None else scene[1],
                k_inertia if k_inertia is not None else scene[2], stall_level=level, stall_confidence=confidence)
    drive = c.drive
    m.stall_scene = float(drive.get("stall_torque_Nm", np.nan))
    m.no_load_speed = float(drive.get("no_load_speed_rad_per_s", np.nan))
    if m.mode not in ("velocity", "motor"):
        m.note = "torque drive: no motor"
        return m
    if m.mode == "velocity":
        m.omega = screw_speed(drive)   # also when no margin can be computed
    avail = available_per_run(c, e, m)
    resistances = _resistances(e, m)
    if resistances is None or (avail is None and not m.undeclared):
        return m
    s, d = resistances
    sel = c.ok & np.isfinite(s) & np.isfinite(d) & (np.isfinite(avail) if avail is not None else True)
    t_file = e.runs.get(REQUIRED)
    if t_file is not None:
        sel &= np.isfinite(t_file)
    m.n_unjudged = int(np.sum(c.ok) - np.sum(sel))
    if not np.any(sel):
        m.note = ("no ok run has a finite static resistance and available torque "
                  f"(/runs/{STATIC} holds none for this campaign)")
        m.missing = True
        return m
    k = train_factor(c)
    s, d = np.maximum(s[sel], 0.0) / k, d[sel] / k   # at the motor shaft; S <= 0: the springs help
    t_min = _required(m, s, d, t_file[sel] if t_file is not None else None, scene)
    m.n = int(np.sum(t_min > 0))
    if m.n == 0:
        m.note = ("no ok run has a resistance to overcome: the diagonals drive the mast and the "
                  "drive only brakes it (as in retraction); its braking torque is the peak drive "
                  "torque of the design loads")
        return m
    keep = t_min > 0
    s, d, t_min = s[keep], d[keep], t_min[keep]
    assert m.losses is not None
    m.losses = m.losses[keep]
    m.s_design, m.d_design = float(np.max(s)), float(np.max(d))
    m.t_min_design = float(np.max(t_min))
    _stall_needed(m, c, e, sel, keep, t_min)
    if avail is not None:
        _available_side(m, e, s, d, avail[sel][keep], t_min, k, scene)
    return m


def _stall_needed(m: Margins, c: Campaign, e: Extras, sel: BoolArray, keep: BoolArray, t_min: Array) -> None:
    """Per run the stall torque that meets the factors exactly, M_stall T_min / T_available (the
    file's motorisation_stall_torque_Nm rebuilt with the report's factors), and the upper bound of
    its m.stall_level percentile at m.stall_confidence."""
    t_av, per_stall = e.runs.get(AVAILABLE), e.runs.get("motorisation_stall_torque_Nm")
    if t_av is None or per_stall is None:
        frac = 1.0 - m.omega / m.no_load_speed if m.mode == "velocity" else 1.0
        m.stall_needed = m.t_min_design / frac if frac > 0 else float("inf")
        return
    stall = c.stall_torque[sel][keep] if c.stall_torque is not None and m.mode == "motor" \
        else np.full(len(t_min), m.stall_scene)
    with np.errstate(divide="ignore", invalid="ignore"):
        need = np.where(t_av[sel][keep] > 0, stall * t_min / t_av[sel][keep], np.inf)
    need = np.sort(need[~np.isnan(need)])
    ci = quantile_ci(need, m.stall_level / 100.0, m.stall_confidence) if len(need) else None
    m.stall_needed = ci.hi if ci is not None else float("nan")
    m.stall_n_needed = int(ci.n_needed_hi or 0) if ci is not None else 0


UNDECLARED = ("the campaign declares no motor: the velocity drive prescribes the motion, and the scene's "
              "[drive] stall_torque_Nm and no_load_speed_rad_per_s are defaults the campaign does not set; "
              "declare the motor in the campaign's [scene.drive] to judge it")


def available_per_run(c: Campaign, e: Extras, m: Margins) -> Array | None:
    """The torque available in each run at the motor shaft (the file's
    motorisation_available_torque_Nm: velocity, the scene's derated motor at the prescribed speed;
    motor, the derated stall torque); None when the file has none (m.note says why, m.missing) or
    when the campaign declares no motor (m.undeclared)."""
    if c.motor_declared_by == "":
        m.note, m.undeclared = UNDECLARED, True
        return None
    if AVAILABLE in e.runs:
        return e.runs[AVAILABLE]
    if m.mode == "motor":
        return c.stall_torque      # a motor drive always has its stall torque
    if c.motor_torque_at_speed is None:
        m.note, m.missing = "the file has no /runs/motor_torque_at_speed_Nm", True
    return c.motor_torque_at_speed


def _available_side(m: Margins, e: Extras, s: Array, d: Array, t_av: Array, t_min: Array, k_train: float,
                    scene: tuple[float, float, float]) -> None:
    """The achieved factors MF_ach = (T_available - k_D T_D) / (k_S S + L), the margin and the runs
    below."""
    k_inertia, k_uncertainty = m.k_inertia, m.k_uncertainty
    assert m.losses is not None
    r = k_uncertainty * s + m.losses
    with np.errstate(divide="ignore"):
        m.mf = np.where(r > 0, (t_av - k_inertia * d) / r, np.where(t_av >= k_inertia * d, np.inf, -np.inf))
    m.mf_min = float(np.min(m.mf))
    m.tm_min = float(np.min(t_av / t_min - 1.0))
    m.n_below = int(np.sum(t_av < t_min))
    m.p_below_ci = clopper_pearson(m.n_below, m.n)
    m.t_avail_min = float(np.min(t_av))
    if e.nominal is not None and e.nominal.get(STATIC, 0) > 0:
        ns = e.nominal[STATIC] / k_train
        nd = max(e.nominal[INERTIAL], 0.0) / k_train if m.mode == "velocity" else 0.0
        na = e.nominal.get(AVAILABLE, e.nominal["motor_torque_at_speed_Nm"] if m.mode == "velocity" else m.stall_scene)
        treq = e.nominal.get(REQUIRED, float("nan"))
        mf0, ks0, kd0 = scene
        nl = (treq - kd0 * nd) / mf0 - ks0 * ns if np.isfinite(treq) else 0.0
        m.mf_nominal = (na - k_inertia * nd) / (k_uncertainty * ns + nl)
