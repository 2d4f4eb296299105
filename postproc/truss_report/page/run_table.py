"""truss_report.page.run_table: the run table as CSV (DIR/runs.csv of the report)."""
import numpy as np


def write_run_table(df, path):
    """The run table as CSV, one row per run: `run_index` (the 0-based row of /runs), `status`
    (its name), the inputs (`input:<key>`, `input:<key>[bay j]`), the per-run outputs, the per-bay
    outputs (`<field>[bay j]`) and last `message` (quoted). Units are in the column names (`_N`,
    `_s`, ...), as in the file; NaN is written as `nan`; numbers with 17 significant digits, so
    that they read back to the file's float64 values exactly."""
    inputs = [c for c in df.columns if c.startswith("input:")]
    per_bay = [c for c in df.columns if "[bay " in c and not c.startswith("input:")]
    responses = [c for c in df.columns if c not in inputs and c not in per_bay
                 and c not in ("status", "message")]
    order = inputs + responses + per_bay
    values = df[order].to_numpy(dtype=np.float64)
    # One %-format per row: about four times faster than DataFrame.to_csv on 10,000 x 600 values.
    row_format = "%d,%s," + ",".join(["%.17g"] * len(order)) + ',"%s"\n'
    status = df["status"].astype(str).tolist()
    with open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(",".join(["run_index", "status", *order, "message"]) + "\n")
        for i, (run, row) in enumerate(zip(df.index.tolist(), values.tolist())):
            fh.write(row_format % (run, status[i], *row, df["message"].iat[i].replace('"', '""')))
