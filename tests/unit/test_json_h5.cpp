// JSON summary and HDF5 output: every field written, NaN as null, exact doubles, escaping; HDF5
// round trip through the C API, units, refusing to overwrite, --force, no temporary files left.
#include <catch2/catch.hpp>
#include <hdf5.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "io/build_info.hpp"
#include "io/h5_output.hpp"
#include "io/json_summary.hpp"
#include "io/scene_toml.hpp"

using truss::io::InputError;
using truss::sim::BayResult;
using truss::sim::RunResult;
using truss::sim::RunStatus;
using truss::sim::TimeHistory;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// --- number of data members of an aggregate (tripwire for fields added to result.hpp) --------
struct AnyField {
  template <class T>
  operator T() const;  // never defined: used in unevaluated contexts only
};
template <class T, class... A>
constexpr std::size_t field_count() {
  if constexpr (requires { T{A{}..., AnyField{}}; })
    return field_count<T, A..., AnyField>();
  else
    return sizeof...(A);
}

// --- a small strict JSON parser, enough to check what to_json writes ---------------------------
struct Json {
  enum Type { null, boolean, number, string, array, object } type = null;
  bool b = false;
  double num = 0;
  std::string raw;  // number text as written
  std::string str;
  std::vector<Json> items;
  std::vector<std::pair<std::string, Json>> members;
  // Defined below, where Json is complete: clang 14 with libstdc++ 12 otherwise instantiates
  // pair<string, Json> (and its explicit(...) default-constructor test) on an incomplete Json.
  Json();
  Json(const Json&);
  Json(Json&&) noexcept;
  Json& operator=(const Json&);
  Json& operator=(Json&&) noexcept;
  ~Json();
  const Json& at(const std::string& key) const;
  bool has(const std::string& key) const;
};
Json::Json() = default;
Json::Json(const Json&) = default;
Json::Json(Json&&) noexcept = default;
Json& Json::operator=(const Json&) = default;
Json& Json::operator=(Json&&) noexcept = default;
Json::~Json() = default;
const Json& Json::at(const std::string& key) const {
  for (const auto& [k, v] : members)
    if (k == key) return v;
  throw std::runtime_error("no key " + key);
}
bool Json::has(const std::string& key) const {
  for (const auto& [k, v] : members)
    if (k == key) return true;
  return false;
}

class JsonParser {
 public:
  explicit JsonParser(std::string text) : s_(std::move(text)) {}
  Json parse() {
    Json v = value();
    ws();
    if (i_ != s_.size()) fail("trailing characters");
    return v;
  }

