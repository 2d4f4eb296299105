// The run result as the simulation layer publishes it: the types live in stages/result.hpp
// (filled by the stage loop); sim/ and everything above use these names.
#pragma once
#include "stages/result.hpp"

namespace truss::sim {
using stages::BayResult;
using stages::kRunStatusCount;
using stages::RunResult;
using stages::RunStatus;
using stages::TimeHistory;
using stages::to_string;
}  // namespace truss::sim
