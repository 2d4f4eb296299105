#!/usr/bin/env bash
# The Simbody cross-check of docs/validation.md: builds truss-sim and simbody-mast, runs every case
# of validation/simbody/compare.py's full suite beside each other and rewrites the generated part
# of docs/validation.md (tables, command, machine, date). About 5 minutes of CPU time.
#   validation/simbody/run_validation.sh [BUILD_DIR]     (default: build, configured by CMake)
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD=${1:-build}
cmake --build "$BUILD" --target truss-sim simbody-mast -j2
exec /usr/bin/python3 validation/simbody/compare.py --truss-sim "$BUILD/truss-sim" \
  --simbody "$BUILD/validation/simbody/simbody-mast" --scenes campaigns/scenes --suite full --repeats 3 \
  --doc docs/validation.md --check
