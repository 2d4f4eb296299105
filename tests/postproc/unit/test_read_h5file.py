"""truss_report.reading.h5file: strings and integers of either HDF5 storage, and every refusal
naming the file and what is wrong (the report's exit 2)."""
import h5py
import numpy as np
import pytest

from truss_report.reading.h5file import H5, InputError, open_h5, read_kind, scalar_int, text


def test_text_of_fixed_and_variable_length_strings(tmp_path):
    p = tmp_path / "s.h5"
    with h5py.File(p, "w") as f:
        f.attrs["v"] = "mN m"
        f.attrs.create("fixed", np.bytes_(b"rail miss\0\0"))
    with h5py.File(p, "r") as f:
        assert text(f.attrs["v"]) == "mN m" and text(f.attrs["fixed"]) == "rail miss"
    with pytest.raises(InputError):
        text(np.array(["a", "b"]))


@pytest.mark.parametrize("value,want", [(3, 3), (np.int64(7), 7), (2.0, 2), (b"12", 12), ("5 ", 5)])
def test_scalar_int_accepts(value, want):
    assert scalar_int(value, "x") == want


@pytest.mark.parametrize("value", [2.5, b"two", np.array([1, 2])])
def test_scalar_int_refuses(value):
    with pytest.raises(InputError, match="x"):
        scalar_int(value, "x")


def test_open_refuses_missing_text_and_directories(tmp_path):
    (tmp_path / "t.h5").write_text("not hdf5")
    for path, what in ((tmp_path / "none.h5", "no such file"), (tmp_path / "t.h5", "not an HDF5 file"),
                       (tmp_path, "is a directory")):
        with pytest.raises(InputError, match=what):
            open_h5(str(path))


def test_dataset_shape_type_and_attributes_checked(tmp_path):
    p = str(tmp_path / "d.h5")
    with h5py.File(p, "w") as f:
        f["x"] = np.arange(4.0)
        f["s"] = np.array([b"a", b"b"])
        f.attrs["n"] = 3
        f.attrs["bad"] = 1.5
    with open_h5(p) as f:
        h5 = H5(f, p)
        assert h5.array("x", (4,)).tolist() == [0.0, 1.0, 2.0, 3.0]
        assert h5.strings("s", (2,)) == ["a", "b"] and h5.attr_int(f, "n") == 3
        for call, what in ((lambda: h5.array("x", (5,)), "shape"), (lambda: h5.array("s"), "not numeric"),
                           (lambda: h5.array("y"), "missing required dataset /y"),
                           (lambda: h5.attr_int(f, "bad"), "malformed"),
                           (lambda: h5.attr_str(f, "nope"), "missing root attribute nope")):
            with pytest.raises(InputError, match=what) as e:
                call()
            assert str(e.value).startswith(p)


def test_read_kind(tmp_path):
    p = str(tmp_path / "k.h5")
    for attrs, what in (({}, "no root attribute schema_version"),
                        ({"schema_version": 1, "kind": "benchmark"}, "kind is 'benchmark'"),
                        ({"schema_version": 9, "kind": "campaign"}, "schema_version is 9")):
        with h5py.File(p, "w") as f:
            f.attrs.update(attrs)
        with open_h5(p) as f, pytest.raises(InputError, match=what):
            read_kind(H5(f, p))
    with h5py.File(p, "w") as f:
        f.attrs.update({"schema_version": 3, "kind": "campaign"})
    with open_h5(p) as f:
        assert read_kind(H5(f, p)) == "campaign"
