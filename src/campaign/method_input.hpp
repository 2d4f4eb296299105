// What a method's row reads (method_options.hpp) and what it reads it with: its own table through
// its option table (option_table.hpp), the [failure] event (failure.hpp) and, for a composite, the
// method it runs. Every message names the file and line of the value, or the --set that gave it.
#pragma once
#include <string>

#include <toml++/toml.h>

#include "campaign/failure.hpp"
#include "campaign/method_options.hpp"
#include "campaign/option_table.hpp"

namespace truss::campaign {

struct MethodInput {
  const TomlSource& source;  // file and --set of each value; source.methods: the catalog
  const toml::table& root;   // the campaign file (the row's root tables, e.g. [failure])
  const toml::table* table;  // its own table ([ensemble.<name>], a composite's [<name>]), or null
  std::string prefix;        // "ensemble.<name>.": its keys' names in messages
};

// The row's own table into o through its option table (the defaults stay without a table).
template <class T>
void read_method_table(const MethodInput& in, const OptionTable<T>& table, T& o) {
  if (in.table != nullptr) read_options(in.source, *in.table, table, o, in.prefix);
}

// [failure] of the file into f (failure.hpp); without one, f stays FailureKind::none.
void read_failure_event(const MethodInput& in, FailureOptions& f);

// A composite's: the method the file chooses as it would without the composite's table
// (ensemble.method, or a row selected by its table), its tables read, other rows' refused.
MethodChoice read_method_choice(const MethodInput& in);

}  // namespace truss::campaign
