// The option reference of docs/campaigns.md (option_docs.hpp).
#include "campaign/option_docs.hpp"

#include <fmt/format.h>

#include "campaign/campaign_tables.hpp"
#include "campaign/failure.hpp"
#include "sim/scene_keys.hpp"

namespace truss::campaign {

namespace {

std::string value_text(const OptionSpec& s) {
  std::string names;
  switch (s.kind) {
    case OptionKind::real: return "number";
    case OptionKind::integer: return "integer";
    case OptionKind::text: return "string";
    case OptionKind::choice:
      for (std::string_view n : s.choices) names += fmt::format("{}`\"{}\"`", names.empty() ? "" : ", ", n);
      return "one of " + names;
    case OptionKind::reals: return "list of numbers";
    case OptionKind::integers: return "list of integers";
    case OptionKind::settings: return "table of `\"table.key\" = value`";
    case OptionKind::method: return "a method's name";
  }
  return {};
}

std::string cell(std::string_view text) {
  std::string out;
  for (char ch : text) out += ch == '|' ? std::string("\\|") : std::string(1, ch);
  return out;
}

bool none_shown(const std::string& value) { return value.empty() || value == "[]" || value == "\"\""; }

std::string table_text(const TableDoc& t) {
  const bool array = t.name.rfind("[[", 0) == 0;
  std::string out = fmt::format("**`{}`** {}.\n\n", array ? t.name : fmt::format("[{}]", t.name), t.doc);
  if (t.rows.empty()) return out + "No keys.\n\n";
  out += "| key | value | unit | range | default | what it is |\n|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const OptionSpec& s = t.rows[i];
    const bool number = s.kind == OptionKind::real || s.kind == OptionKind::integer || s.kind == OptionKind::reals ||
                        s.kind == OptionKind::integers;
    const std::string def = s.required                     ? std::string("required")
                            : s.kind == OptionKind::method ? fmt::format("`\"{}\"`", kDefaultMethod)
                            : none_shown(t.defaults[i])    ? std::string("none")
                                                           : "`" + t.defaults[i] + "`";
    out += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", s.key, value_text(s), number ? cell(s.unit) : "",
                       s.range.is_bounded() ? cell(s.range.text()) : "", cell(def), cell(s.doc));
  }
  if (!t.others.empty()) {
    std::string list;
    for (const std::string& o : t.others) list += fmt::format("{}`{}`", list.empty() ? "" : ", ", o);
    out += fmt::format("\nAnd the tables {}.\n", list);
  }
  return out + "\n";
}

}  // namespace

std::string make_option_reference(const MethodCatalog& methods) {
  std::vector<std::string> method_tables, scene_tables;
  for (const MethodSyntax* r : methods.list())
    if (r->selection != MethodSelection::wraps && r->table_doc != nullptr)
      method_tables.push_back(fmt::format("[{}]", r->own_table()));
  for (std::string_view t : sim::find_scene_tables()) scene_tables.push_back(fmt::format("[scene.{}]", t));
  std::string out = "The campaign's own tables:\n\n";
  out += table_text(describe_options(campaign_table()));
  out += table_text(describe_options(ensemble_table(), method_tables));
  out += table_text(describe_options(output_table()));
  out += table_text(describe_options(scene_table(), scene_tables));
  out += table_text(describe_options(dispersion_table()));
  out += table_text(describe_options(failure_table()));
  out += "The methods' tables (`ensemble.method`, the method table):\n\n";
  for (const MethodSyntax* r : methods.list()) {
    if (r->table_doc != nullptr) {
      TableDoc d = r->table_doc();
      d.name = r->own_table();
      out += table_text(d);
    } else {
      out += fmt::format("**`[{}]`** (`ensemble.method = \"{}\"`): no keys of its own.\n\n", r->own_table(), r->name);
    }
  }
  return out;
}

}  // namespace truss::campaign
