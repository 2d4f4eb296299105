"""truss_report.judging.mechanism: the ECSS margins written out by hand for three runs."""
import numpy as np
import pytest

from conftest import make_campaign
from truss_report.judging.mechanism import compute_margins
from truss_report.reading.extras import Extras

DRIVE = {"mode": "velocity", "speed_m_per_s": 0.1, "screw_lead_m": 0.01, "stall_torque_Nm": 0.03,
         "no_load_speed_rad_per_s": 125.0}


def extras(s, d):
    return Extras(runs={"peak_static_drive_torque_Nm": np.array(s), "peak_inertial_drive_torque_Nm": np.array(d)})


def test_velocity_drive_margins():
    c = make_campaign({"peak_drive_force_N": [1.0, 1.0, 1.0]}, drive=DRIVE,
                      motor_torque_at_speed=np.array([0.015, 0.014, 0.016]))
    m = compute_margins(c, extras([0.004, 0.005, 0.003], [0.004, -0.002, 0.0]), 2.0, 1.2, 1.25)
    t_min = [2 * 1.2 * 0.004 + 1.25 * 0.004, 2 * 1.2 * 0.005, 2 * 1.2 * 0.003]   # T_D < 0 counts as 0
    assert m.n == 3 and m.t_min_design == pytest.approx(max(t_min))
    assert m.tm_min == pytest.approx(min(a / t - 1 for a, t in zip([0.015, 0.014, 0.016], t_min)))
    assert m.mf_min == pytest.approx(min((0.015 - 1.25 * 0.004) / (1.2 * 0.004), 0.014 / (1.2 * 0.005),
                                         0.016 / (1.2 * 0.003)))
    assert m.n_below == 0 and not m.fails
    omega = 2 * np.pi * 0.1 / 0.01
    assert m.omega == pytest.approx(omega)
    assert m.stall_needed == pytest.approx(max(t_min) / (1 - omega / 125.0))


def test_motor_drive_fails_below_the_factor():
    c = make_campaign({"peak_drive_force_N": [1.0, 1.0]}, drive_mode="motor",
                      drive={"mode": "motor", "stall_torque_Nm": 0.01}, stall_torque=np.array([0.01, 0.02]))
    m = compute_margins(c, extras([0.005, 0.005], [0.01, 0.01]), 2.0, 1.2)
    assert m.n_below == 1 and m.fails                  # 0.01 < 2 * 1.2 * 0.005 = 0.012; T_D = 0
    assert m.mf_min == pytest.approx(0.01 / (1.2 * 0.005))


def test_missing_resistance_and_retraction():
    c = make_campaign({"peak_drive_force_N": [1.0]}, drive=DRIVE, motor_torque_at_speed=np.array([0.01]))
    assert compute_margins(c, Extras()).missing
    m = compute_margins(c, extras([-0.001], [0.0]))
    assert m.n == 0 and not m.missing and "brakes" in m.note
    old = make_campaign({"peak_drive_force_N": [1.0]}, drive=DRIVE)     # no /runs/motor_torque_at_speed_Nm
    assert compute_margins(old, extras([0.004], [0.0])).missing


def test_undeclared_motor_gives_the_required_torque_only():
    c = make_campaign({"peak_drive_force_N": [1.0, 1.0]}, drive=DRIVE, motor_torque_at_speed=np.array([0.015, 0.001]),
                      motor_declared_by="")
    m = compute_margins(c, extras([0.004, 0.005], [0.001, 0.0]), 2.0, 1.2, 1.25)
    assert m.undeclared and not m.fails and m.n == 2 and m.n_below == 0
    assert m.t_min_design == pytest.approx(2 * 1.2 * 0.005) and np.isnan(m.t_avail_min) and np.isnan(m.mf_min)
    assert "declares no motor" in m.note


def test_ok_runs_without_a_resistance_are_counted():
    c = make_campaign({"peak_drive_force_N": [1.0, 1.0, 1.0]}, drive=DRIVE,
                      motor_torque_at_speed=np.array([0.015, 0.015, np.nan]))
    m = compute_margins(c, extras([0.004, np.nan, 0.004], [0.0, 0.0, 0.0]))
    assert m.n == 1 and m.n_unjudged == 2


def test_drive_train_losses_from_the_simulator_columns():
    """A 2:1 gear at 80 %, a 90 % screw, 1 mN m friction with k_F 3: T_min at the motor written out
    by hand, as the simulator's column holds it; the report's rebuild with MF 3 instead of the
    scene's 2; the needed stall torque as the upper 95 % bound of P50 over four runs (= their largest,
    the rank order statistic 4 of 4 for p = 0.5: 1 - 0.5^4 >= 0.95 is false, so no bound)."""
    drive = dict(DRIVE, gear_ratio=2.0, gear_efficiency=0.8, screw_efficiency=0.9, friction_torque_Nm=0.001)
    k = 2.0 * 0.8 * 0.9
    s, d = np.array([0.004, 0.005, 0.003, 0.0045]), np.array([0.001, 0.0, 0.002, 0.001])
    loss = 3.0 * 0.001
    t_min = 2.0 * (1.2 * s / k + loss) + 1.25 * d / k
    avail = np.array([0.012, 0.012, 0.012, 0.012])
    c = make_campaign({"peak_drive_force_N": np.ones(4)}, drive=drive, motor_torque_at_speed=avail,
                      motor_declared_by="c.toml:3")
    c.base_scene["motorisation"] = {"factor": 2.0, "spring_factor": 1.2, "inertia_factor": 1.25}
    e = extras(s, d)
    e.runs.update({"motorisation_required_torque_Nm": t_min, "motorisation_available_torque_Nm": avail,
                   "motorisation_stall_torque_Nm": 0.03 * t_min / avail})
    m = compute_margins(c, e, level=50.0)
    assert m.t_min_design == pytest.approx(max(t_min), rel=1e-14)
    assert m.mf_min == pytest.approx(min((avail - 1.25 * d / k) / (1.2 * s / k + loss)), rel=1e-14)
    assert m.n_below == int(np.sum(avail < t_min))
    assert np.isnan(m.stall_needed) and m.stall_n_needed == 5      # 1 - 0.5^5 >= 0.95 needs 5 runs
    m3 = compute_margins(c, e, mf_required=3.0, level=50.0)
    assert m3.t_min_design == pytest.approx(max(3.0 * (1.2 * s / k + loss) + 1.25 * d / k), rel=1e-13)
    e8 = extras(np.repeat(s, 2), np.repeat(d, 2))
    e8.runs.update({k2: np.repeat(v, 2) for k2, v in e.runs.items() if k2.startswith("motorisation")})
    c8 = make_campaign({"peak_drive_force_N": np.ones(8)}, drive=drive, motor_torque_at_speed=np.repeat(avail, 2),
                       motor_declared_by="c.toml:3")
    c8.base_scene["motorisation"] = c.base_scene["motorisation"]
    m8 = compute_margins(c8, e8, level=50.0)
    need = np.sort(np.repeat(0.03 * t_min / avail, 2))
    # Upper 95 % bound of the median from 8 runs: rank s with F_Binom(s - 1; 8, 0.5) >= 0.95: s = 7.
    assert m8.stall_needed == pytest.approx(need[6], rel=1e-14)
