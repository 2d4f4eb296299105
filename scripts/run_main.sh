#!/usr/bin/env bash
# The main job: install, build, run the default uncertainty campaign (Table 1 with per-bay mass,
# stiffness and +-0.5 mm tolerances, 10,000 deployments) over MPI ranks, and turn its results into
# the statistical load report; plus the paper's single Table-1 run with Fig. 4 and 5.
# Outputs go to a new folder under out/ (out/main, out/main-2, ...): nothing is overwritten.
#   scripts/run_main.sh [CAMPAIGN.toml] [--set key=value ...]   (default campaigns/table1_dispersed.toml)
set -euo pipefail
cd "$(dirname "$0")/.."
campaign=campaigns/table1_dispersed.toml
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then campaign=$1; shift; fi
scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > build.log 2>&1 || { cat build.log; exit 1; }
cmake --build build -j"$(nproc)" --target truss-sim truss-campaign >> build.log 2>&1 || { tail -50 build.log; exit 1; }
dir=out/main; k=1
while [ -e "$dir" ]; do k=$((k + 1)); dir=out/main-$k; done
mkdir -p "$dir"

# Open MPI refuses root without these; one rank per core.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
name=$(basename "$campaign" .toml)
# Under mpirun rank 0's stderr is a pipe: ask for the in-place display when ours is a terminal.
progress=(--progress lines); [ -t 2 ] && progress=(--progress tty)
case " $* " in *" --progress"*) progress=() ;; esac      # the user's own choice wins
mpirun -np "$(nproc)" build/truss-campaign "$campaign" -o "$dir/$name.h5" "${progress[@]}" "$@"

# The paper's single run (deploy, with histories) for the report's single-run figures.
build/truss-sim campaigns/scenes/table1.toml -o "$dir/table1_run.h5" --json > "$dir/table1_run.json"
/usr/bin/python3 postproc/report.py "$dir/$name.h5" -o "$dir/report" --csv
/usr/bin/python3 postproc/report.py "$dir/table1_run.h5" -o "$dir/report_table1_run"
echo "campaign results: $dir/$name.h5"
echo "load report:      $dir/report/report.html (run table: $dir/report/runs.csv)"
echo "single run:       $dir/report_table1_run/report.html"
