#!/usr/bin/env python3
"""Layering of src/ (docs/architecture.md): each folder includes project headers only from the
folders allowed here, and model/ and numerics/ include nothing but Eigen and the standard library.
Usage: check_layers.py SRC_DIR; exit 1 on a violation."""
import pathlib
import re
import sys

SIM = {"sim", "free_stack", "stages", "model", "integrators", "numerics"}
ALLOWED = {
    "util": {"util"},
    "sampling": {"sampling"},
    "numerics": set(),
    "model": {"model"},
    "integrators": {"integrators", "numerics"},  # numerics: pure root finders shared with the stages
    "stages": {"stages", "model", "integrators", "numerics"},
    "free_stack": {"free_stack", "stages", "model", "integrators", "numerics"},
    "sim": SIM,
    "io": {"io"} | SIM,
    "app": {"app", "io"} | SIM,
    "campaign": {"campaign", "sampling", "util", "io"} | SIM,
    "results": {"results", "campaign", "sampling", "util", "io"} | SIM,
    "methods": {"methods", "results", "campaign", "sampling", "util", "io"} | SIM,
    "parallel": {"parallel", "methods", "results", "campaign", "sampling", "util", "io"} | SIM,
}
# Besides the standard library: model/ and numerics/ take Eigen only; sampling/ (pure mathematics)
# fmt, Boost.Math (the stopping rules' binomial law) and the compiler's x86 intrinsics (the AVX2
# kernels of the column statistics, chosen at run time), util/ fmt and ISA-L (its CRC): no HDF5,
# no MPI, no TOML.
EXTERNAL_OK = {"numerics": ("",), "model": ("Eigen/",), "sampling": ("fmt/", "boost/math/", "immintrin.h"),
               "util": ("fmt/", "isa-l/")}


def main():
    src = pathlib.Path(sys.argv[1])
    bad = 0
    for p in sorted(src.rglob("*")):
        if p.suffix not in (".cpp", ".hpp", ".inc"):
            continue
        folder = p.relative_to(src).parts[0]
        for n, line in enumerate(p.read_text().splitlines(), 1):
            m = re.match(r'\s*#include\s+"([^/"]+)/', line)
            if m and m.group(1) in ALLOWED and m.group(1) not in ALLOWED.get(folder, set()):
                print(f"{p}:{n}: {folder}/ may not include {m.group(1)}/: {line.strip()}")
                bad += 1
            m = re.match(r"\s*#include\s+<([^>]+)>", line)
            if m and folder in EXTERNAL_OK and "/" in m.group(1) or (m and folder in EXTERNAL_OK and "." in m.group(1)):
                if not any(m.group(1).startswith(pre) and pre for pre in EXTERNAL_OK[folder]):
                    print(f"{p}:{n}: {folder}/ includes only {EXTERNAL_OK[folder]} and the standard library: "
                          f"{line.strip()}")
                    bad += 1
    print(f"layering: {bad} violations")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
