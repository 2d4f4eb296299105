// libFuzzer target: the scene front end. Any input either is refused with an InputError or
// parses to options whose resolved TOML parses back to the same options: every key's value equal
// bit for bit (same_scene.hpp, through the key table, independent of the writer's text), and the
// resolved text a fixed point. Anything else (another exception, a sanitizer report, a mismatch)
// is a finding.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "io/scene_toml.hpp"
#include "same_scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  truss::sim::SceneOptions s;
  try {
    s = truss::io::parse_scene_text(text, "fuzz.toml");
  } catch (const truss::io::InputError&) {
    return 0;  // refused with a message: fine
  }
  const std::string t1 = truss::io::resolved_scene_toml(s);
  std::string t2;
  try {
    const truss::sim::SceneOptions back = truss::io::parse_scene_text(t1, "resolved.toml");
    if (const std::string d = truss::fuzz::find_scene_difference(s, back); !d.empty()) {
      std::fprintf(stderr, "round trip changed a value: %s\n%s\n", d.c_str(), t1.c_str());
      std::abort();
    }
    t2 = truss::io::resolved_scene_toml(back);
  } catch (const truss::io::InputError& e) {
    std::fprintf(stderr, "resolved scene refused: %s\n%s\n", e.what(), t1.c_str());
    std::abort();
  }
  if (t1 != t2) {
    std::fprintf(stderr, "round trip changed the scene:\n%s\n---\n%s\n", t1.c_str(), t2.c_str());
    std::abort();
  }
  return 0;
}
