"""truss_report.reading.schema: what a campaign file holds that the report reads by name
(docs/hdf5-schema.md): the reported outputs, the fields of /stats, the root attributes."""

# The outputs whose distributions are reported (/runs/<key>, /stats/<key>), with a readable name.
OUTPUTS = {
    "peak_drive_force_N": "peak drive force",
    "peak_drive_torque_Nm": "peak drive torque",
    "peak_pin_force_N": "peak rail pin force",
    "peak_diagonal_tension_N": "peak diagonal tension",
    "peak_latch_energy_J": "peak latch energy",
    "deploy_time_s": "deployment time",
}

# Reported percentiles: (percent, name in /stats, label).
LEVELS = [(50.0, "p50", "P50"), (95.0, "p95", "P95"), (99.0, "p99", "P99"),
          (99.865, "p99_865", "P99.865")]

# Every statistic of /stats/<output>: the fields and the percentile levels of its percentiles.
STATS_PERCENTILES = {"p1": 1.0, "p5": 5.0, **{name: q for q, name, _ in LEVELS}}
STATS_FIELDS = ["count", "mean", "std", "min", "max", *STATS_PERCENTILES]

# The per-bay statistics of /stats/bays/lock_time_s.
LOCK_STATS_FIELDS = ("count", "p5", "p50", "p95")

ROOT_ATTRS_STR = ["campaign_name", "campaign_description", "campaign_toml", "base_scene_toml",
                  "sampling", "direction", "drive_mode", "software_version", "git_revision",
                  "start_utc", "end_utc"]

ROOT_ATTRS_INT = ["n_runs", "master_seed", "n_bays_max", "n_ranks", "n_sessions"]

# /runs columns the design-load part of the report reads when present (units from the file).
EXTRA_RUN_COLUMNS = ["start_drive_impulse_Ns", "drive_work_impulses_J", "peak_drive_force_time_s",
                     "peak_drive_force_bay", "peak_pin_force_time_s", "peak_pin_force_bay",
                     "motor_torque_at_speed_Nm", "n_bays", "energy_residual_J",
                     "peak_static_drive_torque_Nm", "peak_inertial_drive_torque_Nm"]
