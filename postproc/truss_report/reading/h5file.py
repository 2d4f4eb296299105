"""truss_report.reading.h5file: opening an HDF5 file, reading its strings, integers, numeric
datasets and units with errors that name the file, and the file kind / schema version check."""
from __future__ import annotations

import hashlib
import os
from collections.abc import Mapping
from typing import Any

import h5py
import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]
AnyArray = npt.NDArray[Any]

# Exit status of a refused input (postproc/report.py's docstring).
EXIT_INPUT_ERROR = 2

# The schema versions this report reads, per file kind (docs/hdf5-schema.md). Campaign files of
# version 1 and 2 have the same layout; 2 changed how a Saltelli design draws A and B; 3 added
# /runs/round (rounds of runs), which the report does not need.
SCHEMA_VERSIONS: dict[str, tuple[int, ...]] = {"single_run": (1,), "campaign": (1, 2, 3)}


class InputError(Exception):
    """A problem with the command line or the input file: reported as `error: ...`, exit 2."""


def text(value: Any) -> str:
    """An HDF5 string attribute or dataset value (variable- or fixed-length) as str."""
    if isinstance(value, np.ndarray):
        if value.size != 1:
            raise InputError(f"expected one string, got an array of shape {value.shape}")
        value = value.reshape(()).item()
    if isinstance(value, (bytes, np.bytes_)):
        return bytes(value).decode("utf-8").rstrip("\0")
    return str(value)


def scalar_int(value: Any, what: str) -> int:
    """One integer (an attribute stored as integer, float or text); InputError otherwise."""
    arr = np.asarray(value)
    if arr.size != 1:
        raise InputError(f"{what} is not a single integer (shape {arr.shape})")
    v = arr.reshape(()).item()
    if isinstance(v, (bytes, str)):
        try:
            return int(text(v).strip())
        except ValueError:
            raise InputError(f"{what} is not an integer: {v!r}") from None
    if isinstance(v, float) and not v.is_integer():
        raise InputError(f"{what} is not an integer: {v}")
    return int(v)


def units_or(ds: h5py.Dataset, default: str) -> str:
    """The `units` attribute of a dataset, or `default` when it has none (or an unreadable one)."""
    if "units" in ds.attrs:
        try:
            return text(ds.attrs["units"])
        except (InputError, UnicodeDecodeError):
            return default
    return default


def open_h5(path: str) -> h5py.File:
    """Open PATH read-only; InputError when it is missing, not HDF5, or damaged."""
    if not os.path.exists(path):
        raise InputError(f"{path}: no such file")
    if os.path.isdir(path):
        raise InputError(f"{path}: is a directory, not an HDF5 file")
    try:
        is_h5 = h5py.is_hdf5(path)
    except OSError as e:
        raise InputError(f"{path}: cannot read ({e})") from None
    if not is_h5:
        raise InputError(f"{path}: not an HDF5 file")
    try:
        return h5py.File(path, "r")
    except OSError as e:
        raise InputError(f"{path}: damaged or truncated HDF5 file ({e})") from None


def file_sha256(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


class H5:
    """An open HDF5 file and its path; reads that raise InputError naming the file."""

    def __init__(self, f: h5py.File, path: str) -> None:
        self.f, self.path = f, path

    def error(self, what: str) -> InputError:
        return InputError(f"{self.path}: {what}")

    def has(self, name: str) -> bool:
        return name in self.f

    def attr_str(self, obj: h5py.HLObject, name: str, where: str = "root attribute") -> str:
        return str(self._attr(obj, name, str, where))

    def attr_int(self, obj: h5py.HLObject, name: str, where: str = "root attribute") -> int:
        return int(self._attr(obj, name, int, where))

    def attr_float(self, obj: h5py.HLObject, name: str, where: str = "root attribute") -> float:
        return float(self._attr(obj, name, float, where))

    def attr_array(self, obj: h5py.HLObject, name: str, where: str = "root attribute") -> Array:
        return np.asarray(self._attr(obj, name, np.ndarray, where), dtype=np.float64)

    def _attr(self, obj: h5py.HLObject, name: str, kind: type, where: str) -> Any:
        if name not in obj.attrs:
            raise self.error(f"missing {where} {name}")
        value = obj.attrs[name]
        try:
            if kind is str:
                return text(value)
            if kind is int:
                return scalar_int(value, f"{where} {name}")
            arr = np.asarray(value, dtype=np.float64)
            if kind is float and arr.size != 1:
                raise ValueError(f"{arr.size} values where one number is expected")
            return float(arr.reshape(())) if kind is float else arr
        except (InputError, ValueError, TypeError, UnicodeDecodeError) as e:
            raise self.error(f"{where} {name} is malformed ({e})") from None

    def dataset(self, name: str, shape: tuple[int, ...] | None = None) -> h5py.Dataset:
        """The dataset /name; checks it exists and has the given shape."""
        if name not in self.f or not isinstance(self.f[name], h5py.Dataset):
            raise self.error(f"missing required dataset /{name}")
        ds = self.f[name]
        if shape is not None and ds.shape != tuple(shape):
            raise self.error(f"/{name} has shape {ds.shape}, expected {tuple(shape)}")
        return ds

    def array(self, name: str, shape: tuple[int, ...] | None = None) -> Array:
        ds = self.dataset(name, shape)
        if ds.dtype.kind not in "fiu":
            raise self.error(f"/{name} is not numeric (dtype {ds.dtype})")
        return np.asarray(ds[()], dtype=np.float64)

    def scalar(self, name: str) -> float:
        return float(self.array(name, ()))

    def strings(self, name: str, shape: tuple[int, ...]) -> list[str]:
        ds = self.dataset(name, shape)
        if ds.dtype.kind not in "OS":
            raise self.error(f"/{name} is not a string dataset (dtype {ds.dtype})")
        return [text(v) for v in np.asarray(ds[()], dtype=object).ravel()]

    def attr_or(self, obj: h5py.HLObject, name: str, default: str) -> str:
        """A descriptive string attribute; `default` when the file does not have it."""
        return self.attr_str(obj, name) if name in obj.attrs else default

    def units(self, name: str) -> str:
        ds = self.dataset(name)
        return self.attr_str(ds, "units", f"attribute of /{name}:")

    def status_enum(self, name: str) -> dict[int, str]:
        """{value: name} of the RunStatus enum dataset /name."""
        enum = h5py.check_enum_dtype(self.dataset(name).dtype)
        if not enum:
            raise self.error(f"/{name} is not an HDF5 enum dataset")
        return {int(v): str(k) for k, v in enum.items()}


def read_kind(h5: H5) -> str:
    """The file's kind ("campaign" or "single_run"), its schema_version checked."""
    if "schema_version" not in h5.f.attrs:
        raise h5.error("no root attribute schema_version: not a truss-sim/truss-campaign file")
    version = h5.attr_int(h5.f, "schema_version")
    kind = h5.attr_str(h5.f, "kind")
    if kind not in SCHEMA_VERSIONS:
        raise h5.error(f"kind is '{kind}'; this report reads 'campaign' and 'single_run' files")
    if version not in SCHEMA_VERSIONS[kind]:
        readable = " and ".join(str(v) for v in SCHEMA_VERSIONS[kind])
        raise h5.error(f"schema_version is {version}; this report reads {kind} files of schema_version "
                       f"{readable}")
    return kind


def scene_table(scene: Mapping[str, Any], table: str) -> dict[str, Any]:
    """A table of a parsed scene TOML ({} when absent or not a table)."""
    tab = scene.get(table)
    return tab if isinstance(tab, dict) else {}
