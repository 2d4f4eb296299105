// A campaign method's options as the campaign sees them. ensemble.method names one row of a method
// table (methods/method_table.hpp: one row per method, its name, the tables it reads, how it reads
// them and how it makes the method); the row reads its own table [ensemble.<name>] (and any root
// table it claims, subset's [failure]) into its own options, which the campaign holds behind this
// interface: their rules (validate), their resolved TOML, the runs they may make. Nothing else of
// the campaign, the engine, the journal or the results file knows a method's options.
//
// Which method: ensemble.method = "<name>"; absent, "design". A row that is selected by its table
// (stop) is also chosen by [ensemble.<name>] under "design", and its resolved TOML is written so.
// A table of a row that is not the campaign's method is refused; `ensemble.<name> = false` (e.g.
// --set ensemble.stop=false) stands for no table. A composite row (a design sweep) is chosen by its
// root table ([sweep]) and runs the method ensemble.method names, at each value of its design axis:
// its options hold that method's (inner_method()) and the axis (design_axis()).
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <typeinfo>
#include <vector>

namespace truss::campaign {

struct CampaignOptions;
struct DesignAxis;      // design_axis.hpp
struct FailureOptions;  // failure.hpp
struct MethodInput;     // what a row's parser reads (method_input.hpp)
struct TableDoc;        // option_table.hpp
class MethodChoice;

inline constexpr const char* kDefaultMethod = "design";

class MethodOptions {
 public:
  virtual ~MethodOptions() = default;
  virtual std::unique_ptr<MethodOptions> clone() const = 0;
  // The method's rules over the whole campaign (its options, the dispersions, ensemble.*): "" or
  // "field: reason" naming the first field that breaks one ("ensemble.stop.max_runs: ..."); the
  // parser reports that field's file and line (or --set).
  virtual std::string validate(const CampaignOptions& c) const = 0;
  // Its tables as TOML that its row reads back to the same options ("" when it has none).
  virtual std::string to_toml() const { return {}; }
  // When the method chooses its own run count: how (for the message that refuses an
  // ensemble.n_runs in the file); "" when ensemble.n_runs is the user's.
  virtual std::string chosen_runs() const { return {}; }
  // With chosen_runs(): the cap on its runs, set as ensemble.n_runs (0 when its options give none:
  // validate() says why).
  virtual std::int64_t calc_n_runs(const CampaignOptions&) const { return 0; }
  // The most runs the campaign can make, what memory and disk are checked for.
  virtual std::int64_t calc_max_runs(const CampaignOptions& c) const;
  // The keys the user wrote that set calc_max_runs, with their values, for messages that refuse
  // the cap ("ensemble.stop.max_runs = 1000000").
  virtual std::string describe_max_runs(const CampaignOptions& c) const;
  // The failure event ([failure], failure.hpp) whose probability the method estimates, or null
  // when it reads none (a design sweep needs one at each of its values).
  virtual const FailureOptions* failure_event() const { return nullptr; }
  // A composite's: the method it runs at each design value (as that value's campaign holds it),
  // and its design axis; null for a method of its own.
  virtual const MethodChoice* inner_method() const { return nullptr; }
  virtual const DesignAxis* design_axis() const { return nullptr; }
};

// Copies a MethodOptions subclass T with the campaign (clone()).
template <class T>
class MethodOptionsOf : public MethodOptions {
 public:
  std::unique_ptr<MethodOptions> clone() const override {
    return std::make_unique<T>(static_cast<const T&>(*this));
  }
};

// The campaign's method: the row's name, the name its resolved TOML writes and its options.
class MethodChoice {
 public:
  MethodChoice() = default;
  MethodChoice(std::string name, std::string written_name, std::unique_ptr<MethodOptions> options)
      : name_(std::move(name)), written_(std::move(written_name)), options_(std::move(options)) {}
  MethodChoice(const MethodChoice& o)
      : name_(o.name_), written_(o.written_), options_(o.options_ ? o.options_->clone() : nullptr) {}
  MethodChoice(MethodChoice&&) noexcept = default;
  MethodChoice& operator=(const MethodChoice& o) { return *this = MethodChoice(o); }
  MethodChoice& operator=(MethodChoice&&) noexcept = default;

  const std::string& name() const { return name_; }            // ensemble.method
  const std::string& written_name() const { return written_; }  // in the resolved TOML
  explicit operator bool() const { return options_ != nullptr; }
  const MethodOptions& options() const {
    if (!options_) throw std::logic_error("the campaign has no method");
    return *options_;
  }
  // The options as the method's own type; a logic error if they are not.
  template <class T>
  const T& as() const {
    const auto* t = dynamic_cast<const T*>(&options());
    if (t == nullptr)
      throw std::logic_error("ensemble.method \"" + name_ + "\": its options are not a " + typeid(T).name());
    return *t;
  }

 private:
  std::string name_, written_;
  std::unique_ptr<MethodOptions> options_;
};

// How a row is chosen: by ensemble.method = "<name>"; also by its table [ensemble.<name>] under
// "design" (stop); or, a composite, by its root table [<name>], around the method chosen so (sweep).
enum class MethodSelection { by_name, by_own_table, wraps };

// A row as the campaign parser sees it.
struct MethodSyntax {
  std::string name;                      // ensemble.method = "<name>"; its table [ensemble.<name>]
  std::vector<std::string> root_tables;  // root tables it reads besides its own ([failure])
  MethodSelection selection = MethodSelection::by_name;
  std::function<std::unique_ptr<MethodOptions>(const MethodInput&)> parse;  // throws io::InputError
  TableDoc (*table_doc)() = nullptr;     // its own table for the reference in docs (null: none)
  // Its own table's path: "ensemble.<name>", a composite's "<name>".
  std::string own_table() const { return selection == MethodSelection::wraps ? name : "ensemble." + name; }
};

// The rows the parser knows (methods::MethodTable). A composite method's parser reads its inner
// methods' tables through the same catalog (MethodInput::ctx.methods).
class MethodCatalog {
 public:
  virtual ~MethodCatalog() = default;
  virtual const MethodSyntax* find(std::string_view name) const = 0;  // null if none
  virtual std::vector<const MethodSyntax*> list() const = 0;          // in table order
};

}  // namespace truss::campaign
