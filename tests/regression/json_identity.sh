#!/usr/bin/env bash
# Before/after identity check of truss-sim over the shipped scenes: every drive mode, both
# directions, both integrators, and variants (panels, few bays, a stall, a step cap, histories).
#   tests/regression/json_identity.sh record TRUSS_SIM OUTDIR     # write one JSON per case
#   tests/regression/json_identity.sh compare DIR_A DIR_B         # exit 1 on any difference
#   tests/regression/json_compare.py DIR_A DIR_B --rtol 1e-12      # the same to a relative tolerance
# wall_time_s is the only field removed: it is a measurement of the machine, not a result.
# The HDF5 histories of the cases that write them are dumped too (h5dump, datasets only).
set -euo pipefail
cmd=$1
if [ "$cmd" = compare ]; then
  diff -r "$2" "$3" && echo "identical: $(ls "$2" | wc -l) cases"
  exit $?
fi
sim=$2 out=$3
repo=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$out"
cases=()
for scene in "$repo"/campaigns/scenes/*.toml; do
  s=$(basename "$scene" .toml)
  for mode in velocity torque motor; do
    for dir in deploy retract; do
      ints=(dopri54); [ "$mode" != velocity ] && ints=(dopri54 cvode)
      for integ in "${ints[@]}"; do
        base="$scene --set drive.mode=$mode --set run.direction=$dir --set run.integrator=$integ"
        cases+=("${s}_${mode}_${dir}_${integ}|$base")
        cases+=("${s}_${mode}_${dir}_${integ}_panels|$base --set panels.count=40 --set panels.length_m=0.5 --set panels.mass_kg=0.05")
        cases+=("${s}_${mode}_${dir}_${integ}_5bays|$base --set mast.n_bays=5 --set mast.strut_inertia_kg_m2=4e-4 --set mast.tip_mass_kg=3")
      done
    done
  done
  cases+=("${s}_motor_stall|$scene --set drive.mode=motor --set drive.stall_torque_Nm=0.0044")
  cases+=("${s}_torque_stall|$scene --set drive.mode=torque --set drive.torque_Nm=0.0002")
  cases+=("${s}_torque_steplimit|$scene --set drive.mode=torque --set run.max_steps=50")
  cases+=("${s}_motor_rtol4|$scene --set drive.mode=motor --set run.rtol=1e-4 --set run.atol=1e-6")
done
for c in "${cases[@]}"; do
  name=${c%%|*} args=${c#*|}
  # shellcheck disable=SC2086
  "$sim" $args --json 2>/dev/null | grep -v '"wall_time_s"' > "$out/$name.json" || true
done
# Histories of three cases through the HDF5 writer.
for c in "table1|" "table1_motor|--set drive.mode=motor" "table1_torque_retract|--set drive.mode=torque --set run.direction=retract"; do
  name=${c%%|*} args=${c#*|}
  rm -f "$out/$name.h5"
  # shellcheck disable=SC2086
  "$sim" "$repo/campaigns/scenes/table1.toml" $args --set run.output_step_s=0.05 -o "$out/$name.h5" >/dev/null 2>&1 || true
  h5dump -m '%.17g' -g /history "$out/$name.h5" 2>&1 | tail -n +2 > "$out/$name.history.txt" || true
  rm -f "$out/$name.h5"
done
echo "recorded ${#cases[@]} cases in $out"
