// Rank 0's side of the engine without MPI (parallel/engine.hpp, Collector): a session that stores
// results and is cut off, then --resume from its journal: the restored records in the results file,
// chunks written as they complete (memory bounded), the journaled plan proposed again, and a
// method that proposes another plan refused.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include "campaign_fixtures.hpp"
#include "io/scene_toml.hpp"
#include "methods/fixed_design.hpp"
#include "methods/two_round.hpp"
#include "parallel/engine.hpp"

using namespace truss;
namespace fs = std::filesystem;

namespace {

struct Session {
  std::unique_ptr<results::Journal> journal;
  std::unique_ptr<results::CampaignFile> file;
  parallel::Progress progress{0, 0, parallel::ProgressMode::none, 1.0};
  std::unique_ptr<parallel::Collector> collector;
  Session(const campaign::CampaignContext& ctx, methods::Method& m, const std::string& out, bool resume) {
    journal = std::make_unique<results::Journal>(resume ? results::Journal::open_existing(out + ".journal", "text")
                                                        : results::Journal::create(out + ".journal", "text"));
    file = std::make_unique<results::CampaignFile>(out, ctx, results::StoreOptions{512, 1});
    collector = std::make_unique<parallel::Collector>(ctx.record, m, *journal, *file, progress,
                                                      parallel::EngineOptions{});
  }
};

// Run `run`'s record of round `plan` as a sealed frame (distinct values, campaign_fixtures.hpp).
std::string frame(const campaign::RecordLayout& L, std::int64_t run, std::int64_t round) {
  std::string f;
  const std::size_t start = results::begin_frame(f);
  f += campaign::test::distinct_record(L, run, round);
  results::seal_frame(f, start, results::FrameKind::run);
  return f;
}

}  // namespace

TEST_CASE("collector: a cut session resumed from its journal, memory bounded, plans checked", "[engine]") {
  const fs::path dir = fs::temp_directory_path() / ("truss_collector_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string out = (dir / "c.h5").string();
  const campaign::CampaignContext ctx(campaign::test::small_campaign("monte_carlo", 3000));
  const campaign::RecordLayout& L = ctx.record;
  methods::FixedDesign design(ctx);
  {
    Session s(ctx, design, out, false);
    s.collector->start_session(0.0, 2);
    const methods::RoundPlan plan = s.collector->plan_round(0, 0);
    REQUIRE(plan.n_runs == 3000);
    // 2,000 runs arrive about in index order (blocks of 50 reversed), as the engine hands them out.
    for (std::int64_t b = 0; b < 2000; b += 50)
      for (std::int64_t r = b + 49; r >= b; --r) s.collector->add_frame(frame(L, r, 0), plan);
    CHECK_THROWS_WITH(s.collector->add_frame(frame(L, 7, 0), plan), Catch::Contains("run 7 received twice"));
    CHECK_THROWS_WITH(s.collector->add_frame(frame(L, 2500, 1), plan), Catch::Contains("(round 1) in round 0"));
    CHECK_THROWS_WITH(s.collector->add_frame(frame(L, 3000, 0), plan), Catch::Contains("in round 0 (runs 0 to 2999)"));
    std::string cut = frame(L, 2100, 0);
    cut.pop_back();
    CHECK_THROWS_AS(s.collector->add_frame(cut, plan), std::runtime_error);
    s.collector->tick(true);  // the journal synced; then the session ends without a results file
  }
  CHECK_FALSE(fs::exists(out));
  {
    Session s(ctx, design, out, true);
    const results::JournalScan scan = s.collector->restore();
    CHECK(scan.records_kept == 2000);
    CHECK(s.collector->session().session == 1);
    const results::ResultStore& store = s.file->store();
    CHECK(store.n_done() == 2000);
    CHECK(store.peak_chunks_in_memory() <= 2);  // chunks of 512 written as they complete
    const methods::RoundPlan plan = s.collector->plan_round(0, 0);  // the journaled one
    CHECK(plan.n_runs == 3000);
    for (std::int64_t r = 2000; r < 3000; ++r) s.collector->add_frame(frame(L, r, 0), plan);
    CHECK(s.collector->plan_round(1, 3000).n_runs == 0);
    s.file->write_summary({}, sim::RunResult{}, results::CampaignFileInfo{});
    s.file->commit(false);
  }
  const hid_t f = H5Fopen(out.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const auto status = results::read_status(f, 3000);
  const auto last = results::read_f64_column(f, "runs/peak_drive_force_N", 3000);
  const int k = L.find_output("peak_drive_force_N");
  int cell = 0;  // peak_drive_force_N's cell among the float64 cells of a record
  for (int i = campaign::RecordLayout::kWallTime + 1; i < k; ++i)
    cell += L.fields()[static_cast<std::size_t>(i)].type == campaign::ValueType::f64;
  for (std::int64_t r = 0; r < 3000; ++r) {
    CHECK(status[static_cast<std::size_t>(r)] == (campaign::test::stalls(r) ? 2 : 0));
    CHECK(last[static_cast<std::size_t>(r)] == campaign::test::cell_value(r, cell));
  }
  H5Fclose(f);
  fs::remove(out);
  fs::remove(out + ".journal");

  // A method that proposes another round 0 than the journal holds: refused, the journal untouched.
  {
    Session s(ctx, design, out, false);
    s.collector->start_session(0.0, 2);
    const methods::RoundPlan plan = s.collector->plan_round(0, 0);
    for (std::int64_t r = 0; r < 100; ++r) s.collector->add_frame(frame(L, r, 0), plan);
    s.collector->tick(true);
  }
  const auto size = fs::file_size(out + ".journal");
  campaign::CampaignOptions more = ctx.options;
  more.ensemble.n_runs = 3500;
  const campaign::CampaignContext other(more);
  methods::FixedDesign other_design(other);
  {
    Session s(other, other_design, out, true);
    CHECK_THROWS_WITH(s.collector->restore(), Catch::Contains("round 0 of the journal is not the round the method"));
  }
  CHECK(fs::file_size(out + ".journal") == size);
  fs::remove_all(dir);
}
