// truss-campaign: MPI entry point. Everything else is in src/parallel/campaign_command.cpp.
#include <mpi.h>

#include <malloc.h>

#include <csignal>

#include "parallel/campaign_command.hpp"

int main(int argc, char** argv) {
  // A write past the file-size limit (ulimit -f) fails with EFBIG and is reported (exit 3, the journal
  // keeps every finished run) instead of killing the rank with SIGXFSZ (docs/campaigns.md).
  std::signal(SIGXFSZ, SIG_IGN);
  // Megabyte buffers (chunks, messages) stay in glibc's heap, reused, instead of each being mapped
  // anew (and faulted in page by page) and returned at free.
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  MPI_Init(&argc, &argv);
  const int status = truss::parallel::run_campaign_command(argc, argv, MPI_COMM_WORLD);
  MPI_Finalize();
  return status;
}
