#!/usr/bin/env bash
# postproc/ installs as a Python package: into a fresh venv that sees Debian's
# numpy/scipy/h5py/matplotlib/pandas, without network; then the `truss-report` entry point runs
# and `truss_report.read_campaign` imports from outside the source tree.
#   test_install.sh REPO SCRATCH
set -euo pipefail
repo=$1; scratch=$2
rm -rf "$scratch"; mkdir -p "$scratch"
cp -r "$repo/postproc" "$scratch/src"          # the build writes into the source: use a copy
/usr/bin/python3 -m venv --system-site-packages "$scratch/venv"
"$scratch/venv/bin/pip" install -q --no-deps --no-build-isolation --no-index "$scratch/src"
# The install leaves the sources as they were: its egg-info and wheel build go to build/ (ignored).
extra=$(cd "$scratch/src" && find . -mindepth 1 -maxdepth 1 ! -name build | sort)
want=$(cd "$repo/postproc" && find . -mindepth 1 -maxdepth 1 ! -name build | sort)
[ "$extra" = "$want" ] || { echo "FAIL: pip install left files beside the sources: $(comm -23 <(echo "$extra") <(echo "$want"))"; exit 1; }
cd "$scratch"
"$scratch/venv/bin/truss-report" --help | grep -q -- "--levels"
"$scratch/venv/bin/truss-report" /nonexistent.h5 -o out && exit 1 || rc=$?
[ "$rc" -eq 2 ] || { echo "FAIL: truss-report on a missing file exits $rc, not 2"; exit 1; }
"$scratch/venv/bin/python" -c "
import truss_report, os
from truss_report import read_campaign
assert truss_report.__file__.startswith('$scratch/venv/'), truss_report.__file__
print('ok: truss-report entry point and read_campaign installed at', os.path.dirname(truss_report.__file__))"
