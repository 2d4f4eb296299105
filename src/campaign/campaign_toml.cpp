// The resolved campaign as TOML (campaign.hpp, resolved_campaign_toml): what the journal's header
// and the results file's campaign_toml hold, and what the other ranks parse. Each table is written
// by its option table's rows (campaign_tables.hpp), the method's by its options (to_toml()).
#include <sstream>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "campaign/campaign_tables.hpp"

namespace truss::campaign {

const char* to_string(Per p) { return p == Per::run ? "run" : p == Per::bay ? "bay" : "frame"; }
const char* to_string(Apply a) {
  return a == Apply::absolute ? "absolute" : a == Apply::relative ? "relative" : "offset";
}

std::string resolved_campaign_toml(const CampaignOptions& c) {
  std::string t = "# Resolved campaign: every value used, the base scene inline.\n";
  t += "[campaign]\n" + write_options(campaign_table(), c) + "\n";
  t += "[ensemble]\n" + write_options(ensemble_table(), c) + "\n";
  t += c.ensemble.method.options().to_toml();
  t += "[output]\n" + write_options(output_table(), c) + "\n";
  // The scene in the single-run format, its tables moved under [scene.].
  std::istringstream scene(io::resolved_scene_toml(c.base));
  for (std::string line; std::getline(scene, line);) {
    if (!line.empty() && line[0] == '[') line = "[scene." + line.substr(1);
    t += line + "\n";
  }
  for (const DispersionOptions& d : c.dispersions) t += "\n[[dispersion]]\n" + write_options(dispersion_table(), d);
  return t;
}

}  // namespace truss::campaign
