"""truss_report.page.run_table: runs.csv reads back to the run table's float64 values bit for bit.
Checked with Python's own float() on every field (and pandas' round-trip parser), on values chosen
where decimal formatting goes wrong: NaN, both infinities, -0.0, the smallest subnormal, the
largest double, 0.1, 2^53 + 2, random doubles of every exponent; and the text columns (a message
with quotes and commas) as csv.reader reads them."""
import csv
import struct

import numpy as np
import pandas as pd

from truss_report.page.run_table import number_fields, write_run_table

EDGES = [float("nan"), float("inf"), -float("inf"), -0.0, 0.0, 5e-324, -5e-324, 1.7976931348623157e308,
         0.1, -0.3, 2.0 ** 53 + 2, 1e-5, 123456789.123456789, 2.2250738585072014e-308]


def bits(x):
    return struct.pack("<d", x)


def table():
    rng = np.random.default_rng(7)
    n = 50
    rand = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-300, 300, (n, 3))
    df = pd.DataFrame({"status": pd.Categorical(["ok"] * (n - 1) + ["failed"]),
                       "input:mast.strut_mass_kg[bay 1]": rand[:, 0], "peak_drive_force_N": rand[:, 1],
                       "lock_time_s[bay 1]": rand[:, 2],
                       "message": [""] * (n - 1) + ['CVODE: "too much work", t = 3.5 s']})
    df.loc[:len(EDGES) - 1, "peak_drive_force_N"] = EDGES
    return df


def test_fields_read_back_bit_for_bit():
    values = EDGES + list(np.random.default_rng(3).standard_normal(200) * 10.0 ** np.arange(-300, 300, 3))
    fields = number_fields(values).split(",")
    assert len(fields) == len(values)
    assert fields[:3] == ["nan", "inf", "-inf"]
    assert all(bits(float(f)) == bits(v) for f, v in zip(fields[3:], values[3:]))


def test_run_table_reads_back(tmp_path):
    df = table()
    path = tmp_path / "runs.csv"
    write_run_table(df, str(path))
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    head = rows[0]
    assert head == ["run_index", "status", "input:mast.strut_mass_kg[bay 1]", "peak_drive_force_N",
                    "lock_time_s[bay 1]", "message"]
    assert [r[0] for r in rows[1:]] == [str(i) for i in range(len(df))]
    assert [r[1] for r in rows[1:]] == list(df["status"].astype(str))
    assert [r[-1] for r in rows[1:]] == list(df["message"])
    for col in head[2:-1]:
        got = [float(r[head.index(col)]) for r in rows[1:]]
        assert all(bits(g) == bits(w) or (np.isnan(g) and np.isnan(w)) for g, w in zip(got, df[col])), col
    back = pd.read_csv(path, float_precision="round_trip")
    assert np.array_equal(back["peak_drive_force_N"].to_numpy(), df["peak_drive_force_N"].to_numpy(), equal_nan=True)