 private:
  std::string s_;
  std::size_t i_ = 0;
  [[noreturn]] void fail(const std::string& why) {
    throw std::runtime_error("JSON error at " + std::to_string(i_) + ": " + why);
  }
  void ws() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\n' || s_[i_] == '\t' || s_[i_] == '\r')) ++i_;
  }
  bool lit(const char* w) {
    const std::string word(w);
    if (s_.compare(i_, word.size(), word) == 0) {
      i_ += word.size();
      return true;
    }
    return false;
  }
  void expect(char c) {
    ws();
    if (i_ >= s_.size() || s_[i_] != c) fail(std::string("expected ") + c);
    ++i_;
  }
  static void put_utf8(std::string& out, unsigned cp) {
    if (cp < 0x80) out += static_cast<char>(cp);
    else if (cp < 0x800) { out += static_cast<char>(0xC0 | (cp >> 6)); out += static_cast<char>(0x80 | (cp & 0x3F)); }
    else if (cp < 0x10000) { out += static_cast<char>(0xE0 | (cp >> 12)); out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F)); out += static_cast<char>(0x80 | (cp & 0x3F)); }
    else { out += static_cast<char>(0xF0 | (cp >> 18)); out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F)); out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F)); out += static_cast<char>(0x80 | (cp & 0x3F)); }
  }
  unsigned hex4() {
    if (i_ + 4 > s_.size()) fail("short \\u escape");
    const unsigned v = static_cast<unsigned>(std::stoul(s_.substr(i_, 4), nullptr, 16));
    i_ += 4;
    return v;
  }
  std::string string_body() {
    expect('"');
    std::string out;
    while (true) {
      if (i_ >= s_.size()) fail("unterminated string");
      const char c = s_[i_++];
      if (c == '"') return out;
      if (static_cast<unsigned char>(c) < 0x20) fail("raw control character in string");
      if (c != '\\') { out += c; continue; }
      const char e = s_[i_++];
      switch (e) {
        case '"': out += '"'; break;
        case '\\': out += '\\'; break;
        case '/': out += '/'; break;
        case 'b': out += '\b'; break;
        case 'f': out += '\f'; break;
        case 'n': out += '\n'; break;
        case 'r': out += '\r'; break;
        case 't': out += '\t'; break;
        case 'u': put_utf8(out, hex4()); break;
        default: fail("bad escape");
      }
    }
  }
  Json value() {
    ws();
    if (i_ >= s_.size()) fail("unexpected end");
    Json v;
    const char c = s_[i_];
    if (c == '{') {
      v.type = Json::object;
      ++i_;
      ws();
      if (s_[i_] == '}') { ++i_; return v; }
      while (true) {
        ws();
        std::string k = string_body();
        expect(':');
        v.members.emplace_back(std::move(k), value());
        ws();
        if (s_[i_] == ',') { ++i_; continue; }
        expect('}');
        return v;
      }
    }
    if (c == '[') {
      v.type = Json::array;
      ++i_;
      ws();
      if (s_[i_] == ']') { ++i_; return v; }
      while (true) {
        v.items.push_back(value());
        ws();
        if (s_[i_] == ',') { ++i_; continue; }
        expect(']');
        return v;
      }
    }
    if (c == '"') { v.type = Json::string; v.str = string_body(); return v; }
    if (lit("null")) return v;
    if (lit("true")) { v.type = Json::boolean; v.b = true; return v; }
    if (lit("false")) { v.type = Json::boolean; return v; }
    // number: -?(0|[1-9]d*)(.d+)?([eE][+-]?d+)?
    const std::size_t start = i_;
    if (s_[i_] == '-') ++i_;
    auto digits = [&] { const std::size_t b = i_; while (i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]))) ++i_; return i_ - b; };
    if (i_ < s_.size() && s_[i_] == '0') ++i_;
    else if (digits() == 0) fail("bad value");
    if (i_ < s_.size() && s_[i_] == '.') { ++i_; if (digits() == 0) fail("bad fraction"); }
    if (i_ < s_.size() && (s_[i_] == 'e' || s_[i_] == 'E')) {
      ++i_;
      if (s_[i_] == '+' || s_[i_] == '-') ++i_;
      if (digits() == 0) fail("bad exponent");
    }
    v.type = Json::number;
    v.raw = s_.substr(start, i_ - start);
    v.num = std::strtod(v.raw.c_str(), nullptr);
    return v;
  }
};

Json parse_json(const std::string& text) { return JsonParser(text).parse(); }

