#include "campaign/campaign.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "campaign/campaign_tables.hpp"
#include "campaign/design_axis.hpp"
#include "campaign/dispersion.hpp"
#include "campaign/failure.hpp"
#include "campaign/toml_read.hpp"
#include "io/scene_toml.hpp"
#include "io/suggest.hpp"
#include "sim/scene_keys.hpp"

namespace truss::campaign {

using io::InputError;

namespace {

// A campaign key that becomes a scene's [run] key in every run (ensemble.max_run_wall_time_s ->
// run.max_wall_time_s, output.history_step_s -> run.output_step_s) takes that key's hard range from
// the scene key table, so that no value the campaign accepts makes every run invalid input.
std::string check_run_key_range(std::string_view run_key, const std::string& key, double v) {
  const sim::SceneKey* k = sim::find_scene_key("run", run_key);
  if (k == nullptr || k->hard.contains(v)) return {};
  return fmt::format("{}: must lie in {} {} (the range of run.{}), got {}", key, k->hard.text(), k->unit, run_key, v);
}

// TOML text of a value given on the command line: numbers, booleans, quoted strings, arrays;
// a bare word is taken as a string (e.g. --set ensemble.sampling=sobol).
toml::table parse_override_value(const std::string& value) {
  try {
    return toml::parse("v = " + value);
  } catch (const toml::parse_error&) {
    toml::table t;
    t.insert("v", value);
    return t;
  }
}

// [ensemble]: its rows, and the tables of the method catalog's rows ([ensemble.stop]).
void read_ensemble(const TomlSource& c, const toml::table& t, CampaignOptions& o) {
  OtherKeys methods;
  methods.take = [&](std::string_view k, const toml::node& v) {
    const MethodSyntax* row = c.methods->find(k);
    if (row == nullptr || row->selection == MethodSelection::wraps) return false;
    detail::check_method_key(c, fmt::format("ensemble.{}", k), v);  // the row reads it (detail::parse_method)
    return true;
  };
  for (const MethodSyntax* r : c.methods->list())
    if (r->selection != MethodSelection::wraps && r->table_doc != nullptr)
      methods.names.push_back(fmt::format("[{}]", r->own_table()));
  read_options(c, t, ensemble_table(), o, "ensemble.", methods);
}

// [scene]: file, overrides, and the scene inline as [scene.<table>] tables. Inline keys and
// overrides become settings that carry their file:line, so the scene parser's messages name them;
// the inline tables come first, then the overrides.
void read_scene(const TomlSource& c, const toml::table& t, CampaignOptions& o) {
  std::vector<io::SceneSetting> inline_settings;
  OtherKeys tables;
  for (std::string_view name : sim::find_scene_tables()) tables.names.push_back(fmt::format("[scene.{}]", name));
  const std::vector<std::string_view> scene_tables = sim::find_scene_tables();
  tables.take = [&](std::string_view k, const toml::node& v) {
    if (std::find(scene_tables.begin(), scene_tables.end(), k) == scene_tables.end()) return false;
    const toml::table* st = v.as_table();
    if (!st) c.fail(&v, fmt::format("scene.{}: expected a table ([scene.{}])", k, k));
    OptionSpec any{"", OptionKind::settings};
    for (io::SceneSetting& s : read_option_value(c, v, fmt::format("scene.{}", k), any).settings)
      inline_settings.push_back({std::string(k) + "." + s.assignment, s.where});
    return true;
  };
  read_options(c, t, scene_table(), o, "scene.", tables);
  o.scene_settings.insert(o.scene_settings.begin(), inline_settings.begin(), inline_settings.end());
}

void read_dispersions(const TomlSource& c, const toml::node& v, CampaignOptions& o) {
  const toml::array* a = v.as_array();
  if (!a || !a->is_array_of_tables()) c.fail(&v, "'dispersion' must be an array of tables: [[dispersion]]");
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::table& t = *a->get(i)->as_table();
    DispersionOptions d;
    d.line = static_cast<int>(t.source().begin.line);
    read_options(c, t, dispersion_table(), d, fmt::format("dispersion[{}].", i + 1));
    o.dispersions.push_back(std::move(d));
  }
}

void read_campaign(const TomlSource& c, const toml::table& t, CampaignOptions& o) {
  read_options(c, t, campaign_table(), o, "campaign.");
}
void read_output(const TomlSource& c, const toml::table& t, CampaignOptions& o) {
  read_options(c, t, output_table(), o, "output.");
}
template <void (*Read)(const TomlSource&, const toml::table&, CampaignOptions&)>
void read_table(const TomlSource& c, const toml::node& v, CampaignOptions& o) {
  Read(c, *v.as_table(), o);  // read_root has checked that it is one
}

// The campaign's own root tables, in the file's usual order: each one's reader, and whether --set
// may name its keys (not [scene]: its keys are the scene's; not the array [[dispersion]]).
struct RootTable {
  std::string_view name;
  bool settable;
  bool array;  // [[name]]
  void (*read)(const TomlSource&, const toml::node&, CampaignOptions&);
};
const std::vector<RootTable>& root_tables() {
  static const std::vector<RootTable> t = {{"ensemble", true, false, &read_table<&read_ensemble>},
                                           {"campaign", true, false, &read_table<&read_campaign>},
                                           {"output", true, false, &read_table<&read_output>},
                                           {"scene", false, false, &read_table<&read_scene>},
                                           {"dispersion", false, true, &read_dispersions}};
  return t;
}

// The rules of one dispersion (index i): "" or "dispersion[i + 1]...: reason".
std::string validate_dispersion(const CampaignOptions& o, std::size_t i) {
  const DispersionOptions& d = o.dispersions[i];
  const std::string where = fmt::format("dispersion[{}]", i + 1);
  if (!is_dispersible_key(d.key))
    return fmt::format("{}.key: \"{}\" is not a scene key that can be dispersed (per bay: mast.strut_*, "
                       "mast.diagonal_*; per frame: mast.frame_side_m, mast.frame_mass_kg; per run: the other numeric "
                       "keys)", where, d.key);
  if (d.per == Per::bay && !is_bay_key(d.key)) return fmt::format("{}.per: \"{}\" is not a per-bay key", where, d.key);
  if (d.per == Per::frame && !is_frame_key(d.key))
    return fmt::format("{}.per: \"{}\" is not a per-frame key", where, d.key);
  // The distribution's parameters: the sampling library's one set of checks.
  const std::string dist = fmt::format("{}: {} distribution: ", where, to_string(d.distribution));
  if (const std::string e = make_distribution(d).validate(); !e.empty()) return dist + e;
  if (d.key == "mast.n_bays") {
    if (d.distribution != DistributionKind::discrete || d.apply != Apply::absolute || d.per != Per::run)
      return where + ": mast.n_bays is an integer: disperse it with distribution = \"discrete\", "
                     "apply = \"absolute\", per = \"run\"";
    for (double v : d.values)
      if (!(v >= 1.0 && v <= 100000.0 && v == std::floor(v)))
        return dist + fmt::format("bay counts must be integers >= 1, got {}", v);
  }
  for (std::size_t j = 0; j < i; ++j)  // two dispersions of one key would silently overwrite each other
    if (o.dispersions[j].key == d.key)
      return fmt::format("{}.key: \"{}\" is already dispersed at {}", where, d.key,
                         o.dispersions[j].line > 0 ? fmt::format("line {}", o.dispersions[j].line)
                                                   : fmt::format("dispersion[{}]", j + 1));
  return {};
}

}  // namespace

