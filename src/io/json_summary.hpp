// Run summaries as JSON, and the field tables (names, units, accessors) of RunResult, BayResult and
// TimeHistory that the JSON and HDF5 writers share, so both always write the same fields.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "sim/result.hpp"
#include "sim/scene.hpp"

namespace truss::io {

// The run summary as a JSON object (pretty-printed, ends with a newline): "status" (the
// to_string(RunStatus) name), "message", every other scalar field of RunResult under its own
// name, "history_samples" (length of the time history) and "bays" (one object per BayResult, with
// every field). Non-finite doubles are written as null; doubles round-trip exactly.
std::string to_json(const sim::RunResult& r);

// --- field tables ----------------------------------------------------------------------------
using FieldValue = std::variant<double, std::int64_t, std::string>;

// Units: "s", "N", "Nm", "J", "Ns", "m", "m/s"; "1" for counts, indices and other dimensionless
// values (never empty).
// Besides the variant `get`, each field has a typed accessor for writers that copy many values a
// run (the campaign record): a float64 field its member (f64), an integer field its value as int64
// (get_i64); the other is null. Both come from the same line of the table.
// A field that only some scenes compute (NaN in every run of the others) says which: defined_when
// returns null for a scene that computes it, else the condition ("drive.mode = \"velocity\"").
struct RunField {
  const char* name;
  const char* units;
  FieldValue (*get)(const sim::RunResult&);
  double sim::RunResult::*f64 = nullptr;
  std::int64_t (*get_i64)(const sim::RunResult&) = nullptr;
  const char* (*defined_when)(const sim::SceneOptions&) = nullptr;
};
struct BayField {
  const char* name;
  const char* units;
  FieldValue (*get)(const sim::BayResult&);  // double or int64 only
  double sim::BayResult::*f64 = nullptr;     // a float64 field's member, else null
};
struct HistoryField {
  const char* name;
  const char* units;
  const std::vector<double>* (*get_double)(const sim::TimeHistory&);  // null for int fields
  const std::vector<int>* (*get_int)(const sim::TimeHistory&);        // null for double fields
};

// Every scalar field of RunResult except status and message (which each writer handles itself),
// in declaration order.
const std::vector<RunField>& run_result_fields();
// Every field of BayResult, in declaration order.
const std::vector<BayField>& bay_result_fields();
// Every vector of TimeHistory, in declaration order.
const std::vector<HistoryField>& history_fields();

// JSON helpers (exposed for tests and other writers).
std::string json_string(std::string_view s);  // quoted and escaped; invalid UTF-8 -> U+FFFD
std::string json_number(double v);            // shortest round-trip, or null if not finite

}  // namespace truss::io
