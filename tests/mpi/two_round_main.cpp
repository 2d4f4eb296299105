// A test driver: truss-campaign with the toy two-round method of tests/methods/two_round.hpp and the
// toy method with a [failure] event of tests/methods/toy_failure.hpp added to the built-in method
// table (ensemble.method = "two_round", its options in [ensemble.two_round]; "toy", [ensemble.toy]);
// the engine, the journal and the results file as they are. TRUSS_TWO_ROUND_TARGET, when set,
// replaces the campaign's rel_half_width in the method alone (the campaign text unchanged): a
// method that plans otherwise than the one that wrote a journal.
#include <mpi.h>

#include <cstdlib>
#include <memory>

#include "methods/toy_failure.hpp"
#include "methods/two_round.hpp"
#include "parallel/campaign_command.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  using namespace truss;
  methods::MethodRow row = test::two_round_row();
  if (const char* target = std::getenv("TRUSS_TWO_ROUND_TARGET"))
    row.make = [rel = std::atof(target)](const campaign::CampaignContext& ctx,
                                         const methods::MethodTable&) -> std::unique_ptr<methods::Method> {
      const auto& o = ctx.options.ensemble.method.as<test::TwoRoundOptions>();
      return std::make_unique<test::TwoRound>(ctx, o.output, rel);
    };
  const int status = parallel::run_campaign_command(argc, argv, MPI_COMM_WORLD,
                                                    methods::builtin_methods().with(row).with(test::toy_row()));
  MPI_Finalize();
  return status;
}
