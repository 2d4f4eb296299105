#!/usr/bin/env bash
# `cmake --install build --prefix P` right after the main job (scripts/run_main.sh), which builds
# only the targets it names (the two programs, and the libraries they link): a fresh build tree
# of this source, configured as the main job configures it, holding only those targets' files
# (copied from BUILD_DIR, where they were built), must install completely: exit 0, the programs,
# the libraries, the package config and the man pages (when help2man is there). This is what a
# user meets; a full build (ctest's) would hide a file that only another target makes.
#   test_install_after_main.sh BUILD_DIR SOURCE_DIR SCRATCH EXPECT_MAN(0|1)
set -euo pipefail
build=$1 src=$2 scratch=$3 expect_man=$4
rm -rf "$scratch"
mkdir -p "$scratch"
fail() { echo "FAIL: $*" >&2; exit 1; }

# The main job's targets, read from the script (one source of truth).
targets=$(grep -o -- '--target [a-z_ -]*' "$src/scripts/run_main.sh" | head -n 1 | sed 's/--target //')
[ -n "$targets" ] || fail "no --target list in scripts/run_main.sh"
fresh=$scratch/build
cmake -S "$src" -B "$fresh" -DCMAKE_BUILD_TYPE=Release > "$scratch/configure.log" 2>&1 \
  || { cat "$scratch/configure.log"; fail "configure"; }
for t in $targets; do
  [ -x "$build/$t" ] || fail "$build/$t: the main job's target $t is not built"
  cp -p "$build/$t" "$fresh/$t"
done
cp -p "$build"/lib*.a "$fresh/"     # the libraries the programs link (built with them)

prefix=$scratch/prefix
if ! cmake --install "$fresh" --prefix "$prefix" > "$scratch/install.log" 2>&1; then
  cat "$scratch/install.log"
  fail "cmake --install after a build of '$targets' only"
fi
for f in bin/truss-sim bin/truss-campaign lib/libtruss_campaign.a include/truss_deploy/sim/simulate.hpp \
         lib/cmake/truss_deploy/truss_deployConfig.cmake share/truss_deploy/campaigns/table1_dispersed.toml; do
  [ -e "$prefix/$f" ] || fail "not installed: $f"
done
if [ "$expect_man" = 1 ]; then
  for prog in truss-sim truss-campaign; do
    head -5 "$prefix/share/man/man1/$prog.1" 2>/dev/null | grep -q '^\.TH' || fail "no man page $prog.1"
  done
fi
echo "install after the main job's build ($targets): complete"
