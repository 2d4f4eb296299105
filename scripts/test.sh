#!/usr/bin/env bash
# Installs what the project needs (Debian 12), builds it in build/, and runs every test with ctest;
# then the sanitizer and fuzzing stage (scripts/sanitize.sh: tests under ASan+UBSan in build-san/,
# each libFuzzer target for FUZZ_SECONDS, 30 by default). SKIP_SANITIZE=1 skips that stage.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > build.log 2>&1 || { cat build.log; exit 1; }
cmake --build build -j"$(nproc)" >> build.log 2>&1 || { tail -50 build.log; exit 1; }
# -j: tests that need both cores (the MPI tests, timing floors) say so with PROCESSORS 2 and run alone.
(cd build && ctest --output-on-failure --timeout 900 -j"$(nproc)" "$@")
if [ "${SKIP_SANITIZE:-0}" != 1 ]; then
  scripts/sanitize.sh
fi
