// Bench only: a run that costs a given wall time and simulates nothing (truss-campaign
// --synthetic-run-cost-s, a hidden option). It sleeps, so that 2 cores can host 32 or 64 ranks
// and the engine's scheduling and rank 0's result handling are measured alone, and it returns a
// record of the campaign's real size: the inputs are the dispersions' values at the run's point,
// so a method's points show in the file as with real runs, and the outputs are pseudo-random
// numbers, a pure function of (run index, column), so files stay comparable across rank counts,
// transports and resumes. Nothing in it is physics. One output is not random: the campaign's
// [failure] column, if it has one, is the sum of each dispersion's first applied value (a linear
// limit state: with normal dispersions its failure probability is known in closed form), so the
// probability methods can be checked against an exact answer through the whole engine.
#pragma once
#include <cstdint>
#include <string>

#include "campaign/evaluate.hpp"

namespace truss::parallel {

void append_synthetic_record(const campaign::CampaignContext& ctx, const double* u, const campaign::RecordHead& head,
                             double cost_s, std::string& out);

}  // namespace truss::parallel
