#include "campaign/motor_declared.hpp"

#include <array>
#include <string_view>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "campaign/design_axis.hpp"

namespace truss::campaign {

namespace {
constexpr std::array<std::string_view, 2> kMotorKeys = {"drive.stall_torque_Nm", "drive.no_load_speed_rad_per_s"};

std::string_view bare(std::string_view key) {
  if (key.substr(0, 6) == "scene.") key.remove_prefix(6);  // --set scene.drive.x = --set drive.x
  return key;
}
bool is_motor_key(std::string_view key) {
  for (auto k : kMotorKeys)
    if (bare(key) == k) return true;
  return false;
}
}  // namespace

std::string find_motor_declared_by(const CampaignOptions& c) {
  if (c.base.drive.mode == model::DriveMode::motor) return "drive.mode = \"motor\"";
  for (auto key : kMotorKeys)  // the stall torque first: it is the motor's size
    for (const auto& s : c.scene_settings)
      if (bare(std::string_view(s.assignment).substr(0, s.assignment.find('='))) == key)
        return s.where.empty() ? "--set " + s.assignment : s.where;
  for (const auto& d : c.dispersions)
    if (is_motor_key(d.key)) return fmt::format("[[dispersion]] {} (line {})", d.key, d.line);
  if (const DesignAxis* a = find_design_axis(c); a && a->variable == SweepVariable::nominal && is_motor_key(a->key))
    return fmt::format("[sweep] {}", a->key);
  return "";
}

}  // namespace truss::campaign
