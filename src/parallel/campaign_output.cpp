// truss-campaign's output (campaign_output.hpp).
#include "parallel/campaign_output.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "io/h5_output.hpp"
#include "parallel/campaign_command.hpp"
#include "io/scene_toml.hpp"
#include "results/resources.hpp"
#include "util/bytes.hpp"
#include "util/isal.hpp"

namespace truss::parallel {

namespace fs = std::filesystem;

namespace {

// The bytes the output's journals hold (rank 0's and the parts).
double journal_bytes(const std::string& output) {
  std::error_code ec;
  double bytes = 0.0;
  const fs::path p(output);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  const std::string prefix = p.filename().string() + ".journal";
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().filename().string().rfind(prefix, 0) == 0) {
      const auto n = fs::file_size(e.path(), ec);
      if (!ec) bytes += static_cast<double>(n);
    }
  return bytes;
}

// Rank 0: the output's lock, then with it held the temporary files and part journals of killed
// sessions removed and the output, journal and resource checks. Throws io::InputError for anything
// the user must decide (another live truss-campaign on the same output among them).
void lock_and_check_output(const CommandOptions& o, const campaign::CampaignContext& ctx, Rank0& r0) {
  if (o.resume && o.force) throw io::InputError("error: --resume and --force exclude each other");
  auto check_path = [&] {
    if (o.resume && fs::exists(o.output_path))
      throw io::InputError(fmt::format("error: {} exists: the campaign is finished, nothing to resume", o.output_path));
    io::check_output_path(o.output_path, o.force);
  };
  check_path();  // before a lock file is made next to it
  const std::string lock = results::CampaignFile::lock_name(o.output_path);
  try {
    r0.lock = std::make_unique<results::LockFile>(lock);
  } catch (const results::LockHeld& e) {
    throw io::InputError(fmt::format("error: {} is in use by another truss-campaign ({}, lock file {}); wait for "
                                     "it to end or stop it (ranks of a killed mpirun may still run)",
                                     o.output_path, e.what(), lock));
  }
  check_path();  // again, under the lock: a session that held it until now may have finished the file
  // No live session of this output exists (we hold its lock): temporary files are of killed ones.
  for (const auto& stale : results::CampaignFile::remove_stale(o.output_path))
    std::cerr << fmt::format("[truss-campaign] removed {}, left by an interrupted session\n", stale);
  const std::string jpath = o.output_path + ".journal";
  const bool has_journal = fs::exists(fs::symlink_status(jpath));
  if (o.resume && !has_journal)
    throw io::InputError(
        fmt::format("error: --resume: no journal {} to resume from (run without --resume to start)", jpath));
  if (!o.resume && has_journal && !o.force)
    throw io::InputError(fmt::format("error: an unfinished campaign journal exists: {}; finish it with --resume "
                                     "(same campaign and --set options) or start over with --force", jpath));
  if (!o.resume) results::remove_part_journals(o.output_path);  // of a session whose journal is gone
  // Memory and disk for every run; the journals on disk are the campaign's already (kept on
  // --resume, replaced on --force).
  if (const std::string e = results::check_resources(ctx, o.output_path, journal_bytes(o.output_path)); !e.empty())
    throw io::InputError(e);
}

// A rank other than 0: rank 0's lock file, as rank 0 wrote it, at the same path.
bool sees_lock(const std::string& path, const std::string& content) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return in.good() && s.str() == content;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

void broadcast_string(MPI_Comm comm, std::string& s) {
  auto len = static_cast<long long>(s.size());
  MPI_Request r;
  MPI_Ibcast(&len, 1, MPI_LONG_LONG, 0, comm, &r);
  wait_idle(&r);
  s.resize(static_cast<std::size_t>(len));
  MPI_Ibcast(s.data(), static_cast<int>(len), MPI_CHAR, 0, comm, &r);
  wait_idle(&r);
}

int run_rank0_step(Rank0& r0, const std::function<void()>& step) {
  int status = kExitOk;
  try {
    step();
  } catch (const io::InputError& e) {
    std::cerr << e.what() << '\n';
    status = kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    status = kExitIoError;
  }
  if (status != kExitOk) r0.drop();
  return status;
}

int check_output_all(MPI_Comm comm, const CommandOptions& o, const campaign::CampaignContext& ctx, Rank0& r0) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  int status = kExitOk;
  std::string lock_path, lock_content;
  if (rank == 0) {
    status = run_rank0_step(r0, [&] {
      lock_and_check_output(o, ctx, r0);
      lock_path = fs::absolute(r0.lock->path()).string();
      lock_content = read_file(lock_path);
    });
  }
  status = broadcast_int_idle(comm, status);
  if (status != kExitOk || size == 1) return status;
  broadcast_string(comm, lock_path);
  broadcast_string(comm, lock_content);
  const int blind = rank != 0 && !sees_lock(lock_path, lock_content) ? rank : 0;
  int first_blind = 0;
  MPI_Allreduce(&blind, &first_blind, 1, MPI_INT, MPI_MAX, comm);
  if (first_blind == 0) return kExitOk;
  if (rank == 0) {
    std::cerr << fmt::format("error: rank {} does not see {} as rank 0 does (its lock file {}): the ranks write the "
                             "results file's chunks and their journals next to it, so the output must be on a file "
                             "system every host shares\n", first_blind, o.output_path, lock_path);
    r0.drop();
  }
  return kExitBadInput;
}

