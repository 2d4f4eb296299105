#!/usr/bin/env bash
# Test of postproc/run_figures.py on synthetic runs (tests/postproc/make_fake_run.py).
# Usage: test_run_figures.sh REPO_ROOT SCRATCH_DIR
# Exit 0 when every check passes; prints one line per failed check otherwise.
set -u

if [ $# -ne 2 ]; then
  echo "usage: $0 REPO_ROOT SCRATCH_DIR" >&2
  exit 2
fi
ROOT=$(cd "$1" && pwd) || exit 2
SCRATCH=$2
PY=${PYTHON:-/usr/bin/python3}
FIG="$ROOT/postproc/run_figures.py"
FAKE="$ROOT/tests/postproc/make_fake_run.py"

mkdir -p "$SCRATCH" || exit 2
SCRATCH=$(cd "$SCRATCH" && pwd)
W="$SCRATCH/run_figures_test"
rm -rf "$W"
mkdir -p "$W"

fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
pass() { echo "ok:   $*"; }

PNG_SIG="$W/png_signature"
printf '\211PNG\r\n\032\n' > "$PNG_SIG"

check_png() {  # file
  if [ ! -s "$1" ]; then fail "missing or empty: $1"; return; fi
  if cmp -s -n 8 "$1" "$PNG_SIG"; then pass "PNG: $(basename "$1")"; else fail "not a PNG: $1"; fi
}

# expect_error NAME OUTDIR ARGS...: exit code 2, stderr has one line starting with "error:",
# and OUTDIR holds no PNG afterwards.
expect_error() {
  local name=$1 outdir=$2; shift 2
  "$PY" "$FIG" "$@" > "$W/$name.out" 2> "$W/$name.err"
  local rc=$?
  if [ $rc -ne 2 ]; then fail "$name: exit code $rc, expected 2"; fi
  if ! grep -q '^error: ' "$W/$name.err"; then
    fail "$name: no 'error:' line on stderr: $(head -c 300 "$W/$name.err")"
  elif [ "$(grep -c . "$W/$name.err")" -ne 1 ]; then
    fail "$name: stderr is not one line: $(head -c 300 "$W/$name.err")"
  fi
  if [ -d "$outdir" ] && [ -n "$(find "$outdir" -name '*.png' -print -quit)" ]; then
    fail "$name: PNG written in $outdir"
  fi
  [ $rc -eq 2 ] && grep -q '^error: ' "$W/$name.err" && pass "$name: $(cat "$W/$name.err")"
}

# --- good run (default bay = top bay) ------------------------------------------------------
"$PY" "$FAKE" "$W/run.h5" --n-bays 4 || { echo "FAIL: make_fake_run.py"; exit 1; }
if "$PY" "$FIG" "$W/run.h5" -o "$W/out" > "$W/good.out" 2> "$W/good.err"; then
  pass "run_figures on the fake run"
else
  fail "run_figures exit code $? on the fake run: $(cat "$W/good.err")"
fi
for f in fig4_hinge_trajectory_bay4.png fig5_drive_and_pin_force.png fig5_bay4_zoom.png; do
  check_png "$W/out/$f"
  grep -qxF "$W/out/$f" "$W/good.out" || fail "path not printed: $W/out/$f"
done

# --- second run without --force refuses, with --force overwrites ----------------------------
before=$(stat -c %Y.%s "$W/out/fig5_drive_and_pin_force.png")
"$PY" "$FIG" "$W/run.h5" -o "$W/out" > /dev/null 2> "$W/again.err"
rc=$?
if [ $rc -eq 2 ] && grep -q '^error: ' "$W/again.err"; then
  pass "second run without --force: $(cat "$W/again.err")"
else
  fail "second run without --force: exit $rc, stderr: $(cat "$W/again.err")"
fi
[ "$(stat -c %Y.%s "$W/out/fig5_drive_and_pin_force.png")" = "$before" ] \
  || fail "second run without --force touched an existing PNG"
if "$PY" "$FIG" "$W/run.h5" -o "$W/out" --force > /dev/null 2> "$W/force.err"; then
  pass "second run with --force"
else
  fail "second run with --force: $(cat "$W/force.err")"
fi

# --- another bay, fixed-length string attributes --------------------------------------------
"$PY" "$FAKE" "$W/run_fixed.h5" --n-bays 3 --fixed-strings || fail "make_fake_run --fixed-strings"
if "$PY" "$FIG" "$W/run_fixed.h5" -o "$W/out_fixed" --bay 1 > /dev/null 2> "$W/fixed.err"; then
  for f in fig4_hinge_trajectory_bay1.png fig5_drive_and_pin_force.png fig5_bay1_zoom.png; do
    check_png "$W/out_fixed/$f"
  done
else
  fail "fixed-length strings, --bay 1: $(cat "$W/fixed.err")"
fi
# no stray temporary files
[ -z "$(find "$W/out" "$W/out_fixed" -name '*.tmp' -print -quit)" ] || fail "temporary files left"

# --- errors: exit 2, one error: line, no PNG --------------------------------------------------
"$PY" "$FAKE" "$W/schema2.h5" --schema-version 2 || fail "make_fake_run --schema-version 2"
expect_error schema_version_2 "$W/err_schema" "$W/schema2.h5" -o "$W/err_schema"

echo "this is not an HDF5 file" > "$W/text.h5"
expect_error text_file "$W/err_text" "$W/text.h5" -o "$W/err_text"

"$PY" "$FAKE" "$W/nohist.h5" --no-history || fail "make_fake_run --no-history"
expect_error no_history "$W/err_nohist" "$W/nohist.h5" -o "$W/err_nohist"
grep -q 'output_step_s > 0' "$W/no_history.err" || fail "no_history: message does not mention output_step_s > 0"

expect_error missing_file "$W/err_missing" "$W/does_not_exist.h5" -o "$W/err_missing"
expect_error bay_too_big "$W/err_bay" "$W/run.h5" -o "$W/err_bay" --bay 5
expect_error bay_zero "$W/err_bay0" "$W/run.h5" -o "$W/err_bay0" --bay 0

if [ $fails -ne 0 ]; then
  echo "$fails check(s) failed"
  exit 1
fi
echo "all checks passed"
