// libFuzzer target: the campaign front end (campaign tables, [scene.*] inline tables and
// overrides, dispersions). Refused with an InputError, or parsed to options whose resolved TOML
// parses back to the same options: the base scene equal key by key, bit for bit (same_scene.hpp,
// independent of the writer's text), and the whole resolved text a fixed point.
// A relative scene.file resolves against the fuzzer's working directory.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "campaign/campaign.hpp"
#include "methods/method_table.hpp"
#include "same_scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  truss::campaign::CampaignOptions c;
  try {
    c = truss::methods::parse_campaign_text(text, "fuzz.toml", ".");
  } catch (const truss::io::InputError&) {
    return 0;
  }
  const std::string t1 = truss::campaign::resolved_campaign_toml(c);
  std::string t2;
  try {
    const truss::campaign::CampaignOptions back = truss::methods::parse_campaign_text(t1, "resolved.toml", ".");
    if (const std::string d = truss::fuzz::find_scene_difference(c.base, back.base); !d.empty()) {
      std::fprintf(stderr, "round trip changed a base-scene value: %s\n%s\n", d.c_str(), t1.c_str());
      std::abort();
    }
    t2 = truss::campaign::resolved_campaign_toml(back);
  } catch (const truss::io::InputError& e) {
    std::fprintf(stderr, "resolved campaign refused: %s\n%s\n", e.what(), t1.c_str());
    std::abort();
  }
  if (t1 != t2) {
    std::fprintf(stderr, "round trip changed the campaign:\n%s\n---\n%s\n", t1.c_str(), t2.c_str());
    std::abort();
  }
  return 0;
}
