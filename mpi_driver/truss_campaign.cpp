// truss-campaign: MPI entry point. Everything else is in src/parallel/campaign_driver.cpp.
#include <mpi.h>

#include <csignal>
#include <cstdio>

#include "parallel/campaign_driver.hpp"

int main(int argc, char** argv) {
  // A write past the file-size limit (ulimit -f) fails with EFBIG and is reported (exit 3, the journal
  // keeps every finished run) instead of killing the rank with SIGXFSZ (docs/campaigns.md).
  std::signal(SIGXFSZ, SIG_IGN);
  // Funneled: rank 0's journal has a writer thread (campaign/journal.hpp) that makes no MPI calls.
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  if (provided < MPI_THREAD_FUNNELED) {
    // A library that promises only MPI_THREAD_SINGLE: the writer thread still makes no MPI call,
    // which every MPI library we know of tolerates; said once, on rank 0, so that it is on record.
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0)
      std::fprintf(stderr, "truss-campaign: warning: the MPI library provides thread level %d, below MPI_THREAD_FUNNELED (%d); "
                   "the journal's writer thread makes no MPI calls\n", provided, MPI_THREAD_FUNNELED);
  }
  const int status = truss::parallel::run_campaign_command(argc, argv, MPI_COMM_WORLD);
  MPI_Finalize();
  return status;
}
