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