std::string validate_sampling(const CampaignOptions& o) {
  const std::int64_t n = o.ensemble.n_runs;
  if (o.ensemble.sampling != SamplingMethod::saltelli) {
    const sampling::SamplePlan plan(o.ensemble.sampling, n, std::max(1, calc_layout(o).total), o.ensemble.master_seed);
    const std::string e = plan.validate();  // "n_runs: ..." or about the dimensions ("d: ...")
    if (e.empty()) return {};
    return e.rfind("n_runs:", 0) == 0 ? "ensemble." + e : "ensemble.sampling: " + e;
  }
  if (o.dispersions.empty()) return "ensemble.sampling: saltelli needs at least one [[dispersion]]";
  const std::int64_t b = saltelli_block_runs(o);
  if (n % b != 0 || n < 2 * b)
    return fmt::format("ensemble.n_runs: saltelli sampling runs blocks of {} runs (A, B and one per dispersion); "
                       "n_runs must be a multiple of {} and at least {}, got {} (e.g. {})",
                       b, b, 2 * b, n, std::max<std::int64_t>(2, n / b) * b);
  return {};
}

std::string CampaignOptions::validate() const {
  if (std::string e = check_option_ranges(ensemble_table(), *this, "ensemble."); !e.empty()) return e;
  if (std::string e = check_run_key_range("max_wall_time_s", "ensemble.max_run_wall_time_s",
                                          ensemble.max_run_wall_time_s);
      !e.empty())
    return e;
  if (std::string e = check_option_ranges(output_table(), *this, "output."); !e.empty()) return e;
  if (std::string e = check_run_key_range("output_step_s", "output.history_step_s", output.history_step_s); !e.empty())
    return e;
  for (std::size_t i = 0; i < output.history_runs.size(); ++i) {
    const std::int64_t r = output.history_runs[i];
    if (r < 0 || r >= ensemble.n_runs)
      return fmt::format("output.history_runs: run {} does not exist (n_runs = {})", r, ensemble.n_runs);
    if (std::find(output.history_runs.begin(), output.history_runs.begin() + static_cast<std::ptrdiff_t>(i), r) !=
        output.history_runs.begin() + static_cast<std::ptrdiff_t>(i))
      return fmt::format("output.history_runs: run {} is listed twice", r);
  }
  for (std::size_t i = 0; i < dispersions.size(); ++i)
    if (std::string e = validate_dispersion(*this, i); !e.empty()) return e;
  if (!ensemble.method) return "ensemble.method: none chosen";
  // A sweep's values, each checked with the dispersions at it, before the dispersions at the
  // campaign's own values.
  if (std::string e = validate_design_axis(*this); !e.empty()) return e;
  // Implausible dispersions (most runs would be invalid input), once every dispersion is well formed.
  for (std::size_t i = 0; i < dispersions.size(); ++i)
    if (std::string e = check_dispersion_draws(*this, i); !e.empty())
      return fmt::format("dispersion[{}]: {}", i + 1, e);
  const MethodOptions& method = ensemble.method.options();
  if (std::string e = method.validate(*this); !e.empty()) return e;
  const FailureOptions* f = method.failure_event();
  return f != nullptr ? validate_failure_event(*f, *this) : std::string();
}

