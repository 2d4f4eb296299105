#include "results/campaign_file.hpp"

#include <utility>
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include "io/h5_util.hpp"
#include "results/summary_h5.hpp"

namespace truss::results {

using namespace io::h5;
namespace fs = std::filesystem;

namespace {
// .NAME<suffix> next to `path`.
std::string hidden_name(const std::string& path, const std::string& suffix) {
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path();
  return (dir / fmt::format(".{}{}", p.filename().string(), suffix)).string();
}
}  // namespace

std::string CampaignFile::temporary_name(const std::string& path) {
  return hidden_name(path, fmt::format(".tmp.{}", static_cast<long>(::getpid())));
}

std::string CampaignFile::lock_name(const std::string& path) { return hidden_name(path, ".lock"); }

CampaignFile::CampaignFile(const std::string& path, const campaign::CampaignContext& ctx, const StoreOptions& opts)
    : path_(path), tmp_(temporary_name(path)), ctx_(ctx) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported through exceptions
  const Handle fapl(make_placement_fapl(placement_), H5Pclose, "file access properties of " + tmp_);
  file_ = H5Fcreate(tmp_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get());
  if (file_ < 0) {
    tmp_.clear();
    throw_h5("create " + temporary_name(path));
  }
  try {
    store_ = std::make_unique<ResultStore>(file_, placement_, ctx.record, opts);
  } catch (...) {
    discard();
    throw;
  }
}

CampaignFile::~CampaignFile() { discard(); }

void CampaignFile::discard() noexcept {
  store_.reset();
  if (file_ >= 0) H5Fclose(file_);
  file_ = -1;
  if (!tmp_.empty()) {
    std::error_code ec;
    fs::remove(tmp_, ec);
    tmp_.clear();
  }
}

void CampaignFile::remove_temporary() noexcept {
  if (!tmp_.empty()) ::unlink(tmp_.c_str());
  tmp_.clear();
}

void CampaignFile::write_summary(StreamedStats streamed,
                                 const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories,
                                 const sim::RunResult& nominal, const CampaignFileInfo& info) {
  store_->finish();
  const std::int64_t n_runs = store_->n_runs();
  store_.reset();  // closes the per-run datasets
  write_root_attributes(file_, ctx_, n_runs, info);
  write_input_attributes(file_, ctx_.options);
  const std::int64_t read_back = write_stats(file_, tmp_, ctx_.record, std::move(streamed));
  write_histories(file_, ctx_.options.output.history_step_s, histories);
  write_timing_attributes(file_, info.schedule, read_back);
  write_nominal_group(file_, nominal, ctx_.dims.n_bays_max);
}

void CampaignFile::commit(bool force) {
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), "flush " + tmp_);
  const hid_t f = file_;
  file_ = -1;
  check(H5Fclose(f), "close " + tmp_);
  sync_file(tmp_);
  io::h5::commit(tmp_, path_, force);
  tmp_.clear();
}

std::vector<std::string> CampaignFile::remove_stale(const std::string& path) {
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  std::string prefix = ".";  // (not "." + name: GCC 12 warns about a memcpy overlap that cannot happen)
  prefix += p.filename().string() + ".tmp.";
  const std::string mine = fs::path(temporary_name(path)).filename().string();
  std::vector<std::string> removed;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() <= prefix.size() || name.rfind(prefix, 0) != 0 || name == mine) continue;
    if (name.find_first_not_of("0123456789", prefix.size()) != std::string::npos) continue;  // .NAME.tmp.PID only
    if (fs::remove(e.path(), ec)) removed.push_back(e.path().string());
  }
  return removed;
}

// The end summary's main design values, as the finished file's /stats holds them (the statistics
// were streamed while the runs arrived: nothing is recomputed here).
std::vector<DesignValue> read_design_values(const std::string& path, const campaign::RecordLayout& layout,
                                            const sim::RunResult& nominal) {
  static const std::pair<const char*, const char*> shown[] = {
      {"peak_drive_force_N", "peak drive force"},           {"peak_drive_torque_Nm", "peak drive torque"},
      {"peak_pin_force_N", "peak rail pin force"},          {"peak_diagonal_tension_N", "peak diagonal tension"},
      {"peak_latch_energy_J", "peak latch energy"},         {"deploy_time_s", "deployment time"}};
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return {};
  auto read = [&](const std::string& ds_path) {
    double v = 0.0;
    const hid_t ds = H5Dopen2(file, ds_path.c_str(), H5P_DEFAULT);
    const herr_t e = ds < 0 ? -1 : H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v);
    if (ds >= 0) H5Dclose(ds);
    if (e < 0) throw std::runtime_error("read " + ds_path);
    return v;
  };
  std::vector<DesignValue> res;
  try {
    for (const auto& [name, label] : shown) {
      const int f = layout.find_output(name);
      if (f < 0) continue;
      const campaign::Field& field = layout.fields()[static_cast<std::size_t>(f)];
      res.push_back({label, field.units, std::get<double>(field.run->get(nominal)),
                     read(fmt::format("stats/{}/p99_865", name)), read(fmt::format("stats/{}/max", name)),
                     static_cast<std::int64_t>(read(fmt::format("stats/{}/count", name)))});
    }
  } catch (const std::exception&) {
    res.clear();  // the summary is a convenience: the file itself is complete
  }
  H5Fclose(file);
  return res;
}

std::string read_example_message(const std::string& path, std::int64_t n_runs, sim::RunStatus status) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return {};
  std::string res;
  try {
    const std::vector<std::int8_t> s = read_status(file, n_runs);
    const auto it = std::find(s.begin(), s.end(), static_cast<std::int8_t>(status));
    if (it != s.end()) {
      const auto run = static_cast<std::int64_t>(it - s.begin());
      res = fmt::format("run {}: {}", run, read_message(file, run));
    }
  } catch (const std::exception&) {
    res.clear();  // a convenience of the end summary, like read_design_values
  }
  H5Fclose(file);
  return res;
}

}  // namespace truss::results
