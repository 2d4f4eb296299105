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
