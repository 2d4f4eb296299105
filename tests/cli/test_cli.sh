#!/usr/bin/env bash
# Command-line checks of truss-sim: bad input exits 2 and writes nothing; the Table 1 scene runs
# (exit 0) and prints valid JSON; an existing output file is kept unless --force.
# Usage: test_cli.sh PATH/TO/truss-sim SCRATCH_DIR
set -u
SIM=${1:?usage: test_cli.sh TRUSS_SIM SCRATCH_DIR}
SCRATCH=${2:?usage: test_cli.sh TRUSS_SIM SCRATCH_DIR}
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
TABLE1="$HERE/../../campaigns/scenes/table1.toml"
PY=/usr/bin/python3

case "$SIM" in */*) SIM="$(cd "$(dirname "$SIM")" && pwd)/$(basename "$SIM")" ;; esac
[ -x "$SIM" ] || { echo "not an executable: $SIM"; exit 1; }
mkdir -p "$SCRATCH" && SCRATCH=$(cd "$SCRATCH" && pwd) || exit 1
WORK=$(mktemp -d "$SCRATCH/run.XXXXXX") || exit 1  # fresh for every run; kept if a check fails
cd "$WORK" || exit 1

passed=0
failed=0
ok() { passed=$((passed + 1)); echo "ok   $1"; }
bad() { failed=$((failed + 1)); echo "FAIL $1"; }

# run NAME EXPECTED_RC ARGS...: runs truss-sim, keeps stdout/stderr in NAME.out/NAME.err
run() {
  local name=$1 want=$2
  shift 2
  "$SIM" "$@" >"$name.out" 2>"$name.err"
  local rc=$?
  if [ "$rc" -eq "$want" ]; then
    ok "$name: exit $rc"
  else
    bad "$name: exit $rc, expected $want"
    sed 's/^/     | /' "$name.err" | head -20
  fi
}

# expect_in FILE TEXT NAME: FILE contains TEXT (fixed string)
expect_in() {
  if grep -qF -- "$2" "$1"; then ok "$3"; else bad "$3: '$2' not in $1"; sed 's/^/     | /' "$1" | head -10; fi
}

# nothing_written NAME: no .h5 file and no temporary file in the scratch dir
nothing_written() {
  local stray
  if ! stray=$(find . -maxdepth 1 \( -name '*.h5' -o -name '.*.tmp.*' \) -newer "$WORK/.start"); then
    bad "$1: cannot list the scratch dir"
  elif [ -z "$stray" ]; then ok "$1: nothing written"; else bad "$1: wrote $stray"; fi
  if [ ! -s "$1.out" ]; then ok "$1: nothing on stdout"; else bad "$1: printed on stdout"; fi
}

scene() { printf '%b' "$2" >"$1"; }

touch "$WORK/.start"
sleep 1  # the -newer test above compares modification times

# --- bad input: exit 2, nothing written ----------------------------------------------------
scene unknown_key.toml '[mast]\nn_bays = 4\nn_bay = 5\n'
run unknown_key 2 unknown_key.toml -o unknown_key.h5 --json
expect_in unknown_key.err "unknown_key.toml:3:" "unknown_key: message has the line"
expect_in unknown_key.err "mast.n_bay" "unknown_key: message names the key"
nothing_written unknown_key

scene wrong_type.toml '[mast]\nn_bays = "four"\n'
run wrong_type 2 wrong_type.toml -o wrong_type.h5
expect_in wrong_type.err "wrong_type.toml:2: mast.n_bays" "wrong_type: message names key and line"
nothing_written wrong_type

scene beta95.toml '[rail]\nx_m = 0.08\nbeta_deg = 95\n'
run beta95 2 beta95.toml -o beta95.h5
expect_in beta95.err "beta95.toml:3: rail.beta_deg" "beta95: message names key and line"
nothing_written beta95

run beta95_set 2 "$TABLE1" --set rail.beta_deg=95 -o beta95_set.h5
expect_in beta95_set.err "rail.beta_deg" "beta95_set: message names the key"
nothing_written beta95_set

# free stack: a rail geometry the held stack refuses is refused with the same message (bay 1 would
# start past its rail entry)
run rail_free 2 "$TABLE1" --set stack.mode=free --set mast.n_bays=2 --set rail.y_m=0.24 -o rail_free.h5 --json
run rail_held 2 "$TABLE1" --set mast.n_bays=2 --set rail.y_m=0.24 -o rail_held.h5 --json
expect_in rail_free.err "rail geometry: bay 1 starts already past its rail entry" "rail_free: the held stack's reason"
if cmp -s rail_free.err rail_held.err; then ok "rail_free: the held stack's message"; else bad "rail_free: messages differ"; fi
nothing_written rail_free

# free stack: retraction runs, here with stack contacts
scene free_retract.toml '[mast]\nn_bays = 3\n[stack]\nmode = "free"\ncontacts = true\n[run]\ndirection = "retract"\n'
run free_retract 0 free_retract.toml --json

# stack contacts: on a held stack, an unknown contact law, a non-boolean value
scene contacts_held.toml '[stack]\nmode = "held"\ncontacts = true\n'
run contacts_held 2 contacts_held.toml -o contacts_held.h5
expect_in contacts_held.err "contacts_held.toml:3: stack.contacts" "contacts_held: message names key and line"
nothing_written contacts_held
scene contact_law.toml '[stack]\nmode = "free"\ncontacts = true\ncontact_law = "elastic"\n'
run contact_law 2 contact_law.toml -o contact_law.h5
expect_in contact_law.err "contact_law.toml:4: stack.contact_law" "contact_law: message names key and line"
nothing_written contact_law
run contacts_set 2 "$TABLE1" --set stack.mode='"free"' --set stack.contacts=yes -o contacts_set.h5
expect_in contacts_set.err "stack.contacts" "contacts_set: message names the key"
nothing_written contacts_set

# run.integrator = "ida" solves the free stack only: refused on a held stack, naming file, line, key
scene ida_held.toml '[run]\nintegrator = "ida"\n'
run ida_held 2 ida_held.toml -o ida_held.h5
expect_in ida_held.err "ida_held.toml:2: run.integrator" "ida_held: message names key and line"
nothing_written ida_held

run set_unknown 2 "$TABLE1" --set mast.n_bay=3 -o set_unknown.h5
expect_in set_unknown.err "--set mast.n_bay=3" "set_unknown: message quotes the --set"
nothing_written set_unknown

run missing_file 2 does_not_exist.toml -o missing_file.h5
expect_in missing_file.err "does_not_exist.toml" "missing_file: message names the file"
nothing_written missing_file

scene syntax.toml '[mast]\nn_bays = = 3\n'
run syntax 2 syntax.toml
expect_in syntax.err "syntax.toml:2:" "syntax: message has line and column"

run no_args 2
run bad_option 2 "$TABLE1" --no-such-option

# --- existing output: refused before simulating, content kept ------------------------------
echo "precious" >existing.h5
run existing 2 "$TABLE1" -o existing.h5 --json
expect_in existing.err "output file exists: existing.h5" "existing: message"
if [ "$(cat existing.h5)" = "precious" ]; then ok "existing: file unchanged"; else bad "existing: file changed"; fi
if [ ! -s existing.out ]; then ok "existing: nothing on stdout"; else bad "existing: printed on stdout"; fi

# --- the Table 1 scene: exit 0, valid JSON, an HDF5 file -------------------------------------
run table1 0 "$TABLE1" --json -o table1.h5
if "$PY" -c 'import json,sys; d=json.load(sys.stdin); assert d["status"] == "ok", d["status"]; assert len(d["bays"]) == d["n_bays"]' <table1.out 2>table1.json.err; then
  ok "table1: valid JSON, status ok, one entry per bay"
else
  bad "table1: stdout is not the expected JSON"
  sed 's/^/     | /' table1.json.err | tail -3
fi
if [ -f table1.h5 ] && [ "$(head -c 8 table1.h5 | od -An -c | tr -d ' ')" = '211HDF\r\n032\n' ]; then
  ok "table1: HDF5 file written"
else
  bad "table1: table1.h5 is not an HDF5 file"
fi

run table1_text 0 "$TABLE1"
if [ -s table1_text.out ]; then ok "table1_text: summary printed"; else bad "table1_text: nothing printed"; fi

# --set before the scene path: each --set takes one value, the scene stays positional
run set_first 0 --set mast.n_bays=3 --set rail.beta_deg=25 "$TABLE1" --json
if "$PY" -c 'import json,sys; d=json.load(sys.stdin); assert d["n_bays"] == 3 and len(d["bays"]) == 3' <set_first.out 2>set_first.json.err; then
  ok "set_first: overrides applied"
else
  bad "set_first: overrides not applied"
fi

# A physical failure (a screw torque far too small to open a bay): exit 1, the file is still written
run failed_run 1 "$TABLE1" --set drive.mode=torque --set drive.torque_Nm=1e-6 --json -o failed_run.h5
if "$PY" -c 'import json,sys; d=json.load(sys.stdin); assert d["status"] != "ok" and d["message"]' <failed_run.out 2>failed_run.json.err; then
  ok "failed_run: JSON with a failure status and a message"
else
  bad "failed_run: stdout is not the expected JSON"
fi
if [ -f failed_run.h5 ] && [ "$(head -c 8 failed_run.h5 | od -An -c | tr -d ' ')" = '211HDF\r\n032\n' ]; then
  ok "failed_run: HDF5 file written"
else
  bad "failed_run: no HDF5 file"
fi

# --force replaces the file
run force 0 "$TABLE1" -o existing.h5 --force
if [ "$(head -c 8 existing.h5 | od -An -c | tr -d ' ')" = '211HDF\r\n032\n' ]; then
  ok "force: file replaced by HDF5 output"
else
  bad "force: file not replaced"
fi
stray=$(find . -maxdepth 1 -name '.*.tmp.*' | head -5)
if [ -z "$stray" ]; then ok "no temporary files left"; else bad "temporary files left: $stray"; fi

# --- hostile input ------------------------------------------------------------------
touch "$WORK/.start"  # nothing_written: only files newer than this count
sleep 1
run huge_mass 2 "$TABLE1" --set mast.strut_mass_kg=1e308 --set run.max_wall_time_s=5 --set run.output_step_s=0 -o huge_mass.h5
expect_in huge_mass.err "--set mast.strut_mass_kg=1e308" "huge_mass: message quotes the --set"
expect_in huge_mass.err "must lie in (0, 10000] kg" "huge_mass: message gives the hard range"
nothing_written huge_mass

run empty_output 2 "$TABLE1" -o ""
expect_in empty_output.err "output file name is empty" "empty_output: message"
nothing_written empty_output

run dev_zero 2 /dev/zero -o dev_zero.h5
expect_in dev_zero.err "larger than the limit" "dev_zero: input bounded"
nothing_written dev_zero

# plausibility: runs (exit 0) with a warning naming key, origin and typical range
scene torque_mm.toml '[mast]\nn_bays = 3\n[drive]\nmode = "motor"\nstall_torque_Nm = 5.2\n'
run plausibility 0 torque_mm.toml --set drive.no_load_speed_rad_per_s=75
expect_in plausibility.err "warning: torque_mm.toml:5: drive.stall_torque_Nm = 5.2 N m is outside the typical range [0.0001, 1] N m" \
  "plausibility: warning with origin and typical range"

run geometry 2 "$TABLE1" --set rail.beta_deg=80 -o geometry.h5
expect_in geometry.err "rail.beta_deg = 80 deg (--set rail.beta_deg=80)" "geometry: the key and its --set"
expect_in geometry.err "table1.toml:18)" "geometry: a key from the file with its line"
nothing_written geometry

# the wall-time cap holds in velocity mode too (kinematic phases): a named status, exit 1
run wall_cap 1 "$TABLE1" --set run.max_wall_time_s=1e-6 --json
if "$PY" -c 'import json,sys; d=json.load(sys.stdin); assert d["status"] == "wall-time limit" and "wall-time cap" in d["message"]' <wall_cap.out 2>wall_cap.json.err; then
  ok "wall_cap: status wall-time limit with its reason"
else
  bad "wall_cap: not stopped by the cap"
fi

# --- a full disk while writing the HDF5 file: exit 3, a clear message, no crash, nothing left ----
# A size-limited file (RLIMIT_FSIZE, SIGXFSZ ignored: writes fail with EFBIG) works without root;
# a 1 MiB tmpfs (ENOSPC) when this runs as root.
( trap '' XFSZ; ulimit -f 200; exec "$SIM" "$TABLE1" --set run.output_step_s=0.001 -o fsize.h5 ) >fsize.out 2>fsize.err
rc=$?
if [ "$rc" -eq 3 ]; then ok "fsize: exit 3"; else bad "fsize: exit $rc, expected 3"; sed 's/^/     | /' fsize.err | head; fi
expect_in fsize.err "File too large" "fsize: the system's reason"
if [ -z "$(find . -maxdepth 1 \( -name 'fsize.h5' -o -name '.fsize.h5.tmp.*' \))" ]; then ok "fsize: nothing left"; else bad "fsize: files left"; fi
# The same limit without the shell ignoring SIGXFSZ: truss-sim ignores it itself (EFBIG, exit 3,
# nothing left), instead of being killed by the signal mid-write with its temporary file left.
( ulimit -f 200; exec "$SIM" "$TABLE1" --set run.output_step_s=0.001 -o fsig.h5 ) >fsig.out 2>fsig.err
rc=$?
if [ "$rc" -eq 3 ]; then ok "fsize, signal not ignored by the shell: exit 3"; else bad "fsize, signal: exit $rc, expected 3"; fi
if [ -z "$(find . -maxdepth 1 \( -name 'fsig.h5' -o -name '.fsig.h5.tmp.*' \))" ]; then ok "fsize, signal: nothing left"; else bad "fsize, signal: files left"; fi
mkdir -p full
if [ "$(id -u)" -eq 0 ] && mount -t tmpfs -o size=1m tmpfs full 2>/dev/null; then
  # data writes fail (0.0001, 0.001); with 800 KiB taken by another file, a smaller file (0.03)
  # fails later, in the final flush
  for step in 0.0001 0.001 0.03; do
    if [ "$step" = 0.03 ]; then head -c 819200 /dev/zero >full/filler; fi
    "$SIM" "$TABLE1" --set run.output_step_s=$step -o full/r.h5 >full.out 2>full.err
    rc=$?
    rm -f full/filler
    if [ "$rc" -eq 3 ]; then ok "tmpfs step $step: exit 3"; else bad "tmpfs step $step: exit $rc, expected 3"; sed 's/^/     | /' full.err | head -5; fi
    expect_in full.err "No space left on device" "tmpfs step $step: the system's reason"
    if [ -z "$(ls -A full)" ]; then ok "tmpfs step $step: nothing left"; else bad "tmpfs step $step: left $(ls -A full)"; fi
  done
  umount full
else
  echo "skip tmpfs disk-full checks (not root or no tmpfs)"
fi

# History memory: a run whose history reaches run.max_history_bytes holds at most 1.1 times the cap
# plus its own working set, measured as the same run's peak resident memory with a cap of a few
# rows (GNU time's %M, KiB). The case: 164 free-stack bays retracting, a row every 0.1 ms (1,404 B
# a row), which fills a 100 MB cap before its end.
hist_args=("$TABLE1" --set stack.mode=free --set run.direction=retract --set mast.n_bays=164
           --set run.output_step_s=0.0001)
/usr/bin/time -f "%M" -o hist_small.rss "$SIM" "${hist_args[@]}" --set run.max_history_bytes=20000 >/dev/null 2>&1
/usr/bin/time -f "%M" -o hist_big.rss "$SIM" "${hist_args[@]}" --set run.max_history_bytes=100000000 >/dev/null 2>&1
small_kib=$(tail -1 hist_small.rss)
big_kib=$(tail -1 hist_big.rss)
bound_kib=$(( (110000000 / 1024) + small_kib ))
# Under AddressSanitizer (scripts/sanitize.sh sets TRUSS_SANITIZED) every allocated byte also has
# its shadow byte per 8 (and redzones): the history's share of the bound is 9/8 of the cap there.
if [ "${TRUSS_SANITIZED:-0}" = 1 ]; then bound_kib=$(( (110000000 / 1024) * 9 / 8 + small_kib )); fi
if [ "$big_kib" -le "$bound_kib" ]; then
  ok "history memory: ${big_kib} KiB resident with a 100 MB cap, within 1.1 x the cap + the run's own ${small_kib} KiB"
else
  bad "history memory: ${big_kib} KiB resident with a 100 MB cap, over 1.1 x the cap + the run's own ${small_kib} KiB"
fi

echo "$passed passed, $failed failed"
if [ "$failed" -eq 0 ]; then
  cd / && rm -rf "$WORK"
  exit 0
fi
echo "outputs kept in $WORK"
exit 1
