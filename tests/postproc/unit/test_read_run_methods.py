"""truss_report.reading.run, .methods and .frame: a single-run file's histories, a /stop and a
/sweep group written here, and the DataFrame of a campaign file."""
import h5py
import numpy as np
import pytest

from truss_report.reading.frame import read_campaign
from truss_report.reading.h5file import InputError
from truss_report.reading.methods import read_stop, read_sweep_table
from truss_report.reading.run import load_run


def test_load_run(run_file):
    run = load_run(run_file)
    with h5py.File(run_file, "r") as f:
        assert np.array_equal(run.history["t_s"], f["history/t_s"][()])
        assert run.history["bay"].dtype == np.int64 and run.n_bays == 4
    assert run.units["drive_force_N"] == "N" and 0 < run.rail_beta_deg < 90


def test_load_run_refuses_a_file_without_history(tmp_path, run_file):
    p = str(tmp_path / "nohist.h5")
    with h5py.File(run_file, "r") as src, h5py.File(p, "w") as dst:
        dst.attrs.update(src.attrs)
    with pytest.raises(InputError, match="no /history"):
        load_run(p)


def test_stop_and_sweep_groups(tmp_path):
    p = str(tmp_path / "m.h5")
    with h5py.File(p, "w") as f:
        g = f.create_group("stop")
        g.attrs.update({"target": "failure_share", "state": "met"})
        for k in ("runs", "used", "estimate", "upper", "achieved_width"):
            g[k] = np.arange(3.0)
        g["estimate"].attrs["units"] = "1"
        g["state"] = np.array([b"more", b"more", b"met"])
        s = f.create_group("sweep")
        s.attrs.update({"variable": "drive.stall_torque_Nm", "units": "Nm", "confidence": 0.95})
        for k in ("values", "p", "cov", "upper_bound", "lower", "upper", "runs", "failures", "master_seed",
                  "index", "refinement"):
            s[k] = np.array([0, 1]) if k in ("index", "refinement") else np.array([1.0, 2.0])
            s[k].attrs["units"] = "Nm" if k == "values" else "1"
        s["status"] = np.array([b"converged", b"level_cap"])
        s["message"] = np.array([b"a", b"b"])
        a = s.create_group("allowable")
        a.attrs.update({"status": "found", "verdict": "PASS"})
        for k in ("value", "estimate", "lower", "upper", "own_value"):
            a[k] = 1.5
        s["inner/1/level_threshold"] = np.array([0.3, 0.0])
    with h5py.File(p, "r") as f:
        stop = read_stop(f)
        assert stop.rounds_state == ["more", "more", "met"] and stop.attrs["state"] == "met"
    t = read_sweep_table(p)
    assert t.table["value"].tolist() == [1.0, 2.0] and t.table["refinement"].tolist() == [False, True]
    assert t.table.attrs["design_units"] == "Nm" and t.table.attrs["allowable"]["value"] == 1.5
    assert t.level_thresholds[0] is None and t.level_thresholds[1].tolist() == [0.3, 0.0]


def test_frame_columns_are_the_file_datasets(motor_file):
    df = read_campaign(motor_file, columns="all")
    with h5py.File(motor_file, "r") as f:
        assert len(df) == f.attrs["n_runs"]
        assert np.array_equal(df["peak_pin_force_N"].to_numpy(), f["runs/peak_pin_force_N"][()], equal_nan=True)
        lock = f["runs/bays/lock_time_s"][()]
        assert np.array_equal(df["lock_time_s[bay 2]"].to_numpy(), lock[:, 1], equal_nan=True)
        assert df.attrs["units"]["peak_pin_force_N"] == f["runs/peak_pin_force_N"].attrs["units"]
    assert set(df["status"].cat.categories) >= {"ok", "stall"}


def test_frame_reads_per_bay_columns_on_demand(motor_file):
    default = read_campaign(motor_file)
    assert not [c for c in default.columns if "[bay " in c or "[frame " in c]
    assert "lock_time_s[bay]" in default.attrs["bay_columns"]
    some = read_campaign(motor_file, columns=["lock_time_s", "peak_drive_force_N", "entry_time_s[bay 2]"])
    with h5py.File(motor_file, "r") as f:
        nb = f.attrs["n_bays_max"]
        assert list(some.columns)[:2] == ["status", "peak_drive_force_N"]     # in the file's order
        assert set(some.columns[2:]) == {f"lock_time_s[bay {j}]" for j in range(1, nb + 1)} | {"entry_time_s[bay 2]"}
        assert np.array_equal(some["entry_time_s[bay 2]"].to_numpy(), f["runs/bays/entry_time_s"][:, 1], equal_nan=True)
    full = read_campaign(motor_file, columns="all")
    assert set(default.columns) | {f"lock_time_s[bay {j}]" for j in range(1, nb + 1)} <= set(full.columns)
    with pytest.raises(ValueError, match="no column 'nope'"):
        read_campaign(motor_file, columns=["nope"])
