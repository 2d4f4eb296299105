#!/usr/bin/env bash
# cmake --install puts truss_deploy into the site-packages of the prefix: into a venv made with
# --system-site-packages (numpy and pandas from Debian), whose python then imports it from any
# folder without PYTHONPATH and gives the installed truss-sim's numbers; and for the default prefix
# /usr/local, a folder that Debian's python and such a venv both search (checked, not written).
#   test_install.sh BUILD_DIR SOURCE_DIR SCRATCH
set -euo pipefail
build=$(realpath "$1") src=$(realpath "$2") scratch=$(realpath -m "$3")
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "$scratch" && mkdir -p "$scratch"
venv=$scratch/venv
/usr/bin/python3 -m venv --system-site-packages --without-pip "$venv"
cmake --install "$build" --prefix "$venv" > "$scratch/install.log"
site=$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_path("purelib"))')
[ -f "$site/truss_deploy/__init__.py" ] || fail "truss_deploy not installed into the venv's $site"
ls "$site"/truss_deploy/_core.*.so > /dev/null || fail "no compiled module in $site/truss_deploy"

scene=$venv/share/truss_deploy/campaigns/scenes/table1.toml
json=$("$venv/bin/truss-sim" "$scene" --set mast.n_bays=4 --set run.output_step_s=0 --json)
version=$("$venv/bin/truss-sim" --version)
(cd / && env -u PYTHONPATH "$venv/bin/python" - "$scene" "$json" "$version" "$site" <<'PY'
import json, sys
import truss_deploy as td
scene, ref, version, site = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3], sys.argv[4]
assert td.__file__.startswith(site), td.__file__
assert version == f"truss-sim {td.__version__} ({td.__git_revision__})", (version, td.__version__)
d = td.simulate(td.Scene.from_toml(scene).with_(**{"mast.n_bays": 4})).to_dict()
for k in ("status", "deploy_time_s", "peak_drive_force_N", "energy_residual_J"):
    assert d[k] == ref[k], (k, d[k], ref[k])
assert [b["lock_time_s"] for b in d["bays"]] == [b["lock_time_s"] for b in ref["bays"]]
print(f"venv: {td.__file__}, {td.__version__}, deploy time {d['deploy_time_s']} s as the installed truss-sim")
PY
) || fail "the venv's python"

# The default prefix: the folder site_dir.py picks is on the search path of Debian's python and of
# a --system-site-packages venv's python.
dir=$(/usr/bin/python3 "$src/python/site_dir.py" /usr/local)
case $dir in /usr/local/*) ;; *) fail "site_dir.py /usr/local gave $dir" ;; esac
for py in /usr/bin/python3 "$venv/bin/python"; do
  "$py" -c 'import sys; sys.exit(0 if sys.argv[1] in sys.path else 1)' "$dir" || fail "$dir is not on $py's path"
done
echo "python install test passed ($site; default prefix: $dir)"
