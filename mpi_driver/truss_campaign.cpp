// truss-campaign: MPI entry point. Everything else is in src/parallel/campaign_command.cpp.
#include <mpi.h>

#include "parallel/campaign_command.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  const int status = truss::parallel::run_campaign_command(argc, argv, MPI_COMM_WORLD);
  MPI_Finalize();
  return status;
}
