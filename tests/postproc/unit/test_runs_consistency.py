"""truss_report.judging.runs, .consistency, .correlations and .sobol on in-memory campaigns:
counts, groups, exceedances and checks written out here."""
import numpy as np
import pytest

from conftest import make_campaign
from truss_report.judging.consistency import consistency_checks
from truss_report.judging.correlations import aggregate_input, input_columns, proportional_to, top_inputs
from truss_report.judging.runs import (failure_groups, lock_stats, message_template, motor_exceedance,
                                       output_stats, rail_miss, status_counts)
from truss_report.judging.sobol import sobol_estimates
from truss_report.judging.stats import column_stats
from truss_report.reading.campaign import Dispersion
from truss_report.reading.schema import OUTPUTS, STATS_FIELDS


def test_failure_groups_and_templates():
    c = make_campaign({"peak_drive_force_N": np.ones(5)}, status=[0, 4, 4, 1, 4])
    c.messages = ["", "cap at 1.5 s", "cap at 2 s", "missed by 3e-3 m", "other"]
    assert message_template("cap at -1.5e-3 s, bay 4") == "cap at # s, bay #"
    assert failure_groups(c) == [("step limit", "cap at # s", [1, 2]), ("rail miss", "missed by # m", [3]),
                                 ("step limit", "other", [4])]
    assert status_counts(c) == {0: 1, 1: 1, 2: 0, 4: 3}


def test_motor_exceedance_counts_stalls():
    torque = np.array([1.0, 1.0 + 1e-12, 1.1, 0.5, np.nan])
    c = make_campaign({"peak_drive_torque_Nm": torque}, status=[0, 0, 0, 2, 4], drive_mode="motor",
                      stall_torque=np.ones(5))
    x = motor_exceedance(c)
    assert (x.n_considered, x.n_ok_exceed, x.k, x.n_other_failures) == (4, 1, 2, 1)   # 1 + 1e-12: rounding
    assert x.utilisation_max == pytest.approx(1.1)


def test_rail_miss():
    c = make_campaign({"peak_drive_force_N": np.ones(4)}, status=[1, 1, 0, 0],
                      rail_approach=np.array([0.002, 0.004, np.nan, np.nan]))
    r = rail_miss(c)
    assert (r.n, r.k) == (4, 2) and r.approach["median"] == pytest.approx(0.003)


def stored_stats(c):
    outs = output_stats(c, 0.95)
    c.stats = {k: dict(o.mine) for k, o in outs.items()}
    lock = lock_stats(c)
    c.stats_lock = {k: v.copy() for k, v in lock.times.items()}
    c.stats_status_names = [c.status_name.get(k, "") for k in range(max(c.status_name) + 1)]
    counted = status_counts(c)
    c.stats_status_counts = np.array([counted.get(k, 0) for k in range(len(c.stats_status_names))])
    c.stats_attrs = {"n_runs": c.n, "n_ok": counted[0], "n_failed": c.n - counted[0]}
    c.status_name = {k: v for k, v in enumerate(c.stats_status_names)}
    return outs, lock


def test_consistency_checks_pass_and_catch_a_changed_statistic():
    rng = np.random.default_rng(3)
    c = make_campaign({k: rng.normal(size=50) for k in OUTPUTS}, lock=rng.uniform(size=(50, 3)))
    outs, lock = stored_stats(c)
    counted = status_counts(c)
    assert all(ch.passed for ch in consistency_checks(c, counted, outs, lock))
    c.stats["peak_pin_force_N"]["p95"] *= 1 + 1e-6
    failed = [ch.what for ch in consistency_checks(c, counted, outs, lock) if not ch.passed]
    assert failed == ["the six outputs recomputed vs /stats/<output>: order statistics"]
    assert set(STATS_FIELDS) == set(column_stats(np.ones(3)))


def test_correlations_inputs_and_proportional_outputs():
    x = np.arange(1.0, 21.0)
    bay = np.column_stack([x, 2 * x])
    d = [Dispersion("mast.k", "bay", "relative", "normal", {}, 10.0, "N/m", 0, bay),
         Dispersion("drive.v", "run", "absolute", "normal", {}, 0.1, "m/s", 1, -x)]
    c = make_campaign({"peak_drive_force_N": x ** 2, "peak_drive_torque_Nm": 3 * x ** 2}, dispersions=d)
    cols = input_columns(c)
    assert [col.label for col in cols] == ["mast.k[bay 1]", "mast.k[bay 2]", "mast.k (mean over bays)", "drive.v"]
    assert np.allclose(aggregate_input(d[0]), (1.5 * x - 10.0) / 10.0)
    assert proportional_to(c) == {"peak_drive_torque_Nm": "peak_drive_force_N"}
    rho = {"peak_drive_force_N": {"mast.k[bay 1]": (0.2, 20), "mast.k[bay 2]": (-0.9, 20),
                                  "mast.k (mean over bays)": (float("nan"), 20), "drive.v": (0.5, 20)}}
    assert [col.label for col in top_inputs(cols, rho, "peak_drive_force_N", 2)] == ["mast.k[bay 2]", "drive.v"]


def test_sobol_estimates_of_an_additive_function():
    """f = a + 2 b: S_a = 1/5, S_b = 4/5 (first order = total); Saltelli blocks of 4000 draws."""
    rng = np.random.default_rng(11)
    A, B = rng.normal(size=(4000, 2)), rng.normal(size=(4000, 2))
    f = lambda m: m[:, 0] + 2 * m[:, 1]    # noqa: E731
    fAB = np.column_stack([f(np.column_stack([B[:, 0], A[:, 1]])), f(np.column_stack([A[:, 0], B[:, 1]]))])
    s1, st = sobol_estimates(f(A), f(B), fAB)
    assert s1 == pytest.approx([0.2, 0.8], abs=0.05) and st == pytest.approx([0.2, 0.8], abs=0.05)
