"""truss_report.constants: see the package docstring (postproc/truss_report/__init__.py)."""



# The schema versions this report reads, per file kind (docs/hdf5-schema.md). Campaign files of
# version 1 and 2 have the same layout; 2 changed how a Saltelli design draws A and B; 3 added
# /runs/round (rounds of runs), which the report does not need.
SCHEMA_VERSIONS = {"single_run": (1,), "campaign": (1, 2, 3)}


EXIT_INPUT_ERROR = 2


# Exit status of a written campaign report, by its verdict (postproc/report.py's docstring):
# 0 PASS (and every report without a verdict: a single run, a subset campaign), 3 FAIL (the
# evidence violates a requirement), 4 NOT ASSESSED (nothing fails, but the runs cannot decide
# every requirement). 1 is left to an unexpected error, 2 to bad input.
EXIT_VERDICT = {"pass": 0, "fail": 3, "not_assessed": 4}


CONFIDENCE = 0.95


REPORT_NAME = "report.html"


# The outputs whose distributions are reported, with a readable name.
OUTPUTS = {
    "peak_drive_force_N": "peak drive force",
    "peak_drive_torque_Nm": "peak drive torque",
    "peak_pin_force_N": "peak rail pin force",
    "peak_diagonal_tension_N": "peak diagonal tension",
    "peak_latch_energy_J": "peak latch energy",
    "deploy_time_s": "deployment time",
}
# The same datasets name other events in a retraction.
RETRACT_LABELS = {"deploy_time_s": "retraction time", "peak_latch_energy_J": "peak unlock energy"}


def output_label(key, direction):
    """Readable name of an output for the campaign's direction (deploy or retract)."""
    if direction == "retract" and key in RETRACT_LABELS:
        return RETRACT_LABELS[key]
    return OUTPUTS.get(key, key)


# Reported percentiles: (percent, name in /stats, label).
LEVELS = [(50.0, "p50", "P50"), (95.0, "p95", "P95"), (99.0, "p99", "P99"),
          (99.865, "p99_865", "P99.865")]


# Every statistic of /stats/<output>, as computed here, for the cross-check.
STATS_PERCENTILES = {"p1": 1.0, "p5": 5.0, **{name: q for q, name, _ in LEVELS}}


STATS_FIELDS = ["count", "mean", "std", "min", "max", *STATS_PERCENTILES]


ROOT_ATTRS_STR = ["campaign_name", "campaign_description", "campaign_toml", "base_scene_toml",
                  "sampling", "direction", "drive_mode", "software_version", "git_revision",
                  "start_utc", "end_utc"]


ROOT_ATTRS_INT = ["n_runs", "master_seed", "n_bays_max", "n_ranks", "n_sessions"]


# A statistic in /stats and its recomputation here agree when they differ by at most this much,
# relative to the largest |value| of the column: the same formula on the same float64 data, where
# only the order of the roundings may differ (sums: about n ulps of the largest value). Counts
# must agree exactly.
AGREE_RTOL = 1e-9


# Motor margin: a peak torque counts as exceeding the stall torque above stall x (1 + this).
# A motor starts from rest at its stall torque, so peak = stall up to rounding in every run.
TORQUE_RTOL = 1e-9


TORNADO_TOP = 15


MAX_HISTORY_FIGURES = 12


MAX_FAILED_LISTED = 2000
