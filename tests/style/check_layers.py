#!/usr/bin/env python3
"""Layering of src/ (docs/architecture.md): each folder includes project headers only from the
folders allowed here, and model/ and numerics/ include nothing but Eigen and the standard library.
No file of src/ holds machine-specific code: no intrinsics header (<immintrin.h>, <emmintrin.h>,
...), no test of the target architecture (__x86_64__, __SSE2__, __AVX2__, ...), no per-function
target or clones attribute, no run-time CPU dispatch (__builtin_cpu_supports). SIMD_FILES lists
the files that may: sampling/simd_clones.hpp (the optional clones, CMake option TRUSS_SIMD_CLONES)
and util/isal.cpp (VZEROUPPER after ISA-L's vector kernels, where the CPU has AVX). ISA-L's headers
are included by util/isal.cpp alone, the wrapper that clears that vector state after every kernel.
Usage: check_layers.py SRC_DIR; exit 1 on a violation."""
import pathlib
import re
import sys

SIM = {"sim", "free_stack", "stages", "model", "integrators", "numerics"}
ALLOWED = {
    "util": {"util"},
    "statistics": {"statistics"},
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
    "results": {"results", "statistics", "campaign", "sampling", "util", "io"} | SIM,
    "methods": {"methods", "results", "statistics", "campaign", "sampling", "util", "io"} | SIM,
    "parallel": {"parallel", "methods", "results", "statistics", "campaign", "sampling", "util", "io"} | SIM,
}
# Besides the standard library: model/ and numerics/ take Eigen only; sampling/ (pure mathematics)
# fmt and Boost.Math (the stopping rules' binomial law), statistics/ fmt, util/ fmt and ISA-L (its
# CRC): no HDF5, no MPI, no TOML.
EXTERNAL_OK = {"numerics": ("",), "model": ("Eigen/",), "sampling": ("fmt/", "boost/math/"), "statistics": ("fmt/",),
               "util": ("fmt/", "isa-l/")}
# Machine-specific code, forbidden in src/ outside SIMD_FILES (paths relative to src/).
SIMD_FILES = {"sampling/simd_clones.hpp", "util/isal.cpp"}
# The one file that includes ISA-L (util/isal.hpp: every call is followed by clearing the vector state).
ISAL_FILE = "util/isal.cpp"
MACHINE_SPECIFIC = re.compile(r"#\s*include\s*<\w*intrin\.h>|__x86_64__|__i386__|__aarch64__|__SSE\d?\w*__|__AVX\w*__"
                              r"|__ARM_NEON|__attribute__\s*\(\(\s*target|target_clones|__builtin_cpu_supports")


def main():
    src = pathlib.Path(sys.argv[1])
    bad = 0
    for p in sorted(src.rglob("*")):
        if p.suffix not in (".cpp", ".hpp", ".inc"):
            continue
        folder = p.relative_to(src).parts[0]
        for n, line in enumerate(p.read_text().splitlines(), 1):
            if MACHINE_SPECIFIC.search(line) and str(p.relative_to(src)) not in SIMD_FILES:
                print(f"{p}:{n}: machine-specific code outside {sorted(SIMD_FILES) or 'an optional SIMD file'}: "
                      f"{line.strip()}")
                bad += 1
            m = re.match(r'\s*#include\s+"([^/"]+)/', line)
            if m and m.group(1) in ALLOWED and m.group(1) not in ALLOWED.get(folder, set()):
                print(f"{p}:{n}: {folder}/ may not include {m.group(1)}/: {line.strip()}")
                bad += 1
            m = re.match(r"\s*#include\s+<([^>]+)>", line)
            if m and m.group(1).startswith("isa-l/") and str(p.relative_to(src)) != ISAL_FILE:
                print(f"{p}:{n}: ISA-L is called through {ISAL_FILE} only (util/isal.hpp): {line.strip()}")
                bad += 1
            if m and folder in EXTERNAL_OK and "/" in m.group(1) or (m and folder in EXTERNAL_OK and "." in m.group(1)):
                if not any(m.group(1).startswith(pre) and pre for pre in EXTERNAL_OK[folder]):
                    print(f"{p}:{n}: {folder}/ includes only {EXTERNAL_OK[folder]} and the standard library: "
                          f"{line.strip()}")
                    bad += 1
    print(f"layering: {bad} violations")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
