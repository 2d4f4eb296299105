// Resource limits of a campaign, checked on rank 0 before any work (before the journal exists):
// the memory rank 0's result table needs against the memory available, and the results file
// plus the journal against the free space of the output directory. The estimates are stated in
// the refusal, so that a user can size n_runs.
#pragma once
#include <cstdint>
#include <string>

#include "campaign/evaluate.hpp"

namespace truss::results {

struct ResourceEstimate {
  double bytes_per_run = 0;  // one run in rank 0's memory (result table, journal scan, to-do list)
  double memory_bytes = 0;   // all runs in rank 0's memory
  double output_bytes = 0;   // the results file (its /runs tables)
  double journal_bytes = 0;  // the journal, which exists next to the results file until the end
};

ResourceEstimate estimate_resources(const campaign::CampaignContext& ctx);

// Memory rank 0 may use: the smallest of MemAvailable (/proc/meminfo), the cgroup limit and
// RLIMIT_AS; +inf if none can be read.
double available_memory_bytes();
// Free bytes for an unprivileged writer in `dir` (statvfs); +inf if it cannot be read.
double free_disk_bytes(const std::string& dir);

// Empty if the campaign fits, else the complete refusal ("error: ...", estimates in it). Memory:
// at most 80 % of the available memory (the rest for the process, MPI and the HDF5 library).
// Disk: the results file and the journal, less `journal_on_disk_bytes` that the campaign's journal
// holds already (counted in the journal's estimate, and no longer free).
std::string check_resources(const campaign::CampaignContext& ctx, const std::string& output_path,
                            double journal_on_disk_bytes = 0.0);

}  // namespace truss::results