// --- a RunResult with a distinct value in every field -----------------------------------------
RunResult sample_result() {
  RunResult r;
  r.status = RunStatus::stall;
  r.message = "stalled in bay 3: \"drive\" \\ force\nlimit\t\x01 \xC3\xA9t\xC3\xA9 \xFF";
  r.direction = "deploy";
  r.drive_mode = "motor";
  r.n_bays = 3;
  r.bays_completed = 2;
  r.deploy_time_s = 12.345678901234567;
  r.peak_drive_force_N = kNaN;
  r.peak_drive_force_time_s = 1.0 / 3.0;
  r.peak_drive_force_bay = 2;
  r.min_drive_force_N = -0.1;
  r.min_drive_force_time_s = 2.5;
  r.min_drive_force_bay = 1;
  r.peak_drive_torque_Nm = 0.0123;
  r.min_drive_torque_Nm = -1e-300;
  r.peak_pin_force_N = 4.75;
  r.peak_pin_force_time_s = 3.25;
  r.peak_pin_force_bay = 3;
  r.peak_diagonal_tension_N = 6.0;
  r.peak_driven_speed_m_per_s = std::numeric_limits<double>::infinity();
  r.drive_work_J = 7.5;
  r.drive_work_smooth_J = 7.25;
  r.drive_work_impulses_J = 0.25;
  r.start_drive_impulse_Ns = 0.01;
  r.energy_lost_J = 0.5;
  r.kinetic_energy_start_J = 0.0;
  r.kinetic_energy_end_J = 0.125;
  r.potential_energy_start_J = 1.5;
  r.potential_energy_end_J = 8.0;
  r.energy_residual_J = 1.2e-12;
  r.max_rail_residual_m = 3e-15;
  r.steps = 123456789012L;
  r.rejected_steps = 17;
  r.rhs_evals = 987654321098L;
  r.wall_time_s = 0.75;
  for (int i = 1; i <= 3; ++i) {
    BayResult b;
    b.bay = i;
    b.entry_time_s = 1.0 * i;
    b.lock_time_s = i == 3 ? kNaN : 1.0 * i + 0.5;
    b.latch_energy_J = 0.01 * i;
    b.entry_impulse_Ns = 0.02 * i;
    b.landing_impulse_Ns = kNaN;
    b.entry_drive_impulse_Ns = 0.03 * i;
    b.entry_energy_loss_J = 0.04 * i;
    b.peak_drive_force_N = 2.0 * i;
    b.peak_drive_force_time_s = 1.0 * i + 0.25;
    b.peak_pin_force_N = 3.0 * i;
    b.peak_pin_force_time_s = 1.0 * i + 0.125;
    r.bays.push_back(b);
  }
  return r;
}

void add_history(RunResult& r, std::size_t n) {
  TimeHistory& h = r.history;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = 0.01 * static_cast<double>(k);
    h.t_s.push_back(t);
    h.bay.push_back(1 + static_cast<int>(k / 4));
    h.y_driven_m.push_back(t * 0.1);
    h.y_lower_m.push_back(0.0);
    h.hinge_x_m.push_back(0.08 - t);
    h.hinge_y_m.push_back(0.09 + t);
    h.drive_force_N.push_back(3.0 - t);
    h.drive_torque_Nm.push_back(0.005);
    h.pin_force_N.push_back(k % 2 ? 0.0 : 1.5);
    h.diagonal_tension_N.push_back(2.0 + t);
    h.driven_speed_m_per_s.push_back(0.1);
  }
}

struct TempDir {
  std::filesystem::path path;
  TempDir() {
    static int counter = 0;
    path = std::filesystem::temp_directory_path() /
           ("truss_h5_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(path)) names.push_back(e.path().filename().string());
    return names;
  }
};

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// --- HDF5 reading helpers (C API) --------------------------------------------------------------
struct H5Id {
  hid_t id;
  herr_t (*close)(hid_t);
  ~H5Id() { if (id >= 0) close(id); }
};

bool h5_exists(hid_t file, const std::string& path) { return H5Lexists(file, path.c_str(), H5P_DEFAULT) > 0; }

std::string read_string_attr(hid_t obj, const char* name) {
  H5Id attr{H5Aopen(obj, name, H5P_DEFAULT), H5Aclose};
  REQUIRE(attr.id >= 0);
  H5Id ftype{H5Aget_type(attr.id), H5Tclose};
  REQUIRE(H5Tget_class(ftype.id) == H5T_STRING);
  REQUIRE(H5Tis_variable_str(ftype.id) > 0);
  H5Id mtype{H5Tcopy(H5T_C_S1), H5Tclose};
  H5Tset_size(mtype.id, H5T_VARIABLE);
  H5Tset_cset(mtype.id, H5T_CSET_UTF8);
  char* p = nullptr;
  REQUIRE(H5Aread(attr.id, mtype.id, &p) >= 0);
  std::string s = p ? p : "";
  H5free_memory(p);
  return s;
}

std::string units_of(hid_t file, const std::string& path) {
  H5Id ds{H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose};
  REQUIRE(ds.id >= 0);
  return read_string_attr(ds.id, "units");
}

// Reads a dataset as doubles (float64) or int64s; checks the stored class and rank.
template <class T>
std::vector<T> read_dataset(hid_t file, const std::string& path, int rank) {
  INFO(path);
  H5Id ds{H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose};
  REQUIRE(ds.id >= 0);
  H5Id space{H5Dget_space(ds.id), H5Sclose};
  REQUIRE(H5Sget_simple_extent_ndims(space.id) == rank);
  H5Id type{H5Dget_type(ds.id), H5Tclose};
  const hid_t mem = std::is_same_v<T, double> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
  REQUIRE(H5Tget_class(type.id) == (std::is_same_v<T, double> ? H5T_FLOAT : H5T_INTEGER));
  REQUIRE(H5Tget_size(type.id) == 8);
  std::vector<T> v(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.id)));
  if (!v.empty()) REQUIRE(H5Dread(ds.id, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0);
  return v;
}

