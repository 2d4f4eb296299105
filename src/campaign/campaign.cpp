#include "campaign/campaign.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "campaign/dispersion.hpp"
#include "campaign/toml_read.hpp"
#include "io/scene_toml.hpp"
#include "sim/scene_keys.hpp"

namespace truss::campaign {

using io::InputError;

namespace {

const std::vector<std::string> kDistributions(std::begin(sampling::kDistributionNames),
                                              std::end(sampling::kDistributionNames));
const std::vector<std::string> kSampling(std::begin(sampling::kSamplingNames), std::end(sampling::kSamplingNames));

// Index of a name already checked against `names`.
int index_of(const std::vector<std::string>& names, const std::string& s) {
  return static_cast<int>(std::find(names.begin(), names.end(), s) - names.begin());
}

using detail::Ctx;
using detail::get_number;
using detail::get_string;
using detail::did_you_mean;
using detail::join;
using detail::unknown_key_text;

// A campaign key that becomes a scene's [run] key in every run (ensemble.max_run_wall_time_s ->
// run.max_wall_time_s, output.history_step_s -> run.output_step_s) takes that key's hard range from
// the scene key table, so that no value the campaign accepts makes every run invalid input.
std::string check_run_key_range(std::string_view run_key, const std::string& key, double v) {
  const sim::SceneKey* k = sim::find_scene_key("run", run_key);
  if (k == nullptr || k->hard.contains(v)) return {};
  return fmt::format("{}: must lie in {} {} (the range of run.{}), got {}", key, k->hard.text(), k->unit, run_key, v);
}

std::vector<double> get_numbers(const Ctx& c, const toml::node& n, const std::string& key) {
  const toml::array* a = n.as_array();
  if (!a) c.fail(&n, fmt::format("{}: expected an array of numbers", key));
  std::vector<double> v;
  for (const auto& e : *a) v.push_back(get_number(c, e, key));
  return v;
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

void parse_campaign_table(const Ctx& c, const toml::table& t, CampaignOptions& o) {
  for (const auto& [k, v] : t) {
    const std::string key = "campaign." + std::string(k.str());
    if (k == "name") o.name = get_string(c, v, key);
    else if (k == "description") o.description = get_string(c, v, key);
    else c.fail(&v, unknown_key_text(key, "campaign.name, campaign.description"));
  }
}

void parse_ensemble_table(const Ctx& c, const toml::table& t, CampaignOptions& o) {
  for (const auto& [k, v] : t) {
    const std::string key = "ensemble." + std::string(k.str());
    if (k == "n_runs") {
      auto i = v.value_exact<std::int64_t>();
      if (!i) c.fail(&v, key + ": expected an integer");
      o.ensemble.n_runs = *i;
    } else if (k == "master_seed") {
      auto i = v.value_exact<std::int64_t>();
      if (!i) c.fail(&v, key + ": expected an integer");
      if (*i < 0) c.fail(&v, fmt::format("{}: must not be negative, got {}", key, *i));
      o.ensemble.master_seed = static_cast<std::uint64_t>(*i);
    } else if (k == "sampling") {
      o.ensemble.sampling = static_cast<SamplingMethod>(index_of(kSampling, get_string(c, v, key, kSampling)));
    } else if (k == "max_run_wall_time_s") {
      o.ensemble.max_run_wall_time_s = get_number(c, v, key);
    } else if (k == "method") {
      get_string(c, v, key, detail::method_names(c));  // the row reads its tables (detail::parse_method)
    } else if (c.methods->find(k.str()) != nullptr) {
      detail::check_method_key(c, key, v);
    } else {
      std::string known = "ensemble.n_runs, ensemble.master_seed, ensemble.sampling, "
                          "ensemble.max_run_wall_time_s, ensemble.method";
      for (const std::string& m : detail::method_names(c))
        if (m != kDefaultMethod) known += ", [ensemble." + m + "]";  // the design has no keys of its own
      c.fail(&v, unknown_key_text(key, known));
    }
  }
}

std::string toml_value_text(const toml::node& v) {
  std::ostringstream ss;
  v.visit([&](const auto& x) { ss << toml::toml_formatter{x}; });
  return ss.str();
}

std::string where_of(const Ctx& c, const toml::node& n) {
  return n.source().begin.line > 0 ? fmt::format("{}:{}", c.file, n.source().begin.line) : c.file;
}

// [scene]: file, overrides, and the scene inline as [scene.<table>] tables. Inline keys and
// overrides become settings that carry their file:line, so the scene parser's messages name them.
void parse_scene_table(const Ctx& c, const toml::table& t, CampaignOptions& o) {
  const auto tables = io::known_scene_keys();
  auto is_scene_table = [&](std::string_view name) {
    return std::any_of(tables.begin(), tables.end(),
                       [&](const std::string& k) { return k.substr(0, k.find('.')) == name; });
  };
  std::vector<io::SceneSetting> inline_settings, override_settings;
  for (const auto& [k, v] : t) {
    const std::string key = "scene." + std::string(k.str());
    if (k == "file") {
      o.scene_file = get_string(c, v, key);
    } else if (k == "overrides") {
      const toml::table* ov = v.as_table();
      if (!ov) c.fail(&v, key + ": expected a table of \"table.key\" = value");
      for (const auto& [ok, ovv] : *ov)
        override_settings.push_back({std::string(ok.str()) + "=" + toml_value_text(ovv), where_of(c, ovv)});
    } else if (is_scene_table(k.str())) {
      const toml::table* st = v.as_table();
      if (!st) c.fail(&v, fmt::format("{}: expected a table ([{}])", key, key));
      for (const auto& [sk, sv] : *st)
        inline_settings.push_back(
            {std::string(k.str()) + "." + std::string(sk.str()) + "=" + toml_value_text(sv), where_of(c, sv)});
    } else {
      c.fail(&v, unknown_key_text(key, "scene.file, scene.overrides, and scene tables [scene.mast], "
                             "[scene.rail], [scene.drive], [scene.stack], [scene.panels], [scene.run], "
                             "[scene.motorisation]"));
    }
  }
  o.scene_settings = inline_settings;
  o.scene_settings.insert(o.scene_settings.end(), override_settings.begin(), override_settings.end());
}

void parse_output_table(const Ctx& c, const toml::table& t, CampaignOptions& o) {
  for (const auto& [k, v] : t) {
    const std::string key = "output." + std::string(k.str());
    if (k == "history_runs") {
      const toml::array* a = v.as_array();
      if (!a) c.fail(&v, key + ": expected an array of run indices");
      o.output.history_runs.clear();
      for (const auto& e : *a) {
        auto i = e.value_exact<std::int64_t>();
        if (!i) c.fail(&e, key + ": run indices are integers");
        o.output.history_runs.push_back(*i);
      }
    } else if (k == "history_step_s") {
      o.output.history_step_s = get_number(c, v, key);
    } else {
      c.fail(&v, unknown_key_text(key, "output.history_runs, output.history_step_s"));
    }
  }
}

DispersionOptions parse_dispersion(const Ctx& c, const toml::table& t, std::size_t index) {
  DispersionOptions d;
  d.line = static_cast<int>(t.source().begin.line);
  const std::string where = fmt::format("dispersion[{}]", index + 1);
  bool has_key = false, has_dist = false;
  for (const auto& [k, v] : t) {
    const std::string key = where + "." + std::string(k.str());
    if (k == "key") {
      d.key = get_string(c, v, key);
      has_key = true;
    } else if (k == "per") {
      const std::string p = get_string(c, v, key, {"run", "bay", "frame"});
      d.per = p == "run" ? Per::run : p == "bay" ? Per::bay : Per::frame;
    } else if (k == "apply") {
      const std::string a = get_string(c, v, key, {"absolute", "relative", "offset"});
      d.apply = a == "absolute" ? Apply::absolute : a == "relative" ? Apply::relative : Apply::offset;
    } else if (k == "distribution") {
      d.distribution = static_cast<DistributionKind>(index_of(kDistributions, get_string(c, v, key, kDistributions)));
      has_dist = true;
    } else if (k == "mean") d.mean = get_number(c, v, key);
    else if (k == "std") d.std = get_number(c, v, key);
    else if (k == "lower") d.lower = get_number(c, v, key);
    else if (k == "upper") d.upper = get_number(c, v, key);
    else if (k == "mu") d.mu = get_number(c, v, key);
    else if (k == "sigma") d.sigma = get_number(c, v, key);
    else if (k == "values") d.values = get_numbers(c, v, key);
    else if (k == "weights") d.weights = get_numbers(c, v, key);
    else c.fail(&v, unknown_key_text(key, "key, per, apply, distribution, mean, std, lower, upper, "
                                "mu, sigma, values, weights"));
  }
  if (!has_key) c.fail(&t, where + ": missing 'key' (the scene key to disperse, e.g. \"mast.strut_mass_kg\")");
  if (!has_dist) c.fail(&t, where + ": missing 'distribution' (one of " + join(kDistributions) + ")");
  return d;
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
  if (ensemble.n_runs < 1)
    return fmt::format("ensemble.n_runs: must be a positive number of runs, got {}", ensemble.n_runs);
  if (std::string e = check_run_key_range("max_wall_time_s", "ensemble.max_run_wall_time_s",
                                          ensemble.max_run_wall_time_s);
      !e.empty())
    return e;
  if (!(output.history_step_s > 0.0))
    return fmt::format("output.history_step_s: must be positive, got {}", output.history_step_s);
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
  // A sweep's values, each checked with the dispersions at it, before the dispersions at the
  // campaign's own values.
  if (std::string e = validate_sweep(*this); !e.empty()) return e;
  // Implausible dispersions (most runs would be invalid input), once every dispersion is well formed.
  for (std::size_t i = 0; i < dispersions.size(); ++i)
    if (std::string e = check_dispersion_draws(*this, i); !e.empty())
      return fmt::format("dispersion[{}]: {}", i + 1, e);
  if (!ensemble.method) return "ensemble.method: none chosen";
  return ensemble.method.options().validate(*this);
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

CampaignOptions parse_campaign_root(toml::table root, Ctx& c, const std::string& base_dir,
                                    const std::vector<std::string>& overrides) {
  const std::string& path = c.file;
  // --set overrides: campaign keys go into the TOML tree (so they are checked like file keys),
  // scene keys ("scene.table.key=v") go to the scene parser.
  std::vector<io::SceneSetting> scene_sets;
  for (const std::string& arg : overrides) {
    const auto eq = arg.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError(fmt::format("error: --set {}: expected table.key=value", arg));
    const std::string key = arg.substr(0, eq), value = arg.substr(eq + 1);
    if (key.rfind("scene.", 0) == 0) { scene_sets.push_back({key.substr(6) + "=" + value, {}}); continue; }
    const auto dot = key.find('.');
    const std::string tname = dot == std::string::npos ? key : key.substr(0, dot);
    // A scene table (mast, drive, ...) names a base-scene key, as truss-sim's --set does.
    const auto scene_keys = io::known_scene_keys();
    if (dot != std::string::npos && std::any_of(scene_keys.begin(), scene_keys.end(), [&](const std::string& k) {
          return k.compare(0, k.find('.'), tname) == 0 && k.find('.') == tname.size();
        })) {
      scene_sets.push_back({arg, {}});
      continue;
    }
    if (dot == std::string::npos ||
        (tname != "ensemble" && tname != "campaign" && tname != "output" && tname != "sweep" &&
         !detail::is_method_table(c, tname))) {
      std::string tables;
      for (const std::string& t : detail::method_root_tables(c)) tables += ", " + t + ".*";
      throw InputError(fmt::format("error: --set {}: only ensemble.*, campaign.*, output.*, sweep.*{} and base-scene "
                                   "keys (mast.n_bays=12 or scene.mast.n_bays=12) can be set", arg, tables));
    }
    toml::table v = parse_override_value(value);
    std::string kname = key.substr(dot + 1);
    toml::table* t = &root;
    for (std::string tn = tname;;) {  // ensemble.subset.p0: the tables on the way, created if missing
      if (!t->contains(tn)) t->insert(tn, toml::table{});
      t = (*t)[tn].as_table();
      if (!t) throw InputError(fmt::format("error: --set {}: '{}' is not a table in {}", arg, tn, path));
      const auto d = kname.find('.');
      if (d == std::string::npos) break;
      tn = kname.substr(0, d);
      kname = kname.substr(d + 1);
    }
    t->insert_or_assign(kname, *v.get("v"));
    // Messages about this value (or an element of it) name the --set, not the campaign file.
    const toml::node* set_node = t->get(kname);
    c.set_by[set_node] = arg;
    if (const toml::array* a = set_node->as_array())
      for (const auto& e : *a) c.set_by[&e] = arg;
  }

  CampaignOptions o;
  for (const auto& [k, v] : root) {
    if (k == "sweep") {
      const toml::table* t = v.as_table();
      if (!t) c.fail(&v, "'sweep' must be a table");
      detail::parse_sweep_table(c, *t, o);
    } else if (detail::is_method_table(c, k.str())) {
      if (!v.as_table()) c.fail(&v, fmt::format("'{}' must be a table", k.str()));  // read by its method's row
    } else if (k == "campaign" || k == "ensemble" || k == "scene" || k == "output") {
      const toml::table* t = v.as_table();
      if (!t) c.fail(&v, fmt::format("'{}' must be a table", k.str()));
      if (k == "campaign") parse_campaign_table(c, *t, o);
      else if (k == "ensemble") parse_ensemble_table(c, *t, o);
      else if (k == "output") parse_output_table(c, *t, o);
      else parse_scene_table(c, *t, o);
    } else if (k == "dispersion") {
      const toml::array* a = v.as_array();
      if (!a || !a->is_array_of_tables()) c.fail(&v, "'dispersion' must be an array of tables: [[dispersion]]");
      for (std::size_t i = 0; i < a->size(); ++i)
        o.dispersions.push_back(parse_dispersion(c, *a->get(i)->as_table(), i));
    } else {
      std::string known = "campaign, ensemble, output, scene, sweep";
      for (const std::string& t : detail::method_root_tables(c)) known += ", " + t;
      known += ", [[dispersion]]";
      c.fail(&v, fmt::format("unknown table '{}'{} (known: {})", k.str(), did_you_mean(std::string(k.str()), known),
                             known));
    }
  }
  detail::parse_method(c, root, o);
  // Base scene: file relative to the campaign file, then inline tables, overrides, --set scene.*.
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
    o.base = io::parse_scene_text_with("", path + " [scene]", sets, &o.warnings);
  }
  // Campaign runs never record histories (only [output] history_runs do): work nobody reads.
  o.base.run.output_step_s = 0.0;
  // Every rule, once: a broken one is reported at the line (or --set) of the field it names.
  if (const std::string e = o.validate(); !e.empty()) c.fail(node_of_field(root, e), e);
  return o;
}

}  // namespace

CampaignOptions parse_campaign_text(std::string_view text, const std::string& source_name, const std::string& base_dir,
                                    const MethodCatalog& methods, const std::vector<std::string>& overrides) {
  Ctx c{source_name, {}, &methods};
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
  Ctx c{path, {}, &methods};
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
