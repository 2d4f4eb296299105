"""Bad input raises ValueError with the message truss-sim prints (and exits 2 for), in Python's
terms: scene files (bad TOML, unknown keys, bad types and ranges) word for word without the
command line's "error: " prefix; settings with the key named as Python wrote it ('mast.n_bays': 12)
where truss-sim names the --set; a geometry the rail cannot take. A missing file raises
FileNotFoundError, a value that is not one (a list, a numpy array) TypeError naming the key;
plausibility warnings are truss-sim's warnings, as UserWarning."""
import warnings

import pytest

import truss_deploy as td
from conftest import run_cli


def cli_error(truss_sim, scene, *sets):
    args = [scene]
    for s in sets:
        args += ["--set", s]
    rc, out, err = run_cli(truss_sim, *args)
    assert rc == 2 and out == "", (rc, out)
    return err.rstrip("\n")


def py_message(cli, settings=()):
    """truss-sim's message as the Python call gives it: no "error: " prefix; a setting (key, value,
    typed) named as Python wrote it ('key': value) where truss-sim names "--set key=typed", and a
    range error "FILE: why (set by --set key=typed)" given as "'key': value: why"."""
    lines = []
    for line in cli.splitlines():
        line = line.removeprefix("error: ")
        for key, value, typed in settings:
            set_by = f" (set by --set {key}={typed})"
            if line.endswith(set_by):
                line = f"{key!r}: {value!r}: " + line[:-len(set_by)].split(": ", 1)[1]
            line = line.replace(f"--set {key}={typed}", f"{key!r}: {value!r}")
        lines.append(line)
    return "\n".join(lines)


def test_missing_file(truss_sim, scratch):
    path = str(scratch / "no_such_scene.toml")
    with pytest.raises(FileNotFoundError) as e:
        td.Scene.from_toml(path)
    assert e.value.filename == path and "cannot read scene file" in cli_error(truss_sim, path)


@pytest.mark.parametrize("text", [
    "[mast]\nn_bays = 12.5\nstrut_lenght_m = 0.2\n[rail]\nbeta_deg = 95\n",  # three diagnostics, by line
    "[mast]\nn_bays = = 3\n",                                                  # TOML syntax
    "[rail]\nbeta_deg = 95.0\n",                                                # range, with its line
    "[drive]\nmode = \"motr\"\n",                                               # enumeration, suggestion
], ids=["keys", "syntax", "range", "enum"])
def test_bad_scene_file(truss_sim, scratch, text):
    path = scratch / "bad_scene.toml"
    path.write_text(text)
    with pytest.raises(ValueError) as e:
        td.Scene.from_toml(str(path))
    assert str(e.value) == py_message(cli_error(truss_sim, str(path)))
    assert "--set" not in str(e.value) and not str(e.value).startswith("error:")


# (Python value, what a user types after --set): the same setting, the same message.
SETTINGS = [
    ("mast.n_baays", 12, "12"),                       # unknown key, with a suggestion
    ("mats.n_bays", 12, "12"),                        # unknown table
    ("mast.n_bays", 12.5, "12.5"),                    # an integer key given a float
    ("mast.n_bays", 0, "0"),                          # its range
    ("rail.beta_deg", 95, "95"),                      # validate(): "(set by --set ...)"
    ("drive.mode", "motr", "motr"),                   # an unknown enumeration value
    ("stack.contacts", "yes", "yes"),                 # a yes/no key given a string
    ("mast.diagonal_stiffness_N_per_m", 5e9, "5000000000.0"),  # beyond its hard range
    ("mast.strut_mass_kg", float("nan"), "nan"),      # not a number
    ("rail.x_m", 0.3, "0.3"),                         # a geometry error, with the keys involved
]


@pytest.mark.parametrize("key,value,typed", SETTINGS, ids=[s[0] + "=" + s[2] for s in SETTINGS])
def test_bad_setting(repo, truss_sim, key, value, typed):
    path = str(repo / "campaigns" / "scenes" / "table1.toml")
    with pytest.raises(ValueError) as e:
        td.Scene.from_toml(path).with_(**{key: value})
    assert str(e.value) == py_message(cli_error(truss_sim, path, f"{key}={typed}"), [(key, value, typed)])
    assert "--set" not in str(e.value) and f"{key!r}: {value!r}" in str(e.value)


