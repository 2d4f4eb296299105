#!/usr/bin/env bash
# End to end: truss-sim writes a real HDF5 file of the Table-1 scene (10 bays), the post-processor
# draws the paper's Fig. 4 and Fig. 5 from it.
set -euo pipefail
SIM=$1; ROOT=$2; SCRATCH=$3
rm -rf "$SCRATCH"; mkdir -p "$SCRATCH"
"$SIM" "$ROOT/campaigns/scenes/table1.toml" --set mast.n_bays=10 --set run.output_step_s=0.01 -o "$SCRATCH/run.h5" --json > "$SCRATCH/run.json"
/usr/bin/python3 - "$SCRATCH/run.h5" "$SCRATCH/run.json" <<'PY'
import sys, json, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
js = json.load(open(sys.argv[2]))
assert f.attrs["schema_version"] == 1
for grp in ("summary", "bays", "history"):
    for k, d in f[grp].items():
        assert "units" in d.attrs, f"{grp}/{k} has no units"
h = f["history"]
assert abs(h["t_s"][-1] - js["deploy_time_s"]) < 1e-12, "history ends at the end of the run"
assert np.all(np.diff(h["t_s"][()]) > 0)
assert abs(f["summary"]["peak_drive_force_N"][()] - js["peak_drive_force_N"]) < 1e-12
assert np.allclose(f["bays"]["lock_time_s"][()], [b["lock_time_s"] for b in js["bays"]], rtol=0, atol=1e-12)
print("hdf5 and json agree")
PY
/usr/bin/python3 "$ROOT/postproc/run_figures.py" "$SCRATCH/run.h5" -o "$SCRATCH/fig" --bay 10
for f in fig4_hinge_trajectory_bay10.png fig5_drive_and_pin_force.png fig5_bay10_zoom.png; do
  head -c 8 "$SCRATCH/fig/$f" | od -An -tx1 | grep -q "89 50 4e 47 0d 0a 1a 0a" || { echo "FAIL: $f is not a PNG"; exit 1; }
done
echo "end-to-end OK"
