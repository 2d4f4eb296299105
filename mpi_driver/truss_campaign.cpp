// truss-campaign: MPI entry point. Everything else is in src/parallel/campaign_driver.cpp.
#include <mpi.h>

#include "parallel/campaign_driver.hpp"

int main(int argc, char** argv) {
  // Funneled: rank 0's journal has a writer thread (campaign/journal.hpp) that makes no MPI calls.
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  const int status = truss::parallel::run_campaign_command(argc, argv, MPI_COMM_WORLD);
  MPI_Finalize();
  return status;
}
