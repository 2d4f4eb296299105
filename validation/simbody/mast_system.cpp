// Builds the mast of mast_system.hpp. Geometry: the mast axis is Ground y; vertex j of a frame lies
// at radius r_f = b_f / sqrt(3) in the direction e_r(j) = (cos phi_j, 0, sin phi_j), phi_j = 2 pi j/3;
// each longeron moves in the plane of e_r(j) and y.
#include "mast_system.hpp"

#include <cmath>

namespace mastcheck {
using namespace SimTK;

namespace {

// Tension-only springs between frame vertices (docs/model.md §1, "Diagonals"): tension
// K (L - l_0) while L > l_0, else 0; potential K (L - l_0)^2 / 2 each.
struct Diagonal {
  MobilizedBody lower, upper;
  Vec3 lower_point, upper_point;  // in the frames' body coordinates
};

class DiagonalSprings : public Force::Custom::Implementation {
 public:
  DiagonalSprings(std::vector<Diagonal> diagonals, double stiffness_N_per_m, double free_length_m)
      : diagonals_(std::move(diagonals)), k_(stiffness_N_per_m), l0_(free_length_m) {}
  void calcForce(const State& s, Vector_<SpatialVec>& body_forces, Vector_<Vec3>&, Vector&) const override {
    for (const Diagonal& d : diagonals_) {
      const Vec3 a = d.lower.findStationLocationInGround(s, d.lower_point);
      const Vec3 b = d.upper.findStationLocationInGround(s, d.upper_point);
      const Vec3 ab = b - a;
      const Real length = ab.norm();
      if (length <= l0_) continue;
      const Vec3 pull = k_ * (length - l0_) / length * ab;  // on the lower end, towards the upper
      d.lower.applyForceToBodyPoint(s, d.lower_point, pull, body_forces);
      d.upper.applyForceToBodyPoint(s, d.upper_point, -pull, body_forces);
    }
  }
  Real calcPotentialEnergy(const State& s) const override {
    Real energy = 0;
    for (const Diagonal& d : diagonals_) {
      const Real length = (d.upper.findStationLocationInGround(s, d.upper_point) -
                           d.lower.findStationLocationInGround(s, d.lower_point)).norm();
      if (length > l0_) energy += 0.5 * k_ * square(length - l0_);
    }
    return energy;
  }

 private:
  std::vector<Diagonal> diagonals_;
  double k_, l0_;
};

// The screws' axial force on the driven frame in torque and motor modes (model.md §2):
// F = 2 pi M_d / h, or F = (2 pi / h) M_stall (1 - omega / omega_0) with omega = 2 pi y' / h.
// In velocity mode the driven frame's speed is prescribed instead (a velocity lock).
class ScrewDrive : public Force::Custom::Implementation {
 public:
  ScrewDrive(const MastSystem& mast) : mast_(mast) {}
  void calcForce(const State& s, Vector_<SpatialVec>&, Vector_<Vec3>&, Vector& mobility_forces) const override {
    const DriveCommand& d = mast_.getDrive();
    if (d.mode == DriveMode::velocity) return;
    const MobilizedBody::Slider& frame = mast_.getFrame(d.driven_frame);
    const Real force = d.stall_force_N - d.damping_N_s_per_m * frame.getOneU(s, MobilizerUIndex(0));
    frame.applyOneMobilityForce(s, MobilizerUIndex(0), force, mobility_forces);
  }
  Real calcPotentialEnergy(const State&) const override { return 0; }