// Which keys may be dispersed, and how: the scene key table (sim/scene_keys.hpp).
bool is_bay_key(const std::string& key) {
  const sim::SceneKey* k = sim::find_scene_key(key);
  return k && k->scope == sim::KeyScope::bay;
}
bool is_frame_key(const std::string& key) {
  const sim::SceneKey* k = sim::find_scene_key(key);
  return k && k->scope == sim::KeyScope::frame;
}
bool is_dispersible_key(const std::string& key) {
  const sim::SceneKey* k = sim::find_scene_key(key);
  return k && k->is_dispersible();
}

namespace {

// The node that the field of a validate() message ("ensemble.n_runs: ...", "dispersion[2].per: ...")
// was read from: the value, its table, or null (the file as a whole).
const toml::node* node_of_field(const toml::table& root, const std::string& message) {
  const std::string field = message.substr(0, message.find(':'));
  if (field.rfind("dispersion[", 0) == 0) {
    const std::size_t i = std::stoul(field.substr(11)) - 1;
    const toml::array* a = root["dispersion"].as_array();
    return a && i < a->size() ? a->get(i) : nullptr;
  }
  // The value at the field's path, else the nearest table above it that exists.
  for (std::string path = field; !path.empty();) {
    if (const toml::node* n = root.at_path(path).node()) return n;
    const auto dot = path.rfind('.');
    path = dot == std::string::npos ? std::string() : path.substr(0, dot);
  }
  return nullptr;
}

// The tables --set may name: the campaign's own (not [scene]: its keys are the scene's) and the
// tables the method catalog's rows read ([failure], [sweep]).
std::vector<std::string> settable_tables(const TomlSource& c) {
  std::vector<std::string> t;
  for (const RootTable& r : root_tables())
    if (r.settable) t.emplace_back(r.name);
  for (const std::string& m : detail::method_root_tables(c)) t.push_back(m);
  return t;
}

// A --set of a campaign key into the tree (so that it is checked as a file's key would be), its node
// then naming the --set in messages.
void put_set(const std::string& arg, const std::string& key, const std::string& value, toml::table& root,
             TomlSource& c) {
  const auto dot = key.find('.');
  const std::vector<std::string> tables = settable_tables(c);
  const std::string tname = dot == std::string::npos ? key : key.substr(0, dot);
  if (dot == std::string::npos || std::find(tables.begin(), tables.end(), tname) == tables.end()) {
    std::string list;
    for (const std::string& t : tables) list += t + ".*, ";
    throw InputError(fmt::format("error: --set {}: only {}and base-scene keys (mast.n_bays=12 or scene.mast.n_bays=12) "
                                 "can be set", arg, list));
  }
  toml::table v = parse_override_value(value);
  std::string kname = key.substr(dot + 1);
  toml::table* t = &root;
  for (std::string tn = tname;;) {  // ensemble.subset.p0: the tables on the way, created if missing
    if (!t->contains(tn)) t->insert(tn, toml::table{});
    t = (*t)[tn].as_table();
    if (!t) throw InputError(fmt::format("error: --set {}: '{}' is not a table in {}", arg, tn, c.file));
    const auto d = kname.find('.');
    if (d == std::string::npos) break;
    tn = kname.substr(0, d);
    kname = kname.substr(d + 1);
  }
  t->insert_or_assign(kname, *v.get("v"));
  const toml::node* set_node = t->get(kname);
  c.set_by[set_node] = arg;
  if (const toml::array* a = set_node->as_array())
    for (const auto& e : *a) c.set_by[&e] = arg;
}

// --set overrides: campaign keys go into the TOML tree, scene keys ("scene.table.key=v", or a scene
// table's key as truss-sim takes it, "mast.n_bays=12") are returned for the scene parser.
std::vector<io::SceneSetting> apply_sets(const std::vector<std::string>& overrides, toml::table& root,
                                         TomlSource& c) {
  std::vector<io::SceneSetting> scene_sets;
  const std::vector<std::string_view> scene_tables = sim::find_scene_tables();
  for (const std::string& arg : overrides) {
    const auto eq = arg.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError(fmt::format("error: --set {}: expected table.key=value", arg));
    const std::string key = arg.substr(0, eq), value = arg.substr(eq + 1);
    const auto dot = key.find('.');
    if (key.rfind("scene.", 0) == 0) scene_sets.push_back({key.substr(6) + "=" + value, {}});
    else if (dot != std::string::npos &&
             std::find(scene_tables.begin(), scene_tables.end(), key.substr(0, dot)) != scene_tables.end())
      scene_sets.push_back({arg, {}});
    else put_set(arg, key, value, root, c);
  }
  return scene_sets;
}

// The root's tables: the campaign's own, read here; the method catalog's, read by its rows.
void read_root(const TomlSource& c, const toml::table& root, CampaignOptions& o) {
  for (const auto& [k, v] : root) {
    const std::string_view name = k.str();  // clang: a lambda cannot capture a structured binding
    const auto own = std::find_if(root_tables().begin(), root_tables().end(),
                                  [&](const RootTable& r) { return name == r.name; });
    if (own != root_tables().end()) {
      if (!own->array && !v.as_table()) c.fail(&v, fmt::format("'{}' must be a table", k.str()));
      own->read(c, v, o);
    } else if (detail::is_method_table(c, k.str())) {  // read by its method's row
      if (!v.as_table()) c.fail(&v, fmt::format("'{}' must be a table", k.str()));
    } else {
      std::vector<std::string> known;
      for (const RootTable& r : root_tables())
        if (!r.array) known.emplace_back(r.name);
      for (const std::string& t : detail::method_root_tables(c)) known.push_back(t);
      for (const RootTable& r : root_tables())
        if (r.array) known.push_back(fmt::format("[[{}]]", r.name));
      const std::vector<std::string_view> names(known.begin(), known.end());
      const auto best = io::suggest_value(k.str(), names);
      std::string list;
      for (const std::string& t : known) list += (list.empty() ? "" : ", ") + t;
      c.fail(&v, fmt::format("unknown table '{}'{} (known: {})", k.str(),
                             best ? fmt::format("; did you mean {}?", *best) : std::string(), list));
    }
  }
}

// The base scene: the file relative to the campaign file, then inline tables, overrides, --set scene.*.
void read_base_scene(const TomlSource& c, const toml::table& root, const std::string& base_dir,
                     const std::vector<io::SceneSetting>& scene_sets, CampaignOptions& o) {
  std::vector<io::SceneSetting> sets = o.scene_settings;
  sets.insert(sets.end(), scene_sets.begin(), scene_sets.end());
  if (!o.scene_file.empty()) {
    std::filesystem::path p(o.scene_file);
    if (p.is_relative()) p = std::filesystem::path(base_dir) / p;
    std::string text;
    try {
      text = io::read_input_file(p.string(), "scene file");
    } catch (const InputError& e) {  // blame the campaign line that names the file
      c.fail(root["scene"]["file"].node(),
             fmt::format("scene.file = \"{}\": {}", o.scene_file, std::string(e.what()).substr(7)));
    }
    o.base = io::parse_scene_text_with(text, p.string(), sets, &o.warnings);
  } else {
    o.base = io::parse_scene_text_with("", c.file + " [scene]", sets, &o.warnings);
  }
  o.scene_settings = sets;  // with the --set ones, in order (campaign.hpp)
  // Campaign runs never record histories (only [output] history_runs do): work nobody reads.
  o.base.run.output_step_s = 0.0;
}

CampaignOptions parse_campaign_root(toml::table root, TomlSource& c, const std::string& base_dir,
                                    const std::vector<std::string>& overrides) {
  const std::vector<io::SceneSetting> scene_sets = apply_sets(overrides, root, c);
  CampaignOptions o;
  read_root(c, root, o);
  detail::parse_method(c, root, o);
  read_base_scene(c, root, base_dir, scene_sets, o);
  // Every rule, once: a broken one is reported at the line (or --set) of the field it names.
  if (const std::string e = o.validate(); !e.empty()) c.fail(node_of_field(root, e), e);
  return o;
}

}  // namespace

CampaignOptions parse_campaign_text(std::string_view text, const std::string& source_name, const std::string& base_dir,
                                    const MethodCatalog& methods, const std::vector<std::string>& overrides) {
  TomlSource c{source_name, {}, &methods};
  toml::table root;
  try {
    root = toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    const auto& b = e.source().begin;
    throw InputError(fmt::format("error: {}:{}:{}: {}", source_name, b.line, b.column, e.description()));
  }
  return parse_campaign_root(std::move(root), c, base_dir, overrides);
}

CampaignOptions parse_campaign_file(const std::string& path, const MethodCatalog& methods,
                                    const std::vector<std::string>& overrides) {
  TomlSource c{path, {}, &methods};
  toml::table root;
  const std::string text = io::read_input_file(path, "campaign file");  // bounded in size
  try {
    root = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    const auto& b = e.source().begin;
    throw InputError(fmt::format("error: {}:{}:{}: {}", path, b.line, b.column, e.description()));
  }
  return parse_campaign_root(std::move(root), c, std::filesystem::path(path).parent_path().string(), overrides);
}

}  // namespace truss::campaign
