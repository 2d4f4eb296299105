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
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "campaign/evaluate.hpp"
#include "sampling/allowable.hpp"

namespace truss::methods {

// One round: its runs and the state (the method's own bytes, opaque to the engine) from which any
// rank computes any of their points. The engine journals its digest (PlanDigest) before the round's
// first record and sends it to every rank.
struct RoundPlan {
  std::int64_t round = 0;
  std::int64_t first_run = 0;
  std::int64_t n_runs = 0;  // 0: the method is done
  std::string state;
  std::int64_t end_run() const { return first_run + n_runs; }
  bool contains(std::int64_t run) const { return run >= first_run && run < end_run(); }
  bool operator==(const RoundPlan&) const = default;
  // Little-endian: i64 round, i64 first_run, i64 n_runs, u32 state length, state.
  static constexpr std::size_t kHeaderBytes = 3 * sizeof(std::int64_t) + sizeof(std::uint32_t);
  void append_bytes(std::string& out) const;  // appended to `out`
  static RoundPlan from_bytes(std::string_view bytes);  // throws std::runtime_error for bytes that are not one
};

// What the journal keeps of a round's plan: its runs, and its state's length and CRC-32 (zlib's).
// --resume has the method propose every journaled round again and compares digests, so the state
// itself (up to hundreds of bytes a run: a subset simulation's points) is neither written nor kept.
struct PlanDigest {
  std::int64_t round = 0;
  std::int64_t first_run = 0;
  std::int64_t n_runs = 0;
  std::uint32_t state_bytes = 0;
  std::uint32_t state_crc32 = 0;
  static PlanDigest of(const RoundPlan& plan);
  std::int64_t end_run() const { return first_run + n_runs; }
  bool contains(std::int64_t run) const { return run >= first_run && run < end_run(); }
  bool operator==(const PlanDigest&) const = default;
  // Little-endian: i64 round, i64 first_run, i64 n_runs, u32 state length, u32 state CRC-32.
  std::string to_bytes() const;
  static PlanDigest from_bytes(std::string_view bytes);  // throws std::runtime_error unless 36 such bytes
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

// Where a method writes its results (write_results): its group under `group` (the file's root, or
// the group a composite gives it), its runs rows of the file's /runs: rows[i] is its run i's row
// (empty: run i is row i).
struct ResultsPlace {
  hid_t file = -1;
  hid_t group = -1;
  std::int64_t n_runs = 0;         // the rows of /runs
  std::vector<std::int64_t> rows;  // an inner method's runs' rows
  std::int64_t find_row(std::int64_t run) const { return rows.empty() ? run : rows.at(static_cast<std::size_t>(run)); }
};

// What a method that estimates the probability of its failure event (its options' failure_event())
// has found after its last propose(): p with its interval and one-sided upper bound at the
// confidence asked, the coefficient of variation the bounds use, the runs and how it ended.
struct FailureEstimate {
  sampling::ProbabilityBounds bounds;
  double cov = std::numeric_limits<double>::quiet_NaN();
  std::int64_t runs = 0;
  std::int64_t failures = -1;  // failing runs counted (-1: p is not a count, subset simulation)
  std::string status, message;
  double nearest_margin = std::numeric_limits<double>::quiet_NaN();  // the smallest finite margin of its runs
  std::int64_t unusable = 0;  // runs without a usable result (capped, solver failure, NaN margin)
  std::string untrusted;      // empty: the estimate stands; else why it may lie below the true p
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
  // Rank 0, once every run is in the results file: the method's own results, its group under
  // place.group (Saltelli: the Sobol' indices, /sensitivity).
  virtual void write_results(const ResultsPlace& place) const;
  // A method whose options have a failure event: the estimate of its probability (after the last
  // propose()); nothing from the others. A composite (a design sweep) reads its inner methods' so.
  virtual std::optional<FailureEstimate> calc_failure_estimate(double confidence) const;
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
  // Empty unless the method's verdict is NOT ASSESSED (a design sweep); else why (the campaign
  // then exits 6).
  virtual std::string calc_not_assessed() const { return {}; }
};

}  // namespace truss::methods
