// The one table of scene keys: for each key of a scene TOML file its table and name, value kind,
// unit, the comment the resolved scene carries, whether a campaign may disperse it and how
// (per run, or also per bay / per frame), and accessors to SceneOptions and to the per-bay and
// per-frame parameters of MastParams. The TOML parser and writer (io/scene_toml), the campaign's
// key checks and its dispersions (campaign/) all read this table: adding a scene key is one line
// here (and the field in SceneOptions).
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/params.hpp"
#include "sim/scene.hpp"

namespace truss::sim {

enum class KeyKind { real, opt_real, integer, enumeration };

// A closed or open interval of values in the key's unit.
struct KeyRange {
  double lo = 0, hi = 0;
  bool lo_open = false, hi_open = false;
  bool contains(double v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  std::string text() const;  // "(0, 1000]"
};
// How a campaign may disperse a key: not at all, per run, or per bay / per frame (which also
// allows per run: build_mast spreads a per-run value over the bays or frames).
enum class KeyScope { fixed, run, bay, frame };

struct SceneKey {
  std::string_view table;
  std::string_view key;
  KeyKind kind;
  std::string_view unit;                     // SI unit of the value ("1" for counts and ratios)
  std::string_view comment;                  // unit and meaning, written in the resolved TOML
  KeyScope scope = KeyScope::fixed;
  std::vector<std::string_view> allowed;     // enumeration: values, in enum order
  std::int64_t int_min = 0, int_max = 0;     // integer: range of the C++ field
  void (*set_real)(SceneOptions&, double) = nullptr;                // real, opt_real, integer (rounded)
  double (*get_real)(const SceneOptions&) = nullptr;                // the resolved value (defaults filled in)
  std::optional<double> (*get_opt)(const SceneOptions&) = nullptr;  // opt_real: unset stays unset
  void (*set_int)(SceneOptions&, std::int64_t) = nullptr;           // integer
  std::int64_t (*get_int)(const SceneOptions&) = nullptr;           // integer
  void (*set_enum)(SceneOptions&, std::size_t) = nullptr;           // enumeration (index in allowed)
  std::size_t (*get_enum)(const SceneOptions&) = nullptr;           // enumeration
  double* (*bay_field)(model::BayParams&) = nullptr;                // scope bay
  double* (*frame_field)(model::FrameParams&) = nullptr;            // scope frame
  // Numeric keys. hard: outside it a value is refused (parse, --set, campaign draws): it keeps
  // absurd magnitudes (1e308) away from the physics, with margins of about 1000 around any
  // plausible mast. typical: a value outside it runs but draws a plausibility warning (a torque
  // typed in N m where mN m was meant, a length in mm). Semantic checks (beta in (0, 90), an even
  // panel count) stay in SceneOptions::validate().
  KeyRange hard{}, typical{};

  std::string dotted() const { return std::string(table) + "." + std::string(key); }
  bool is_dispersible() const { return scope != KeyScope::fixed; }
};

const std::vector<SceneKey>& scene_keys();

// Empty if v lies in the key's hard range (enumerations: always), else
// "table.key: must lie in RANGE UNIT, got V".
std::string check_hard_range(const SceneKey& k, double v);
// Empty if v lies in the key's typical range, else a sentence naming the key, the value, the
// typical range, and a likely unit slip when v / 1000 (or v * 1000) would be typical.
std::string check_typical_range(const SceneKey& k, double v);
// The first key of the scene whose value lies outside its hard range ("" if none): the values
// each key's get_real/get_int/get_opt returns (unset optional keys are skipped).
std::string check_scene_ranges(const SceneOptions& s);
// Per-bay and per-frame values of a (dispersed) mast against the hard ranges of their keys.
std::string check_mast_ranges(const model::MastParams& m);
// The value of a numeric key in a scene; nullopt for enumerations and unset optional keys.
std::optional<double> key_value(const SceneKey& k, const SceneOptions& s);
// Cheap look-ups by table and key, or by "table.key"; nullptr if unknown.
const SceneKey* find_scene_key(std::string_view table, std::string_view key);
const SceneKey* find_scene_key(std::string_view dotted);
// Table names in the order of the table.
std::vector<std::string_view> find_scene_tables();

}  // namespace truss::sim