@pytest.mark.parametrize("key,value,typed", SETTINGS, ids=[s[0] + "=" + s[2] for s in SETTINGS])
def test_bad_row_of_simulate_many(repo, truss_sim, key, value, typed):
    """A batch's rows are variants of the base scene, checked without reading its file again; a
    bad row's message is still the one truss-sim gives (with the file's lines of the keys involved)."""
    path = str(repo / "campaigns" / "scenes" / "table1.toml")
    base = td.Scene.from_toml(path).with_(**{"mast.n_bays": 3})
    with pytest.raises(ValueError) as e:
        td.simulate_many(base, [{"rail.beta_deg": 20.0}, {key: value}, {"rail.beta_deg": 96.0}], threads=2)
    cli = cli_error(truss_sim, path, "mast.n_bays=3", f"{key}={typed}")
    assert str(e.value) == "simulate_many: run 1: " + py_message(cli, [("mast.n_bays", 3, "3"), (key, value, typed)])


def test_warnings_are_truss_sim_warnings(repo, truss_sim):
    path = str(repo / "campaigns" / "scenes" / "table1.toml")
    sets = {"drive.torque_Nm": 5.2, "mast.n_bays": 3}
    rc, _, err = run_cli(truss_sim, path, "--set", "drive.torque_Nm=5.2", "--set", "mast.n_bays=3")
    assert rc == 0
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        td.Scene.from_toml(path).with_(**sets)
    as_python = [(k, v, repr(v)) for k, v in sets.items()]
    assert [str(x.message) for x in w] == py_message(err, as_python).removeprefix("warning: ").splitlines()
    assert len(w) == 1 and w[0].category is UserWarning and "--set" not in str(w[0].message)
    # A batch warns once, naming how many runs and the first one's warning.
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        td.simulate_many(td.Scene.from_toml(path).with_(**{"mast.n_bays": 3}),
                         {"drive.torque_Nm": [0.01, 5.2, 6.0]}, bays=False)
    row = py_message(err.splitlines()[0], [("drive.torque_Nm", 5.2, "5.2")]).removeprefix("warning: ")
    assert [str(x.message) for x in w] == ["simulate_many: 2 of 3 runs set a key outside its typical range; run 1: "
                                           + row]


def test_wrong_types():
    s = td.Scene.table1()
    with pytest.raises(TypeError, match=r"mast\.n_bays: expected a number, a bool or a string, got list"):
        s.with_(**{"mast.n_bays": [3]})
    with pytest.raises(KeyError, match="unknown scene key 'mast.n_baays'"):
        s["mast.n_baays"]
    np = pytest.importorskip("numpy")
    with pytest.raises(TypeError, match=r"mast\.n_bays: expected a number, a bool or a string, got ndarray of "
                                        r"shape \(2,\)"):
        s.with_(**{"mast.n_bays": np.array([3, 4])})
    assert s.with_(**{"mast.n_bays": np.int64(4)})["mast.n_bays"] == 4     # numpy scalars are values
    assert s.with_(**{"mast.n_bays": np.array(5)})["mast.n_bays"] == 5     # and 0-d arrays
    with pytest.raises(TypeError):
        td.simulate_many(s)  # one scene: give a list, or a base and overrides
    with pytest.raises(TypeError, match=r"element 0 is int 1, not a Scene"):
        td.simulate_many([1, 2])
    with pytest.raises(ValueError, match="threads: must be a positive integer"):
        td.simulate_many([s], threads=0)


def test_unbuilt_package_says_how_to_build(repo, tmp_path):
    """The package folder without its compiled part (a build of the programs only): importing it
    raises ImportError with the command that builds it, not an AttributeError later."""
    import shutil
    import subprocess
    import sys
    pkg = tmp_path / "truss_deploy"
    pkg.mkdir()
    shutil.copy(repo / "python" / "truss_deploy" / "__init__.py", pkg / "__init__.py")
    p = subprocess.run([sys.executable, "-c", "import truss_deploy"], capture_output=True, text=True,
                       env={"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin"}, cwd=tmp_path)
    assert p.returncode == 1
    assert "ImportError" in p.stderr and "cmake --build build --target truss_deploy_core" in p.stderr, p.stderr