void prepare_output(const CommandOptions& o, const std::string& campaign_text, const campaign::CampaignContext& ctx,
                    methods::Method& method, Rank0& r0) {
  const std::string jpath = o.output_path + ".journal";
  const results::StoreOptions store{results::find_chunk_runs(ctx.options.ensemble.n_runs), o.compression};
  r0.file = std::make_unique<results::CampaignFile>(o.output_path, ctx, store);
  try {
    if (o.force) {
      fs::remove(jpath);
      results::remove_part_journals(o.output_path);
    }
    r0.journal = std::make_unique<results::Journal>(o.resume ? results::Journal::open_existing(jpath, campaign_text)
                                                             : results::Journal::create(jpath, campaign_text));
  } catch (const std::runtime_error& e) {  // JournalRefused included: another campaign's journal
    throw io::InputError(std::string(o.resume ? "error: --resume: " : "error: ") + e.what());
  }
  r0.progress = std::make_unique<Progress>(ctx.options.ensemble.n_runs, 0, ProgressMode::none, 1.0);
  EngineOptions engine = o.engine;
  engine.max_runs = campaign::calc_max_runs(ctx.options);
  r0.collector = std::make_unique<Collector>(ctx.record, method, *r0.journal, *r0.file, *r0.progress, engine);
  r0.collector->keep_plans_of(ctx.options.output.history_runs);
}

SessionSetup restore_output(const CommandOptions& o, const std::string& campaign_text, Rank0& r0, ChunkOwner& owner,
                            Engine& engine) {
  if (o.resume) {
    try {
      r0.restored = r0.collector->restore(
          campaign_text, {[&](const methods::RoundPlan& p) { owner.add_round(p); },
                          [&](std::string_view record, std::int64_t session) { owner.replay_record(record, session); },
                          [&] { engine.serve_local(); }});
    } catch (const io::InputError&) {
      throw;
    } catch (const results::JournalRefused& e) {
      throw io::InputError(std::string("error: --resume: ") + e.what());
    }
  }
  SessionSetup s;
  s.session = r0.collector->session().session;
  s.output = fs::absolute(o.output_path).string();
  s.temporary = fs::absolute(r0.file->temporary_path()).string();
  s.campaign_crc = util::calc_crc32(campaign_text);
  s.rank0_chunks = owner.open_chunks();
  return s;
}

std::string SessionSetup::to_bytes() const {
  std::string out;
  util::put(out, session);
  util::put(out, campaign_crc);
  for (const std::string* p : {&output, &temporary}) {
    util::put(out, static_cast<std::uint64_t>(p->size()));
    out += *p;
  }
  util::put(out, static_cast<std::uint64_t>(rank0_chunks.size()));
  for (std::int64_t k : rank0_chunks) util::put(out, k);
  util::put(out, static_cast<std::int32_t>(stats.first));
  util::put(out, static_cast<std::int32_t>(stats.count));
  return out;
}

SessionSetup SessionSetup::from_bytes(std::string_view bytes) {
  util::ByteReader in(bytes, "the session's setup");
  SessionSetup s;
  s.session = in.get<std::int64_t>();
  s.campaign_crc = in.get<std::uint32_t>();
  for (std::string* p : {&s.output, &s.temporary}) p->assign(in.get_bytes(in.get<std::uint64_t>()));
  s.rank0_chunks.resize(in.get<std::uint64_t>());
  for (std::int64_t& k : s.rank0_chunks) k = in.get<std::int64_t>();
  s.stats.first = in.get<std::int32_t>();
  s.stats.count = in.get<std::int32_t>();
  in.expect_end();
  return s;
}

}  // namespace truss::parallel
