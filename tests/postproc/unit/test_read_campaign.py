"""truss_report.reading.campaign and .extras on a synthetic campaign file: every field is the
file's dataset read here directly with h5py; a missing required dataset is refused by name."""
import shutil

import h5py
import numpy as np
import pytest

from truss_report.reading.campaign import load_campaign
from truss_report.reading.extras import load_extras
from truss_report.reading.h5file import H5, InputError, open_h5
from truss_report.reading.schema import OUTPUTS


def read(path):
    with open_h5(path) as f:
        h5 = H5(f, path)
        c = load_campaign(h5, "sha")
        return c, load_extras(h5, c)


def test_campaign_fields_are_the_file_datasets(motor_file):
    c, e = read(motor_file)
    with h5py.File(motor_file, "r") as f:
        n = f.attrs["n_runs"]
        assert c.n == n == len(f["runs/status"])
        assert np.array_equal(c.status, f["runs/status"][()].astype(np.int64))
        assert c.status_name == {int(v): k for k, v in h5py.check_enum_dtype(f["runs/status"].dtype).items()}
        for k in OUTPUTS:
            assert np.array_equal(c.outputs[k], f[f"runs/{k}"][()], equal_nan=True)
            assert c.units[k] == f[f"runs/{k}"].attrs["units"]
        assert np.array_equal(c.lock, f["runs/bays/lock_time_s"][()], equal_nan=True)
        assert [d.key for d in c.dispersions] == sorted(f["runs/inputs"], key=lambda k: f[f"runs/inputs/{k}"].attrs["factor"])
        assert c.stats["peak_drive_force_N"]["p99"] == f["stats/peak_drive_force_N/p99"][()]
        assert sorted(c.histories) == [0, 3] and c.histories[3].n_bays == f["runs/n_bays"][3]
        assert set(e.bays) == set(f["runs/bays"]) and "nominal" not in f and e.nominal is None
        assert np.isnan(e.nominal_value("peak_drive_force_N"))
    assert c.drive_mode == "motor" and c.stall_torque is not None and len(c.stall_torque) == c.n
    assert int(c.ok.sum()) == int(np.sum(c.status == 0)) and c.status_mask("stall").sum() > 0


def test_missing_dataset_is_named(motor_file, tmp_path):
    broken = str(tmp_path / "broken.h5")
    shutil.copy(motor_file, broken)
    with h5py.File(broken, "a") as f:
        del f["runs/peak_pin_force_N"]
    with pytest.raises(InputError, match="missing required dataset /runs/peak_pin_force_N"):
        read(broken)


def test_status_outside_its_enum_refused(motor_file, tmp_path):
    broken = str(tmp_path / "enum.h5")
    shutil.copy(motor_file, broken)
    with h5py.File(broken, "a") as f:
        d = f["runs/run_index"][()]
        d[0] = 7
        f["runs/run_index"][...] = d
    with pytest.raises(InputError, match="run_index is not 0 .. n_runs-1"):
        read(broken)
