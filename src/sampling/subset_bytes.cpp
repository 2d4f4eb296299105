// subset_bytes.cpp — byte formats of subset simulation: a round's plan (the per-round blob every
// rank reads) and the whole state (SubsetSimulation::save/load). Native little-endian integers and
// IEEE-754 doubles (x86-64, AArch64), each format opened by a 4-byte tag with its version; a
// reader refuses a cut, an overlong or an inconsistent buffer before allocating for it.
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "sampling/byte_image.hpp"
#include "sampling/subset_simulation.hpp"

namespace truss::sampling {

namespace {

constexpr std::uint32_t kRoundTag = 0x31525353;  // "SSR1"
constexpr std::uint32_t kStateTag = 0x32535353;  // "SSS2"

using ByteWriter = detail::ByteWriter;
using ByteReader = detail::ByteReader;

void put_level(ByteWriter& w, const SubsetLevel& l) {
  for (double v : {l.threshold, l.probability, l.gamma, l.cov, l.scale}) w.put(v);
  for (std::int64_t v : {l.runs, l.steps, l.moved, l.unusable, l.ties}) w.put(v);
}

SubsetLevel get_level(ByteReader& r) {
  SubsetLevel l;
  for (double* v : {&l.threshold, &l.probability, &l.gamma, &l.cov, &l.scale}) *v = r.get<double>();
  for (std::int64_t* v : {&l.runs, &l.steps, &l.moved, &l.unusable, &l.ties}) *v = r.get<std::int64_t>();
  return l;
}

}  // namespace

std::string SubsetRound::encode() const {
  ByteWriter w;
  w.put(kRoundTag);
  w.put(index);
  w.put(first_evaluation);
  w.put(static_cast<std::int32_t>(level));
  w.put(static_cast<std::int32_t>(step));
  w.put(threshold);
  w.put(n_points);
  if (step > 0) {
    w.out.reserve(w.out.size() + 2 * sizeof(std::uint64_t) + 8 * (chains.size() + z.size()));  // i64s, doubles
    w.put_all(chains);
    w.put_all(z);
  }
  return std::move(w.out);
}

SubsetRound SubsetRound::decode(std::string_view bytes, int dims) {
  ByteReader r{bytes, "subset round"};
  if (r.get<std::uint32_t>() != kRoundTag) throw std::runtime_error("subset round: not an encoded round (tag)");
  SubsetRound s;
  s.index = r.get<std::int64_t>();
  s.first_evaluation = r.get<std::int64_t>();
  s.level = r.get<std::int32_t>();
  s.step = r.get<std::int32_t>();
  s.threshold = r.get<double>();
  s.n_points = r.get<std::int64_t>();
  if (s.step > 0) {
    s.chains = r.get_all<std::int64_t>();
    s.z = r.get_all<double>();
  }
  r.expect_end();
  const bool sizes = s.step == 0 || (static_cast<std::int64_t>(s.chains.size()) == s.n_points &&
                                     s.z.size() == s.chains.size() * static_cast<std::size_t>(dims));
  if (s.index < 0 || s.first_evaluation < 0 || s.level < 0 || s.step < 0 || s.n_points < 0 || !sizes ||
      (s.step == 0) != (s.level == 0))
    throw std::runtime_error(fmt::format("subset round: inconsistent plan (level {}, step {}, {} points, {} chains, "
                                         "{} coordinates for {} dimensions)", s.level, s.step, s.n_points,
                                         s.chains.size(), s.z.size(), dims));
  return s;
}

std::string SubsetSimulation::save() const {
  ByteWriter w;
  w.put(kStateTag);
  w.put(static_cast<std::int32_t>(opt_.dims));
  w.put(static_cast<std::int32_t>(opt_.proposal));
  w.put(opt_.n_per_level);
  w.put(opt_.p0);
  w.put(static_cast<std::int32_t>(opt_.max_levels));
  w.put(opt_.proposal_half_width);
  w.put(opt_.seed);
  w.put(static_cast<std::int32_t>(status_));
  w.put_all(std::vector<char>(message_.begin(), message_.end()));
  const std::string round = round_.encode();
  w.put_all(std::vector<char>(round.begin(), round.end()));
  w.put(evaluations_);
  w.put(rounds_);
  w.put(domain_);
  w.put(static_cast<std::uint64_t>(samples_.size()));
  for (const Sample& s : samples_) {
    w.put(s.margin);
    for (std::int64_t v : {s.chain, s.step, s.evaluation, s.root}) w.put(v);
  }
  w.put_all(z_);
  w.put_all(head_);
  w.put(static_cast<std::uint64_t>(levels_.size()));
  for (const SubsetLevel& l : levels_) put_level(w, l);
  w.put_all(lineage_);
  w.put(scale_);
  w.put_all(spread0_);
  w.put(static_cast<std::uint64_t>(unit_terms_.size()));
  for (const auto& v : unit_terms_) w.put_all(v);
  w.put(static_cast<std::uint64_t>(parents_.size()));
  for (const auto& v : parents_) w.put_all(v);
  return std::move(w.out);
}

SubsetSimulation SubsetSimulation::load(std::string_view bytes) {
  ByteReader r{bytes, "subset state"};
  if (r.get<std::uint32_t>() != kStateTag) throw std::runtime_error("subset state: not a saved state (tag)");
  SubsetSimulation s;
  s.opt_.dims = r.get<std::int32_t>();
  const auto proposal = r.get<std::int32_t>();
  if (proposal < 0 || proposal > static_cast<int>(SubsetProposal::adaptive_conditional))
    throw std::runtime_error(fmt::format("subset state: proposal {}", proposal));
  s.opt_.proposal = static_cast<SubsetProposal>(proposal);
  s.opt_.n_per_level = r.get<std::int64_t>();
  s.opt_.p0 = r.get<double>();
  s.opt_.max_levels = r.get<std::int32_t>();
  s.opt_.proposal_half_width = r.get<double>();
  s.opt_.seed = r.get<std::uint64_t>();
  if (const std::string why = s.opt_.validate(); !why.empty()) throw std::runtime_error("subset state: " + why);
  const auto status = r.get<std::int32_t>();
  if (status < 0 || status > static_cast<int>(SubsetStatus::chains_stuck))
    throw std::runtime_error(fmt::format("subset state: status {}", status));
  s.status_ = static_cast<SubsetStatus>(status);
  const auto message = r.get_all<char>();
  s.message_.assign(message.begin(), message.end());
  const auto round = r.get_all<char>();
  s.round_ = SubsetRound::decode(std::string_view(round.data(), round.size()), s.opt_.dims);
  s.evaluations_ = r.get<std::int64_t>();
  s.rounds_ = r.get<std::int64_t>();
  s.domain_ = r.get<double>();
  s.samples_.resize(r.get_count(40));
  for (Sample& x : s.samples_) {
    x.margin = r.get<double>();
    for (std::int64_t* v : {&x.chain, &x.step, &x.evaluation, &x.root}) *v = r.get<std::int64_t>();
  }
  s.z_ = r.get_all<double>();
  s.head_ = r.get_all<std::int64_t>();
  s.levels_.resize(r.get_count(80));
  for (SubsetLevel& l : s.levels_) l = get_level(r);
  s.lineage_ = r.get_all<double>();
  s.scale_ = r.get<double>();
  s.spread0_ = r.get_all<double>();
  s.unit_terms_.resize(r.get_count(8));
  for (auto& v : s.unit_terms_) v = r.get_all<double>();
  s.parents_.resize(r.get_count(8));
  for (auto& v : s.parents_) v = r.get_all<std::int64_t>();
  r.expect_end();
  const auto n = static_cast<std::int64_t>(s.samples_.size());
  bool ok = s.z_.size() == s.samples_.size() * static_cast<std::size_t>(s.opt_.dims) && !s.levels_.empty() &&
            n <= s.opt_.n_per_level &&
            (s.head_.empty() || static_cast<std::int64_t>(s.head_.size()) == s.opt_.n_chains());
  const auto chains = s.head_.empty() ? n : static_cast<std::int64_t>(s.head_.size());  // level 0: one per sample
  for (const Sample& x : s.samples_) ok = ok && x.chain >= 0 && x.chain < chains;
  for (std::int64_t h : s.head_) ok = ok && h >= 0 && h < n;
  for (const Sample& x : s.samples_) ok = ok && x.root >= 0 && x.root < s.opt_.n_per_level;
  ok = ok && (s.lineage_.empty() || static_cast<std::int64_t>(s.lineage_.size()) == s.opt_.n_per_level);
  const bool spread = s.opt_.proposal != SubsetProposal::adaptive_conditional || s.levels_.size() == 1;
  ok = ok && s.scale_ > 0.0 && std::isfinite(s.scale_) &&
       (spread ? s.spread0_.empty() : static_cast<int>(s.spread0_.size()) == s.opt_.dims);
  ok = ok && s.parents_.size() == s.levels_.size() && s.unit_terms_.size() <= s.levels_.size();
  const auto units = [&](std::size_t k) { return k == 0 ? s.opt_.n_per_level : s.opt_.n_chains(); };
  for (std::size_t k = 0; ok && k < s.parents_.size(); ++k) {
    ok = k == 0 ? s.parents_[k].empty() : static_cast<std::int64_t>(s.parents_[k].size()) == s.opt_.n_chains();
    for (std::int64_t a : s.parents_[k]) ok = ok && a >= 0 && a < units(k - 1);
  }
  for (std::size_t k = 0; ok && k < s.unit_terms_.size(); ++k)
    ok = static_cast<std::int64_t>(s.unit_terms_[k].size()) == units(k);
  if (!ok) throw std::runtime_error(fmt::format("subset state: inconsistent ({} samples, {} coordinates, {} chains)",
                                                n, s.z_.size(), s.head_.size()));
  return s;
}

}  // namespace truss::sampling
