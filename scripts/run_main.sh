#!/usr/bin/env bash
# The main job: install, build, run the default uncertainty campaign (the Table-1 mast deployed at
# 0.1 m/s by a sized motor, per-bay mass, stiffness and +-0.5 mm tolerances, 10,000 deployments)
# over MPI ranks, turn its results into the statistical load report, and run the campaign's
# nominal scene once more as a single run with its figures (paper Fig. 4 and 5). Ends with the
# verdict, its key figures and the paths.
# Outputs go to a new folder named after the campaign (out/table1_dispersed, then
# out/table1_dispersed-2, ...): nothing is overwritten.
#   scripts/run_main.sh [CAMPAIGN.toml] [--set key=value ...]   (default campaigns/table1_dispersed.toml)
# Exit status: 0 when every step ran (the verdict, PASS, FAIL or NOT ASSESSED, is the campaign's
# result, printed at the end and in DIR/summary.txt, the same lines); the failing step's status
# otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/progress.sh
t0=$SECONDS
campaign=campaigns/table1_dispersed.toml
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then campaign=$1; shift; fi
[ -f "$campaign" ] || { echo "error: $campaign: no such campaign file" >&2; exit 2; }

echo "[main] checking the Debian packages (scripts/install-deps.sh)"
scripts/install-deps.sh
# The programs and their man pages (cmake --install after this job installs them).
watch_step build configure build.log cmake -S . -B build -DCMAKE_BUILD_TYPE=Release ${CMAKE_ARGS:-}
watch_step build build build.log cmake --build build -j"$(nproc)" --target truss-sim truss-campaign

name=$(basename "$campaign" .toml)
dir=out/$name; k=1
while [ -e "$dir" ]; do k=$((k + 1)); dir=out/$name-$k; done
mkdir -p "$dir"

# Open MPI refuses root without these; one rank per core. No -q: it would hide Open MPI's own
# errors (too few slots, a missing library), leaving an exit status without a message.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Under mpirun rank 0's stderr is a pipe: ask for the in-place display when ours is a terminal.
progress=(--progress lines); [ -t 2 ] && progress=(--progress tty)
case " $* " in *" --progress"*) progress=() ;; esac      # the user's own choice wins
t_campaign=$SECONDS
mpirun -np "$(nproc)" build/truss-campaign "$campaign" -o "$dir/$name.h5" "${progress[@]}" "$@"
t_campaign=$((SECONDS - t_campaign))

# The campaign's nominal scene (its base scene, without dispersions) as a single run with time
# histories, for the paper's figures: the scene the campaign ran, whatever its drive.
/usr/bin/python3 -c 'import h5py, sys; open(sys.argv[2], "w").write(h5py.File(sys.argv[1], "r").attrs["base_scene_toml"])' \
  "$dir/$name.h5" "$dir/nominal_scene.toml"
echo "[main] nominal run: build/truss-sim $dir/nominal_scene.toml"
build/truss-sim "$dir/nominal_scene.toml" --set run.output_step_s=0.01 -o "$dir/nominal_run.h5" --json \
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
