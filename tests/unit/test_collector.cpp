// Rank 0's side of the engine on one rank without mpirun (MPI started as a singleton; parallel/
// engine.hpp: Collector, ChunkOwner, Engine::serve_local): a session on "2 ranks" whose records are
// in rank 0's journal and in rank 1's part journal is cut off, then --resume from both: the
// restored records in the results file, chunks written as they complete (memory bounded), the
// journaled plan proposed again; a part journal that lost its tail ends the restored rounds (the
// later plans and records cut from the journals); a method that proposes another plan refused,
// the journals untouched.
#include <catch2/catch.hpp>

#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "campaign_fixtures.hpp"
#include "io/scene_toml.hpp"
#include "methods/fixed_design.hpp"
#include "parallel/engine.hpp"
#include "parallel/owner.hpp"
#include "util/isal.hpp"

using namespace truss;
namespace fs = std::filesystem;

namespace {

constexpr const char* kText = "text";  // the journals' campaign text
constexpr std::int64_t kChunk = 512;

void start_mpi() {
  int started = 0;
  MPI_Initialized(&started);
  if (started) return;
  MPI_Init(nullptr, nullptr);  // a singleton: the test runs without mpirun
  std::atexit([] { MPI_Finalize(); });
}

// A method of fixed rounds (runs 600 each, `rounds` of them) that reads its records: the engine
// hands it every round's statuses, and on --resume it proposes the journaled rounds again.
class FixedRounds : public methods::Method {
 public:
  explicit FixedRounds(std::int64_t rounds, std::int64_t runs = 600) : rounds_(rounds), runs_(runs) {}
  bool reads_records() const override { return true; }
  methods::Proposal propose(std::int64_t round, const methods::RoundRecords& previous) override {
    if (round > 0) REQUIRE(std::count(previous.status.begin(), previous.status.end(), -1) == 0);
    return {round < rounds_ ? runs_ : 0, {}};
  }
  void calc_uniforms(const methods::RoundPlan&, std::int64_t, double*) const override {}

