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
#include "io/scene_toml.hpp"
#include "campaign/sampling.hpp"
#include "sim/scene_keys.hpp"

namespace truss::campaign {

using io::InputError;

namespace {

const std::vector<std::string> kDistributions(std::begin(kDistributionNames), std::end(kDistributionNames));
const std::vector<std::string> kSampling(std::begin(kSamplingNames), std::end(kSamplingNames));

// Index of a name already checked against `names`.
int index_of(const std::vector<std::string>& names, const std::string& s) {
  return static_cast<int>(std::find(names.begin(), names.end(), s) - names.begin());
}

struct Ctx {
  std::string file;
  std::map<const toml::node*, std::string> set_by;  // values put in the tree by --set: the argument
  [[noreturn]] void fail(const toml::node* at, const std::string& what) const {
    if (const auto it = set_by.find(at); it != set_by.end()) throw InputError(fmt::format("error: --set {}: {}", it->second, what));
    if (at && at->source().begin.line > 0) throw InputError(fmt::format("error: {}:{}: {}", file, at->source().begin.line, what));
    throw InputError(fmt::format("error: {}: {}", file, what));
  }
};

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "\"" : ", \"") + x + "\"";
  return s;
}

double get_number(const Ctx& c, const toml::node& n, const std::string& key) {
  if (auto i = n.value_exact<std::int64_t>()) return static_cast<double>(*i);
  if (auto d = n.value_exact<double>()) return *d;
  c.fail(&n, fmt::format("{}: expected a number", key));
}

std::string get_string(const Ctx& c, const toml::node& n, const std::string& key, const std::vector<std::string>& allowed = {}) {
  auto s = n.value_exact<std::string>();
  if (!s) c.fail(&n, fmt::format("{}: expected a string", key));
  if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), *s) == allowed.end())
    c.fail(&n, fmt::format("{}: \"{}\" is not one of {}", key, *s, join(allowed)));
  return *s;
}

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
    else c.fail(&v, fmt::format("unknown key '{}' (known: campaign.name, campaign.description)", key));
  }
}

