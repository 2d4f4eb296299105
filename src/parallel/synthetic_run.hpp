// Bench only: a run that costs a given wall time and simulates nothing (truss-campaign
// --synthetic-run-cost-s, a hidden option). It sleeps, so that 2 cores can host 32 or 64 ranks
// and the scheduler and rank 0's result handling are measured alone, and it returns a record of
// the campaign's real size (every column present, so a result message is as long as a real one)
// whose values are a pure function of (run index, column): files stay comparable across rank
// counts and transports. Nothing in it is physics.
#pragma once
#include <cstdint>

#include "campaign/run_record.hpp"

namespace truss::parallel {

campaign::RunRecord synthetic_run_record(const campaign::CampaignContext& ctx, std::int64_t run_index, int rank,
                                         double cost_s);

}  // namespace truss::parallel
