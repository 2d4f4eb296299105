// The fuzzers' round-trip check, made independent of the writer's text: two scenes are the same
// when every key of the key table reads back the same value, bit for bit (a double written with
// too few digits gives the same text twice but a different value; text equality alone would
// miss it). Returns "" or the first key that differs with both values.
#pragma once
#include <bit>
#include <cstdint>
#include <string>

#include <fmt/format.h>

#include "sim/scene_keys.hpp"

namespace truss::fuzz {

inline bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

inline std::string find_scene_difference(const sim::SceneOptions& a, const sim::SceneOptions& b) {
  for (const auto& k : sim::scene_keys()) {
    switch (k.kind) {
      case sim::KeyKind::real:
        if (!same_bits(k.get_real(a), k.get_real(b)))
          return fmt::format("{}: {:.17g} became {:.17g}", k.dotted(), k.get_real(a), k.get_real(b));
        break;
      case sim::KeyKind::opt_real: {
        const auto va = k.get_opt(a), vb = k.get_opt(b);
        if (va.has_value() != vb.has_value() || (va && !same_bits(*va, *vb)))
          return fmt::format("{}: {} became {}", k.dotted(), va ? fmt::format("{:.17g}", *va) : "unset",
                             vb ? fmt::format("{:.17g}", *vb) : "unset");
        break;
      }
      case sim::KeyKind::integer:
        if (k.get_int(a) != k.get_int(b)) return fmt::format("{}: {} became {}", k.dotted(), k.get_int(a), k.get_int(b));
        break;
      case sim::KeyKind::enumeration:
        if (k.get_enum(a) != k.get_enum(b))
          return fmt::format("{}: enum {} became {}", k.dotted(), k.get_enum(a), k.get_enum(b));
        break;
    }
  }
  return "";
}

}  // namespace truss::fuzz
