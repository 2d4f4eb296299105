#!/usr/bin/env bash
# The main job: install, build, run the default uncertainty campaign (the Table-1 mast deployed at
# 0.1 m/s by a sized motor, per-bay mass, stiffness and +-0.5 mm tolerances, 10,000 deployments)
# over MPI ranks, turn its results into the statistical load report, and run the campaign's
# nominal scene once more as a single run with its figures (paper Fig. 4 and 5). Ends with the
# verdict, its key figures and the paths.
# Outputs go to a new folder named after the campaign (out/table1_dispersed, then
# out/table1_dispersed-2, ...): nothing is overwritten.
#   scripts/run_main.sh [CAMPAIGN.toml] [--set key=value ...]   (default campaigns/table1_dispersed.toml)
#   scripts/run_main.sh [CAMPAIGN.toml] --resume   finishes the last interrupted run of CAMPAIGN (Ctrl-C, a
#                                                  kill, a power cut): its folder, its --set options
# Environment: OUT_DIR (default out), BUILD_DIR (default build).
# Exit status: 0 when every step ran (the verdict, PASS, FAIL or NOT ASSESSED, is the campaign's
# result, printed at the end and in DIR/summary.txt, the same lines); the failing step's status
# otherwise (an interrupted campaign: 130, with the line that resumes it).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/progress.sh
t0=$SECONDS
out_dir=${OUT_DIR:-out}
build=${BUILD_DIR:-build}
campaign=campaigns/table1_dispersed.toml
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then campaign=$1; shift; fi
[ -f "$campaign" ] || { echo "error: $campaign: no such campaign file" >&2; exit 2; }
resume=0
args=()
for a in "$@"; do if [ "$a" = --resume ]; then resume=1; else args+=("$a"); fi; done
name=$(basename "$campaign" .toml)

# The folder: a new one, or with --resume the last one whose campaign was interrupted (its journal
# is there, its results file is not).
if [ $resume -eq 1 ]; then
  dir=; d=$out_dir/$name; k=1
  while [ -e "$d" ]; do  # the folders of this campaign in the order they were made; the last interrupted one
    if [ -e "$d/$name.h5.journal" ] && [ ! -e "$d/$name.h5" ]; then dir=$d; fi
    k=$((k + 1)); d=$out_dir/$name-$k
  done
  if [ -z "$dir" ]; then
    echo "error: --resume: no interrupted campaign $name under $out_dir/ (a folder whose $name.h5.journal" \
         "remains and $name.h5 does not); start it without --resume" >&2
    exit 2
  fi
  # Its --set options as first given, unless others are given now (the journal refuses another campaign).
  [ ${#args[@]} -eq 0 ] && [ -s "$dir/campaign.args" ] && mapfile -t args < "$dir/campaign.args"
  echo "[main] resuming the campaign in $dir"
else
  dir=$out_dir/$name; k=1
  while [ -e "$dir" ]; do k=$((k + 1)); dir=$out_dir/$name-$k; done
  mkdir -p "$dir"
  printf '%s\n' ${args[@]+"${args[@]}"} > "$dir/campaign.args"
fi

echo "[main] checking the Debian packages (scripts/install-deps.sh)"
scripts/install-deps.sh
# The programs and their man pages (cmake --install after this job installs them).
watch_step build configure build.log cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release ${CMAKE_ARGS:-}
watch_step build build build.log cmake --build "$build" -j"$(nproc)" --target truss-sim truss-campaign

# Open MPI refuses root without these; one rank per core. No -q: it would hide Open MPI's own
# errors (too few slots, a missing library), leaving an exit status without a message.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Under mpirun rank 0's stderr is a pipe: ask for the in-place display when ours is a terminal.
progress=(--progress lines); [ -t 2 ] && progress=(--progress tty)
case " ${args[*]-} " in *" --progress"*) progress=() ;; esac      # the user's own choice wins
resume_flag=(); [ $resume -eq 1 ] && resume_flag=(--resume)
t_campaign=$SECONDS
# Ctrl-C reaches mpirun, which stops the ranks; the campaign keeps what is done (its journal) and
# says so. This script then says how to go on, after Open MPI's own lines.
trap 'interrupted=1' INT TERM
interrupted=0; rc=0
mpirun -np "$(nproc)" "$build/truss-campaign" "$campaign" -o "$dir/$name.h5" ${progress[@]+"${progress[@]}"} \
  ${args[@]+"${args[@]}"} ${resume_flag[@]+"${resume_flag[@]}"} || rc=$?
trap - INT TERM
if [ $rc -ne 0 ] && [ -e "$dir/$name.h5.journal" ] && [ ! -e "$dir/$name.h5" ]; then
  echo "[main] the campaign stopped (exit $rc) and kept its finished runs in $dir; resume with:" \
       "scripts/run_main.sh $campaign --resume" >&2
  exit $(( interrupted ? 130 : rc ))
fi
[ $rc -eq 0 ] || exit $rc
t_campaign=$((SECONDS - t_campaign))

# The campaign's nominal scene (its base scene, without dispersions) as a single run with time
# histories, for the paper's figures: the scene the campaign ran, whatever its drive.
/usr/bin/python3 -c 'import h5py, sys; open(sys.argv[2], "w").write(h5py.File(sys.argv[1], "r").attrs["base_scene_toml"])' \
  "$dir/$name.h5" "$dir/nominal_scene.toml"
echo "[main] nominal run: $build/truss-sim $dir/nominal_scene.toml"
"$build/truss-sim" "$dir/nominal_scene.toml" --set run.output_step_s=0.01 -o "$dir/nominal_run.h5" --json \
  > "$dir/nominal_run.json" || [ $? -eq 1 ]      # 1: a physical status (stall, ...), still a result

t_report=$SECONDS
# The report's status is its verdict (0 PASS, 3 FAIL, 4 NOT ASSESSED: postproc/report.py); any
# other status is a failed step.
rc=0
/usr/bin/python3 postproc/report.py "$dir/$name.h5" -o "$dir/report" --csv > "$dir/verdict.txt" || rc=$?
case $rc in 0|3|4) ;; *) echo "error: the report failed (exit $rc)" >&2; exit "$rc" ;; esac
t_report=$((SECONDS - t_report))
/usr/bin/python3 postproc/report.py "$dir/nominal_run.h5" -o "$dir/report_nominal_run" --quiet > /dev/null

{
  head -n -1 "$dir/verdict.txt"        # the verdict and its key figures (the last line is the path)
  echo "campaign results: $dir/$name.h5 (campaign ${t_campaign} s)"
  echo "load report:      $dir/report/report.html and report.pdf (report ${t_report} s; run table: $dir/report/runs.csv)"
  echo "nominal run:      $dir/report_nominal_run/report.html (paper Fig. 4 and 5)"
  echo "main job:         $(elapsed_text $((SECONDS - t0)))"
} > "$dir/summary.txt"
rm "$dir/verdict.txt"
echo
cat "$dir/summary.txt"