void parse_ensemble_table(const Ctx& c, const toml::table& t, CampaignOptions& o) {
  for (const auto& [k, v] : t) {
    const std::string key = "ensemble." + std::string(k.str());
    if (k == "n_runs") {
      auto i = v.value_exact<std::int64_t>();
      if (!i) c.fail(&v, key + ": expected an integer");
      if (*i < 1) c.fail(&v, fmt::format("{}: must be a positive number of runs, got {}", key, *i));
      o.ensemble.n_runs = *i;
    } else if (k == "master_seed") {
      auto i = v.value_exact<std::int64_t>();
      if (!i) c.fail(&v, key + ": expected an integer");
      if (*i < 0) c.fail(&v, fmt::format("{}: must not be negative, got {}", key, *i));
      o.ensemble.master_seed = static_cast<std::uint64_t>(*i);
    } else if (k == "sampling") {
      o.ensemble.sampling = static_cast<SamplingMethod>(index_of(kSampling, get_string(c, v, key, kSampling)));
    } else if (k == "max_run_wall_time_s") {
      const double w = get_number(c, v, key);
      if (const std::string e = check_run_key_range("max_wall_time_s", key, w); !e.empty()) c.fail(&v, e);
      o.ensemble.max_run_wall_time_s = w;
    } else {
      c.fail(&v, fmt::format("unknown key '{}' (known: ensemble.n_runs, ensemble.master_seed, ensemble.sampling, "
                             "ensemble.max_run_wall_time_s)", key));
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
    return std::any_of(tables.begin(), tables.end(), [&](const std::string& k) { return k.substr(0, k.find('.')) == name; });
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
        inline_settings.push_back({std::string(k.str()) + "." + std::string(sk.str()) + "=" + toml_value_text(sv), where_of(c, sv)});
    } else {
      c.fail(&v, fmt::format("unknown key '{}' (known: scene.file, scene.overrides, and scene tables [scene.mast], "
                             "[scene.rail], [scene.drive], [scene.stack], [scene.panels], [scene.run])", key));
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
        if (!i || *i < 0) c.fail(&e, key + ": run indices are integers >= 0");
        if (std::find(o.output.history_runs.begin(), o.output.history_runs.end(), *i) != o.output.history_runs.end())
          c.fail(&e, fmt::format("{}: run {} is listed twice", key, *i));
        o.output.history_runs.push_back(*i);
      }
    } else if (k == "history_step_s") {
      const double h = get_number(c, v, key);
      if (!(h > 0.0)) c.fail(&v, fmt::format("{}: must be positive, got {}", key, h));
      if (const std::string e = check_run_key_range("output_step_s", key, h); !e.empty()) c.fail(&v, e);
      o.output.history_step_s = h;
    } else {
      c.fail(&v, fmt::format("unknown key '{}' (known: output.history_runs, output.history_step_s)", key));
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
    if (k == "key") { d.key = get_string(c, v, key); has_key = true; }
    else if (k == "per") {
      const std::string p = get_string(c, v, key, {"run", "bay", "frame"});
      d.per = p == "run" ? Per::run : p == "bay" ? Per::bay : Per::frame;
    } else if (k == "apply") {
      const std::string a = get_string(c, v, key, {"absolute", "relative", "offset"});
      d.apply = a == "absolute" ? Apply::absolute : a == "relative" ? Apply::relative : Apply::offset;
    } else if (k == "distribution") { d.distribution = static_cast<DistributionKind>(index_of(kDistributions, get_string(c, v, key, kDistributions))); has_dist = true; }
    else if (k == "mean") d.mean = get_number(c, v, key);
    else if (k == "std") d.std = get_number(c, v, key);
    else if (k == "lower") d.lower = get_number(c, v, key);
    else if (k == "upper") d.upper = get_number(c, v, key);
    else if (k == "mu") d.mu = get_number(c, v, key);
    else if (k == "sigma") d.sigma = get_number(c, v, key);
    else if (k == "values") d.values = get_numbers(c, v, key);
    else if (k == "weights") d.weights = get_numbers(c, v, key);
    else c.fail(&v, fmt::format("unknown key '{}' (known: key, per, apply, distribution, mean, std, lower, upper, mu, "
                                "sigma, values, weights)", key));
  }
  if (!has_key) c.fail(&t, where + ": missing 'key' (the scene key to disperse, e.g. \"mast.strut_mass_kg\")");
  if (!has_dist) c.fail(&t, where + ": missing 'distribution' (one of " + join(kDistributions) + ")");
  // The key and the distribution's parameters.
  const std::string& K = d.key;
  if (!is_dispersible_key(K))
    c.fail(&t, fmt::format("{}.key: \"{}\" is not a scene key that can be dispersed (per bay: {}; per frame: {}; "
                           "per run: the other numeric keys)", where, K, "mast.strut_*, mast.diagonal_*",
                           "mast.frame_side_m, mast.frame_mass_kg"));
  if (d.per == Per::bay && !is_bay_key(K)) c.fail(&t, fmt::format("{}.per: \"{}\" is not a per-bay key", where, K));
  if (d.per == Per::frame && !is_frame_key(K)) c.fail(&t, fmt::format("{}.per: \"{}\" is not a per-frame key", where, K));
  auto bad = [&](const std::string& what) { c.fail(&t, fmt::format("{}: {} distribution: {}", where, to_string(d.distribution), what)); };
  // The distribution's parameters: the sampling library's one set of checks, with this entry's file and line.
  if (const std::string e = make_distribution(d).validate(); !e.empty()) bad(e);
  if (K == "mast.n_bays") {
    if (d.distribution != DistributionKind::discrete || d.apply != Apply::absolute || d.per != Per::run)
      c.fail(&t, where + ": mast.n_bays is an integer: disperse it with distribution = \"discrete\", apply = \"absolute\", per = \"run\"");
    for (double v : d.values)
      if (!(v >= 1.0 && v <= 100000.0 && v == std::floor(v))) bad(fmt::format("bay counts must be integers >= 1, got {}", v));
  }
  return d;
}

}  // namespace

