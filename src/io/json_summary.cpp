// JSON run summaries and the shared result field tables. See json_summary.hpp.
#include "io/json_summary.hpp"

#include <fmt/format.h>

#include <cmath>

namespace truss::io {

using sim::BayResult;
using sim::RunResult;
using sim::TimeHistory;

#define TRUSS_RUN_F64(NAME, UNITS) \
  RunField { #NAME, UNITS, [](const RunResult& r) -> FieldValue { return double{r.NAME}; }, &RunResult::NAME }
#define TRUSS_RUN_I64(NAME)                                                                 \
  RunField {                                                                                \
    #NAME, "1", [](const RunResult& r) -> FieldValue { return std::int64_t{r.NAME}; }, nullptr, \
        [](const RunResult& r) { return std::int64_t{r.NAME}; }                             \
  }
#define TRUSS_RUN_STR(NAME) \
  RunField { #NAME, "1", [](const RunResult& r) -> FieldValue { return std::string{r.NAME}; } }
#define TRUSS_BAY_F64(NAME, UNITS) \
  BayField { #NAME, UNITS, [](const BayResult& b) -> FieldValue { return double{b.NAME}; }, &BayResult::NAME }
#define TRUSS_HIST_F64(NAME, UNITS)                                                    \
  HistoryField {                                                                       \
    #NAME, UNITS, [](const TimeHistory& h) -> const std::vector<double>* { return &h.NAME; }, \
        nullptr                                                                        \
  }

const std::vector<RunField>& run_result_fields() {
  static const std::vector<RunField> f = {
      TRUSS_RUN_STR(direction),
      TRUSS_RUN_STR(drive_mode),
      TRUSS_RUN_I64(n_bays),
      TRUSS_RUN_I64(bays_completed),
      TRUSS_RUN_F64(deploy_time_s, "s"),
      TRUSS_RUN_F64(end_time_s, "s"),
      TRUSS_RUN_F64(peak_drive_force_N, "N"),
      TRUSS_RUN_F64(peak_drive_force_time_s, "s"),
      TRUSS_RUN_I64(peak_drive_force_bay),
      TRUSS_RUN_F64(min_drive_force_N, "N"),
      TRUSS_RUN_F64(min_drive_force_time_s, "s"),
      TRUSS_RUN_I64(min_drive_force_bay),
      TRUSS_RUN_F64(peak_drive_torque_Nm, "Nm"),
      TRUSS_RUN_F64(min_drive_torque_Nm, "Nm"),
      TRUSS_RUN_F64(motor_torque_at_speed_Nm, "Nm"),
      TRUSS_RUN_F64(motor_torque_margin_Nm, "Nm"),
      TRUSS_RUN_F64(peak_motor_torque_Nm, "Nm"),
      TRUSS_RUN_F64(peak_static_drive_torque_Nm, "Nm"),
      TRUSS_RUN_F64(peak_inertial_drive_torque_Nm, "Nm"),
      TRUSS_RUN_F64(motorisation_required_torque_Nm, "Nm"),
      TRUSS_RUN_F64(motorisation_available_torque_Nm, "Nm"),
      TRUSS_RUN_F64(motorisation_margin, "1"),
      TRUSS_RUN_F64(motorisation_stall_torque_Nm, "Nm"),
      TRUSS_RUN_F64(peak_pin_force_N, "N"),
      TRUSS_RUN_F64(peak_pin_force_time_s, "s"),
      TRUSS_RUN_I64(peak_pin_force_bay),
      TRUSS_RUN_F64(peak_diagonal_tension_N, "N"),
      TRUSS_RUN_F64(peak_latch_energy_J, "J"),
      TRUSS_RUN_F64(peak_driven_speed_m_per_s, "m/s"),
      TRUSS_RUN_F64(drive_work_J, "J"),
      TRUSS_RUN_F64(drive_work_smooth_J, "J"),
      TRUSS_RUN_F64(drive_work_impulses_J, "J"),
      TRUSS_RUN_F64(start_drive_impulse_Ns, "Ns"),
      TRUSS_RUN_F64(energy_lost_J, "J"),
      TRUSS_RUN_F64(kinetic_energy_start_J, "J"),
      TRUSS_RUN_F64(kinetic_energy_end_J, "J"),
      TRUSS_RUN_F64(potential_energy_start_J, "J"),
      TRUSS_RUN_F64(potential_energy_end_J, "J"),
      TRUSS_RUN_F64(energy_residual_J, "J"),
      TRUSS_RUN_F64(max_rail_residual_m, "m"),
      TRUSS_RUN_I64(rail_miss_bay),
      TRUSS_RUN_F64(rail_miss_closest_approach_m, "m"),
      TRUSS_RUN_F64(rail_margin_m, "m"),
      TRUSS_RUN_F64(rail_miss_closest_approach_time_s, "s"),
      TRUSS_RUN_F64(rail_miss_above_rail_top_time_s, "s"),
      TRUSS_RUN_F64(min_bay_opening_m, "m"),
      TRUSS_RUN_F64(min_bay_opening_time_s, "s"),
      TRUSS_RUN_I64(min_bay_opening_bay),
      TRUSS_RUN_I64(contact_landings),
      TRUSS_RUN_I64(contact_lift_offs),
      TRUSS_RUN_F64(contact_energy_loss_J, "J"),
      TRUSS_RUN_I64(steps),
      TRUSS_RUN_I64(rejected_steps),
      TRUSS_RUN_I64(rhs_evals),
      TRUSS_RUN_F64(wall_time_s, "s"),
  };
  return f;
}

const std::vector<BayField>& bay_result_fields() {
  static const std::vector<BayField> f = {
      BayField{"bay", "1", [](const BayResult& b) -> FieldValue { return std::int64_t{b.bay}; }},
      TRUSS_BAY_F64(entry_time_s, "s"),
      TRUSS_BAY_F64(lock_time_s, "s"),
      TRUSS_BAY_F64(latch_energy_J, "J"),
      TRUSS_BAY_F64(entry_impulse_Ns, "Ns"),
      TRUSS_BAY_F64(landing_impulse_Ns, "Ns"),
      TRUSS_BAY_F64(entry_drive_impulse_Ns, "Ns"),
      TRUSS_BAY_F64(unlock_impulse_Ns, "Ns"),
      TRUSS_BAY_F64(entry_energy_loss_J, "J"),
      TRUSS_BAY_F64(peak_drive_force_N, "N"),
      TRUSS_BAY_F64(peak_drive_force_time_s, "s"),
      TRUSS_BAY_F64(peak_pin_force_N, "N"),
      TRUSS_BAY_F64(peak_pin_force_time_s, "s"),
  };
  return f;
}

const std::vector<HistoryField>& history_fields() {
  static const std::vector<HistoryField> f = {
      TRUSS_HIST_F64(t_s, "s"),
      HistoryField{"bay", "1", nullptr,
                   [](const TimeHistory& h) -> const std::vector<int>* { return &h.bay; }},
      TRUSS_HIST_F64(y_driven_m, "m"),
      TRUSS_HIST_F64(y_lower_m, "m"),
      TRUSS_HIST_F64(hinge_x_m, "m"),
      TRUSS_HIST_F64(hinge_y_m, "m"),
      TRUSS_HIST_F64(drive_force_N, "N"),
      TRUSS_HIST_F64(drive_torque_Nm, "Nm"),
      TRUSS_HIST_F64(pin_force_N, "N"),
      TRUSS_HIST_F64(diagonal_tension_N, "N"),
      TRUSS_HIST_F64(driven_speed_m_per_s, "m/s"),
  };
  return f;
}

#undef TRUSS_RUN_F64
#undef TRUSS_RUN_I64
#undef TRUSS_RUN_STR
#undef TRUSS_BAY_F64
#undef TRUSS_HIST_F64

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  // fmt 9: shortest representation that reads back exactly; ".0" keeps integral values floats.
  std::string s = fmt::format("{}", v);
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

namespace {

// Length of the valid UTF-8 sequence starting at s[i], or 0 if it is not valid.
std::size_t utf8_sequence(std::string_view s, std::size_t i) {
  const auto b0 = static_cast<unsigned char>(s[i]);
  std::size_t n;
  std::uint32_t cp;
  if (b0 < 0x80) return 1;
  if ((b0 & 0xE0) == 0xC0) { n = 2; cp = b0 & 0x1F; }
  else if ((b0 & 0xF0) == 0xE0) { n = 3; cp = b0 & 0x0F; }
  else if ((b0 & 0xF8) == 0xF0) { n = 4; cp = b0 & 0x07; }
  else return 0;
  if (i + n > s.size()) return 0;
  for (std::size_t k = 1; k < n; ++k) {
    const auto b = static_cast<unsigned char>(s[i + k]);
    if ((b & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (b & 0x3F);
  }
  // Overlong forms, surrogates and values beyond U+10FFFF are invalid.
  if ((n == 2 && cp < 0x80) || (n == 3 && cp < 0x800) || (n == 4 && cp < 0x10000)) return 0;
  if ((cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF) return 0;
  return n;
}

void append_field_value(std::string& out, const FieldValue& v) {
  if (const auto* d = std::get_if<double>(&v)) out += json_number(*d);
  else if (const auto* i = std::get_if<std::int64_t>(&v)) out += fmt::format("{}", *i);
  else out += json_string(std::get<std::string>(v));
}

}  // namespace

std::string json_string(std::string_view s) {
  std::string r = "\"";
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x80) {
      const std::size_t n = utf8_sequence(s, i);
      if (n == 0) {
        r += "\\ufffd";
        ++i;
      } else {
        r.append(s.substr(i, n));
        i += n;
      }
      continue;
    }
    switch (c) {
      case '"': r += "\\\""; break;
      case '\\': r += "\\\\"; break;
      case '\b': r += "\\b"; break;
      case '\f': r += "\\f"; break;
      case '\n': r += "\\n"; break;
      case '\r': r += "\\r"; break;
      case '\t': r += "\\t"; break;
      default:
        if (c < 0x20 || c == 0x7f)
          r += fmt::format("\\u{:04x}", static_cast<unsigned>(c));
        else
          r += static_cast<char>(c);
    }
    ++i;
  }
  return r + "\"";
}

std::string to_json(const RunResult& r) {
  std::string out = "{\n";
  out += fmt::format("  \"status\": {},\n", json_string(sim::to_string(r.status)));
  out += fmt::format("  \"message\": {},\n", json_string(r.message));
  for (const auto& f : run_result_fields()) {
    out += fmt::format("  {}: ", json_string(f.name));
    append_field_value(out, f.get(r));
    out += ",\n";
  }
  out += fmt::format("  \"history_samples\": {},\n", r.history.size());
  out += "  \"bays\": [";
  for (std::size_t i = 0; i < r.bays.size(); ++i) {
    out += i == 0 ? "\n    {" : ",\n    {";
    bool first = true;
    for (const auto& f : bay_result_fields()) {
      out += fmt::format("{}{}: ", first ? "" : ", ", json_string(f.name));
      append_field_value(out, f.get(r.bays[i]));
      first = false;
    }
    out += "}";
  }
  out += r.bays.empty() ? "]\n" : "\n  ]\n";
  out += "}\n";
  return out;
}

}  // namespace truss::io
