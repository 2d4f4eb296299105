// A run's record: the one definition of what a campaign stores for each run. RecordLayout lists
// the fields (name, group of the results file, type, width, units, byte offset); a worker writes a
// record with RecordWriter, rank 0 reads it through RecordView, the journal keeps its bytes as
// they are, and the results file has one dataset per field, in this order. Nothing else parses a
// record.
//
// Bytes (little-endian): the fixed part, every field at its offset (run_index i64, round i64,
// status i8, rank i64, run_wall_time_s f64, the outputs, the inputs), then the message: u32 length
// and its bytes. A record depends on (campaign, run index, round plan) only, but for `rank` and
// `run_wall_time_s` (where and when it ran).
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "campaign/campaign.hpp"
#include "campaign/dispersion.hpp"
#include "io/json_summary.hpp"
#include "sim/result.hpp"

namespace truss::campaign {

enum class ValueType : std::uint8_t { status, i64, f64 };  // status: int8, an HDF5 enum in the file
std::size_t value_bytes(ValueType t);

// The group of the results file a field's dataset is in.
enum class Group : std::uint8_t { runs, bays, inputs, timing };
const char* group_path(Group g);  // "runs", "runs/bays", "runs/inputs", "timing"

// The second dimension of a field's dataset: none (a column of one value a run), the bays
// (1 .. n_bays_max) or the frames (0 .. n_bays_max).
enum class Scale : std::uint8_t { none, bay, frame };

struct Field {
  std::string name;  // the dataset's name in its group
  Group group = Group::runs;
  ValueType type = ValueType::f64;
  int width = 1;                       // values a run (> 1 only with a scale)
  Scale scale = Scale::none;
  std::string units;
  bool statistics = false;             // an output whose /stats the file holds (float64, outputs only)
  std::size_t offset = 0;              // of its first value in the record
  const io::RunField* run = nullptr;   // an output of RunResult
  const io::BayField* bay = nullptr;   // a per-bay output of BayResult
  int dispersion = -1;                 // an input: the index of its dispersion
  std::size_t bytes() const { return value_bytes(type) * static_cast<std::size_t>(width); }
};

class RecordLayout {
 public:
  // The fields that every record starts with, in this order.
  static constexpr std::size_t kRun = 0, kRound = 1, kStatus = 2, kRank = 3, kWallTime = 4;

  // A campaign's records: the head fields, every numeric scalar of RunResult (wall_time_s apart: it
  // is the head's run_wall_time_s), every float64 field of BayResult by bay, and each dispersion's
  // applied values (dims: where each dispersion's values are in a run's inputs).
  RecordLayout(const CampaignOptions& c, const DimensionLayout& dims);

  const std::vector<Field>& fields() const { return fields_; }
  std::size_t fixed_bytes() const { return fixed_bytes_; }
  int n_bays_max() const { return n_bays_max_; }
  int n_inputs() const { return n_inputs_; }
  // The index of the float64 output field `name`, or -1.
  int find_output(const std::string& name) const;

  // "" if `record` is a record of this layout, else what is wrong with it.
  std::string check(std::string_view record) const;
  // A record's fixed part before its setters (RecordWriter): every float64 NaN, every integer 0.
  const std::string& blank_fixed_part() const { return blank_; }

 private:
  void add(Field f);
  std::vector<Field> fields_;
  std::string blank_;
  std::size_t fixed_bytes_ = 0;
  int n_bays_max_ = 0, n_inputs_ = 0;
};

// A record's bytes read through its layout (check() first: the accessors do not).
class RecordView {
 public:
  RecordView(std::string_view bytes, const RecordLayout& layout) : b_(bytes), L_(&layout) {}
  std::int64_t run() const { return i64(RecordLayout::kRun); }
  std::int64_t round() const { return i64(RecordLayout::kRound); }
  std::int8_t status() const;
  std::int64_t rank() const { return i64(RecordLayout::kRank); }
  double wall_time_s() const { return f64(RecordLayout::kWallTime); }
  std::string_view message() const;
  double f64(std::size_t field, int k = 0) const;
  std::int64_t i64(std::size_t field, int k = 0) const;
  const char* field_data(std::size_t field) const { return b_.data() + L_->fields()[field].offset; }
  std::string_view bytes() const { return b_; }

 private:
  std::string_view b_;
  const RecordLayout* L_;
};

// Writes one record at the end of `out`: the constructor appends the fixed part (every float64
// NaN, every integer 0), the setters fill it, finish() appends the message.
class RecordWriter {
 public:
  RecordWriter(const RecordLayout& layout, std::string& out);
  void set_i64(std::size_t field, std::int64_t v, int k = 0);
  void set_f64(std::size_t field, double v, int k = 0);
  void set_status(sim::RunStatus s);
  void finish(std::string_view message);
  // Where value k of `field` goes (valid until the next append to `out`).
  char* at(std::size_t field, int k);

 private:
  const RecordLayout& L_;
  std::string& out_;
  std::size_t start_;
};

// Where and when a record was made.
struct RecordHead {
  std::int64_t run = 0, round = 0, rank = 0;
};

// The record of a run's result: its outputs, `inputs` (the applied values of every dispersion
// dimension, DimensionLayout order) and the head.
void append_record(const RecordLayout& layout, const RecordHead& head, const sim::RunResult& r,
                   const std::vector<double>& inputs, std::string& out);

}  // namespace truss::campaign
