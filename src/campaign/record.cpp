#include "campaign/record.hpp"

#include <limits>

#include <fmt/format.h>

#include "campaign/design_axis.hpp"
#include "util/bytes.hpp"

namespace truss::campaign {

std::size_t value_bytes(ValueType t) { return t == ValueType::status ? 1 : 8; }

const char* group_path(Group g) {
  switch (g) {
    case Group::runs: return "runs";
    case Group::bays: return "runs/bays";
    case Group::inputs: return "runs/inputs";
    case Group::timing: return "timing";
  }
  return "runs";
}

void RecordLayout::add(Field f) {
  f.offset = fixed_bytes_;
  fixed_bytes_ += f.bytes();
  fields_.push_back(std::move(f));
}

RecordLayout::RecordLayout(const CampaignOptions& c, const DimensionLayout& dims)
    : n_bays_max_(dims.n_bays_max), n_inputs_(dims.total) {
  add({"run_index", Group::runs, ValueType::i64, 1, Scale::none, "1"});
  add({"round", Group::runs, ValueType::i64, 1, Scale::none, "1"});
  add({"status", Group::runs, ValueType::status, 1, Scale::none, "1"});
  add({"rank", Group::timing, ValueType::i64, 1, Scale::none, "1"});
  add({"run_wall_time_s", Group::timing, ValueType::f64, 1, Scale::none, "s"});
  for (const auto& f : io::run_result_fields()) {  // float64 outputs first, then int64 (the file's order)
    if (std::string_view(f.name) == "wall_time_s" || !f.f64) continue;
    Field o{f.name, Group::runs, ValueType::f64, 1, Scale::none, f.units, true};
    o.run = &f;
    add(std::move(o));
  }
  for (const auto& f : io::run_result_fields()) {
    if (!f.get_i64) continue;
    Field o{f.name, Group::runs, ValueType::i64, 1, Scale::none, f.units};
    o.run = &f;
    add(std::move(o));
  }
  for (const auto& f : io::bay_result_fields()) {
    if (!f.f64) continue;  // bay: the column index
    Field o{f.name, Group::bays, ValueType::f64, n_bays_max_, Scale::bay, f.units, true};
    o.bay = &f;
    add(std::move(o));
  }
  for (std::size_t k = 0; k < c.dispersions.size(); ++k) {
    const DispersionOptions& d = c.dispersions[k];
    const Scale s = d.per == Per::run ? Scale::none : d.per == Per::bay ? Scale::bay : Scale::frame;
    Field in{d.key, Group::inputs, ValueType::f64, dims.count[k], s, find_key_units(d.key)};
    in.dispersion = static_cast<int>(k);
    add(std::move(in));
  }
  if (find_design_axis(c) != nullptr) {  // a sweep's design value (the run's last input, calc_run_inputs)
    Field in{"sweep_value", Group::runs, ValueType::f64, 1, Scale::none, sweep_variable_units(c)};
    in.dispersion = static_cast<int>(c.dispersions.size());
    add(std::move(in));
  }
  blank_.assign(fixed_bytes_, '\0');
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Field& f : fields_)
    if (f.type == ValueType::f64)
      for (int k = 0; k < f.width; ++k) util::put_at(blank_.data() + f.offset + 8 * static_cast<std::size_t>(k), nan);
}

int RecordLayout::find_output(const std::string& name) const {
  for (std::size_t i = 0; i < fields_.size(); ++i)
    if (fields_[i].run && fields_[i].type == ValueType::f64 && fields_[i].name == name) return static_cast<int>(i);
  return -1;
}

std::string RecordLayout::check(std::string_view record) const {
  if (record.size() < fixed_bytes_ + 4)
    return fmt::format("a record of {} bytes, shorter than the {} of this campaign's", record.size(), fixed_bytes_ + 4);
  const auto message = util::get_at<std::uint32_t>(record.data() + fixed_bytes_);
  if (record.size() != fixed_bytes_ + 4 + message)
    return fmt::format("a record of {} bytes, where its message makes it {}", record.size(),
                       fixed_bytes_ + 4 + std::size_t{message});
  const std::int8_t s = RecordView(record, *this).status();
  if (s < 0 || s >= sim::kRunStatusCount) return fmt::format("a record with an unknown status {}", s);
  return {};
}

std::int8_t RecordView::status() const { return static_cast<std::int8_t>(*field_data(RecordLayout::kStatus)); }

std::string_view RecordView::message() const {
  const std::size_t at = L_->fixed_bytes();
  return b_.substr(at + 4, util::get_at<std::uint32_t>(b_.data() + at));
}

double RecordView::f64(std::size_t field, int k) const {
  return util::get_at<double>(field_data(field) + 8 * static_cast<std::size_t>(k));
}

std::int64_t RecordView::i64(std::size_t field, int k) const {
  return util::get_at<std::int64_t>(field_data(field) + 8 * static_cast<std::size_t>(k));
}

RecordWriter::RecordWriter(const RecordLayout& layout, std::string& out) : L_(layout), out_(out), start_(out.size()) {
  out_.append(L_.blank_fixed_part());
}

char* RecordWriter::at(std::size_t field, int k) {
  return out_.data() + start_ + L_.fields()[field].offset + 8 * static_cast<std::size_t>(k);
}

void RecordWriter::set_i64(std::size_t field, std::int64_t v, int k) { util::put_at(at(field, k), v); }
void RecordWriter::set_f64(std::size_t field, double v, int k) { util::put_at(at(field, k), v); }
void RecordWriter::set_status(sim::RunStatus s) { *at(RecordLayout::kStatus, 0) = static_cast<char>(s); }

void RecordWriter::finish(std::string_view message) {
  util::put(out_, static_cast<std::uint32_t>(message.size()));
  out_.append(message);
}

void append_record(const RecordLayout& layout, const RecordHead& head, const sim::RunResult& r,
                   const std::vector<double>& inputs, std::string& out) {
  RecordWriter w(layout, out);
  w.set_i64(RecordLayout::kRun, head.run);
  w.set_i64(RecordLayout::kRound, head.round);
  w.set_status(r.status);
  w.set_i64(RecordLayout::kRank, head.rank);
  w.set_f64(RecordLayout::kWallTime, r.wall_time_s);
  const auto& fields = layout.fields();
  const std::size_t n_bays = std::min(r.bays.size(), static_cast<std::size_t>(layout.n_bays_max()));
  for (std::size_t i = RecordLayout::kWallTime + 1; i < fields.size(); ++i) {
    const Field& f = fields[i];
    if (f.run && f.run->f64) w.set_f64(i, r.*(f.run->f64));
    else if (f.run) w.set_i64(i, f.run->get_i64(r));
    else if (f.bay) {
      // Pointer and member held in locals: the stores through char* may alias anything reloaded.
      char* p = w.at(i, 0);
      const auto member = f.bay->f64;
      for (std::size_t b = 0; b < n_bays; ++b) util::put_at(p + 8 * b, r.bays[b].*member);
    }
  }
  std::size_t k = 0;  // the inputs: each dispersion's values in DimensionLayout order, the fields' order
  for (std::size_t i = 0; i < fields.size(); ++i)
    if (fields[i].dispersion >= 0)
      for (int j = 0; j < fields[i].width; ++j) w.set_f64(i, inputs[k++], j);
  w.finish(r.message);
}

}  // namespace truss::campaign
