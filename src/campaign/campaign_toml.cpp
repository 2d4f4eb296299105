// The resolved campaign as TOML (campaign.hpp, resolved_campaign_toml): what the journal's header
// and the results file's campaign_toml hold, and what the other ranks parse.
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "campaign/campaign.hpp"
#include "campaign/toml_read.hpp"

namespace truss::campaign {

const char* to_string(Per p) { return p == Per::run ? "run" : p == Per::bay ? "bay" : "frame"; }
const char* to_string(Apply a) {
  return a == Apply::absolute ? "absolute" : a == Apply::relative ? "relative" : "offset";
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


}  // namespace

std::string resolved_campaign_toml(const CampaignOptions& c) {
  std::string t = "# Resolved campaign: every value used, the base scene inline.\n[campaign]\n";
  t += fmt::format("name = {}\ndescription = {}\n\n[ensemble]\n", toml_str(c.name), toml_str(c.description));
  const MethodOptions& method = c.ensemble.method.options();
  if (method.chosen_runs().empty()) t += fmt::format("n_runs = {}\n", c.ensemble.n_runs);
  t += fmt::format("master_seed = {}\nsampling = {}\nmax_run_wall_time_s = {}\nmethod = \"{}\"\n\n",
                   c.ensemble.master_seed, toml_str(to_string(c.ensemble.sampling)),
                   toml_num(c.ensemble.max_run_wall_time_s), c.ensemble.method.written_name());
  t += method.to_toml();
  t += sweep_toml(c.sweep);
  t += "[output]\nhistory_runs = [";
  for (std::size_t i = 0; i < c.output.history_runs.size(); ++i)
    t += fmt::format("{}{}", i ? ", " : "", c.output.history_runs[i]);
  t += fmt::format("]\nhistory_step_s = {}\n\n", toml_num(c.output.history_step_s));
  // The scene in the single-run format, its tables moved under [scene.].
  std::istringstream scene(io::resolved_scene_toml(c.base));
  for (std::string line; std::getline(scene, line);) {
    if (!line.empty() && line[0] == '[') line = "[scene." + line.substr(1);
    t += line + "\n";
  }
  for (const auto& d : c.dispersions) {
    t += fmt::format("\n[[dispersion]]\nkey = {}\nper = \"{}\"\napply = \"{}\"\ndistribution = {}\n", toml_str(d.key),
                     to_string(d.per), to_string(d.apply), toml_str(to_string(d.distribution)));
    if (d.distribution == DistributionKind::normal || d.distribution == DistributionKind::truncated_normal)
      t += fmt::format("mean = {}\nstd = {}\n", toml_num(d.mean), toml_num(d.std));
    if (d.distribution == DistributionKind::truncated_normal || d.distribution == DistributionKind::uniform)
      t += fmt::format("lower = {}\nupper = {}\n", toml_num(d.lower), toml_num(d.upper));
    if (d.distribution == DistributionKind::lognormal)
      t += fmt::format("mu = {}\nsigma = {}\n", toml_num(d.mu), toml_num(d.sigma));
    if (d.distribution == DistributionKind::discrete) {
      t += "values = " + toml_nums(d.values) + "\n";
      if (!d.weights.empty()) t += "weights = " + toml_nums(d.weights) + "\n";
    }
  }
  return t;
}

}  // namespace truss::campaign
