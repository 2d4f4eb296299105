// The statistics read back by every rank (stats_read_back.hpp).
#include "parallel/stats_read_back.hpp"

#include <iostream>
#include <string>
#include <vector>

#include "parallel/engine.hpp"
#include "results/read_back.hpp"
#include "results/result_store.hpp"

namespace truss::parallel {

namespace {

// Rank 0's plan: the datasets to read back, or empty (none, or no statistics to complete).
std::string find_plan(const campaign::RecordLayout& layout, Rank0& r0) {
  const std::optional<results::StreamedStats>& s = r0.collector->stats();
  if (!s) return {};
  const hid_t file = r0.file->handle();
  const std::int64_t n = r0.file->store().n_runs();
  results::ReadBackPlan plan;
  plan.jobs = results::find_read_back(file, layout, *s, n);
  if (plan.jobs.empty()) return {};
  plan.path = r0.file->temporary_path();
  const std::vector<std::int8_t> status = results::read_status(file, n);
  plan.ok.resize(status.size());
  for (std::size_t i = 0; i < status.size(); ++i) plan.ok[i] = status[i] == 0;
  return results::to_bytes(plan);
}

// Collective: every rank's bytes on rank 0 (in rank order), waiting with wait_idle.
std::vector<std::string> gather_strings(MPI_Comm comm, const std::string& mine) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  int len = static_cast<int>(mine.size());
  std::vector<int> lens(rank == 0 ? static_cast<std::size_t>(size) : 0), at(lens.size());
  MPI_Request r;
  MPI_Igather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, 0, comm, &r);
  wait_idle(&r);
  std::string all;
  if (rank == 0) {
    for (std::size_t i = 1; i < lens.size(); ++i) at[i] = at[i - 1] + lens[i - 1];
    all.resize(static_cast<std::size_t>(at.back() + lens.back()));
  }
  MPI_Igatherv(mine.data(), len, MPI_CHAR, all.data(), lens.data(), at.data(), MPI_CHAR, 0, comm, &r);
  wait_idle(&r);
  std::vector<std::string> out;
  for (std::size_t i = 0; i < lens.size(); ++i) out.push_back(all.substr(static_cast<std::size_t>(at[i]),
                                                                         static_cast<std::size_t>(lens[i])));
  return out;
}

}  // namespace

int read_back_statistics(MPI_Comm comm, const campaign::RecordLayout& layout, Rank0* r0) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::string bytes;
  if (r0) {
    try {
      bytes = find_plan(layout, *r0);
    } catch (const std::exception& e) {  // rank 0 reads them back itself when it writes /stats
      std::cerr << "[truss-campaign] the statistics' read-back is rank 0's alone: " << e.what() << "\n";
      bytes.clear();
    }
  }
  broadcast_string(comm, bytes);
  if (bytes.empty()) return 0;
  const results::ReadBackPlan plan = results::read_read_back_plan(bytes);
  std::vector<results::ReadBackAnswer> answers;
  for (const std::size_t j : results::find_jobs_of(plan.jobs, rank, size)) {
    try {
      std::vector<results::ReadBackAnswer> a = results::calc_read_back(plan.path, plan.jobs[j], plan.ok);
      answers.insert(answers.end(), a.begin(), a.end());
    } catch (const std::exception& e) {  // left unresolved: rank 0 reads it back when it writes /stats
      std::cerr << "[truss-campaign] rank " << rank << " could not read back " << plan.jobs[j].path << ": " << e.what()
                << "\n";
    }
  }
  const std::vector<std::string> all = gather_strings(comm, results::to_bytes(answers));
  if (!r0) return 0;
  results::StreamedStats s = *r0->collector->stats();
  int ranks = 0;
  try {
    for (const std::string& b : all) {
      const std::vector<results::ReadBackAnswer> a = results::read_read_back_answers(b);
      results::apply_read_back(s, a);
      ranks += !a.empty();
    }
  } catch (const std::exception& e) {  // the statistics as they were: rank 0 reads them back itself
    std::cerr << "[truss-campaign] the statistics read back by the ranks are not usable: " << e.what() << "\n";
    return 0;
  }
  r0->collector->set_stats(std::move(s));
  return ranks;
}

}  // namespace truss::parallel
