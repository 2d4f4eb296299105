// The nominal run of a campaign: the base scene without any dispersion, computed once on rank 0
// (so it cannot depend on the rank count) with its time history, and stored in the results file
// as /nominal (docs/hdf5-schema.md): the fields of a /runs row, its per-bay values and history.
#pragma once
#include <hdf5.h>

#include "campaign/campaign.hpp"
#include "sim/result.hpp"

namespace truss::campaign {

// Simulates the base scene and mast (no draw applied) with the campaign's per-run wall-time cap
// and a history sampled every `step_s` (the campaign's [output] history_step_s). Never throws for
// a run that fails: the status and message say why.
sim::RunResult calc_nominal_run(const CampaignOptions& c, double step_s);

// Writes /nominal into an open campaign file: status (enum, message attribute), every scalar
// field of RunResult except wall_time_s (not reproducible), /nominal/bays/<field> of length
// n_bays_max (NaN beyond the run's bays, as a /runs/bays row) and /nominal/history.
void write_nominal_group(hid_t file, const sim::RunResult& r, int n_bays_max);

}  // namespace truss::campaign
