// A test driver: truss-campaign with the toy two-round method of tests/methods/two_round.hpp in
// place of the campaign's sampling method, over peak_drive_force_N; the engine, the journal and the
// results file as they are. TRUSS_TWO_ROUND_TARGET sets the relative half-width of the mean's 95 %
// interval that round 0 must reach (default 0.02).
#include <mpi.h>

#include <cstdlib>
#include <memory>

#include "methods/two_round.hpp"
#include "parallel/campaign_command.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  const char* target = std::getenv("TRUSS_TWO_ROUND_TARGET");
  const double rel = target ? std::atof(target) : 0.02;
  const int status = truss::parallel::run_campaign_command(
      argc, argv, MPI_COMM_WORLD, [rel](const truss::campaign::CampaignContext& ctx) {
        return std::make_unique<truss::test::TwoRound>(ctx, "peak_drive_force_N", rel);
      });
  MPI_Finalize();
  return status;
}
