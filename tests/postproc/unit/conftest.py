"""pytest set-up of the truss_report unit tests: the package under postproc/ is imported from the
source tree (the repository's postproc/ is put first on sys.path), matplotlib draws off-screen."""
import os
import sys

import matplotlib

matplotlib.use("Agg")
POSTPROC = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", "postproc"))
sys.path.insert(0, POSTPROC)

import subprocess  # noqa: E402

import pytest  # noqa: E402

FIXTURES = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))


def make_file(script, path, *args):
    """A synthetic file written by tests/postproc/make_fake_campaign.py or make_fake_run.py."""
    subprocess.run([sys.executable, os.path.join(FIXTURES, script), str(path), *map(str, args)], check=True)
    return str(path)


@pytest.fixture(scope="session")
def motor_file(tmp_path_factory):
    """A motor campaign of 200 runs: 12 failed runs of three kinds, stalls, histories of runs 0 and 3."""
    return make_file("make_fake_campaign.py", tmp_path_factory.mktemp("c") / "motor.h5",
                     "--drive-mode", "motor", "--n-fail", 12, "--histories", "0,3")


@pytest.fixture(scope="session")
def run_file(tmp_path_factory):
    return make_file("make_fake_run.py", tmp_path_factory.mktemp("r") / "run.h5")


def make_campaign(outputs, status=None, drive_mode="velocity", direction="deploy", drive=None,
                  dispersions=(), lock=None, **extra):
    """A Campaign built in memory (no file): `outputs` {key: values}, the other outputs NaN."""
    import numpy as np
    from truss_report.reading.campaign import Campaign
    from truss_report.reading.schema import OUTPUTS
    n = len(next(iter(outputs.values())))
    out = {k: np.asarray(outputs.get(k, np.full(n, np.nan)), dtype=float) for k in OUTPUTS}
    status = np.zeros(n, dtype=np.int64) if status is None else np.asarray(status, dtype=np.int64)
    scene = {"drive": drive if drive is not None else {"mode": drive_mode}}
    return Campaign(path="x.h5", sha256="", attrs={"campaign_name": "t", "direction": direction,
                                                   "drive_mode": drive_mode, "sampling": "monte_carlo",
                                                   "n_bays_max": 3},
                    wall_time_s=1.0, base_scene=scene, status=status,
                    status_name={0: "ok", 1: "rail miss", 2: "stall", 4: "step limit"},
                    messages=[""] * n, outputs=out, units={k: "N" for k in OUTPUTS},
                    lock=np.full((n, 3), np.nan) if lock is None else lock, dispersions=list(dispersions),
                    stats_attrs={}, stats={}, stats_lock={}, stats_status_names=[],
                    stats_status_counts=np.zeros(0, dtype=np.int64), **extra)
