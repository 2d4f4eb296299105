"""A run from Python is truss-sim's run: every field of `truss-sim --json` (but wall_time_s, a
measurement) bit for bit, for each shipped scene and variants (drive modes, retraction, physical
failures), and the histories against truss-sim's HDF5 file, dataset by dataset."""
import math

import h5py
import numpy as np
import pytest

import truss_deploy as td
from conftest import cli_json, differences, run_cli

VARIANTS = [
    [],
    ["drive.mode=motor", "mast.n_bays=8"],
    ["drive.mode=torque", "run.direction=retract", "mast.n_bays=6"],
    ["drive.mode=motor", "drive.stall_torque_Nm=0.0044"],          # a stall: status stall, exit 1
    ["drive.mode=torque", "run.max_steps=1000"],                    # the step cap: step_limit
]
SCENES = ["table1", "paper_free", "paper_free_slack", "free_singular"]


@pytest.mark.parametrize("name", SCENES)
@pytest.mark.parametrize("sets", VARIANTS, ids=lambda s: ",".join(s) or "as-shipped")
def test_summary_is_truss_sim_json(repo, truss_sim, name, sets):
    path = str(repo / "campaigns" / "scenes" / f"{name}.toml")
    rc, _, err = run_cli(truss_sim, path, *[a for s in sets for a in ("--set", s)])
    if rc == 2:  # bad input for truss-sim (a retraction the rail cannot take): the same ValueError
        with pytest.raises(ValueError) as e:
            td.simulate(td.Scene.from_toml(path).with_settings(sets))
        assert str(e.value) == "\n".join(line.removeprefix("error: ") for line in err.rstrip("\n").splitlines())
        return
    scene = td.Scene.from_toml(path).with_settings(sets)
    # As shipped (run.output_step_s = 0.01): histories recorded, history_samples > 0.
    ref = cli_json(truss_sim, path, *sets)
    r = td.simulate(scene, histories=True)
    assert differences(r.to_dict(), ref) == []
    assert ref["history_samples"] > 0 and r.history_samples == ref["history_samples"]
    # Without histories: as truss-sim with run.output_step_s = 0 (fewer model evaluations).
    ref0 = cli_json(truss_sim, path, *sets, "run.output_step_s=0")
    r0 = td.simulate(scene)
    assert differences(r0.to_dict(), ref0) == []
    assert r0.history is None and r0.history_samples == 0
    # The attributes are the dict's values; the status is the enum of the JSON's name.
    assert str(r0.status) == ref0["status"]
    assert r0.status == getattr(td.RunStatus, ref0["status"].replace(" ", "_").replace("-", "_"))
    for k, v in r0.to_dict().items():
        if k not in ("status", "bays"):
            a = getattr(r0, k)
            assert a == v or (isinstance(v, float) and math.isnan(v) and math.isnan(a)), k
    assert math.isfinite(r0.wall_time_s) and r0.wall_time_s > 0


def test_bays_frame_is_the_json_bays(repo, truss_sim):
    path = str(repo / "campaigns" / "scenes" / "table1.toml")
    ref = cli_json(truss_sim, path, "drive.mode=motor", "mast.n_bays=7", "run.output_step_s=0")
    df = td.simulate(td.Scene.from_toml(path).with_(**{"drive.mode": "motor", "mast.n_bays": 7})).bays
    assert list(df.columns) == list(ref["bays"][0])
    assert df.dtypes["bay"] == np.int64 and list(df["bay"]) == [b["bay"] for b in ref["bays"]]
    for col in df.columns[1:]:
        want = np.array([np.nan if b[col] is None else b[col] for b in ref["bays"]])
        np.testing.assert_array_equal(df[col].to_numpy(), want)  # exact, NaN where null
    assert df.attrs["units"]["lock_time_s"] == "s" and df.attrs["units"]["peak_drive_force_N"] == "N"


@pytest.mark.parametrize("name,sets", [("table1", ["drive.mode=motor", "mast.n_bays=5"]),
                                       ("paper_free", ["mast.n_bays=5"])])
def test_histories_are_truss_sim_hdf5(repo, truss_sim, scratch, name, sets):
    path = str(repo / "campaigns" / "scenes" / f"{name}.toml")
    out = scratch / f"histories_{name}.h5"
    args = [path, "-o", out, "--force"]
    for s in sets:
        args += ["--set", s]
    rc, _, err = run_cli(truss_sim, *args)
    assert rc in (0, 1), err
    h = td.simulate(td.Scene.from_toml(path).with_settings(sets), histories=True).history
    with h5py.File(out, "r") as f:
        names = sorted(k for k in f["history"] if isinstance(f["history"][k], h5py.Dataset))
        assert sorted(h) == names  # the same datasets (frame_height_m for the free stack)
        for k in names:
            want = f["history"][k][()]
            assert h[k].dtype.kind == want.dtype.kind and h[k].shape == want.shape, k
            np.testing.assert_array_equal(h[k], want, err_msg=k)
            units = f["history"][k].attrs["units"]
            assert td.history_units.get(k, "m") == (units.decode() if isinstance(units, bytes) else units), k


def test_histories_need_a_step():
    with pytest.raises(ValueError, match=r"run\.output_step_s = 0"):
        td.simulate(td.Scene.table1(), histories=True)
    r = td.simulate(td.Scene.table1().with_(**{"run.output_step_s": 0.5, "mast.n_bays": 3}), histories=True)
    assert r.history_samples == len(r.history["t_s"]) > 0