bool same(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

}  // namespace

// =============================================================================================
// JSON

TEST_CASE("the field tables cover every field of the result structs", "[json][h5]") {
  // If one of these fails, a field was added to (or removed from) sim/result.hpp: add it to the
  // tables in src/io/json_summary.cpp (and to docs/hdf5-schema.md).
  CHECK(field_count<BayResult>() == truss::io::bay_result_fields().size());
  // + step_s (an attribute), frame_height_m and n_frames (the free stack's 2-D dataset, written by
  // write_history apart from the 1-D table)
  CHECK(field_count<TimeHistory>() == truss::io::history_fields().size() + 3);
  // + status, message, bays, history
  CHECK(field_count<RunResult>() == truss::io::run_result_fields().size() + 4);
  for (const auto& f : truss::io::run_result_fields()) CHECK(std::string(f.units) != "");
  for (const auto& f : truss::io::bay_result_fields()) CHECK(std::string(f.units) != "");
  for (const auto& f : truss::io::history_fields()) CHECK(std::string(f.units) != "");
}

TEST_CASE("to_json writes every field, null for NaN, exact doubles", "[json]") {
  const RunResult r = sample_result();
  const std::string text = truss::io::to_json(r);
  CHECK_THAT(text, !Contains("nan"));
  CHECK_THAT(text, !Contains("inf"));
  const Json j = parse_json(text);
  REQUIRE(j.type == Json::object);

  for (const char* key : {"status", "message", "deploy_time_s", "peak_drive_force_N", "min_drive_force_N",
                          "peak_drive_torque_Nm", "peak_pin_force_N", "peak_diagonal_tension_N",
                          "drive_work_J", "energy_residual_J", "steps", "rhs_evals", "wall_time_s", "bays"}) {
    INFO(key);
    CHECK(j.has(key));
  }
  // No key twice.
  std::map<std::string, int> seen;
  for (const auto& [k, v] : j.members) CHECK(++seen[k] == 1);

  CHECK(j.at("status").str == truss::sim::to_string(RunStatus::stall));
  CHECK(j.at("message").str ==
        "stalled in bay 3: \"drive\" \\ force\nlimit\t\x01 \xC3\xA9t\xC3\xA9 \xEF\xBF\xBD");
  CHECK(j.at("deploy_time_s").num == 12.345678901234567);
  CHECK(j.at("peak_drive_force_time_s").num == 1.0 / 3.0);
  CHECK(j.at("min_drive_torque_Nm").num == -1e-300);
  CHECK(j.at("peak_drive_force_N").type == Json::null);        // NaN
  CHECK(j.at("peak_driven_speed_m_per_s").type == Json::null); // inf
  CHECK(j.at("steps").raw == "123456789012");
  CHECK(j.at("rhs_evals").raw == "987654321098");
  CHECK(j.at("n_bays").raw == "3");
  CHECK(j.at("drive_mode").str == "motor");
  CHECK(j.at("history_samples").raw == "0");

  // Every scalar field of the table, with the value its getter gives.
  for (const auto& f : truss::io::run_result_fields()) {
    INFO(f.name);
    REQUIRE(j.has(f.name));
    const auto v = f.get(r);
    const Json& x = j.at(f.name);
    if (const auto* d = std::get_if<double>(&v)) {
      if (std::isfinite(*d)) {
        REQUIRE(x.type == Json::number);
        CHECK(x.num == *d);
      } else {
        CHECK(x.type == Json::null);
      }
    } else if (const auto* i = std::get_if<std::int64_t>(&v)) {
      REQUIRE(x.type == Json::number);
      CHECK(x.raw == std::to_string(*i));
    } else {
      CHECK(x.str == std::get<std::string>(v));
    }
  }

  const Json& bays = j.at("bays");
  REQUIRE(bays.type == Json::array);
  REQUIRE(bays.items.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    const Json& b = bays.items[i];
    for (const auto& f : truss::io::bay_result_fields()) {
      INFO("bay " << i + 1 << " " << f.name);
      REQUIRE(b.has(f.name));
    }
    CHECK(b.at("bay").raw == std::to_string(i + 1));
    CHECK(b.at("entry_time_s").num == r.bays[i].entry_time_s);
    CHECK(b.at("latch_energy_J").num == r.bays[i].latch_energy_J);
    CHECK(b.at("entry_impulse_Ns").num == r.bays[i].entry_impulse_Ns);
    CHECK(b.at("peak_drive_force_N").num == r.bays[i].peak_drive_force_N);
    CHECK(b.at("peak_pin_force_N").num == r.bays[i].peak_pin_force_N);
    CHECK(b.at("landing_impulse_Ns").type == Json::null);
  }
  CHECK(bays.items[2].at("lock_time_s").type == Json::null);
  CHECK(bays.items[1].at("lock_time_s").num == 2.5);
}

