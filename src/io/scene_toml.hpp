// Scene files: TOML text -> SceneOptions, with user-facing error messages, and the way back
// (resolved_scene_toml) so that every output file can carry the exact scene it was run with.
//
// Tables and keys: see the table in scene_toml.cpp (kKeys) and campaigns/scenes/table1.toml.
// Every error is an InputError whose what() is complete and ready to print, e.g.
//   error: scene.toml:7: rail.beta_deg: must lie in (0, 90) degrees, got 95
//   error: --set mast.n_bays=12.5: mast.n_bays: expected an integer, got a floating-point number 12.5
#pragma once
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "sim/scene.hpp"

namespace truss::io {

// Bad user input (scene file, --set override, output path). what() is the complete message,
// starting with "error: ".
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Reads and parses a scene file, then applies the overrides ("table.key=value", as given to
// --set, in order), SceneOptions::validate() (with every numeric key's hard range, from the key
// table) and the mast's geometry (an error names the keys involved and where each came from).
// Throws InputError. If `warnings` is given, it receives one line per key set outside its
// typical range ("warning: FILE:LINE: drive.stall_torque_Nm = 5.2 N m is outside ...").
sim::SceneOptions parse_scene_file(const std::string& path,
                                   const std::vector<std::string>& overrides = {},
                                   std::vector<std::string>* warnings = nullptr);

// Input files (scenes, campaigns) are bounded: a larger file, or a device like /dev/zero, is
// refused with an InputError naming it.
inline constexpr std::size_t kMaxInputFileBytes = std::size_t{16} << 20;
// The whole file as text; InputError ("error: PATH: cannot read WHAT: reason") if it is a
// directory, cannot be read, or holds more than max_bytes.
std::string read_input_file(const std::string& path, const char* what, std::size_t max_bytes = kMaxInputFileBytes);

// Same, for scene text already in memory; source_name is used in messages (e.g. the file name).
sim::SceneOptions parse_scene_text(std::string_view text, const std::string& source_name,
                                   const std::vector<std::string>& overrides = {});

// A scene key set outside the scene file: `assignment` is "table.key=value"; `where` names its
// origin in messages ("FILE:LINE" of a campaign file), empty for a command-line --set.
struct SceneSetting {
  std::string assignment;
  std::string where;
};
// As parse_scene_file / parse_scene_text, with settings that carry their origin.
sim::SceneOptions parse_scene_file_with(const std::string& path, const std::vector<SceneSetting>& settings,
                                        std::vector<std::string>* warnings = nullptr);
sim::SceneOptions parse_scene_text_with(std::string_view text, const std::string& source_name,
                                        const std::vector<SceneSetting>& settings,
                                        std::vector<std::string>* warnings = nullptr);

// A variant of a scene that parse_scene_text_with(text, source_name, settings) gave as `base`: the
// same options, checks and messages as parse_scene_text_with(text, source_name, settings + more),
// at the cost of the `more` settings alone (the text is read again only to word an error, with the
// lines its keys came from). Warnings: for the keys `more` sets. For batches of variants of one scene.
sim::SceneOptions parse_scene_variant(const sim::SceneOptions& base, std::string_view text,
                                      const std::string& source_name,
                                      const std::vector<SceneSetting>& settings, const std::vector<SceneSetting>& more,
                                      std::vector<std::string>* warnings = nullptr);

// As parse_scene_text but without SceneOptions::validate(): checks syntax, keys, types and
// enumeration values only. For tools that change the options further and validate afterwards.
sim::SceneOptions parse_scene_text_unvalidated(std::string_view text,
                                               const std::string& source_name,
                                               const std::vector<std::string>& overrides = {});

// The full scene as TOML: every table and key, defaults included, doubles written so that they
// read back bit-exactly; optional keys that are unset appear only as comments. Parsing the text
// again gives the same options.
std::string resolved_scene_toml(const sim::SceneOptions& scene);

// A TOML float that reads back to exactly v ("12.0", "1e-05", "nan", "-inf").
std::string toml_double(double v);
// A TOML basic string (double quotes, escaped) that reads back to exactly s.
std::string toml_string(std::string_view s);

// All known keys, "table.key", in the order resolved_scene_toml writes them.
std::vector<std::string> known_scene_keys();

}  // namespace truss::io
