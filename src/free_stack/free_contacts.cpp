#include "free_stack/free_contacts.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <vector>

#include "model/bay.hpp"
#include "model/contacts.hpp"

namespace truss::stages {

using namespace truss::model;

void ContactLayout::expand_clusters(const double* cluster, double* frame) const {
  const int C = static_cast<int>(starts.size());
  for (int c = 0; c < C; ++c) {
    const int q = c + 1 < C ? starts[static_cast<std::size_t>(c + 1)] : frames;
    for (int k = starts[static_cast<std::size_t>(c)]; k < q; ++k) frame[k] = cluster[c];
  }
}

ContactWatch calc_contact_watch(const MastParams& mast, const ContactLayout& layout, int lo, int m, const double* ys,
                                const double* vs, int first, const FrameSystem& sys, const double* a) {
  ContactWatch w;
  if (!layout.enabled) return w;
  auto y = [&](int k) { return ys[k - first]; };
  // Landing: every open contact at a cluster bottom (the lowest one rests on the block's top).
  double closing = 0.0;
  for (int s : layout.starts) {
    const int i = lo + s;
    if (i < 1 || i > m || (i == m && !layout.driven_contact)) continue;  // frame 0: no contact below; bay m deploys
    const double D = y(i) - y(i - 1), g = -D - ContactLayout::kGapTolerance * mast.bay(i).strut_length_m;
    if (w.landing_bay == 0 || g > w.landing_g) { w.landing_g = g; w.landing_bay = i; }
    const double rate = vs[i - first] - (i - 1 >= lo ? vs[i - 1 - first] : 0.0);
    if (D <= 0.0 && rate < 0.0 && (w.touching_bay == 0 || rate < closing)) { w.touching_bay = i; closing = rate; }
  }
  // Lift-off of the resting block's top frame lo - 1 (model/contacts.hpp).
  double lambda_min = __builtin_inf();
  if (layout.block_liftable) {
    const BayParams& b = mast.bay(lo);
    const double D = y(lo) - y(lo - 1), dD = vs[lo - first];
    const double b2 = calc_diagonal_offset_sq_m2(mast.frame(lo - 1), mast.frame(lo));
    const double coupling = calc_regular_coupling_mass_kg(b) - 2.0 * calc_G(b, D);
    lambda_min = coupling * a[0] - (calc_dG_dD(b, D) * dD * dD + calc_bay_dU_dD_N(b, b2, D));
    w.lift_off_bay = lo - 1;
  }
  if (layout.reduces()) {
    const int N = layout.frames;
    const Eigen::VectorXd F = (sys.velocity_terms + sys.spring_forces).head(N);
    int at = -1;
    const double lam = calc_min_cluster_contact_force_N(sys.diag.head(N), sys.sub.head(N), F,
                                                        Eigen::Map<const Eigen::VectorXd>(a, N), layout.starts, at);
    if (at >= 0 && lam < lambda_min) { lambda_min = lam; w.lift_off_bay = lo + at; }
  }
  if (w.lift_off_bay > 0) w.lift_off_g = -lambda_min - ContactLayout::kForceTolerance_N;
  return w;
}

ContactWatch calc_contact_watch(const PhaseModel& phase, const ContactLayout& layout, int lo, const double* q,
                                const double* qdot, const double* ys, const double* vs, ContactWatchWork& work) {
  PhaseScratch& sys = work.sys;
  std::vector<double>& acc = work.acc;
  std::vector<double>& a = work.a;
  acc.resize(static_cast<std::size_t>(phase.dof()));
  a.resize(static_cast<std::size_t>(layout.frames));
  phase.calc_motion(q, qdot, acc.data(), sys);
  layout.expand(acc.data(), a.data());
  const PhaseContext& ctx = phase.context();
  return calc_contact_watch(*ctx.mast, layout, lo, ctx.bay, ys, vs, std::max(lo - 1, 0), sys, a.data());
}

}  // namespace truss::stages
