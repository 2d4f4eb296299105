// libFuzzer target: the campaign front end (campaign tables, [scene.*] inline tables and
// overrides, dispersions). Refused with an InputError, or parsed to options whose resolved TOML
// parses back to the same options (compared as resolved texts, which are bit-exact images).
// A relative scene.file resolves against the fuzzer's working directory.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "campaign/campaign.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  truss::campaign::CampaignOptions c;
  try {
    c = truss::campaign::parse_campaign_text(text, "fuzz.toml", ".");
  } catch (const truss::io::InputError&) {
    return 0;
  }
  const std::string t1 = truss::campaign::resolved_campaign_toml(c);
  std::string t2;
  try {
    t2 = truss::campaign::resolved_campaign_toml(truss::campaign::parse_campaign_text(t1, "resolved.toml", "."));
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
