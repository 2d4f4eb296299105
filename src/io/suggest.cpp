#include "io/suggest.hpp"

#include <algorithm>
#include <cctype>
#include <limits>

#include <fmt/format.h>

#include "sim/scene_keys.hpp"

namespace truss::io {

namespace {

const std::vector<sim::SceneKey>& keys() { return sim::scene_keys(); }
std::vector<std::string_view> table_names() { return sim::find_scene_tables(); }


std::string lower(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

// Distance between a typed name and a known one, with prefixes counted as close
// ("beta" ~ "beta_deg", "speed" ~ "speed_m_per_s").
std::size_t name_distance(std::string_view typed, std::string_view known) {
  const std::string a = lower(typed), b = lower(known);
  std::size_t d = edit_distance(a, b);
  const std::size_t shorter = std::min(a.size(), b.size());
  if (shorter >= 3 && (a.rfind(b, 0) == 0 || b.rfind(a, 0) == 0)) d = std::min<std::size_t>(d, 1);
  return d;
}

std::size_t close_enough(std::string_view typed) {
  return std::max<std::size_t>(2, typed.size() / 3);
}

}  // namespace

// Closest known "table.key" to a key typed in `table` (empty table: typed at the top level).
std::optional<std::string> suggest_key(std::string_view table, std::string_view key) {
  std::optional<std::string> best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (const auto& d : keys()) {
    std::size_t dist = name_distance(key, d.key);
    if (!table.empty() && d.table != table) dist += 1;  // prefer the table the user wrote
    if (dist < best_d) {
      best_d = dist;
      best = d.dotted();
    }
  }
  if (best && best_d <= close_enough(key)) return best;
  return std::nullopt;
}

std::optional<std::string> suggest_table(std::string_view table) {
  std::optional<std::string> best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (auto t : table_names()) {
    const std::size_t dist = name_distance(table, t);
    if (dist < best_d) {
      best_d = dist;
      best = std::string(t);
    }
  }
  if (best && best_d <= std::max<std::size_t>(1, table.size() / 3)) return best;
  return std::nullopt;
}

std::optional<std::string> suggest_value(std::string_view value,
                                         const std::vector<std::string_view>& allowed) {
  std::optional<std::string> best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (auto a : allowed) {
    const std::size_t dist = name_distance(value, a);
    if (dist < best_d) {
      best_d = dist;
      best = std::string(a);
    }
  }
  if (best && best_d <= close_enough(value)) return best;
  return std::nullopt;
}

std::string known_tables_text() {
  std::string s;
  for (auto t : table_names()) s += fmt::format("{}[{}]", s.empty() ? "" : ", ", t);
  return s;
}

std::string known_keys_text(std::string_view table) {
  std::string s;
  for (const auto& d : keys())
    if (d.table == table) s += fmt::format("{}{}", s.empty() ? "" : ", ", d.key);
  return s;
}


}  // namespace truss::io