TEST_CASE("to_json of a default result and of every status", "[json]") {
  for (int s = 0; s < truss::sim::kRunStatusCount; ++s) {
    RunResult r;
    r.status = static_cast<RunStatus>(s);
    const Json j = parse_json(truss::io::to_json(r));
    CHECK(j.at("status").str == truss::sim::to_string(r.status));
    CHECK(j.at("bays").type == Json::array);
    CHECK(j.at("bays").items.empty());
    CHECK(j.at("deploy_time_s").type == Json::null);
  }
}

TEST_CASE("json_string and json_number", "[json]") {
  CHECK(truss::io::json_string("a\"b\\c\n") == "\"a\\\"b\\\\c\\n\"");
  CHECK(truss::io::json_string("\x1f") == "\"\\u001f\"");
  CHECK(truss::io::json_string("\xE2\x82\xAC") == "\"\xE2\x82\xAC\"");  // valid UTF-8 kept
  CHECK(truss::io::json_string("\xC0\xAF") == "\"\\ufffd\\ufffd\"");    // overlong form
  CHECK(truss::io::json_number(kNaN) == "null");
  CHECK(truss::io::json_number(-std::numeric_limits<double>::infinity()) == "null");
  CHECK(truss::io::json_number(45.0) == "45.0");
  CHECK(std::strtod(truss::io::json_number(0.1 + 0.2).c_str(), nullptr) == 0.1 + 0.2);
}

// =============================================================================================
// HDF5