 private:
  const MastSystem& mast_;
};

// Body frame aligned with Ground, sliding along Ground y (a Slider moves along its F/M frames' x).
const Transform kSlideAlongY(Rotation(Pi / 2, ZAxis), Vec3(0));

}  // namespace

MastSystem::MastSystem(const MastScene& scene, int longerons_per_bay)
    : scene_(scene), longerons_(longerons_per_bay), matter_(system_), forces_(system_) {
  const double cot_beta = 1 / std::tan(scene_.rail_beta_deg * Pi / 180);
  rail_scale_ = std::sqrt(1 + cot_beta * cot_beta);
  addFrames();
  bays_.resize(scene_.n_bays + 1);
  for (int i = 1; i <= scene_.n_bays; ++i) addBay(i);
  addForces();
  const double two_pi_over_lead = 2 * Pi / scene_.screw_lead_m;
  drive_.mode = scene_.drive;
  drive_.driven_frame = scene_.n_bays;
  if (scene_.drive == DriveMode::torque) drive_.stall_force_N = two_pi_over_lead * scene_.torque_Nm;
  if (scene_.drive == DriveMode::motor) {
    drive_.stall_force_N = two_pi_over_lead * scene_.stall_torque_Nm;
    drive_.damping_N_s_per_m = two_pi_over_lead * two_pi_over_lead * scene_.stall_torque_Nm /
                               scene_.no_load_speed_rad_per_s;
  }
  system_.setUseUniformBackground(true);
}

Vec3 MastSystem::calcVertex(int j) const {
  const double phi = 2 * Pi * j / 3, radius = scene_.frame_side_m / std::sqrt(3.0);
  return radius * Vec3(std::cos(phi), 0, std::sin(phi));
}

void MastSystem::addFrames() {
  const double m = scene_.frame_mass_kg, r2 = square(scene_.frame_side_m) / 3;
  // Only the frames' axial translation moves; the inertia (a ring) is for completeness.
  const Body::Rigid frame_body(MassProperties(m, Vec3(0), Inertia(m * r2 / 2, m * r2, m * r2 / 2)));
  for (int k = 0; k <= scene_.n_bays; ++k)
    frames_.emplace_back(matter_.updGround(), kSlideAlongY, frame_body, kSlideAlongY);
  const double m_tip = scene_.calcTipMass();
  if (m_tip > 0) {
    const Body::Rigid tip_body(MassProperties(m_tip, Vec3(0), Inertia(m_tip * r2 / 2, m_tip * r2, m_tip * r2 / 2)));
    MobilizedBody::Weld(frames_.back(), Transform(), tip_body, Transform());
  }
}

void MastSystem::addBay(int bay) {
  const double l = scene_.strut_length_m, share = 3.0 / longerons_;
  const double m = share * scene_.strut_mass_kg, jc = share * scene_.calcStrutInertia();
  // A strut along its body x from its pin (x = 0) to its other end (x = l); J_c about the
  // centroidal axes across it (only the one along the pin axis, z, moves).
  const Inertia about_centroid(Vec3(0, jc, jc));
  const Vec3 centroid(l / 2, 0, 0);
  const Body::Rigid strut_body(MassProperties(m, centroid, about_centroid.shiftFromMassCenter(centroid, m)));
  const double cot_beta = 1 / std::tan(scene_.rail_beta_deg * Pi / 180);
  const double r_f = scene_.frame_side_m / std::sqrt(3.0);
  for (int j = 0; j < longerons_; ++j) {
    const double phi = 2 * Pi * j / 3;
    const Vec3 e_r(std::cos(phi), 0, std::sin(phi));
    Longeron lg;
    // Pin frame: x radial outward, y along the mast, z = x cross y (the hinge axis).
    const Transform at_vertex(Rotation(-phi, YAxis), calcVertex(j));
    lg.lower = MobilizedBody::Pin(frames_[bay - 1], at_vertex, strut_body, Transform());
    lg.upper = MobilizedBody::Pin(lg.lower, Transform(Vec3(l, 0, 0)), strut_body, Transform());
    // Symmetric fold: 2 theta + psi - pi = 0.
    const std::vector<MobilizedBodyIndex> coupled = {lg.lower.getMobilizedBodyIndex(),
                                                     lg.upper.getMobilizedBodyIndex()};
    const std::vector<MobilizerQIndex> coordinate = {MobilizerQIndex(0), MobilizerQIndex(0)};
    lg.fold = Constraint::CoordinateCoupler(matter_, new Function::Linear(Vector(Vec3(2, 1, -Pi))), coupled,
                                            coordinate);
    // The upper strut's end lies in the plane of frame `bay` (its vertex, given the fold).
    lg.closure = Constraint::PointInPlane(frames_[bay], UnitVec3(YAxis), 0, lg.upper, Vec3(l, 0, 0));
    // Rail: f = y - y_l + cot(beta) (r - r_f - x_l) = 0, as n . p = h with the unit normal n.
    const Vec3 normal = (Vec3(0, 1, 0) + cot_beta * e_r) / rail_scale_;
    const double height = (scene_.rail_y_m + cot_beta * (r_f + scene_.rail_x_m)) / rail_scale_;
    lg.rail = Constraint::PointInPlane(matter_.updGround(), UnitVec3(normal), height, lg.lower, Vec3(l, 0, 0));
    lg.rail.setDisabledByDefault(true);
    bays_[bay].push_back(lg);
  }
}

void MastSystem::addForces() {
  std::vector<Diagonal> diagonals;
  for (int bay = 1; bay <= scene_.n_bays; ++bay)
    for (int a = 0; a < 3; ++a) {  // two crossed diagonals on the face between vertices a and b
      const int b = (a + 1) % 3;
      diagonals.push_back({frames_[bay - 1], frames_[bay], calcVertex(a), calcVertex(b)});
      diagonals.push_back({frames_[bay - 1], frames_[bay], calcVertex(b), calcVertex(a)});
    }
  Force::Custom(forces_, new DiagonalSprings(std::move(diagonals), scene_.diagonal_stiffness_N_per_m,
                                             scene_.diagonal_free_length_m));
  Force::Custom(forces_, new ScrewDrive(*this));
}

double MastSystem::calcHingeOffset(const State& s, int bay, int j) const {
  const double phi = 2 * Pi * j / 3;
  const Vec3 hinge = bays_[bay][j].lower.findStationLocationInGround(s, Vec3(scene_.strut_length_m, 0, 0));
  return hinge[0] * std::cos(phi) + hinge[2] * std::sin(phi) - scene_.frame_side_m / std::sqrt(3.0);
}

double MastSystem::calcRailFunction(const State& s, int bay, int j) const {
  const double cot_beta = 1 / std::tan(scene_.rail_beta_deg * Pi / 180);
  const Vec3 hinge = bays_[bay][j].lower.findStationLocationInGround(s, Vec3(scene_.strut_length_m, 0, 0));
  return hinge[1] - scene_.rail_y_m + cot_beta * (calcHingeOffset(s, bay, j) - scene_.rail_x_m);
}

double MastSystem::calcDiagonalTension(const State& s, int bay) const {
  const Vec3 a = frames_[bay - 1].findStationLocationInGround(s, calcVertex(0));
  const Vec3 b = frames_[bay].findStationLocationInGround(s, calcVertex(1));
  return std::max(0.0, scene_.diagonal_stiffness_N_per_m * ((b - a).norm() - scene_.diagonal_free_length_m));
}

State MastSystem::makeStowedState() {
  system_.realizeTopology();
  State s = system_.getDefaultState();
  for (int bay = 1; bay <= scene_.n_bays; ++bay)
    for (const Longeron& lg : bays_[bay]) {
      lg.lower.setOneQ(s, MobilizerQIndex(0), 0);
      lg.upper.setOneQ(s, MobilizerQIndex(0), Pi);
    }
  return s;
}

}  // namespace mastcheck
