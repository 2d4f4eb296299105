#!/bin/sh
# The two-rank efficiency on this machine, to re-measure on a quiet machine (nothing else
# running): the Table-1 campaign on 1 rank and on 2 ranks over shared memory (CMA), shared memory
# with single-copy off and TCP, 4,000 runs, 5 interleaved repeats, medians; prints the table of
# docs/benchmarks.md with the load average before and after. With a second argument, that
# truss-campaign binary (an older build) is run beside this build's in every repeat.
#   bench/two_rank_efficiency.sh [BUILD_DIR] [BEFORE_BINARY]     (default: build)
set -eu
here=$(dirname "$0")
if [ $# -ge 2 ]; then
  exec /usr/bin/python3 "$here/bench_scheduler.py" "${1:-$here/../build}" real --runs 4000 --repeats 5 --driver "$2"
fi
exec /usr/bin/python3 "$here/bench_scheduler.py" "${1:-$here/../build}" real --runs 4000 --repeats 5
