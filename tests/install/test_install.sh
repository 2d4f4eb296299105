#!/usr/bin/env bash
# cmake --install into a temporary prefix, then a project outside this tree finds the package with
# find_package(truss_deploy), builds against the installed headers and libraries and runs.
#   test_install.sh BUILD_DIR SOURCE_DIR SCRATCH EXPECT_MAN(0|1)
# Checks: the two programs, the libraries, the headers and the package config are installed; the
# man pages (when help2man was found) hold every option that --help lists; the consumer finds the
# package in the prefix (not in the build tree), and its result for a 4-bay Table-1 deployment is
# the installed truss-sim's (same library code: the same double, compared exactly), and it
# evaluates normal_quantile(0.975) to the tabulated 1.959963984540054 (AS 241 is accurate to
# ~1e-16 relative; 1e-14 allows the last printed digits).
set -euo pipefail
build=$1 src=$2 scratch=$3 expect_man=$4
rm -rf "$scratch"
mkdir -p "$scratch"
prefix=$scratch/prefix
fail() { echo "FAIL: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$prefix" > "$scratch/install.log"
for f in bin/truss-sim bin/truss-campaign \
         lib/libtruss_core.a lib/libtruss_io.a lib/libtruss_util.a lib/libtruss_sampling.a lib/libtruss_campaign.a lib/libtruss_results.a lib/libtruss_methods.a lib/libtruss_parallel.a \
         include/truss_deploy/sim/simulate.hpp include/truss_deploy/sampling/sampling.hpp include/truss_deploy/model/bay.hpp \
         lib/cmake/truss_deploy/truss_deployConfig.cmake lib/cmake/truss_deploy/truss_deployConfigVersion.cmake \
         lib/cmake/truss_deploy/truss_deployTargets.cmake share/truss_deploy/campaigns/scenes/table1.toml; do
  [ -e "$prefix/$f" ] || fail "not installed: $f"
done
# Exported targets must not point into the source or build tree (the package must stand alone).
if grep -q -e "$src/" -e "$build/" "$prefix"/lib/cmake/truss_deploy/*.cmake; then
  fail "package config refers to the source or build tree"
fi

if [ "$expect_man" = 1 ]; then
  for prog in truss-sim truss-campaign; do
    page=$prefix/share/man/man1/$prog.1
    [ -s "$page" ] || fail "no man page $page"
    head -5 "$page" | grep -q '^\.TH' || fail "$page has no .TH header"
    # Every long option of --help appears in the page (troff escapes '-' as '\-').
    opts=$(OMPI_MCA_btl=self "$prefix/bin/$prog" --help | grep -o -- '--[a-z][a-z-]*' | sort -u)
    [ -n "$opts" ] || fail "$prog --help lists no options"
    for o in $opts; do
      grep -q -- "${o//-/\\\\-}" "$page" || fail "$page lacks $o"
    done
  done
fi

cmake -S "$src/tests/install/consumer" -B "$scratch/consumer" -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$prefix" > "$scratch/consumer_configure.log" 2>&1 \
  || { cat "$scratch/consumer_configure.log"; fail "consumer configure"; }
found=$(grep '^truss_deploy_DIR' "$scratch/consumer/CMakeCache.txt" | cut -d= -f2)
[ "$found" = "$prefix/lib/cmake/truss_deploy" ] || fail "consumer found the package at '$found', not in the prefix"
cmake --build "$scratch/consumer" -j2 > "$scratch/consumer_build.log" 2>&1 \
  || { cat "$scratch/consumer_build.log"; fail "consumer build"; }

scene=$prefix/share/truss_deploy/campaigns/scenes/table1.toml
read -r status peak t_deploy q975 < <("$scratch/consumer/consumer" "$scene")
json=$("$prefix/bin/truss-sim" "$scene" --set mast.n_bays=4 --json)
/usr/bin/python3 - "$status" "$peak" "$t_deploy" "$q975" "$json" <<'PY'
import json, sys
status, peak, t_deploy, q975 = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
ref = json.loads(sys.argv[5])
assert status == "ok" == ref["status"], (status, ref["status"])
assert peak == ref["peak_drive_force_N"], (peak, ref["peak_drive_force_N"])
assert t_deploy == ref["deploy_time_s"], (t_deploy, ref["deploy_time_s"])
assert abs(q975 - 1.959963984540054) < 1e-14, q975
print(f"consumer: {status}, peak drive force {peak:.6f} N, deploy time {t_deploy:.4f} s, as installed truss-sim")
PY
echo "install test passed"
