// The end of a campaign, every rank: the statistics columns whose streamed windows missed are read
// back from the results file by all the ranks, each its share of the datasets
// (results/read_back.hpp), instead of by rank 0 alone.
#pragma once
#include <mpi.h>

#include "campaign/record.hpp"
#include "parallel/campaign_output.hpp"

namespace truss::parallel {

// Collective, after Engine::run on every rank; r0 on rank 0 only (nullptr elsewhere). Rank 0 lists
// the datasets (none: nothing happens) and broadcasts them with the file's path and the ok runs;
// each rank computes its share's percentiles and rank 0 gathers them into its collector's streamed
// statistics. A share that fails (the file unreadable from that rank) is left unresolved: rank 0
// reads it back when it writes /stats. Returns the ranks whose answers it applied (rank 0; 0 elsewhere).
int read_back_statistics(MPI_Comm comm, const campaign::RecordLayout& layout, Rank0* r0);

}  // namespace truss::parallel
