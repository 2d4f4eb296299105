"""pytest options of the truss_deploy tests (ctest python_module passes them): the truss-sim they
compare against, the repository (shipped scenes, examples) and a scratch folder."""
import json
import math
import pathlib
import struct
import subprocess

import pytest


def pytest_addoption(parser):
    parser.addoption("--truss-sim", required=True, help="the truss-sim program of the same build")
    parser.addoption("--repo", required=True, help="the repository root")
    parser.addoption("--scratch", required=True, help="a folder the tests may write into")


@pytest.fixture(scope="session")
def truss_sim(request):
    return request.config.getoption("--truss-sim")


@pytest.fixture(scope="session")
def repo(request):
    return pathlib.Path(request.config.getoption("--repo"))


@pytest.fixture(scope="session")
def scratch(request):
    p = pathlib.Path(request.config.getoption("--scratch"))
    p.mkdir(parents=True, exist_ok=True)
    return p


def run_cli(truss_sim, *args):
    """truss-sim ARGS: (exit code, stdout, stderr)."""
    p = subprocess.run([truss_sim, *map(str, args)], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def cli_json(truss_sim, scene, *sets):
    """The run summary truss-sim --json prints for SCENE with --set SETS (exit 0 or 1)."""
    args = [scene, "--json"]
    for s in sets:
        args += ["--set", s]
    rc, out, err = run_cli(truss_sim, *args)
    assert rc in (0, 1), err
    return json.loads(out)


def bits(x):
    return struct.pack("<d", x)


def same_value(py, ref):
    """py (from the module) is ref (from truss-sim's JSON) bit for bit: null is NaN, floats compare
    by their 8 bytes (so -0.0 != 0.0), ints and strings by value and type."""
    if ref is None:
        return isinstance(py, float) and math.isnan(py)
    if isinstance(ref, float):
        return isinstance(py, float) and bits(py) == bits(ref)
    return type(py) is type(ref) and py == ref


def differences(py_dict, ref_dict, skip=("wall_time_s",)):
    """Keys whose values differ (recursing into the bays); [] when every field agrees."""
    diffs = []
    if list(py_dict) != list(ref_dict):
        diffs.append(f"keys: {list(py_dict)} != {list(ref_dict)}")
    for k, ref in ref_dict.items():
        if k in skip:
            continue
        py = py_dict.get(k)
        if isinstance(ref, list):
            if len(py) != len(ref):
                diffs.append(f"{k}: {len(py)} != {len(ref)} entries")
            for i, (a, b) in enumerate(zip(py, ref)):
                diffs += [f"{k}[{i}].{d}" for d in differences(a, b, skip)]
        elif not same_value(py, ref):
            diffs.append(f"{k}: {py!r} != {ref!r}")
    return diffs
