"""simulate_many: each row is the run simulate() gives for the same scene (every field bit for bit
but wall_time_s; per-bay columns NaN past a run's own bays), on 1 and 2 threads, in every input
form (a list of scenes, a base with a dict, a DataFrame or a list of dicts of settings)."""
import math

import numpy as np
import pandas as pd
import pytest

import truss_deploy as td
from conftest import same_value

# Modes, directions, failures (a stall) and different bay counts in one batch.
SETTINGS = [
    {"mast.n_bays": 4},
    {"mast.n_bays": 6, "drive.mode": "motor"},
    {"mast.n_bays": 5, "drive.mode": "torque", "run.direction": "retract"},
    {"mast.n_bays": 3, "drive.mode": "motor", "drive.stall_torque_Nm": 0.0044},
    {"mast.n_bays": 2, "drive.speed_m_per_s": 0.05, "mast.diagonal_stiffness_N_per_m": 25.0},
    {"mast.n_bays": 7, "stack.mode": "free", "stack.contacts": True},
]


def check_row(row, r, n_max):
    """Row `row` of a simulate_many frame against the Result r of simulate()."""
    d = r.to_dict()
    assert row["status"] == d["status"] and row["message"] == d["message"]
    for name in td.run_units:
        if name in ("wall_time_s", "history_samples"):
            continue
        value = row[name]
        value = value.item() if isinstance(value, np.generic) else value
        assert same_value(value, d[name]), (name, value, d[name])
    for b in range(1, n_max + 1):
        for name in td.bay_units:
            if name == "bay":
                continue
            want = d["bays"][b - 1][name] if b <= len(d["bays"]) else math.nan
            assert same_value(float(row[f"{name}[bay {b}]"]), want), (name, b)


@pytest.mark.parametrize("threads", [1, 2])
def test_rows_are_simulate(threads):
    base = td.Scene.table1()
    scenes = [base.with_(**s) for s in SETTINGS]
    df = td.simulate_many(scenes, threads=threads)
    assert list(df.index) == list(range(len(scenes))) and df.index.name == "run"
    assert list(df["status"].cat.categories) == [str(s) for s in td.RunStatus.__members__.values()]
    assert set(df["status"]) >= {"ok", "stall"}
    n_max = max(s["mast.n_bays"] for s in SETTINGS)
    assert f"lock_time_s[bay {n_max}]" in df and f"lock_time_s[bay {n_max + 1}]" not in df
    for i, s in enumerate(scenes):
        check_row(df.iloc[i], td.simulate(s), n_max)
    assert df.attrs["units"]["peak_drive_force_N"] == "N" and df.attrs["units"]["lock_time_s[bay 1]"] == "s"


def test_override_forms_agree():
    base = td.Scene.table1()
    rows = [{"mast.n_bays": 3 + i, "drive.speed_m_per_s": 0.05 * (i + 1)} for i in range(5)]
    by_scenes = td.simulate_many([base.with_(**r) for r in rows], threads=2)
    as_dict = td.simulate_many(base, {k: [r[k] for r in rows] for k in rows[0]}, threads=2)
    as_list = td.simulate_many(base, rows, threads=1)
    frame = pd.DataFrame(rows, index=pd.Index([10, 20, 30, 40, 50], name="case"))
    as_frame = td.simulate_many(base, frame, threads=2, bays=False)
    outputs = [c for c in by_scenes.columns if c != "wall_time_s"]
    for df in (as_dict, as_list):
        pd.testing.assert_frame_equal(df[outputs], by_scenes[outputs], check_exact=True)
        assert list(df["input:mast.n_bays"]) == [r["mast.n_bays"] for r in rows]
    assert list(as_frame.index) == [10, 20, 30, 40, 50] and as_frame.index.name == "case"
    assert not any("[bay" in c for c in as_frame.columns)
    scalar = [c for c in outputs if "[bay" not in c]
    pd.testing.assert_frame_equal(as_frame[scalar].reset_index(drop=True), by_scenes[scalar].reset_index(drop=True),
                                  check_exact=True)
    assert as_frame.attrs["units"]["input:drive.speed_m_per_s"] == "m/s"


def test_base_settings_are_kept():
    base = td.Scene.table1().with_(**{"drive.mode": "motor", "mast.n_bays": 5})
    df = td.simulate_many(base, {"mast.diagonal_stiffness_N_per_m": [18.0, 22.0]})
    for i, k in enumerate([18.0, 22.0]):
        r = td.simulate(base.with_(**{"mast.diagonal_stiffness_N_per_m": k}))
        assert df["drive_mode"].iloc[i] == "motor" and df["deploy_time_s"].iloc[i] == r.deploy_time_s


def test_empty():
    df = td.simulate_many([], threads=2)
    assert len(df) == 0 and "peak_drive_force_N" in df
