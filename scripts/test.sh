#!/usr/bin/env bash
# Installs what the project needs (Debian 12), builds it in build/, and runs every test with ctest;
# then the sanitizer and fuzzing stage (scripts/sanitize.sh: tests under ASan+UBSan in build-san/,
# each libFuzzer target for FUZZ_SECONDS, 30 by default). SKIP_SANITIZE=1 skips that stage. CI runs this (.ci/run).
#   scripts/test.sh [ctest options]     everything (20-30 min on 2 cores from a fresh clone)
#   scripts/test.sh --quick             everyday check: build, then the tests labelled quick (the
#                                       unit, command-line, report and small MPI tests), no
#                                       sanitizers (about 8 min, 14 CPU-minutes, on 2 cores from a fresh clone)
# Progress: a line at least every 10 s during the build, each test as it ends.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/progress.sh
quick=0
if [ "${1:-}" = --quick ]; then quick=1; shift; fi
t0=$SECONDS
echo "[test] checking the Debian packages (scripts/install-deps.sh)"
scripts/install-deps.sh
watch_step build configure build.log cmake -S . -B build -DCMAKE_BUILD_TYPE=Release ${CMAKE_ARGS:-}
watch_step build build build.log cmake --build build -j"$(nproc)"
sanitize=0; [ "$quick" = 0 ] && [ "${SKIP_SANITIZE:-0}" != 1 ] && sanitize=1
# The sanitizer build runs beside the ctest run (the tests leave about 40 % of the cores idle: runs
# that sleep, start-ups, Python), at nice 19 and idle I/O priority. It runs in its own session, and
# where the kernel groups tasks by session (autogroup) a nice value ranks tasks only inside their
# group: the build then takes up to an even share of the cores. So the tests that judge speed
# (label timing: efficiency floors of the scheduler) run after it, with nothing beside them.
if [ "$sanitize" = 1 ]; then
  echo "[test] building the sanitizer stage beside the tests (log: build-san.log)"
  setsid nice -n 19 ionice -c 3 scripts/sanitize.sh build > build-san.bg.log 2>&1 & san_build=$!
  trap 'kill -- -"$san_build" 2> /dev/null || true' EXIT  # its own process group: stopped with us
fi
# -j: tests that need both cores (real runs on 2 ranks, timing floors) say so with PROCESSORS 2 and run alone.
labels=(); [ "$quick" = 1 ] && labels=(-L quick); [ "$sanitize" = 1 ] && labels=(-LE timing)
watch_step stream ctest build/ctest.log ctest --test-dir build --output-on-failure --timeout 900 -j"$(nproc)" \
  "${labels[@]}" "$@"
if [ "$sanitize" = 1 ]; then
  t_wait=$SECONDS
  while kill -0 "$san_build" 2> /dev/null; do
    [ $(((SECONDS - t_wait) % 10)) -eq 0 ] && echo "[test] the sanitizer build, after the tests: $(build_status build-san.log)"
    sleep 1
  done
  wait "$san_build" || { cat build-san.bg.log; echo "[test] the sanitizer build FAILED"; exit 1; }
  trap - EXIT
  tail -n 1 build-san.bg.log
  watch_step stream ctest build/ctest-timing.log ctest --test-dir build --output-on-failure --timeout 900 \
    -L timing "$@"
  scripts/sanitize.sh
fi
echo "[test] all passed in $(elapsed_text $((SECONDS - t0)))"