std::string CampaignOptions::validate() const {
  if (ensemble.n_runs < 1) return fmt::format("ensemble.n_runs: must be >= 1, got {}", ensemble.n_runs);
  if (!(ensemble.max_run_wall_time_s > 0.0))
    return fmt::format("ensemble.max_run_wall_time_s: must be positive, got {}", ensemble.max_run_wall_time_s);
  if (!(output.history_step_s > 0.0)) return fmt::format("output.history_step_s: must be positive, got {}", output.history_step_s);
  for (std::int64_t r : output.history_runs)
    if (r < 0 || r >= ensemble.n_runs) return fmt::format("output.history_runs: run {} is not in [0, {})", r, ensemble.n_runs);
  if (std::string e = base.validate(); !e.empty()) return "scene." + e;
  if (ensemble.sampling == SamplingMethod::saltelli &&
      (dispersions.empty() || ensemble.n_runs % saltelli_block_runs(*this) != 0))
    return fmt::format("ensemble.n_runs: saltelli needs dispersions and a multiple of {} runs", saltelli_block_runs(*this));
  for (std::size_t i = 0; i < dispersions.size(); ++i) {
    const DispersionOptions& d = dispersions[i];
    if (!is_dispersible_key(d.key)) return fmt::format("dispersion[{}].key: \"{}\" cannot be dispersed", i + 1, d.key);
    if ((d.per == Per::bay && !is_bay_key(d.key)) || (d.per == Per::frame && !is_frame_key(d.key)))
      return fmt::format("dispersion[{}].per: \"{}\" is not dispersible per {}", i + 1, d.key, d.per == Per::bay ? "bay" : "frame");
    if (std::string e = make_distribution(d).validate(); !e.empty()) return fmt::format("dispersion[{}]: {}", i + 1, e);
  }
  return {};
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

CampaignOptions parse_campaign_root(toml::table root, Ctx& c, const std::string& base_dir,
                                    const std::vector<std::string>& overrides) {
  const std::string& path = c.file;
  // --set overrides: campaign keys go into the TOML tree (so they are checked like file keys),
  // scene keys ("scene.table.key=v") go to the scene parser.
  std::vector<io::SceneSetting> scene_sets;
  for (const std::string& arg : overrides) {
    const auto eq = arg.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError(fmt::format("error: --set {}: expected table.key=value", arg));
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
    if (dot == std::string::npos || (tname != "ensemble" && tname != "campaign" && tname != "output"))
      throw InputError(fmt::format("error: --set {}: only ensemble.*, campaign.*, output.* and base-scene keys "
                                   "(mast.n_bays=12 or scene.mast.n_bays=12) can be set", arg));
    toml::table v = parse_override_value(value);
    const std::string kname = key.substr(dot + 1);
    if (!root.contains(tname)) root.insert(tname, toml::table{});
    toml::table* t = root[tname].as_table();
    if (!t) throw InputError(fmt::format("error: --set {}: '{}' is not a table in {}", arg, tname, path));
    t->insert_or_assign(kname, *v.get("v"));
    // Messages about this value (or an element of it) name the --set, not the campaign file.
    const toml::node* set_node = t->get(kname);
    c.set_by[set_node] = arg;
    if (const toml::array* a = set_node->as_array())
      for (const auto& e : *a) c.set_by[&e] = arg;
  }

  CampaignOptions o;
  for (const auto& [k, v] : root) {
    if (k == "campaign" || k == "ensemble" || k == "scene" || k == "output") {
      const toml::table* t = v.as_table();
      if (!t) c.fail(&v, fmt::format("'{}' must be a table", k.str()));
      if (k == "campaign") parse_campaign_table(c, *t, o);
      else if (k == "ensemble") parse_ensemble_table(c, *t, o);
      else if (k == "output") parse_output_table(c, *t, o);
      else parse_scene_table(c, *t, o);
    } else if (k == "dispersion") {
      const toml::array* a = v.as_array();
      if (!a || !a->is_array_of_tables()) c.fail(&v, "'dispersion' must be an array of tables: [[dispersion]]");
      for (std::size_t i = 0; i < a->size(); ++i) o.dispersions.push_back(parse_dispersion(c, *a->get(i)->as_table(), i));
    } else {
      c.fail(&v, fmt::format("unknown table '{}' (known: campaign, ensemble, output, scene, [[dispersion]])", k.str()));
    }
  }
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
      c.fail(root["scene"]["file"].node(), fmt::format("scene.file = \"{}\": {}", o.scene_file, std::string(e.what()).substr(7)));
    }
    o.base = io::parse_scene_text_with(text, p.string(), sets, &o.warnings);
  } else {
    o.base = io::parse_scene_text_with("", path + " [scene]", sets, &o.warnings);
  }
  // Campaign runs never record histories (only [output] history_runs do): work nobody reads.
  o.base.run.output_step_s = 0.0;
  // Two dispersions of one key would silently overwrite each other.
  for (std::size_t i = 0; i < o.dispersions.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (o.dispersions[i].key == o.dispersions[j].key)
        throw InputError(fmt::format("error: {}:{}: dispersion[{}].key: \"{}\" is already dispersed at line {}", path,
                                     o.dispersions[i].line, i + 1, o.dispersions[i].key, o.dispersions[j].line));
  // Implausible dispersions are refused before any run (most of the runs would be invalid input).
  for (std::size_t i = 0; i < o.dispersions.size(); ++i)
    if (const std::string e = check_dispersion_draws(o, i); !e.empty())
      throw InputError(fmt::format("error: {}:{}: dispersion[{}]: {}", path, o.dispersions[i].line, i + 1, e));
  const toml::node* n_runs_node = root["ensemble"]["n_runs"].node();
  if (o.ensemble.sampling == SamplingMethod::saltelli) {
    if (o.dispersions.empty()) c.fail(root["ensemble"]["sampling"].node(), "ensemble.sampling: saltelli needs at least one [[dispersion]]");
    const std::int64_t b = saltelli_block_runs(o);
    if (o.ensemble.n_runs % b != 0 || o.ensemble.n_runs < 2 * b)
      c.fail(n_runs_node, fmt::format("ensemble.n_runs: saltelli sampling runs blocks of {} runs (A, B and one per dispersion); "
                                      "n_runs must be a multiple of {} and at least {}, got {} (e.g. {})",
                                      b, b, 2 * b, o.ensemble.n_runs, std::max<std::int64_t>(2, o.ensemble.n_runs / b) * b));
  }
  if (o.ensemble.sampling != SamplingMethod::saltelli) {
    const SamplePlan plan(o.ensemble.sampling, o.ensemble.n_runs, std::max(1, calc_layout(o).total), o.ensemble.master_seed);
    if (const std::string e = plan.validate(); !e.empty()) c.fail(n_runs_node, "ensemble: " + e);
  }
  for (std::int64_t r : o.output.history_runs)
    if (r >= o.ensemble.n_runs)
      c.fail(root["output"]["history_runs"].node(),
             fmt::format("output.history_runs: run {} does not exist (n_runs = {})", r, o.ensemble.n_runs));
  return o;
}

}  // namespace

