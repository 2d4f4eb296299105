// Where a campaign declares the motor its runs are judged against (the root attribute
// motor_declared_by, docs/hdf5-schema.md). The report judges the motorisation only of a declared
// motor: a scene file's [drive] motor keys are defaults shared by the campaigns that use it, so
// they declare nothing; a campaign declares its motor by its own lines ([scene.drive], overrides,
// --set of drive.stall_torque_Nm or drive.no_load_speed_rad_per_s), by dispersing or sweeping one
// of them, or by driving with the motor itself (drive.mode = "motor").
#pragma once
#include <string>

namespace truss::campaign {

struct CampaignOptions;

// "" when the campaign declares no motor; else what declares it: the setting's origin
// ("campaign.toml:12", "--set drive.stall_torque_Nm=0.03"), "[[dispersion]] drive.stall_torque_Nm
// (campaign.toml:30)", "[sweep] drive.stall_torque_Nm" or "drive.mode = \"motor\"".
std::string find_motor_declared_by(const CampaignOptions& c);

}  // namespace truss::campaign
