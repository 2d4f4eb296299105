"""truss_report.page.run_table: the run table as CSV (DIR/runs.csv of the report)."""
import ujson     # Debian's python3-ujson: shortest round-trip float formatting, in C
import numpy as np


def number_fields(values):
    """A row's floats as CSV fields: the shortest decimal that reads back to each float64 (the
    same value, -0.0 included), NaN as `nan`, infinities as `inf` and `-inf`."""
    text = ujson.dumps(values, allow_nan=True)[1:-1]
    if "N" in text or "I" in text:
        text = text.replace("NaN", "nan").replace("Infinity", "inf")
    return text


def write_run_table(df, path):
    """The run table as CSV, one row per run: `run_index` (the 0-based row of /runs), `status`
    (its name), the inputs (`input:<key>`, `input:<key>[bay j]`), the per-run outputs, the per-bay
    outputs (`<field>[bay j]`) and last `message` (quoted). Units are in the column names (`_N`,
    `_s`, ...), as in the file; numbers as number_fields writes them (they read back to the file's
    float64 values exactly; formatting them is the report's largest single cost, and ujson's C
    formatting takes 0.6 of the time of Python's "%.17g")."""
    inputs = [c for c in df.columns if c.startswith("input:")]
    per_bay = [c for c in df.columns if "[bay " in c and not c.startswith("input:")]
    responses = [c for c in df.columns if c not in inputs and c not in per_bay
                 and c not in ("status", "message")]
    order = inputs + responses + per_bay
    values = df[order].to_numpy(dtype=np.float64)
    status = df["status"].astype(str).tolist()
    messages = df["message"].tolist()
    with open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(",".join(["run_index", "status", *order, "message"]) + "\n")
        for i, (run, row) in enumerate(zip(df.index.tolist(), values.tolist())):
            message = messages[i].replace('"', '""')
            fh.write(f'{run},{status[i]},{number_fields(row)},"{message}"\n')
