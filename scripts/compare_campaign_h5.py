#!/usr/bin/env python3
"""Compare two campaign HDF5 files bit for bit, outside what may differ between invocations.

    /usr/bin/python3 scripts/compare_campaign_h5.py A.h5 B.h5

Every dataset (raw bytes of its values, dtype and shape) and every attribute of every group and
dataset must be equal, except /timing (wall times, ranks) and the root attributes that describe the
invocation: start_utc, end_utc, wall_time_s, git_revision, software_version, n_ranks, n_sessions.
Exit 0 when equal, 1 with the differences listed otherwise. Used to show that a refactoring leaves
campaign output unchanged (a build before and a build after, same campaign and rank count).
"""
import sys

import h5py
import numpy as np

SKIP_GROUPS = {"/timing"}
SKIP_ROOT_ATTRS = {"start_utc", "end_utc", "wall_time_s", "git_revision", "software_version", "n_ranks",
                   "n_sessions"}


def resolve(f, v):
    """Object references (dimension scales' DIMENSION_LIST, REFERENCE_LIST) hold file addresses,
    which depend on the order the file was written in: compare the names they point to."""
    if isinstance(v, h5py.Reference):
        return f[v].name if v else None
    if isinstance(v, np.void) or (isinstance(v, np.ndarray) and v.dtype.names):
        return [resolve(f, x) for x in (v.tolist() if isinstance(v, np.void) else v.ravel())]
    if isinstance(v, tuple):
        return tuple(resolve(f, x) for x in v)
    if isinstance(v, np.ndarray) and v.dtype.kind == "O":
        return [resolve(f, x) for x in v.ravel()]
    return v


def same_value(a, b, fa=None, fb=None):
    if fa is not None:
        ra, rb = resolve(fa, a), resolve(fb, b)
        if isinstance(ra, list) or isinstance(rb, list):
            return str(ra) == str(rb)
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.kind == "O":
        return all(x == y for x, y in zip(a.ravel(), b.ravel()))
    return a.tobytes() == b.tobytes()


def walk(h):
    out = {}
    h.visititems(lambda name, obj: out.__setitem__("/" + name, obj))
    return out


def compare(path_a, path_b):
    diffs = []
    with h5py.File(path_a, "r") as fa, h5py.File(path_b, "r") as fb:
        objs_a, objs_b = walk(fa), walk(fb)
        keep = lambda n: not any(n == g or n.startswith(g + "/") for g in SKIP_GROUPS)
        names_a = {n for n in objs_a if keep(n)}
        names_b = {n for n in objs_b if keep(n)}
        diffs += [f"only in {path_a}: {n}" for n in sorted(names_a - names_b)]
        diffs += [f"only in {path_b}: {n}" for n in sorted(names_b - names_a)]
        for name in ["/"] + sorted(names_a & names_b):
            oa, ob = (fa, fb) if name == "/" else (objs_a[name], objs_b[name])
            skip = SKIP_ROOT_ATTRS if name == "/" else set()
            ka, kb = set(oa.attrs) - skip, set(ob.attrs) - skip
            if ka != kb:
                diffs.append(f"{name}: attributes differ: {sorted(ka ^ kb)}")
            for k in sorted(ka & kb):
                if not same_value(oa.attrs[k], ob.attrs[k], fa, fb):
                    diffs.append(f"{name}: attribute {k} differs")
            if isinstance(oa, h5py.Dataset) != isinstance(ob, h5py.Dataset):
                diffs.append(f"{name}: dataset in one file, group in the other")
            elif isinstance(oa, h5py.Dataset) and not same_value(oa[()], ob[()]):
                diffs.append(f"{name}: values differ")
        n = len(names_a & names_b)
    return diffs, n


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    diffs, n = compare(sys.argv[1], sys.argv[2])
    for d in diffs:
        print(d)
    print(f"{n} objects compared, {len(diffs)} differences")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