CampaignOptions parse_campaign_text(std::string_view text, const std::string& source_name, const std::string& base_dir,
                                    const std::vector<std::string>& overrides) {
  Ctx c{source_name, {}};
  toml::table root;
  try {
    root = toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    const auto& b = e.source().begin;
    throw InputError(fmt::format("error: {}:{}:{}: {}", source_name, b.line, b.column, e.description()));
  }
  return parse_campaign_root(std::move(root), c, base_dir, overrides);
}

CampaignOptions parse_campaign_file(const std::string& path, const std::vector<std::string>& overrides) {
  Ctx c{path, {}};
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

namespace {

std::string toml_str(const std::string& s) {
  std::ostringstream ss;
  ss << toml::value<std::string>(s);
  return ss.str();
}

// Shortest text that reads back to the same double, always with a '.' or an exponent.
std::string toml_num(double v) {
  std::string t = fmt::format("{}", v);
  if (t.find_first_of(".eEni") == std::string::npos) t += ".0";
  return t;
}

std::string toml_nums(const std::vector<double>& v) {
  std::string t = "[";
  for (std::size_t i = 0; i < v.size(); ++i) t += (i ? ", " : "") + toml_num(v[i]);
  return t + "]";
}

const char* per_name(Per p) { return p == Per::run ? "run" : p == Per::bay ? "bay" : "frame"; }
const char* apply_name(Apply a) { return a == Apply::absolute ? "absolute" : a == Apply::relative ? "relative" : "offset"; }

}  // namespace

std::string resolved_campaign_toml(const CampaignOptions& c) {
  std::string t = "# Resolved campaign: every value used, the base scene inline.\n[campaign]\n";
  t += fmt::format("name = {}\ndescription = {}\n\n[ensemble]\n", toml_str(c.name), toml_str(c.description));
  t += fmt::format("n_runs = {}\nmaster_seed = {}\nsampling = {}\nmax_run_wall_time_s = {}\n\n", c.ensemble.n_runs,
                   c.ensemble.master_seed, toml_str(to_string(c.ensemble.sampling)), toml_num(c.ensemble.max_run_wall_time_s));
  t += "[output]\nhistory_runs = [";
  for (std::size_t i = 0; i < c.output.history_runs.size(); ++i) t += fmt::format("{}{}", i ? ", " : "", c.output.history_runs[i]);
  t += fmt::format("]\nhistory_step_s = {}\n\n", toml_num(c.output.history_step_s));
  // The scene in the single-run format, its tables moved under [scene.].
  std::istringstream scene(io::resolved_scene_toml(c.base));
  for (std::string line; std::getline(scene, line);) {
    if (!line.empty() && line[0] == '[') line = "[scene." + line.substr(1);
    t += line + "\n";
  }
  for (const auto& d : c.dispersions) {
    t += fmt::format("\n[[dispersion]]\nkey = {}\nper = \"{}\"\napply = \"{}\"\ndistribution = {}\n", toml_str(d.key),
                     per_name(d.per), apply_name(d.apply), toml_str(to_string(d.distribution)));
    if (d.distribution == DistributionKind::normal || d.distribution == DistributionKind::truncated_normal)
      t += fmt::format("mean = {}\nstd = {}\n", toml_num(d.mean), toml_num(d.std));
    if (d.distribution == DistributionKind::truncated_normal || d.distribution == DistributionKind::uniform)
      t += fmt::format("lower = {}\nupper = {}\n", toml_num(d.lower), toml_num(d.upper));
    if (d.distribution == DistributionKind::lognormal) t += fmt::format("mu = {}\nsigma = {}\n", toml_num(d.mu), toml_num(d.sigma));
    if (d.distribution == DistributionKind::discrete) {
      t += "values = " + toml_nums(d.values) + "\n";
      if (!d.weights.empty()) t += "weights = " + toml_nums(d.weights) + "\n";
    }
  }
  return t;
}

}  // namespace truss::campaign
