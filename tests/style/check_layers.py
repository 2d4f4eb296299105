#!/usr/bin/env python3
"""Layering of src/ (docs/architecture.md): each folder includes project headers only from the
folders allowed here, and model/ and numerics/ include nothing but Eigen and the standard library.
Usage: check_layers.py SRC_DIR; exit 1 on a violation."""
import pathlib
import re
import sys

ALLOWED = {
    "numerics": set(),
    "model": {"model"},
    "integrators": {"integrators", "numerics"},  # numerics: pure root finders shared with the stages
    "stages": {"stages", "model", "integrators", "numerics"},
    "sim": {"sim", "stages", "model", "integrators", "numerics"},
    "io": {"io", "sim", "stages", "model", "integrators", "numerics"},
    "app": {"app", "io", "sim", "stages", "model", "integrators", "numerics"},
    "campaign": {"campaign", "io", "sim", "stages", "model", "integrators", "numerics"},
    # sampling/: pure mathematics (subset simulation, stopping rules); it reuses the keyed
    # generator and the normal law of campaign/sampling.hpp, itself pure (fmt only).
    "sampling": {"sampling", "campaign"},
    "parallel": {"parallel", "campaign", "io", "sim", "stages", "model", "integrators", "numerics"},
}
EXTERNAL_OK = {"numerics": ("",), "model": ("Eigen/",)}  # besides the standard library


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
                    print(f"{p}:{n}: {folder}/ includes only Eigen and the standard library: {line.strip()}")
                    bad += 1
    print(f"layering: {bad} violations")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
