#include "parallel/campaign_command.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>


#include <chrono>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "campaign/motor_declared.hpp"
#include "io/build_info.hpp"
#include "io/h5_output.hpp"
#include "io/h5_util.hpp"
#include "io/scene_toml.hpp"
#include "parallel/campaign_output.hpp"
#include "parallel/engine_detail.hpp"
#include "parallel/interrupt.hpp"
#include "parallel/owner.hpp"
#include "parallel/progress.hpp"
#include "parallel/stats_read_back.hpp"
#include "parallel/synthetic_run.hpp"

namespace truss::parallel {

namespace fs = std::filesystem;

namespace {

// The error state of all ranks: true on every rank if any rank failed.
bool any_rank(MPI_Comm comm, bool mine) {
  int in = mine ? 1 : 0, out = 0;
  MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_MAX, comm);
  return out != 0;
}

double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

ProgressMode progress_mode(const std::string& s) {
  if (s == "tty") return ProgressMode::terminal;
  if (s == "lines") return ProgressMode::lines;
  if (s == "none") return ProgressMode::none;
  return ProgressMode::automatic;
}

// The command line (identical on every rank). Returns an exit status when the command is done
// (--help, --version, a parse error), nothing when the campaign is to run.
std::optional<int> parse_command(int argc, char** argv, bool root, int size, CommandOptions& o) {
  CLI::App app{"Runs an uncertainty campaign of folding truss mast deployments over MPI ranks.", "truss-campaign"};
  app.add_option("campaign", o.campaign_path, "Campaign file (TOML), e.g. campaigns/table1_dispersed.toml")
      ->required();
  app.add_option("-o,--output", o.output_path, "Results file (HDF5, docs/hdf5-schema.md); required unless --dry-run");
  app.add_option("--set", o.sets, "Override a campaign key (ensemble.n_runs=40) or a base-scene key "
                                  "(drive.mode=motor, also scene.drive.mode=motor); repeatable")
      ->type_name("KEY=VALUE")->expected(1)->allow_extra_args(false)->take_all();
  app.add_flag("--resume", o.resume, "Finish an interrupted campaign from its journal (OUTPUT.journal)");
  app.add_flag("--force", o.force, "Overwrite an existing output file and discard an unfinished journal");
  app.add_flag("--dry-run", o.dry_run, "Validate the campaign, print it resolved, run nothing");
  app.add_option("--flush-interval", o.engine.flush_interval_s, "Seconds between journal flushes to disk")
      ->check(CLI::Range(0.01, 3600.0));
  app.add_option("--progress", o.progress, "Progress display: auto (in place when stderr is a terminal, lines "
                                           "otherwise; under mpirun stderr is a pipe, so pass tty there), tty, "
                                           "lines, none")
      ->check(CLI::IsMember({"auto", "tty", "lines", "none"}));
  app.add_option("--progress-interval", o.progress_interval_s, "Seconds between progress lines when not in place")
      ->check(CLI::Range(0.01, 1e6));
  app.add_option("--max-batch", o.engine.max_batch, "Largest batch of runs handed to a rank at once")
      ->check(CLI::Range(1, 100000));
  app.add_option("--statistics-ranks", o.engine.statistics_ranks,
                 fmt::format("Ranks that merge the statistics, each a share of the columns (ranks 1 to N; 0: "
                             "one per {} ranks; rank 0 alone on one rank and when resuming)", kRanksPerStatisticsRank))
      ->check(CLI::Range(0, 1 << 20));
  app.add_option("--compression", o.compression, "zlib level (0-9) of the results file's per-run datasets; 0 stores "
                 "them uncompressed (largest file, least work for rank 0)")->check(CLI::Range(0, 9));
  // Bench only, hidden (empty group): see parallel/synthetic_run.hpp and docs/benchmarks.md.
  app.add_option("--synthetic-run-cost-s", o.synthetic_run_cost_s, "")->check(CLI::Range(0.0, 60.0))->group("");
  app.set_version_flag("--version",
                     fmt::format("truss-campaign {} ({})", io::get_software_version(), io::get_git_revision()));
  app.footer("Exit status: 0 results written (failed runs are data in them); 2 bad input, nothing written; "
             "3 I/O or internal error; 4 results written, but most runs are invalid input (the dispersions give "
             "scenes the model refuses); 5 results written, but the method has no result; 6 results written, but "
             "the sweep's verdict is NOT ASSESSED (the reason printed).");
  try {
    app.parse(argc, argv);
    if (o.output_path.empty() && !o.dry_run) throw CLI::RequiredError("--output");
    if (const int most = std::max(1, size - 1); o.engine.statistics_ranks > most)
      throw CLI::ValidationError("--statistics-ranks", fmt::format("{} statistics ranks on {} rank{}: at most {}",
                                                                   o.engine.statistics_ranks, size, size > 1 ? "s" : "",
                                                                   most));
  } catch (const CLI::ParseError& e) {
    int rc = 0;
    if (root) {
      rc = app.exit(e);
    } else {
      std::ostringstream sink;
      rc = app.exit(e, sink, sink);
    }
    return rc == 0 ? kExitOk : kExitBadInput;
  }
  o.engine.tick_interval_s = std::min(0.25, o.engine.flush_interval_s);
  return std::nullopt;
}

// Where the campaign's tail began on rank 0 (after the last chunk written): wall and CPU time.
struct TailStart {
  std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
  std::clock_t cpu = std::clock();  // rank 0's CPU time: the tail without the other processes' share
};

// Rank 0, every run in: histories, the nominal run, statistics, the method's results, the file
// committed and the journal removed. Returns the exit status.
int write_results(const CommandOptions& o, const campaign::CampaignContext& ctx, const methods::Method& method,
                  const std::string& campaign_text, Rank0& r0, int size, std::chrono::steady_clock::time_point wall0,
                  const EngineResult& done, std::int64_t peak_chunks, const TailStart& tail) {
  const SessionState& st = r0.collector->session();
  const campaign::CampaignOptions& c = ctx.options;
  try {
    const auto t_finish = tail.wall;
    const std::clock_t cpu_finish = tail.cpu;
    std::vector<std::pair<std::int64_t, sim::RunResult>> histories;
    std::vector<double> u(static_cast<std::size_t>(ctx.dims.total));
    for (std::int64_t run : c.output.history_runs)
      for (const methods::RoundPlan& plan : r0.collector->kept_plans())
        if (plan.contains(run)) {
          method.calc_uniforms(plan, run, u.data());
          histories.emplace_back(run, campaign::calc_run_with_history(ctx, u.data(), c.output.history_step_s));
        }
    const sim::RunResult nominal = campaign::calc_nominal_run(c, c.output.history_step_s);
    results::CampaignFileInfo info;
    info.campaign_toml = campaign_text;
    info.base_scene_toml = io::resolved_scene_toml(c.base);
    info.motor_declared_by = campaign::find_motor_declared_by(c);
    info.n_ranks = size;
    info.n_sessions = static_cast<int>(st.session) + 1;
    info.n_rounds = done.n_rounds;
    info.start_utc = io::h5::utc_iso8601(st.first_start);
    info.end_utc = io::h5::utc_now_iso8601();
    info.wall_time_s = st.previous_wall_s + seconds_since(wall0);
    info.schedule = done.schedule;
    info.schedule.synthetic_run_cost_s = o.synthetic_run_cost_s;
    const results::ResultStore& store = r0.file->store();
    const std::int64_t n_runs = store.n_runs(), chunk_runs = store.chunk_runs();
    const results::StatusCounts counts = r0.collector->status_counts();
    if (!r0.collector->stats()) throw std::logic_error("the campaign ended without its statistics");
    r0.file->write_summary(*r0.collector->stats(), histories, nominal, info);  // the store is gone after this
    method.write_results({r0.file->handle(), r0.file->handle(), n_runs, {}});
    r0.file->commit(o.force);
    r0.journal->close_and_remove();
    results::remove_part_journals(o.output_path);
    std::cerr << fmt::format("[truss-campaign] nominal run (base scene, no dispersion): {}{}\n",
                             sim::to_string(nominal.status), nominal.message.empty() ? "" : ": " + nominal.message);
    if (method.runs_are_draws())
      print_design_summary(stderr, results::read_design_values(o.output_path, ctx.record, nominal));
    std::cerr << method.calc_result_text();
    const results::ScheduleSummary& s = done.schedule;
    const double per = 1e6 / std::max(1.0, static_cast<double>(s.runs_by_rank0 + s.runs_by_workers));  // us a result
    std::cerr << fmt::format("[truss-campaign] wrote {}: {} runs in {} round{} ({}), {:.3g} s on {} rank{} "
                             "(statistics and file: {:.3g} s, {:.3g} s CPU; rank 0: {} runs computed, {:.3g} us per "
                             "result handled ({:.3g} us CPU); at most {} chunks of {} runs in a rank's memory)\n",
                             o.output_path, n_runs, info.n_rounds, info.n_rounds > 1 ? "s" : "",
                             format_status_counts(counts), info.wall_time_s, size, size > 1 ? "s" : "",
                             done.last_chunks_s + seconds_since(t_finish),
                             static_cast<double>(std::clock() - cpu_finish) / CLOCKS_PER_SEC,
                             s.runs_by_rank0, per * (s.rank0_poll_s + s.rank0_write_s + s.rank0_tick_s),
                             per * s.rank0_handle_cpu_s, peak_chunks, chunk_runs);
    const std::string example = results::read_example_message(o.output_path, n_runs, sim::RunStatus::invalid_input);
    const bool verdict_ok = print_campaign_verdict(stderr, counts, example);
    if (const std::string why = method.calc_result_failure(); !why.empty()) {
      std::cerr << "error: " << why << "\n";
      return kExitNoResult;
    }
    if (!verdict_ok) return kExitMostlyInvalid;
    return method.calc_not_assessed().empty() ? kExitOk : kExitNotAssessed;
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
std::optional<int> load_campaign(MPI_Comm comm, bool root, const CommandOptions& o, const methods::MethodTable& methods,
                                 std::optional<campaign::CampaignContext>& ctx, std::string& campaign_text) {
  std::string error;
  try {
    if (root) {
      ctx.emplace(campaign::parse_campaign_file(o.campaign_path, methods, o.sets));
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
    if (!root) ctx.emplace(campaign::parse_campaign_text(campaign_text, "resolved campaign from rank 0", ".", methods));
  } catch (const std::exception& e) {
    error = fmt::format("error: the resolved campaign does not parse on rank {}: {}", root ? 0 : 1, e.what());
  }
  if (any_rank(comm, !error.empty())) {
    std::cerr << error << '\n';  // an internal error: every rank that has one reports it
    return kExitIoError;
  }
  return std::nullopt;
}

// Every rank's chunks and rank 0's output, agreed on by every rank: rank 0 prepares the results file
// and the journal (restoring its chunks on --resume), then sends every rank the session's setup.
int prepare_session(MPI_Comm comm, const CommandOptions& o, const std::string& campaign_text,
                    const campaign::CampaignContext& ctx, methods::Method& method, Rank0& r0, Engine& engine,
                    std::unique_ptr<ChunkOwner>& owner) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const results::StoreOptions store{results::find_chunk_runs(ctx.options.ensemble.n_runs), o.compression};
  auto make_owner = [&](const SessionSetup& s, results::Journal* journal, const std::vector<std::size_t>& observed) {
    owner = std::make_unique<ChunkOwner>(
        ctx.record, store, observed,
        OwnerFiles{rank, s.session, s.output, s.temporary, s.campaign_crc, journal, s.stats}, engine.sender(),
        o.engine.flush_interval_s);
  };
  // The statistics are merged off rank 0 (engine.hpp), but where rank 0 restores chunks alone
  // before the other ranks join (--resume), by rank 0.
  const results::StatsRanks stats = find_stats_ranks(o.engine.statistics_ranks, size, o.resume,
                                                     results::ChunkColumns(ctx.record).n_stats);
  int status = kExitOk;
  SessionSetup setup;
  if (rank == 0) {
    status = run_rank0_step(r0, [&] {
      prepare_output(o, campaign_text, ctx, method, r0);
      setup.output = o.output_path;
      setup.temporary = r0.file->temporary_path();
      setup.stats = stats;
      make_owner(setup, r0.journal.get(), r0.collector->observed_fields());
      engine.attach(*owner, r0.collector.get(), stats);
      setup = restore_output(o, campaign_text, r0, *owner, engine);
      setup.stats = stats;
      owner->set_session(setup.session);
    });
  }
  if ((status = broadcast_int_idle(comm, status)) != kExitOk) return status;
  std::string bytes = rank == 0 ? setup.to_bytes() : std::string();
  broadcast_string(comm, bytes);
  if (rank != 0) {
    setup = SessionSetup::from_bytes(bytes);
    std::vector<std::size_t> observed;
    for (const std::string& name : method.observed_outputs())
      observed.push_back(static_cast<std::size_t>(ctx.record.find_output(name)));
    make_owner(setup, nullptr, observed);
    engine.attach(*owner, nullptr, setup.stats);
  }
  engine.set_rank0_chunks(setup.rank0_chunks);
  detail::set_abort_removes(setup.temporary);
  return kExitOk;
}

// Rank 0: the session's start in the journal, and the banner.
void start_session(const CommandOptions& o, const campaign::CampaignContext& ctx, Rank0& r0, double t_start,
                   int size) {
  const Collector& c = *r0.collector;
  const std::int64_t n_runs = c.store().n_runs();
  if (c.session().session > 0) {
    std::cerr << fmt::format("[truss-campaign] resuming: {} of {} runs restored from {}\n", c.n_done(), n_runs,
                             r0.journal->path());
    for (const std::string& note : r0.restored.notes) std::cerr << "[truss-campaign] " << note << '\n';
  }
  r0.collector->start_session(t_start, size);
  *r0.progress = Progress(std::max(ctx.options.ensemble.n_runs, n_runs), c.n_done(), progress_mode(o.progress),
                          o.progress_interval_s);
  r0.progress->banner(ctx.options.name, size, o.output_path);
}

// The command that resumes this campaign: this one's arguments, with --resume and without --force.
std::string resume_command(int argc, char** argv, int size) {
  auto quote = [](std::string a) {
    if (!a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=./,:@%")
                          == std::string::npos)
      return a;
    std::string q = "'";
    for (char ch : a) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    return q + "'";
  };
  std::string cmd = size > 1 ? fmt::format("mpirun -np {}", size) : "mpirun -np 1";
  bool resume = false;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--force") continue;
    resume |= a == "--resume";
    cmd += " " + quote(a);
  }
  return resume ? cmd : cmd + " --resume";
}

// SIGINT or SIGTERM during the runs: what is journaled stays, the results file's temporary name and
// the output's lock go, and rank 0 says in one line what was kept and how to resume, first (mpirun,
// which sent the signal, forwards the ranks' output for well under a second). Every rank leaves
// at once.
[[noreturn]] void leave_interrupted(int argc, char** argv, int size, Rank0& r0, ChunkOwner* owner) {
  const int sig = interrupt_signal();
  if (r0.collector) {
    std::fprintf(stderr, "[truss-campaign] interrupted (%s) after %lld of %lld runs: their records are kept in the "
                 "journal %s (those still on their way to their chunk's rank, at most a batch per rank, are "
                 "computed again); resume with: %s\n",
                 sig == SIGINT ? "SIGINT" : "SIGTERM", static_cast<long long>(r0.collector->n_computed()),
                 static_cast<long long>(r0.collector->store().n_runs()), r0.journal->path().c_str(),
                 resume_command(argc, argv, size).c_str());
    std::fflush(stderr);
  }
  if (owner) owner->write_out_journal();
  if (r0.collector) {
    try {
      r0.journal->write_out();
    } catch (const std::exception&) {
    }
    r0.file->remove_temporary();
    r0.lock.reset();
  } else {
    // mpirun kills the whole job as soon as one rank has left: the others let rank 0, which
    // notices the signal within a run of its own or a look at its messages (kPollInterval), say
    // its line and leave first.
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }
  std::_Exit(128 + sig);
}

}  // namespace

int run_campaign_command(int argc, char** argv, MPI_Comm comm, const methods::MethodTable& methods) {
  // Before any HDF5 call: a write that fails (disk full) leaves HDF5 1.10 an identifier whose
  // exit-time cleanup crashes (io/h5_util.cpp, write_file_atomically); every identifier is closed
  // by its owner, so the library's atexit cleanup is switched off.
  H5dont_atexit();
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const bool root = rank == 0;
  const double t_start = unix_now();
  const auto wall0 = std::chrono::steady_clock::now();
  CommandOptions o;
  if (auto rc = parse_command(argc, argv, root, size, o)) return *rc;
  std::optional<campaign::CampaignContext> ctx;
  std::string campaign_text;
  if (auto rc = load_campaign(comm, root, o, methods, ctx, campaign_text)) return *rc;
  const std::unique_ptr<methods::Method> method = methods.make(*ctx);
  Rank0 r0;
  if (int rc = check_output_all(comm, o, *ctx, r0); rc != kExitOk) return rc;
  install_interrupt_handlers();  // from here on Ctrl-C keeps what is done (leave_interrupted)
  Engine engine(comm, results::find_chunk_runs(ctx->options.ensemble.n_runs),
                ctx->record.fields()[campaign::RecordLayout::kStatus].offset, o.engine);
  std::unique_ptr<ChunkOwner> owner;
  if (int rc = prepare_session(comm, o, campaign_text, *ctx, *method, r0, engine, owner); rc != kExitOk) return rc;
  if (root) start_session(o, *ctx, r0, t_start, size);

  std::vector<double> u(static_cast<std::size_t>(ctx->dims.total));
  const Evaluate evaluate = [&](const methods::RoundPlan& plan, std::int64_t run, std::string& out) {
    method->calc_uniforms(plan, run, u.data());
    const std::size_t start = results::begin_frame(out);
    const campaign::RecordHead head{run, plan.round, rank};
    if (o.synthetic_run_cost_s >= 0.0) append_synthetic_record(*ctx, u.data(), head, o.synthetic_run_cost_s, out);
    else campaign::append_run_record(*ctx, u.data(), head, out);
    results::seal_frame(out, start, results::FrameKind::run);
  };
  EngineResult done;
  try {
    done = engine.run(evaluate);
  } catch (const Interrupted&) {
    leave_interrupted(argc, argv, size, r0, owner.get());
  }
  long long peak = static_cast<long long>(owner->peak_chunks()), peak_all = 0;
  MPI_Reduce(&peak, &peak_all, 1, MPI_LONG_LONG, MPI_MAX, 0, comm);
  const TailStart tail;
  done.schedule.stats_read_back_ranks = read_back_statistics(comm, ctx->record, root ? &r0 : nullptr);
  int status = kExitOk;
  if (root) {
    try {
      r0.collector->tick(true);
      r0.progress->finish(r0.collector->n_computed(), r0.collector->computed_counts());
      status = write_results(o, *ctx, *method, campaign_text, r0, size, wall0, done, peak_all, tail);
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << " (the journal " << r0.journal->path() << " keeps every run)\n";
      status = kExitIoError;
    }
    if (status != kExitOk && status != kExitMostlyInvalid && status != kExitNoResult) r0.drop();
  }
  return broadcast_int_idle(comm, status);
}

}  // namespace truss::parallel
