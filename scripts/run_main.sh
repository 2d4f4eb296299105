#!/usr/bin/env bash
# The main job: install, build, simulate the paper's Table-1 deployment and draw its figures.
# Outputs go to out/ (a new numbered folder if out/table1 already exists: nothing is overwritten).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > build.log 2>&1 || { cat build.log; exit 1; }
cmake --build build -j"$(nproc)" --target truss-sim >> build.log 2>&1 || { tail -50 build.log; exit 1; }
dir=out/table1; k=1
while [ -e "$dir" ]; do k=$((k + 1)); dir=out/table1-$k; done
mkdir -p "$dir"
build/truss-sim campaigns/scenes/table1.toml -o "$dir/table1.h5" --json > "$dir/summary.json"
build/truss-sim campaigns/scenes/table1.toml --set run.direction=retract --set run.output_step_s=0.05 \
  -o "$dir/table1_retract.h5" --json > "$dir/summary_retract.json"
/usr/bin/python3 postproc/run_figures.py "$dir/table1.h5" -o "$dir/figures"
build/truss-sim campaigns/scenes/table1.toml --set run.output_step_s=0
echo "results in $dir"
