// The option tables of a campaign file's own tables (option_table.hpp): [campaign], [ensemble],
// [output], [scene] and [[dispersion]]. The parser (campaign.cpp), the resolved TOML
// (campaign_toml.cpp) and the reference in docs (option_docs.hpp) read them; a method's tables are
// its row's (method_options.hpp), [failure] failure_table() (failure.hpp).
#pragma once
#include <vector>

#include "campaign/campaign.hpp"
#include "campaign/option_table.hpp"

namespace truss::campaign {

const OptionTable<CampaignOptions>& campaign_table();  // [campaign]
const OptionTable<CampaignOptions>& ensemble_table();  // [ensemble], besides the methods' [ensemble.<name>]
const OptionTable<CampaignOptions>& output_table();    // [output]
const OptionTable<CampaignOptions>& scene_table();     // [scene], besides the inline [scene.<table>]
const OptionTable<DispersionOptions>& dispersion_table();  // each [[dispersion]]

}  // namespace truss::campaign
