// The folding truss mast of docs/model.md §1 as a Simbody multibody system, built from its parts
// and joints (not from the reduced equations of docs/model.md §3):
//
//   frame k = 0..n     a triangle (side b_f, mass m_f) on a Slider along the mast axis (Ground y):
//                      the three lead screws keep it level and centred
//   tip                a body of mass m_tip welded on frame n
//   bay i = 1..n       per longeron: a lower strut on a Pin at a vertex of frame i-1 (angle theta
//                      from the outward radial), an upper strut on a Pin at the mid hinge (relative
//                      angle psi), closed on frame i by two constraints (below);
//                      six diagonals, tension-only springs from each vertex of frame i-1 to the
//                      next vertex of frame i (Force::Custom)
//   rail               per pin: a PointInPlane constraint of the hinge on the rail plane through
//                      the line y = y_l - cot(beta) (x - x_l) (x: hinge offset from the longeron
//                      line), enabled from the pin's rail entry to its latch
//
// Loop closure. The upper strut's end must sit at the upper frame's vertex. Written as that point
// coincidence, the closure is singular in the stowed stack (D = 0: both struts lie on one radial
// line and a second branch, frames together and struts swinging, crosses the deploying one), which
// is where every bay starts. The deploying branch is the symmetric fold, psi = pi - 2 theta
// (CoordinateCoupler "fold"); with it the radial part of the coincidence holds identically, and
// the axial part is "the strut's end lies in the frame's plane" (PointInPlane "closure"). The two
// have a full-rank Jacobian everywhere from folded (theta = 0) to straight (theta = pi/2), and on
// the symmetric branch they are the same holonomic constraint as the coincidence.
//
// Longerons. The three longerons of a bay move alike (the frames only slide), so they can be
// modelled once with 3x the strut mass and inertia and the pin force shared by three pins
// (`longerons_per_bay = 1`), or all three (`= 3`; the three rails of a bay are then redundant
// constraints, which Simbody solves in the least-squares sense).
#pragma once
#include <vector>

#include "Simbody.h"
#include "scene.hpp"

namespace mastcheck {

struct Longeron {
  SimTK::MobilizedBody::Pin lower, upper;   // q: theta (lower), psi (upper relative to lower)
  SimTK::Constraint::CoordinateCoupler fold;
  SimTK::Constraint::PointInPlane closure, rail;
};

// What the screws do to the driven frame (model.md §2 "Drive modes"); read by the drive force.
struct DriveCommand {
  int driven_frame = 0;
  DriveMode mode = DriveMode::velocity;
  double stall_force_N = 0;        // torque: 2 pi M_d / h; motor: 2 pi M_stall / h
  double damping_N_s_per_m = 0;    // motor: (2 pi / h)^2 M_stall / omega_0
};

class MastSystem {
 public:
  MastSystem(const MastScene& scene, int longerons_per_bay);
  MastSystem(const MastSystem&) = delete;
  MastSystem& operator=(const MastSystem&) = delete;

  const MastScene& getScene() const { return scene_; }
  int getLongeronsPerBay() const { return longerons_; }
  double getRailNormalScale() const { return rail_scale_; }  // sqrt(1 + cot^2 beta) = 1 / sin(beta)
  DriveCommand& updDrive() { return drive_; }
  const DriveCommand& getDrive() const { return drive_; }

  SimTK::MultibodySystem& updSystem() { return system_; }
  const SimTK::MultibodySystem& getSystem() const { return system_; }
  const SimTK::SimbodyMatterSubsystem& getMatter() const { return matter_; }
  const SimTK::MobilizedBody::Slider& getFrame(int k) const { return frames_[k]; }
  const Longeron& getLongeron(int bay, int j) const { return bays_[bay][j]; }

  // Hinge of longeron j of bay i: offset x from the longeron line (m) and the rail function
  // f = y - y_l + cot(beta) (x - x_l) (m), docs/model.md §1.
  double calcHingeOffset(const SimTK::State& s, int bay, int j = 0) const;
  double calcRailFunction(const SimTK::State& s, int bay, int j = 0) const;
  // Tension in one diagonal of bay i (N), 0 when slack.
  double calcDiagonalTension(const SimTK::State& s, int bay) const;
  // Ends the construction (event handlers must be added before) and returns the stowed state:
  // every frame at height 0, every bay folded (theta = 0, psi = pi), at rest.
  SimTK::State makeStowedState();

 private:
  void addFrames();
  void addBay(int bay);
  void addForces();
  SimTK::Vec3 calcVertex(int j) const;  // vertex j of a frame, in the frame's body coordinates

  MastScene scene_;
  int longerons_;
  double rail_scale_;
  DriveCommand drive_;
  SimTK::MultibodySystem system_;
  SimTK::SimbodyMatterSubsystem matter_;
  SimTK::GeneralForceSubsystem forces_;
  std::vector<SimTK::MobilizedBody::Slider> frames_;
  std::vector<std::vector<Longeron>> bays_;  // bays_[i], i = 1..n (bays_[0] empty)
};

}  // namespace mastcheck