TEST_CASE("HDF5 round trip", "[h5]") {
  TempDir dir;
  const std::string out = (dir.path / "run.h5").string();
  RunResult r = sample_result();
  add_history(r, 10);
  const std::string scene = truss::io::resolved_scene_toml(truss::sim::SceneOptions{});
  truss::io::write_run_h5(out, r, scene, false);
  CHECK(dir.entries() == std::vector<std::string>{"run.h5"});  // no temporary file left

  H5Id file{H5Fopen(out.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  REQUIRE(file.id >= 0);

  SECTION("root attributes") {
    H5Id a{H5Aopen(file.id, "schema_version", H5P_DEFAULT), H5Aclose};
    REQUIRE(a.id >= 0);
    std::int64_t version = 0;
    REQUIRE(H5Aread(a.id, H5T_NATIVE_INT64, &version) >= 0);
    CHECK(version == 1);
    CHECK(read_string_attr(file.id, "kind") == "single_run");
    CHECK(read_string_attr(file.id, "scene_toml") == scene);
    CHECK(read_string_attr(file.id, "software_version") == truss::io::get_software_version());
    CHECK(read_string_attr(file.id, "git_revision") == truss::io::get_git_revision());
    const std::string created = read_string_attr(file.id, "created_utc");
    REQUIRE(created.size() == 20);
    CHECK(created[4] == '-');
    CHECK(created[10] == 'T');
    CHECK(created[19] == 'Z');
    // The stored scene parses back.
    CHECK(truss::io::resolved_scene_toml(truss::io::parse_scene_text(scene, "stored", {})) == scene);
  }

  SECTION("summary scalars with units") {
    for (const auto& f : truss::io::run_result_fields()) {
      const std::string path = std::string("/summary/") + f.name;
      INFO(path);
      REQUIRE(h5_exists(file.id, path));
      CHECK(units_of(file.id, path) == f.units);
      const auto v = f.get(r);
      if (const auto* d = std::get_if<double>(&v)) {
        const auto x = read_dataset<double>(file.id, path, 0);
        REQUIRE(x.size() == 1);
        CHECK(same(x[0], *d));
      } else if (const auto* i = std::get_if<std::int64_t>(&v)) {
        const auto x = read_dataset<std::int64_t>(file.id, path, 0);
        REQUIRE(x.size() == 1);
        CHECK(x[0] == *i);
      }
    }
    CHECK(read_dataset<double>(file.id, "/summary/deploy_time_s", 0)[0] == 12.345678901234567);
    CHECK(units_of(file.id, "/summary/deploy_time_s") == "s");
    CHECK(std::isnan(read_dataset<double>(file.id, "/summary/peak_drive_force_N", 0)[0]));
    CHECK(units_of(file.id, "/summary/peak_drive_force_N") == "N");
    CHECK(units_of(file.id, "/summary/peak_drive_torque_Nm") == "Nm");
    CHECK(units_of(file.id, "/summary/drive_work_J") == "J");
    CHECK(units_of(file.id, "/summary/start_drive_impulse_Ns") == "Ns");
    CHECK(read_dataset<std::int64_t>(file.id, "/summary/steps", 0)[0] == 123456789012L);
    CHECK(units_of(file.id, "/summary/steps") == "1");
  }

  SECTION("status is an enum with the status names and a message") {
    H5Id ds{H5Dopen2(file.id, "/summary/status", H5P_DEFAULT), H5Dclose};
    REQUIRE(ds.id >= 0);
    H5Id type{H5Dget_type(ds.id), H5Tclose};
    REQUIRE(H5Tget_class(type.id) == H5T_ENUM);
    CHECK(H5Tget_nmembers(type.id) == truss::sim::kRunStatusCount);
    H5Id base{H5Tget_super(type.id), H5Tclose};
    CHECK(H5Tget_size(base.id) == 1);
    std::int8_t value = -1;
    REQUIRE(H5Dread(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, &value) >= 0);
    CHECK(value == static_cast<std::int8_t>(RunStatus::stall));
    char name[64] = {};
    REQUIRE(H5Tenum_nameof(type.id, &value, name, sizeof name) >= 0);
    CHECK(std::string(name) == truss::sim::to_string(RunStatus::stall));
    CHECK(read_string_attr(ds.id, "units") == "1");
    CHECK(read_string_attr(ds.id, "message") == r.message);
  }

  SECTION("bays") {
    for (const auto& f : truss::io::bay_result_fields()) {
      const std::string path = std::string("/bays/") + f.name;
      INFO(path);
      REQUIRE(h5_exists(file.id, path));
      CHECK(units_of(file.id, path) == f.units);
      if (std::holds_alternative<std::int64_t>(f.get(BayResult{}))) {
        const auto x = read_dataset<std::int64_t>(file.id, path, 1);
        REQUIRE(x.size() == r.bays.size());
        for (std::size_t i = 0; i < x.size(); ++i) CHECK(x[i] == std::get<std::int64_t>(f.get(r.bays[i])));
      } else {
        const auto x = read_dataset<double>(file.id, path, 1);
        REQUIRE(x.size() == r.bays.size());
        for (std::size_t i = 0; i < x.size(); ++i) CHECK(same(x[i], std::get<double>(f.get(r.bays[i]))));
      }
    }
    CHECK(read_dataset<std::int64_t>(file.id, "/bays/bay", 1) == std::vector<std::int64_t>{1, 2, 3});
    const auto lock = read_dataset<double>(file.id, "/bays/lock_time_s", 1);
    CHECK(lock[0] == 1.5);
    CHECK(std::isnan(lock[2]));
    CHECK(units_of(file.id, "/bays/latch_energy_J") == "J");
    CHECK(units_of(file.id, "/bays/entry_impulse_Ns") == "Ns");
  }

  SECTION("history") {
    for (const auto& f : truss::io::history_fields()) {
      const std::string path = std::string("/history/") + f.name;
      INFO(path);
      REQUIRE(h5_exists(file.id, path));
      CHECK(units_of(file.id, path) == f.units);
    }
    CHECK(read_dataset<double>(file.id, "/history/t_s", 1) == r.history.t_s);
    CHECK(read_dataset<double>(file.id, "/history/drive_force_N", 1) == r.history.drive_force_N);
    const auto bay = read_dataset<std::int64_t>(file.id, "/history/bay", 1);
    CHECK(std::vector<int>(bay.begin(), bay.end()) == r.history.bay);
    CHECK(units_of(file.id, "/history/driven_speed_m_per_s") == "m/s");
    CHECK(units_of(file.id, "/history/hinge_x_m") == "m");
  }
}

TEST_CASE("HDF5 without history has no /history group; empty bays are empty datasets", "[h5]") {
  TempDir dir;
  const std::string out = (dir.path / "empty.h5").string();
  RunResult r;  // no bays, no history
  r.status = RunStatus::ok;
  truss::io::write_run_h5(out, r, "", false);
  H5Id file{H5Fopen(out.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  REQUIRE(file.id >= 0);
  CHECK(!h5_exists(file.id, "/history"));
  CHECK(h5_exists(file.id, "/summary/status"));
  CHECK(read_dataset<double>(file.id, "/bays/lock_time_s", 1).empty());
  CHECK(read_string_attr(file.id, "scene_toml").empty());
}

TEST_CASE("HDF5 output never overwrites without force", "[h5]") {
  TempDir dir;
  const std::string out = (dir.path / "run.h5").string();
  std::ofstream(out) << "precious data";
  const RunResult r = sample_result();

  try {
    truss::io::write_run_h5(out, r, "", false);
    FAIL("no InputError for an existing file");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()) == "error: output file exists: " + out + " (use --force to overwrite)");
  }
  CHECK(read_all(out) == "precious data");
  CHECK(dir.entries() == std::vector<std::string>{"run.h5"});
  CHECK_THROWS_AS(truss::io::check_output_path(out, false), InputError);
  CHECK_NOTHROW(truss::io::check_output_path(out, true));

  truss::io::write_run_h5(out, r, "", true);
  CHECK(read_all(out) != "precious data");
  CHECK(H5Fis_hdf5(out.c_str()) > 0);
  CHECK(dir.entries() == std::vector<std::string>{"run.h5"});
}

TEST_CASE("HDF5 output path errors", "[h5]") {
  TempDir dir;
  const RunResult r = sample_result();
  SECTION("missing directory is bad input") {
    const std::string out = (dir.path / "no" / "such" / "run.h5").string();
    CHECK_THROWS_AS(truss::io::write_run_h5(out, r, "", false), InputError);
    CHECK(!std::filesystem::exists(out));
  }
  SECTION("a directory as the output is bad input, even with force") {
    CHECK_THROWS_AS(truss::io::write_run_h5(dir.path.string(), r, "", true), InputError);
  }
  SECTION("an HDF5 failure throws runtime_error and leaves no temporary file") {
    // A file name too long for the file system: HDF5 cannot create the temporary file.
    const std::string out = (dir.path / (std::string(250, 'x') + ".h5")).string();
    try {
      truss::io::write_run_h5(out, r, "", false);
      FAIL("no exception");
    } catch (const InputError&) {
      FAIL("InputError instead of runtime_error");
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Contains("HDF5"));
    }
    CHECK(dir.entries().empty());
  }
}
