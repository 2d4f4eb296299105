// How a campaign chooses its points: a method proposes them round by round. The engine
// (parallel/engine.hpp) evaluates a round's runs on every rank and hands the method the records
// of that round before it proposes the next one; a one-shot design (Monte Carlo, Latin hypercube,
// Sobol', Saltelli) has one round. Adding a method is one class like the ones here, its options,
// and a row of the method table (method_table.hpp): the scheduler, the journal, the results file and
// the campaign's options do not change.
//
// Run indices are global and contiguous across rounds: round r's runs are first_run ..
// first_run + n_runs - 1, right after round r - 1's. The records a method reads come in run-index
// order, whatever the ranks and the order in which runs finished, and a run's point is a pure
// function of its round's plan and its run index: the same campaign gives the same points, and the
// same file, on any number of ranks and after --resume.
#pragma once
#include <hdf5.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "campaign/evaluate.hpp"

namespace truss::methods {

// One round: its runs and the state (the method's own bytes, opaque to the engine) from which any
// rank computes any of their points. The engine journals it before the round's first record and
// sends it to every rank.
struct RoundPlan {
  std::int64_t round = 0;
  std::int64_t first_run = 0;
  std::int64_t n_runs = 0;  // 0: the method is done
  std::string state;
  std::int64_t end_run() const { return first_run + n_runs; }
  bool contains(std::int64_t run) const { return run >= first_run && run < end_run(); }
  bool operator==(const RoundPlan&) const = default;
  // Little-endian: i64 round, i64 first_run, i64 n_runs, u32 state length, state.
  std::string to_bytes() const;
  static RoundPlan from_bytes(std::string_view bytes);  // throws std::runtime_error for bytes that are not one
};

// A finished round's records as a method reads them, in run-index order: run first_run + i has
// status[i] (a RunStatus value) and outputs[k][i] for the k-th of the method's observed_outputs().
struct RoundRecords {
  std::int64_t first_run = 0;
  std::vector<std::int8_t> status;
  std::vector<std::vector<double>> outputs;
};

// What a method proposes for a round: how many runs (0: done) and their state.
struct Proposal {
  std::int64_t n_runs = 0;
  std::string state;
};

class Method {
 public:
  virtual ~Method() = default;
  // The float64 outputs of a run's record (RunResult fields, by name) that propose() reads.
  virtual std::vector<std::string> observed_outputs() const { return {}; }
  // Whether propose() reads the previous round's records (the statuses at least); a method that
  // observes an output does. Without it, `previous` is empty (a one-shot design keeps no table).
  virtual bool reads_records() const { return !observed_outputs().empty(); }
  // Rank 0: round `round`'s runs. `previous` holds round - 1's records (nothing for round 0). The
  // engine calls it once per round, in order, so a method may keep what it learns from one call to
  // the next; it must depend on nothing else: on --resume the engine calls it again with the same
  // records and refuses a journal whose plans it does not reproduce.
  virtual Proposal propose(std::int64_t round, const RoundRecords& previous) = 0;
  // Any rank: the point of run `run` of round `plan`, as the campaign's uniforms u[0 .. dims).
  virtual void calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const = 0;
  // Rank 0, once every run is in the results file: the method's own results (Saltelli: the Sobol'
  // indices, /sensitivity). `n_runs`: the runs of all rounds.
  virtual void write_results(hid_t file, std::int64_t n_runs) const;
  // False when the runs are not draws of the dispersions (subset simulation's Markov chains): the
  // command then prints no design values (percentiles) of them.
  virtual bool runs_are_draws() const { return true; }
  // Rank 0, after write_results: the method's result for the terminal (lines), or nothing.
  virtual std::string calc_result_text() const { return {}; }
  // Rank 0, after propose(): what the progress line says of the round being run (subset: "level
  // 2 (margin <= 0.0013 m), Markov step 3 of 9"), empty for a one-shot design; and the cap on the
  // runs of all rounds it counts against (0: the runs of the rounds proposed so far).
  virtual std::string progress_stage() const { return {}; }
  virtual std::int64_t run_cap() const { return 0; }
  // Empty when the method's result stands; else why there is none (the campaign then exits 5).
  virtual std::string calc_result_failure() const { return {}; }
};

}  // namespace truss::methods
