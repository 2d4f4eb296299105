#include "parallel/campaign_driver.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "campaign/campaign.hpp"
#include "campaign/campaign_h5.hpp"
#include "campaign/journal.hpp"
#include "campaign/nominal.hpp"
#include "campaign/progress.hpp"
#include "campaign/resources.hpp"
#include "campaign/results.hpp"
#include "campaign/run_record.hpp"
#include "io/h5_output.hpp"
#include "io/h5_util.hpp"
#include "io/scene_toml.hpp"
#include "parallel/scheduler.hpp"
#include "parallel/synthetic_run.hpp"

namespace truss::parallel {

namespace fs = std::filesystem;
using campaign::FrameKind;

namespace {

struct CommandOptions {
  std::string campaign_path;
  std::string output_path;
  std::vector<std::string> sets;
  bool resume = false;
  bool force = false;
  bool dry_run = false;
  double flush_interval_s = 2.0;
  std::string progress = "auto";
  double progress_interval_s = 2.0;  // a person watching a log sees it move
  int max_batch = 32;
  int compression = 1;                 // zlib level of the results file's datasets (0: none)
  double synthetic_run_cost_s = -1.0;  // bench only (hidden): runs sleep this long and simulate nothing
  bool no_write_thread = false;        // hidden --no-write-thread: rank 0 writes returned chunks itself (A/B benchmarks)
};

// The error state of all ranks: true on every rank if any rank failed.
bool any_rank(MPI_Comm comm, bool mine) {
  int in = mine ? 1 : 0, out = 0;
  MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_MAX, comm);
  return out != 0;
}

int broadcast_int(MPI_Comm comm, int v) { return broadcast_int_idle(comm, v); }

double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

template <class T>
void put(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <class T>
T get_at(std::string_view s, std::size_t at) {
  T v{};
  if (s.size() >= at + sizeof(T)) std::memcpy(&v, s.data() + at, sizeof(T));
  return v;
}

// What rank 0 carries from the journal into this session.
struct SessionState {
  int session = 0;             // index of this invocation (0 unless resumed)
  double previous_wall_s = 0;  // wall time of the earlier sessions
  double first_start = 0;      // unix time of the first session
  double session_wall = 0;     // while reading the journal: the last heartbeat of the session read
};

// Rank 0's state between the checks and the end.
struct Rank0 {
  std::unique_ptr<campaign::CampaignFile> file;  // the results file being written (a temporary name)
  std::unique_ptr<campaign::Journal> journal;
  std::string journal_path;
  campaign::JournalScan scan;
  SessionState st;
  double journal_s = 0.0;  // appending results to the journal (part of the schedule's rank0_result_s)
};

// Rank 0, --resume: one journal frame into the session state or the results file. A frame that
// passed its CRC but makes no sense (a short payload, a run index out of range, a run twice) is
// not a crash's doing: the journal is refused (exit 2) with what is wrong and where.
void restore_frame(Rank0& r0, const campaign::CampaignContext& ctx, FrameKind kind, std::string_view payload,
                   std::size_t offset) {
  SessionState& st = r0.st;
  const std::string where = fmt::format("{}: record at byte {}", r0.journal_path, offset);
  auto need = [&](std::size_t n, const char* what) {
    if (payload.size() != n)
      throw io::InputError(fmt::format("error: --resume: {}: a {} record of {} bytes (expected {}): the journal is "
                                       "inconsistent; start over with --force", where, what, payload.size(), n));
  };
  if (kind == FrameKind::session) {
    need(sizeof(double) + sizeof(std::int32_t), "session");
    if (st.session == 0) st.first_start = get_at<double>(payload, 0);
    st.previous_wall_s += st.session_wall;
    st.session_wall = 0.0;
    ++st.session;
    return;
  }
  if (kind == FrameKind::heartbeat) {
    need(sizeof(double), "heartbeat");
    st.session_wall = get_at<double>(payload, 0);
    return;
  }
  campaign::RunRecord rec;
  try {
    rec = campaign::RunRecord::from_bytes(payload, ctx.columns);
  } catch (const std::exception& e) {
    throw io::InputError(fmt::format("error: --resume: {}: not a run record of this campaign ({}, {} bytes); the journal "
                                     "is inconsistent; start over with --force", where, e.what(), payload.size()));
  }
  const std::int64_t n = ctx.options.ensemble.n_runs;
  if (rec.run_index < 0 || rec.run_index >= n)
    throw io::InputError(fmt::format("error: --resume: {}: run index {} out of range (the campaign has runs 0 to {}); the "
                                     "journal is inconsistent; start over with --force", where, rec.run_index, n - 1));
  if (r0.file->store().has(rec.run_index))
    throw io::InputError(fmt::format("error: --resume: {}: run {} recorded twice; the journal is inconsistent; start "
                                     "over with --force", where, rec.run_index));
  r0.file->store().add_bytes(payload, std::max(0, st.session - 1));
}

// Rank 0: output and journal checks; creates the results file (a temporary name until the end)
// and opens or creates the journal, restoring its runs into the file. Throws io::InputError for
// anything the user must decide.
void prepare_output(const CommandOptions& o, const std::string& campaign_text, const campaign::CampaignContext& ctx,
                    Rank0& r0, int size) {
  if (o.resume && o.force) throw io::InputError("error: --resume and --force exclude each other");
  if (o.resume && fs::exists(o.output_path))
    throw io::InputError(fmt::format("error: {} exists: the campaign is finished, nothing to resume", o.output_path));
  io::check_output_path(o.output_path, o.force);
  // Memory and disk for every run, before the journal exists (a refusal leaves nothing behind).
  if (const std::string e = campaign::check_resources(ctx, o.output_path); !e.empty()) throw io::InputError(e);
  const std::string jpath = o.output_path + ".journal";
  r0.journal_path = jpath;
  const bool has_journal = fs::exists(fs::symlink_status(jpath));
  if (o.resume && !has_journal)
    throw io::InputError(fmt::format("error: --resume: no journal {} to resume from (run without --resume to start)", jpath));
  if (!o.resume && has_journal && !o.force)
    throw io::InputError(fmt::format("error: an unfinished campaign journal exists: {}; finish it with --resume "
                                     "(same campaign and --set options) or start over with --force", jpath));
  // A job travels in a work message with up to max_batch run indices and the trailer after it.
  const campaign::StoreOptions store{campaign::find_chunk_runs(ctx.options.ensemble.n_runs), o.compression, size > 1,
                                     8 * static_cast<std::size_t>(o.max_batch) + 64, size > 1 && !o.no_write_thread};
  r0.file = std::make_unique<campaign::CampaignFile>(o.output_path, ctx, store);
  if (o.resume) {
    try {
      auto on_frame = [&](FrameKind k, std::string_view p, std::size_t at) { restore_frame(r0, ctx, k, p, at); };
      r0.journal = std::make_unique<campaign::Journal>(campaign::Journal::resume(jpath, campaign_text, on_frame, r0.scan));
    } catch (const io::InputError&) {
      throw;
    } catch (const std::runtime_error& e) {  // JournalRefused included
      throw io::InputError(std::string("error: --resume: ") + e.what());
    }
    r0.st.previous_wall_s += r0.st.session_wall;
  } else {
    try {
      if (has_journal) campaign::Journal::remove_unused(jpath);
      r0.journal = std::make_unique<campaign::Journal>(campaign::Journal::create(jpath, campaign_text));
    } catch (const campaign::JournalRefused& e) {
      throw io::InputError(std::string(has_journal ? "error: --force: " : "error: ") + e.what());  // held by a live campaign: exit 2, as --resume
    }
  }
  // Temporary files of killed sessions: no live session of this campaign exists (we hold the lock).
  for (const auto& stale : campaign::CampaignFile::remove_stale(o.output_path))
    std::cerr << fmt::format("[truss-campaign] removed {}, left by an interrupted session\n", stale);
}

campaign::ProgressMode progress_mode(const std::string& s) {
  if (s == "tty") return campaign::ProgressMode::terminal;
  if (s == "lines") return campaign::ProgressMode::lines;
  if (s == "none") return campaign::ProgressMode::none;
  return campaign::ProgressMode::automatic;
}

// The command line (identical on every rank). Returns an exit status when the command is done
// (--help, --version, a parse error), nothing when the campaign is to run.
std::optional<int> parse_command(int argc, char** argv, bool root, CommandOptions& o) {
  CLI::App app{"Runs an uncertainty campaign of folding truss mast deployments over MPI ranks.", "truss-campaign"};
  app.add_option("campaign", o.campaign_path, "Campaign file (TOML), e.g. campaigns/table1_dispersed.toml")->required();
  app.add_option("-o,--output", o.output_path, "Results file (HDF5, docs/hdf5-schema.md); required unless --dry-run");
  app.add_option("--set", o.sets, "Override a campaign key (ensemble.n_runs=40) or a base-scene key (drive.mode=motor, also scene.drive.mode=motor); repeatable")
      ->type_name("KEY=VALUE")->expected(1)->allow_extra_args(false)->take_all();
  app.add_flag("--resume", o.resume, "Finish an interrupted campaign from its journal (OUTPUT.journal)");
  app.add_flag("--force", o.force, "Overwrite an existing output file and discard an unfinished journal");
  app.add_flag("--dry-run", o.dry_run, "Validate the campaign, print it resolved, run nothing");
  app.add_option("--flush-interval", o.flush_interval_s, "Seconds between journal flushes to disk")->check(CLI::Range(0.01, 3600.0));
  app.add_option("--progress", o.progress, "Progress display: auto (in place when stderr is a terminal, lines otherwise; under mpirun stderr is a pipe, so pass tty there), tty, lines, none")
      ->check(CLI::IsMember({"auto", "tty", "lines", "none"}));
  app.add_option("--progress-interval", o.progress_interval_s, "Seconds between progress lines when not in place")
      ->check(CLI::Range(0.01, 1e6));
  app.add_option("--max-batch", o.max_batch, "Largest batch of runs handed to a rank at once")->check(CLI::Range(1, 100000));
  app.add_option("--compression", o.compression, "zlib level (0-9) of the results file's per-run datasets; 0 stores "
                 "them uncompressed (largest file, least work for rank 0)")->check(CLI::Range(0, 9));
  // Bench only, hidden (empty group): see parallel/synthetic_run.hpp and docs/benchmarks.md.
  app.add_option("--synthetic-run-cost-s", o.synthetic_run_cost_s, "")->check(CLI::Range(0.0, 60.0))->group("");
  app.add_flag("--no-write-thread", o.no_write_thread, "bench only: rank 0 writes returned chunks itself")->group("");
  app.set_version_flag("--version", std::string("truss-campaign ") + TRUSS_VERSION + " (" + TRUSS_GIT_REV + ")");
  app.footer("Exit status: 0 results written (failed runs are data in them); 2 bad input, nothing written; "
             "3 I/O or internal error; 4 results written, but most runs are invalid input (the dispersions give "
             "scenes the model refuses).");
  try {
    app.parse(argc, argv);
    if (o.output_path.empty() && !o.dry_run) throw CLI::RequiredError("--output");
  } catch (const CLI::ParseError& e) {
    int rc = 0;
    if (root) rc = app.exit(e);
    else {
      std::ostringstream sink;
      rc = app.exit(e, sink, sink);
    }
    return rc == 0 ? kExitOk : kExitBadInput;
  }
  return std::nullopt;
}

// Rank 0: journals this session's start and returns the runs still to do.
std::vector<std::int64_t> start_session(Rank0& r0, std::int64_t n_runs, double t_start, int size) {
  if (r0.st.session == 0) r0.st.first_start = t_start;
  const campaign::ResultStore& store = r0.file->store();
  if (r0.st.session > 0) {
    std::cerr << fmt::format("[truss-campaign] resuming: {} of {} runs restored from {}\n", store.n_done(), n_runs,
                             r0.journal->path());
    if (const std::string d = r0.scan.describe(r0.journal->path()); !d.empty()) std::cerr << "[truss-campaign] " << d << '\n';
  }
  std::string s;
  put(s, t_start);
  put(s, static_cast<std::int32_t>(size));
  r0.journal->append(FrameKind::session, s);
  r0.journal->flush();
  std::vector<std::int64_t> todo;
  todo.reserve(static_cast<std::size_t>(n_runs - store.n_done()));
  for (std::int64_t i = 0; i < n_runs; ++i)
    if (!store.has(i)) todo.push_back(i);
  return todo;
}

// Runs per status so far (restored and new), from the results store.
// Rank 0: histories, statistics and the results file; removes the journal. Returns the exit status.
int write_results(const CommandOptions& o, const campaign::CampaignContext& ctx, const std::string& campaign_text,
                  Rank0& r0, int size, std::chrono::steady_clock::time_point wall0, const ScheduleSummary& sched) {
  const SessionState& st = r0.st;
  const campaign::CampaignOptions& c = ctx.options;
  try {
    const auto t_finish = std::chrono::steady_clock::now();
    const std::clock_t cpu_finish = std::clock();  // rank 0's CPU time: the tail without the other processes' share
    std::vector<std::pair<std::int64_t, sim::RunResult>> histories;
    for (std::int64_t run : c.output.history_runs)
      histories.emplace_back(run, campaign::calc_run_with_history(ctx, run, c.output.history_step_s));
    const sim::RunResult nominal = campaign::calc_nominal_run(c, c.output.history_step_s > 0 ? c.output.history_step_s : 0.01);
    campaign::CampaignFileInfo info;
    info.campaign_toml = campaign_text;
    info.base_scene_toml = io::resolved_scene_toml(c.base);
    info.n_ranks = size;
    info.n_sessions = st.session + 1;
    info.start_utc = io::h5::utc_iso8601(st.first_start);
    info.end_utc = io::h5::utc_now_iso8601();
    info.wall_time_s = st.previous_wall_s + std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    info.schedule = {sched.wall_s, sched.rank0_compute_s, sched.rank0_poll_s, sched.rank0_tick_s, sched.rank0_idle_s,
                     sched.runs_by_rank0, sched.runs_by_workers, o.synthetic_run_cost_s, sched.rank0_handle_cpu_s,
                     sched.rank0_compute_cpu_s};
    info.schedule.rank0_mpi_s = sched.rank0_mpi_s;
    info.schedule.rank0_result_s = sched.rank0_result_s;
    info.schedule.rank0_journal_s = r0.journal_s;
    info.schedule.rank0_job_output_s = sched.rank0_job_output_s;
    r0.file->store().finish_writes();
    info.schedule.rank0_write_thread_cpu_s = r0.file->store().calc_write_thread_cpu_s();
    info.write_extra = [&](hid_t file) { campaign::write_nominal_group(file, nominal, ctx.columns.n_bays_max); };
    const campaign::ResultStore& store = r0.file->store();
    const std::int64_t n_runs = store.n_runs();
    const campaign::StatusCounts counts = store.status_counts();
    const std::size_t peak_chunks = store.peak_chunks_in_memory();
    const std::int64_t chunk_runs = store.chunk_runs();
    const std::int64_t jobs_offloaded = store.jobs_offloaded();
    const bool write_thread = store.has_write_thread();  // (the store is gone after finish)
    r0.file->store().drain_jobs();
    const std::int64_t jobs_local = store.jobs_local();
    r0.file->finish(histories, info, o.force);
    r0.journal->close_and_remove();
    std::cerr << fmt::format("[truss-campaign] nominal run (base scene, no dispersion): {}{}\n", sim::to_string(nominal.status),
                             nominal.message.empty() ? "" : ": " + nominal.message);
    campaign::print_design_summary(stderr, campaign::read_design_values(o.output_path, ctx.columns, nominal));
    const double results = std::max(1.0, static_cast<double>(sched.runs_by_rank0 + sched.runs_by_workers));
    auto us = [&](double s) { return 1e6 * s / results; };  // a result
    const std::string thread_cpu =
        write_thread ? fmt::format(" + {:.3g} us CPU on the write thread", us(info.schedule.rank0_write_thread_cpu_s)) : "";
    std::cerr << fmt::format("[truss-campaign] wrote {}: {} runs ({}), {:.3g} s on {} rank{} "
                             "(statistics and file: {:.3g} s, {:.3g} s CPU; rank 0: {} runs computed, {:.3g} us per result handled "
                             "({:.3g} us CPU{}), at most {} chunks of {} runs in memory, {} of {} chunk encodings by workers)\n",
                             o.output_path, n_runs, campaign::format_status_counts(counts), info.wall_time_s, size, size > 1 ? "s" : "",
                             std::chrono::duration<double>(std::chrono::steady_clock::now() - t_finish).count(),
                             static_cast<double>(std::clock() - cpu_finish) / CLOCKS_PER_SEC, sched.runs_by_rank0,
                             us(sched.rank0_poll_s + sched.rank0_tick_s), us(sched.rank0_handle_cpu_s), thread_cpu, peak_chunks,
                             chunk_runs, jobs_offloaded, jobs_offloaded + jobs_local);
    const std::string example = campaign::read_example_message(o.output_path, n_runs, sim::RunStatus::invalid_input);
    return campaign::print_campaign_verdict(stderr, counts, example) ? kExitOk : kExitMostlyInvalid;
  } catch (const io::InputError& e) {
    std::cerr << e.what() << " (the journal " << r0.journal->path() << " keeps every run)\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << " (the journal " << r0.journal->path() << " keeps every run)\n";
    return kExitIoError;
  }
}

// Rank 0 reads the campaign file (and its scene file) and sends the resolved campaign text, which
// holds everything inline, to the other ranks: only rank 0 needs the input files, as only it
// needs the output and journal paths (a multi-host run needs them on rank 0's host alone). Errors
// are agreed on and reported once. Returns an exit status when the command is done (bad input,
// --dry-run).
std::optional<int> load_campaign(MPI_Comm comm, bool root, const CommandOptions& o,
                                 std::optional<campaign::CampaignContext>& ctx, std::string& campaign_text) {
  std::string error;
  try {
    if (root) {
      ctx.emplace(campaign::parse_campaign_file(o.campaign_path, o.sets));
      for (const auto& w : ctx->options.warnings) std::cerr << w << '\n';
      campaign_text = campaign::resolved_campaign_toml(ctx->options);
    }
  } catch (const io::InputError& e) {
    error = e.what();
  } catch (const std::exception& e) {
    error = fmt::format("error: {}: {}", o.campaign_path, e.what());
  }
  if (any_rank(comm, !error.empty())) {
    if (root) std::cerr << error << '\n';
    return kExitBadInput;
  }
  if (o.dry_run) {
    if (root) std::cout << campaign_text;
    return kExitOk;
  }
  auto len = static_cast<long long>(campaign_text.size());
  MPI_Bcast(&len, 1, MPI_LONG_LONG, 0, comm);
  campaign_text.resize(static_cast<std::size_t>(len));
  MPI_Bcast(campaign_text.data(), static_cast<int>(len), MPI_CHAR, 0, comm);
  try {
    if (!root) ctx.emplace(campaign::parse_campaign_text(campaign_text, "resolved campaign from rank 0", ".", {}));
  } catch (const std::exception& e) {
    error = fmt::format("error: the resolved campaign does not parse on rank {}: {}", root ? 0 : 1, e.what());
  }
  if (any_rank(comm, !error.empty())) {
    std::cerr << error << '\n';  // an internal error: every rank that has one reports it
    return kExitIoError;
  }
  return std::nullopt;
}

// Rank 0: the output and journal checks, agreed on by every rank.
int prepare_output_all(MPI_Comm comm, bool root, const CommandOptions& o, const std::string& campaign_text,
                       const campaign::CampaignContext& ctx, Rank0& r0) {
  int status = kExitOk, size = 1;
  MPI_Comm_size(comm, &size);
  if (root) {
    try {
      prepare_output(o, campaign_text, ctx, r0, size);
    } catch (const io::InputError& e) {
      std::cerr << e.what() << '\n';
      status = kExitBadInput;
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << '\n';
      status = kExitIoError;
    }
    if (status != kExitOk && status != kExitMostlyInvalid) {  // nothing written: no results file, the journal as it was
      r0.journal.reset();
      r0.file.reset();
    }
  }
  return broadcast_int(comm, status);
}

}  // namespace

int run_campaign_command(int argc, char** argv, MPI_Comm comm) {
  // Before any HDF5 call: a write that fails (disk full) leaves HDF5 1.10 an identifier whose
  // exit-time cleanup crashes (io/h5_util.cpp, write_file_atomically); every identifier is closed
  // by its owner, so the library's atexit cleanup is switched off.
  H5dont_atexit();
  // Megabyte buffers (chunks, messages, jobs) stay in the heap: no page faults for each new one.
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const bool root = rank == 0;
  const double t_start = unix_now();
  const auto wall0 = std::chrono::steady_clock::now();
  CommandOptions o;
  if (auto rc = parse_command(argc, argv, root, o)) return *rc;
  std::optional<campaign::CampaignContext> ctx;
  std::string campaign_text;
  if (auto rc = load_campaign(comm, root, o, ctx, campaign_text)) return *rc;
  Rank0 r0;
  if (int rc = prepare_output_all(comm, root, o, campaign_text, *ctx, r0); rc != kExitOk) return rc;

  const campaign::CampaignOptions& c = ctx->options;
  std::vector<std::int64_t> todo;
  if (root) todo = start_session(r0, c.ensemble.n_runs, t_start, size);
  const std::int64_t restored = root ? c.ensemble.n_runs - static_cast<std::int64_t>(todo.size()) : 0;
  campaign::Progress progress(c.ensemble.n_runs, restored, progress_mode(o.progress), o.progress_interval_s);
  if (root) progress.banner(c.name, size, o.output_path);
  auto last_flush = std::chrono::steady_clock::now();
  // Periodic flushes do not wait for the disk (the journal's writer thread syncs); the last does.
  auto flush_journal = [&](bool wait) {
    std::string s;
    put(s, std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count());
    r0.journal->append(FrameKind::heartbeat, s);
    // The results file's pages go to disk during the run, not in the tail: after the journal's
    // sync, on its writer thread (submitting the I/O takes milliseconds).
    if (wait) {
      r0.journal->flush();
      r0.file->start_writeback();
    } else {
      r0.journal->flush_async(r0.file->writeback_task());
    }
    last_flush = std::chrono::steady_clock::now();
  };
  // A result is the record as a sealed journal frame (its CRC computed where the run ran): rank 0
  // journals it as it came and stores the record inside it.
  constexpr std::size_t kFrameHeader = campaign::Journal::kFrameHeader;
  auto compute = [&](std::int64_t run, std::string& out) {
    out.assign(kFrameHeader, '\0');
    if (o.synthetic_run_cost_s >= 0.0) synthetic_run_record(*ctx, run, rank, o.synthetic_run_cost_s).append_bytes(out);
    else campaign::calc_run_record(*ctx, run, rank).append_bytes(out);
    campaign::Journal::seal_frame(out, FrameKind::run);
  };
  ScheduleOptions so;
  so.max_batch = o.max_batch;
  so.tick_interval_s = std::min(0.25, o.flush_interval_s);
  // Workers encode the results file's chunks (campaign/result_store.hpp), rank 0 writes them.
  so.take_job = [&](std::string& job) { return r0.file->store().take_job(job); };
  so.on_job_done = [&](auto owner, std::size_t n, std::string_view out) { r0.file->store().job_done(std::move(owner), n, out); };
  so.do_job = [](std::string_view job, std::string& out) { campaign::encode_job_output(job, out); };
  so.do_local_job = [&] { return r0.file->store().drain_one(); };
  so.on_job_sent = [&](std::string&& buffer) { r0.file->store().recycle(std::move(buffer)); };
  so.side_jobs_pending = [&] { return r0.file->store().jobs_pending(); };
  // A worker's message: its frames journaled from the message itself (the journal checks them),
  // then its records stored from it too (on the write thread, if any): both keep `message` alive.
  so.on_message = [&](std::shared_ptr<const char[]> message, const std::vector<std::string_view>& frames) {
    const auto t0 = std::chrono::steady_clock::now();
    r0.journal->append_frames(message, frames);
    r0.journal_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r0.file->store().add_records(std::move(message), frames, kFrameHeader, r0.st.session);
  };
  ScheduleSummary sched;
  try {
    sched = run_schedule(
        comm, todo, compute,
        [&](std::string_view frame) {  // rank 0's own runs
          const auto t0 = std::chrono::steady_clock::now();
          r0.journal->append_frame(frame);
          r0.journal_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          r0.file->store().add_bytes(frame.substr(kFrameHeader), r0.st.session);  // checked by the journal
        },
        [&] {
          if (std::chrono::duration<double>(std::chrono::steady_clock::now() - last_flush).count() >= o.flush_interval_s)
            flush_journal(false);
          progress.update(r0.file->store().n_done(), [&] { return r0.file->store().status_counts(); });
        },
        so);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    MPI_Abort(comm, kExitIoError);
  }
  int status = kExitOk;
  if (root) {
    try {
      flush_journal(true);
      progress.finish(r0.file->store().n_done(), r0.file->store().status_counts());
      status = write_results(o, *ctx, campaign_text, r0, size, wall0, sched);
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << " (the journal " << r0.journal->path() << " keeps every run)\n";
      status = kExitIoError;
    }
    if (status != kExitOk && status != kExitMostlyInvalid) {  // nothing written: no results file, the journal as it was
      r0.journal.reset();
      r0.file.reset();
    }
  }
  return broadcast_int(comm, status);
}

}  // namespace truss::parallel
