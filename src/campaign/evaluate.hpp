// Evaluating one point of a campaign: a run's uniforms (from its method's round plan) through the
// dispersions to a scene and a mast, the simulation, and the record (record.hpp) of its outputs.
// A pure function of (campaign, uniforms, run index, round): the same record on any rank, `rank`
// and the wall time apart.
#pragma once
#include <cstdint>
#include <string>

#include "campaign/campaign.hpp"
#include "campaign/dispersion.hpp"
#include "campaign/record.hpp"
#include "sim/result.hpp"

namespace truss::campaign {

// What every rank holds to evaluate the campaign's points. `options` must be valid (validate()):
// parse_campaign_file and parse_campaign_text return valid options.
struct CampaignContext {
  CampaignOptions options;
  DimensionLayout dims;  // uniforms a run, and which belong to which dispersion
  RecordLayout record;
  explicit CampaignContext(CampaignOptions c);
};

// Appends the record of run `head.run` at the point u (dims.total uniforms): dispersed, simulated
// with the campaign's wall-time cap. Never throws for a failed run: a dispersed value the model
// cannot take is the record's status (invalid_input) and message.
void append_run_record(const CampaignContext& ctx, const double* u, const RecordHead& head, std::string& out);

// The run at the point u again, with time histories every step_s: for [output] history_runs.
sim::RunResult calc_run_with_history(const CampaignContext& ctx, const double* u, double step_s);

// The base scene and mast (no draw applied), with the campaign's per-run wall-time cap and a
// history every step_s: the file's /nominal. Never throws for a run that fails.
sim::RunResult calc_nominal_run(const CampaignOptions& c, double step_s);

}  // namespace truss::campaign