 private:
  std::int64_t rounds_, runs_;
};

// One session of rank 0 alone, as truss-campaign's rank 0 holds it.
struct Session {
  std::string out;
  std::unique_ptr<results::Journal> journal;
  std::unique_ptr<results::CampaignFile> file;
  parallel::Progress progress{0, 0, parallel::ProgressMode::none, 1.0};
  std::unique_ptr<parallel::Collector> collector;
  std::unique_ptr<parallel::Engine> engine;
  std::unique_ptr<parallel::ChunkOwner> owner;
  Session(const campaign::CampaignContext& ctx, methods::Method& m, const std::string& o, bool resume) : out(o) {
    start_mpi();
    journal = std::make_unique<results::Journal>(resume ? results::Journal::open_existing(out + ".journal", kText)
                                                        : results::Journal::create(out + ".journal", kText));
    const results::StoreOptions store{kChunk, 1};
    file = std::make_unique<results::CampaignFile>(out, ctx, store);
    collector = std::make_unique<parallel::Collector>(ctx.record, m, *journal, *file, progress, parallel::EngineOptions{});
    engine = std::make_unique<parallel::Engine>(MPI_COMM_SELF, kChunk,
                                                ctx.record.fields()[campaign::RecordLayout::kStatus].offset,
                                                parallel::EngineOptions{});
    owner = std::make_unique<parallel::ChunkOwner>(
        ctx.record, store, collector->observed_fields(),
        parallel::OwnerFiles{0, 0, out, file->temporary_path(), util::calc_crc32(kText), journal.get(), {}},
        engine->sender(), 2.0);
    engine->attach(*owner, collector.get(), {});
  }
  parallel::RestoreSummary restore() {
    const parallel::RestoreSummary s = collector->restore(
        kText, {[&](const methods::RoundPlan& p) { owner->add_round(p); },
                [&](std::string_view r, std::int64_t session) { owner->replay_record(r, session); },
                [&] { engine->serve_local(); }});
    owner->set_session(collector->session().session);
    return s;
  }
  methods::RoundPlan plan(std::int64_t round, std::int64_t first) {
    const methods::RoundPlan p = collector->plan_round(round, first);
    if (p.n_runs > 0) owner->add_round(p);
    return p;
  }
  void add(const std::string& frames) {
    owner->add_records(frames);
    engine->serve_local();
  }
  void finish() {
    owner->end_rounds();
    engine->serve_local();
    REQUIRE(owner->done());
    owner->finish();
    REQUIRE(collector->stats());  // every chunk merged: the statistics rank (rank 0 here) sent them
    file->write_summary(*collector->stats(), {}, sim::RunResult{}, results::CampaignFileInfo{});
    file->commit(false);
    journal->close_and_remove();
    results::remove_part_journals(out);
  }
};

// Run `run`'s record of round `round` as a sealed frame (distinct values, computed on rank 1:
// campaign_fixtures.hpp).
std::string frame(const campaign::RecordLayout& L, std::int64_t run, std::int64_t round) {
  std::string f;
  const std::size_t start = results::begin_frame(f);
  f += campaign::test::distinct_record(L, run, round);
  results::seal_frame(f, start, results::FrameKind::run);
  return f;
}

// A part journal of rank 1 in session 0 holding runs [from, to) of round `round`, in reversed blocks of 50.
void write_part(const std::string& out, const campaign::RecordLayout& L, std::int64_t from, std::int64_t to,
                std::int64_t round) {
  results::Journal part = results::Journal::create_part(results::part_journal_path(out, 0, 1),
                                                        util::calc_crc32(kText), 0, 1);
  for (std::int64_t b = from; b < to; b += 50)
    for (std::int64_t r = std::min(to, b + 50) - 1; r >= b; --r) part.append_frame(frame(L, r, round));
  part.flush();
}

std::vector<std::int64_t> read_sessions(const std::string& out, std::int64_t n) {
  std::vector<std::int64_t> v(static_cast<std::size_t>(n));
  const hid_t f = H5Fopen(out.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t d = H5Dopen2(f, "timing/session", H5P_DEFAULT);
  REQUIRE(H5Dread(d, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0);
  H5Dclose(d);
  H5Fclose(f);
  return v;
}

}  // namespace

// The statistics ranks by the documented rule: rank 0 alone on one rank and when it restores
// chunks; else ranks 1 .. S, S = ceil((P - 1) / 32) unless asked, at most P - 1 and the columns.
TEST_CASE("statistics ranks: where the statistics are merged", "[engine]") {
  using parallel::find_stats_ranks;
  auto is = [](results::StatsRanks r, int first, int count) { return r.first == first && r.count == count; };
  CHECK(is(find_stats_ranks(0, 1, false, 395), 0, 1));
  CHECK(is(find_stats_ranks(0, 8, true, 395), 0, 1));
  CHECK(is(find_stats_ranks(3, 8, true, 395), 0, 1));
  CHECK(is(find_stats_ranks(0, 2, false, 395), 1, 1));
  CHECK(is(find_stats_ranks(0, 33, false, 395), 1, 1));
  CHECK(is(find_stats_ranks(0, 34, false, 395), 1, 2));
  CHECK(is(find_stats_ranks(0, 1001, false, 395), 1, 32));
  CHECK(is(find_stats_ranks(0, 100000, false, 395), 1, 395));
  CHECK(is(find_stats_ranks(3, 8, false, 395), 1, 3));
  CHECK(is(find_stats_ranks(9, 8, false, 395), 1, 7));
  CHECK(is(find_stats_ranks(5, 8, false, 2), 1, 2));
}

TEST_CASE("collector: a cut session resumed from its journals, memory bounded, plans checked", "[engine]") {
  const fs::path dir = fs::temp_directory_path() / ("truss_collector_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string out = (dir / "c.h5").string();
  const campaign::CampaignContext ctx(campaign::test::small_campaign("monte_carlo", 3000));
  const campaign::RecordLayout& L = ctx.record;
  methods::FixedDesign design(ctx);
  {
    Session s(ctx, design, out, false);
    s.collector->start_session(0.0, 2);
    const methods::RoundPlan plan = s.plan(0, 0);
    REQUIRE(plan.n_runs == 3000);
    // Runs 0..999 reach rank 0's chunks about in index order (blocks of 50 reversed), runs
    // 1000..1999 rank 1's (its part journal).
    for (std::int64_t b = 0; b < 1000; b += 50)
      for (std::int64_t r = b + 49; r >= b; --r) s.add(frame(L, r, 0));
    CHECK_THROWS_WITH(s.add(frame(L, 7, 0)), Catch::Contains("run 7 received twice"));
    CHECK_THROWS_WITH(s.add(frame(L, 3000, 0)), Catch::Contains("a record of run 3000 in round 0"));
    std::string cut = frame(L, 2100, 0);
    cut.pop_back();
    CHECK_THROWS_AS(s.add(cut), std::runtime_error);
    CHECK(s.collector->n_done() == 512);  // round parts: chunk 0's; chunk 1 waits for runs 1000..1023
    s.collector->tick(true);  // the journal synced; then the session ends without a results file
  }
  write_part(out, L, 1000, 2000, 0);
  CHECK_FALSE(fs::exists(out));
  {
    Session s(ctx, design, out, true);
    const parallel::RestoreSummary sum = s.restore();
    CHECK(sum.records == 2000);
    CHECK(sum.notes.empty());
    CHECK(s.collector->session().session == 1);
    CHECK(s.collector->n_done() == 2000);
    CHECK(s.owner->peak_chunks() <= 3);  // chunks of 512 written as they complete
    const methods::RoundPlan plan = s.plan(0, 0);  // the journaled one
    CHECK(plan.n_runs == 3000);
    for (std::int64_t r = 2000; r < 3000; ++r) s.add(frame(L, r, 0));
    CHECK(s.collector->round_complete(plan));
    CHECK(s.collector->plan_round(1, 3000).n_runs == 0);
    s.finish();
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
  const auto session = read_sessions(out, 3000);
  for (std::int64_t r = 0; r < 3000; ++r) CHECK(session[static_cast<std::size_t>(r)] == (r < 2000 ? 0 : 1));
  CHECK(fs::directory_iterator(dir) != fs::directory_iterator());
  CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 1);  // the file alone
  fs::remove(out);

  // A method that proposes another round 0 than the journal holds: refused, the journals untouched.
  {
    Session s(ctx, design, out, false);
    s.collector->start_session(0.0, 2);
    s.plan(0, 0);
    for (std::int64_t r = 0; r < 100; ++r) s.add(frame(L, r, 0));
    s.collector->tick(true);
  }
  write_part(out, L, 100, 600, 0);
  const auto size = fs::file_size(out + ".journal"), part_size = fs::file_size(out + ".journal.0.1");
  campaign::CampaignOptions more = ctx.options;
  more.ensemble.n_runs = 3500;
  const campaign::CampaignContext other(more);
  methods::FixedDesign other_design(other);
  {
    Session s(other, other_design, out, true);
    CHECK_THROWS_WITH(s.restore(), Catch::Contains("round 0 of the journal is not the round the method"));
  }
  CHECK(fs::file_size(out + ".journal") == size);
  CHECK(fs::file_size(out + ".journal.0.1") == part_size);
  fs::remove_all(dir);
}

// Rank 1's part journal lost its last records (its host went down before it synced them), while
// rank 0's journal holds the next round's plan: the restored rounds end at the round that misses
// records, the later plan and the later records are cut from the journals (said so), and the
// session computes the rest: the file is every run's, once.
TEST_CASE("collector: a round that misses records ends the restored rounds", "[engine]") {
  const fs::path dir = fs::temp_directory_path() / ("truss_collector_cut_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string out = (dir / "c.h5").string();
  const campaign::CampaignContext ctx(campaign::test::small_campaign("monte_carlo", 600));
  const campaign::RecordLayout& L = ctx.record;
  FixedRounds rounds(2);
  {
    Session s(ctx, rounds, out, false);
    s.collector->start_session(0.0, 2);
    s.plan(0, 0);
    for (std::int64_t r = 0; r < 300; ++r) s.add(frame(L, r, 0));  // rank 0's share of round 0
    // Rank 1's share, 300..599, reached rank 0 as round parts (so round 1 was planned), but its
    // part journal kept 300..549 only; round 1's first records were journaled by rank 1 too.
    REQUIRE(s.collector->plan_round(1, 600).n_runs == 600);
    s.collector->tick(true);
  }
  {
    results::Journal part = results::Journal::create_part(results::part_journal_path(out, 0, 1),
                                                          util::calc_crc32(kText), 0, 1);
    for (std::int64_t r = 300; r < 550; ++r) part.append_frame(frame(L, r, 0));
    for (std::int64_t r = 600; r < 640; ++r) part.append_frame(frame(L, r, 1));
    part.flush();
  }
  const auto part_size = fs::file_size(out + ".journal.0.1");
  {
    Session s(ctx, rounds, out, true);
    const parallel::RestoreSummary sum = s.restore();
    CHECK(sum.records == 550);
    REQUIRE(sum.notes.size() == 1);
    CHECK_THAT(sum.notes[0], Catch::Contains("round 0 misses 50 of its 600 runs") &&
                                 Catch::Contains("rounds 1 to 1 are computed again"));
    CHECK(s.collector->plans().size() == 1);
    CHECK(fs::file_size(out + ".journal.0.1") < part_size);  // round 1's records cut
    const methods::RoundPlan p0 = s.plan(0, 0);
    for (std::int64_t r = 550; r < 600; ++r) s.add(frame(L, r, 0));
    REQUIRE(s.collector->round_complete(p0));
    const methods::RoundPlan p1 = s.plan(1, 600);  // proposed again from the records
    REQUIRE(p1.n_runs == 600);
    for (std::int64_t r = 600; r < 1200; ++r) s.add(frame(L, r, 1));
    CHECK(s.plan(2, 1200).n_runs == 0);
    s.finish();
  }
  const auto session = read_sessions(out, 1200);
  for (std::int64_t r = 0; r < 1200; ++r) CHECK(session[static_cast<std::size_t>(r)] == (r < 550 ? 0 : 1));
  fs::remove_all(dir);
}

// A resume in the middle of a later round: round 0 complete, round 1 journaled with part of its
// records. The rounds are planned again in order (round 0's plan first, then round 1's): the runs
// restored in round 1 stay in and are not handed out again, and the session completes round 1 with
// the others only.
TEST_CASE("collector: a resume inside a later round keeps that round's restored runs", "[engine]") {
  const fs::path dir = fs::temp_directory_path() / ("truss_collector_r1_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string out = (dir / "c.h5").string();
  const campaign::CampaignContext ctx(campaign::test::small_campaign("monte_carlo", 600));
  const campaign::RecordLayout& L = ctx.record;
  FixedRounds rounds(2);
  {
    Session s(ctx, rounds, out, false);
    s.collector->start_session(0.0, 2);  // the records say rank 1 computed them
    s.plan(0, 0);
    for (std::int64_t r = 0; r < 600; ++r) s.add(frame(L, r, 0));
    REQUIRE(s.plan(1, 600).n_runs == 600);
    for (std::int64_t r = 600; r < 900; ++r) s.add(frame(L, r, 1));
    s.collector->tick(true);
  }
  {
    Session s(ctx, rounds, out, true);
    CHECK(s.restore().records == 900);
    const methods::RoundPlan p0 = s.plan(0, 0);
    CHECK(s.collector->round_complete(p0));
    const methods::RoundPlan p1 = s.plan(1, 600);
    std::int64_t in = 0;
    for (std::int64_t r = 600; r < 1200; ++r) in += s.collector->has(r);
    CHECK(in == 300);
    for (std::int64_t r = 900; r < 1200; ++r) s.add(frame(L, r, 1));
    CHECK(s.collector->round_complete(p1));
    CHECK(s.plan(2, 1200).n_runs == 0);
    s.finish();
  }
  const auto session = read_sessions(out, 1200);
  for (std::int64_t r = 0; r < 1200; ++r) CHECK(session[static_cast<std::size_t>(r)] == (r < 900 ? 0 : 1));
  fs::remove_all(dir);
}
