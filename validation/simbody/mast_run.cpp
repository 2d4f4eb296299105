// The deployment stages on the Simbody mast (see mast_run.hpp): stage changes as Simbody event
// handlers, the impacts of mast_impact.hpp, and the peaks of the smooth motion.
#include "mast_run.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "mast_impact.hpp"
#include "mast_peaks.hpp"
#include "mast_system.hpp"

namespace mastcheck {
using namespace SimTK;

namespace {

std::unique_ptr<Integrator> make_integrator(const std::string& name, const System& system) {
  if (name == "rkm") return std::make_unique<RungeKuttaMersonIntegrator>(system);
  if (name == "rkf") return std::make_unique<RungeKuttaFeldbergIntegrator>(system);
  if (name == "rk3") return std::make_unique<RungeKutta3Integrator>(system);
  if (name == "cpodes") return std::make_unique<CPodesIntegrator>(system, CPodes::BDF, CPodes::Newton);
  throw std::invalid_argument("unknown integrator " + name + " (rkm, rkf, rk3, cpodes)");
}

class DeploymentRun {
 public:
  DeploymentRun(const MastScene& scene, const RunOptions& options)
      : mast_(scene, options.longerons_per_bay), options_(options), n_(scene.n_bays), deploying_(scene.n_bays) {
    if (options_.accuracy <= 0) options_.accuracy = scene.rtol;
    summary_.bays.resize(n_ + 1);
    if (!options.history_path.empty()) {
      history_.reset(std::fopen(options.history_path.c_str(), "w"));
      if (!history_) throw std::runtime_error("cannot write " + options.history_path);
      std::fprintf(history_.get(),
                   "t_s,bay,y_driven_m,y_lower_m,v_lower_m_per_s,hinge_x_m,rail_f_m,drive_force_N,pin_force_N\n");
    }
  }
  MastSystem& updMast() { return mast_; }
  RunSummary& updSummary() { return summary_; }

  State makeStartState();
  // Witnesses: > 0 until the event; a constant 1 while the event cannot happen.
  double calcRailWitness(const State& s) const { return on_rail_ ? 1.0 : mast_.calcRailFunction(s, deploying_); }
  // On the rail: the latch (x = 0). Off it, model.md §2's "rail miss": the bay comes within
  // 1e-4 l_s of straight, or the driven frame passes the lock height y_r + l_s plus one bay.
  double calcLatchWitness(const State& s) const {
    const MastScene& sc = mast_.getScene();
    const double x = mast_.calcHingeOffset(s, deploying_);
    if (on_rail_) return x;
    const double y_r = sc.rail_y_m + sc.rail_x_m / std::tan(sc.rail_beta_deg * Pi / 180);
    const double y_driven = mast_.getFrame(deploying_).getOneQ(s, MobilizerQIndex(0));
    return std::min(x - 1e-4 * sc.strut_length_m, y_r + 3 * sc.strut_length_m - y_driven);
  }
  void handleRailEntry(State& s);
  void handleLatch(State& s, bool& terminate);
  void observe(const State& s);

 private:
  void holdBay(State& s, int bay) const;
  void releaseBay(State& s, int bay) const;
  double calcDriveForce(const State& s) const;
  double calcPinForce(const State& s) const;
  double calcSignal(int k, const State& s) const;
  void considerPeak(int k, const State& like);
  void refinePeak(int k, const State& like, double& t_peak, double& v_peak) const;
  void endSegments() { samples_.clear(); }
  Peak* findBayPeak(int k);  // the stage's peak of signal k (none for the tension)
  Peak& findRunPeak(int k);

  MastSystem mast_;
  RunOptions options_;
  int n_, deploying_;
  bool on_rail_ = false;
  bool finished_ = false;  // bay 1 latched: later states are not part of the deployment
  RunSummary summary_;
  SegmentSamples samples_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> history_{nullptr, &std::fclose};
};

void DeploymentRun::holdBay(State& s, int bay) const {
  for (int j = 0; j < mast_.getLongeronsPerBay(); ++j) {
    const Longeron& lg = mast_.getLongeron(bay, j);
    lg.lower.lock(s);
    lg.upper.lock(s);
    lg.fold.disable(s);      // with both struts locked their rows would be empty (redundant)
    lg.closure.disable(s);
  }
}

void DeploymentRun::releaseBay(State& s, int bay) const {
  for (int j = 0; j < mast_.getLongeronsPerBay(); ++j) {
    const Longeron& lg = mast_.getLongeron(bay, j);
    lg.lower.unlock(s);
    lg.upper.unlock(s);
    lg.fold.enable(s);
    lg.closure.enable(s);
  }
}

State DeploymentRun::makeStartState() {
  State s = mast_.makeStowedState();
  const MastScene& scene = mast_.getScene();
  mast_.getFrame(0).lock(s);  // the root frame stays on the canister floor until bay 1's rail
  if (!scene.free_stack) {
    for (int k = 1; k < n_; ++k) mast_.getFrame(k).lock(s);
    for (int bay = 1; bay < n_; ++bay) holdBay(s, bay);
  }
  mast_.updDrive().driven_frame = n_;
  if (scene.drive == DriveMode::velocity) {
    const Vector u_before = s.getU();
    mast_.getFrame(n_).lockAt(s, scene.speed_m_per_s, Motion::Velocity);
    const ImpactResult kick = apply_plastic_impact(mast_.getSystem(), mast_.getMatter(), s, u_before);
    summary_.start_drive_impulse_Ns = kick.findPrescribedImpulse(mast_.getFrame(n_).getFirstUIndex(s));
  }
  observe(s);
  return s;
}

double DeploymentRun::calcDriveForce(const State& s) const {
  const DriveCommand& d = mast_.getDrive();
  const MobilizedBody::Slider& frame = mast_.getFrame(d.driven_frame);
  if (d.mode != DriveMode::velocity)
    return d.stall_force_N - d.damping_N_s_per_m * frame.getOneU(s, MobilizerUIndex(0));
  // tau of M udot + tau = f: minus the force that keeps a prescribed speed. In velocity mode the
  // latched frames above the driven one are speed-locked too (handleLatch): the screws carry them all.
  Vector motion_forces;
  mast_.getMatter().findMotionForces(s, motion_forces);
  double force = 0;
  for (int k = d.driven_frame; k <= n_; ++k) force -= motion_forces[mast_.getFrame(k).getFirstUIndex(s)];
  return force;
}

// Normal force on one pin: |lambda| of the unit-normal rail plane, shared by 3 / L pins.
double DeploymentRun::calcPinForce(const State& s) const {
  double force = 0;
  const int L = mast_.getLongeronsPerBay();
  for (int j = 0; j < L; ++j)
    force = std::max(force, std::abs(mast_.getLongeron(deploying_, j).rail.getMultiplier(s)) * L / 3.0);
  return force;
}

// The sampled signals: drive force, pin force (on the rail), and the tension of one diagonal in
// the bays that are not latched (the deploying one and those below it).
double DeploymentRun::calcSignal(int k, const State& s) const {
  mast_.getSystem().realize(s, Stage::Acceleration);
  if (k == 0) return calcDriveForce(s);
  if (k == 1) return on_rail_ ? calcPinForce(s) : 0.0;
  double tension = 0;
  for (int i = 1; i <= deploying_; ++i) tension = std::max(tension, mast_.calcDiagonalTension(s, i));
  return tension;
}

Peak* DeploymentRun::findBayPeak(int k) {
  BayRecord& rec = summary_.bays[deploying_];
  return k == 0 ? &rec.drive_force_N : k == 1 ? &rec.pin_force_N : nullptr;
}

Peak& DeploymentRun::findRunPeak(int k) {
  return k == 0 ? summary_.drive_force_N : k == 1 ? summary_.pin_force_N : summary_.diagonal_tension_N;
}

void DeploymentRun::observe(const State& s) {
  if (finished_) return;
  mast_.getSystem().realize(s, Stage::Acceleration);
  const double t = s.getTime();
  const int bay = deploying_;
  Sample sample{t, s.getQ(), s.getU(), {calcSignal(0, s), calcSignal(1, s), calcSignal(2, s)}};
  if (history_)
    std::fprintf(history_.get(), "%.17g,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", t, bay,
                 mast_.getFrame(bay).getOneQ(s, MobilizerQIndex(0)),
                 mast_.getFrame(bay - 1).getOneQ(s, MobilizerQIndex(0)),
                 mast_.getFrame(bay - 1).getOneU(s, MobilizerUIndex(0)), mast_.calcHingeOffset(s, bay),
                 mast_.calcRailFunction(s, bay), sample.value[0], sample.value[1]);
  for (int k = 0; k < kSignals; ++k) {
    if (k == 1 && !on_rail_) continue;
    findRunPeak(k).offer(sample.value[k], t, bay);
    if (Peak* p = findBayPeak(k)) p->offer(sample.value[k], t, bay);
  }
  if (samples_.add(std::move(sample)))
    for (int k = 0; k < kSignals; ++k)
      if ((k != 1 || on_rail_) && samples_.bracketsMaximum(k)) considerPeak(k, s);
  summary_.max_constraint_error = std::max(summary_.max_constraint_error,
                                           s.getQErr().size() ? max(abs(s.getQErr())) : 0.0);
}

void DeploymentRun::considerPeak(int k, const State& like) {
  double t[3], v[3], t_peak, v_peak;
  for (int i = 0; i < 3; ++i) { t[i] = samples_[i].t; v[i] = samples_[i].value[k]; }
  if (!calc_parabola_peak(t, v, t_peak, v_peak)) return;
  Peak* bay_peak = findBayPeak(k);
  const Peak& target = bay_peak ? *bay_peak : findRunPeak(k);
  if (v_peak + (v_peak - v[1]) < target.value) return;  // cannot beat the peak so far
  refinePeak(k, like, t_peak, v_peak);
  if (bay_peak) bay_peak->offer(v_peak, t_peak, deploying_);
  findRunPeak(k).offer(v_peak, t_peak, deploying_);
}

void DeploymentRun::refinePeak(int k, const State& like, double& t_peak, double& v_peak) const {
  State s = like;  // the segment's locks and constraints, at the bracket's first sample
  s.setTime(samples_[0].t);
  s.updQ() = samples_[0].q;
  s.updU() = samples_[0].u;
  double lo = samples_[0].t, hi = samples_[2].t;
  constexpr int kGrid = 8;
  for (int level = 0; level < 2; ++level) {
    std::unique_ptr<Integrator> aux = make_integrator(options_.integrator, mast_.getSystem());
    aux->setAccuracy(options_.accuracy);
    aux->setConstraintTolerance(options_.accuracy);
    aux->setAllowInterpolation(false);  // every grid point an integrated state
    aux->initialize(s);
    std::vector<State> states{aux->getState()};
    std::vector<double> t{lo}, v{calcSignal(k, aux->getState())};
    for (int i = 1; i <= kGrid; ++i) {
      if (aux->stepTo(lo + (hi - lo) * i / kGrid) == Integrator::ReachedEventTrigger) break;
      states.push_back(aux->getState());
      t.push_back(aux->getTime());
      v.push_back(calcSignal(k, aux->getState()));
    }
    const int last = static_cast<int>(t.size()) - 1;
    const int b = static_cast<int>(std::max_element(v.begin(), v.end()) - v.begin());
    t_peak = t[b];
    v_peak = v[b];
    const int a = std::max(b - 1, 0), c = std::min(b + 1, last);
    if (level == 0) {
      s = states[a];
      lo = t[a];
      hi = t[c];
    } else if (a < b && b < c) {
      const double tt[3] = {t[a], t[b], t[c]}, vv[3] = {v[a], v[b], v[c]};
      double tp, vp;
      if (calc_parabola_peak(tt, vv, tp, vp)) { t_peak = tp; v_peak = vp; }
    }
  }
}

void DeploymentRun::handleRailEntry(State& s) {
  observe(s);
  endSegments();
  const int m = deploying_;
  const Vector u_before = s.getU();
  for (int j = 0; j < mast_.getLongeronsPerBay(); ++j) mast_.getLongeron(m, j).rail.enable(s);
  if (mast_.getFrame(m - 1).isLocked(s)) mast_.getFrame(m - 1).unlock(s);  // the rail takes the lower frame
  if (m >= 2 && mast_.getLongeron(m - 1, 0).lower.isLocked(s)) releaseBay(s, m - 1);
  mast_.getSystem().projectQ(s);
  const ImpactResult hit = apply_plastic_impact(mast_.getSystem(), mast_.getMatter(), s, u_before);
  BayRecord& rec = summary_.bays[m];
  rec.entry_time_s = s.getTime();
  rec.entry_energy_loss_J = hit.energy_lost_J;
  rec.entry_impulse_Ns = 0;
  const int L = mast_.getLongeronsPerBay();
  for (int j = 0; j < L; ++j) {
    Vector part;
    mast_.getLongeron(m, j).rail.getMyPartFromConstraintSpaceVector(s, hit.impulse, part);
    rec.entry_impulse_Ns = std::max(rec.entry_impulse_Ns, std::abs(part[0]) * L / 3.0);
  }
  if (mast_.getScene().drive == DriveMode::velocity) {
    rec.entry_drive_impulse_Ns = 0;
    for (int k = m; k <= n_; ++k)
      rec.entry_drive_impulse_Ns += hit.findPrescribedImpulse(mast_.getFrame(k).getFirstUIndex(s));
  }
  on_rail_ = true;
  observe(s);
}

void DeploymentRun::handleLatch(State& s, bool& terminate) {
  observe(s);
  if (!on_rail_) {
    terminate = finished_ = true;
    summary_.status = "rail miss";
    return;
  }
  endSegments();
  const int m = deploying_;
  const bool velocity_mode = mast_.getScene().drive == DriveMode::velocity;
  const Vector u_before = s.getU();
  for (int j = 0; j < mast_.getLongeronsPerBay(); ++j) {
    const Longeron& lg = mast_.getLongeron(m, j);
    lg.lower.lockAt(s, Pi / 2);  // straight
    lg.upper.lockAt(s, 0);
    lg.fold.disable(s);
    lg.rail.disable(s);            // the pin leaves the rail at its top
    // One closure ties the frames (more would be redundant). In velocity mode none: every frame of
    // the locked part keeps the drive's speed lock, which holds them as rigidly, without a
    // constraint equation per latched bay (Simbody's constrained solve costs O(m n) per step).
    if (j > 0 || velocity_mode) lg.closure.disable(s);
  }
  mast_.updDrive().driven_frame = m - 1;
  if (velocity_mode) mast_.getFrame(m - 1).lockAt(s, mast_.getScene().speed_m_per_s, Motion::Velocity);
  mast_.getSystem().projectQ(s);
  const ImpactResult hit = apply_plastic_impact(mast_.getSystem(), mast_.getMatter(), s, u_before);
  BayRecord& rec = summary_.bays[m];
  rec.lock_time_s = s.getTime();
  rec.latch_energy_J = hit.energy_lost_J;
  on_rail_ = false;
  if (m == 1) {
    terminate = true;
    finished_ = true;
    summary_.status = "ok";
    summary_.deploy_time_s = s.getTime();
    return;
  }
  deploying_ = m - 1;
  observe(s);
}

// The two stage events, each a witness falling through zero, localized to 1e-3 accuracy x timescale.
class StageEvent : public TriggeredEventHandler {
 public:
  enum class Kind { rail_entry, latch };
  StageEvent(DeploymentRun* run, Kind kind) : TriggeredEventHandler(Stage::Position), run_(run), kind_(kind) {
    getTriggerInfo().setTriggerOnRisingSignTransition(false);
    getTriggerInfo().setRequiredLocalizationTimeWindow(1e-3);
  }
  Real getValue(const State& s) const override {
    return kind_ == Kind::rail_entry ? run_->calcRailWitness(s) : run_->calcLatchWitness(s);
  }
  void handleEvent(State& s, Real, bool& terminate) const override {
    if (kind_ == Kind::rail_entry) run_->handleRailEntry(s);
    else run_->handleLatch(s, terminate);
  }

 private:
  DeploymentRun* run_;
  Kind kind_;
};

}  // namespace

RunSummary run_deployment(const MastScene& scene, const RunOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();
  DeploymentRun run(scene, options);
  MultibodySystem& system = run.updMast().updSystem();
  system.addEventHandler(new StageEvent(&run, StageEvent::Kind::rail_entry));
  system.addEventHandler(new StageEvent(&run, StageEvent::Kind::latch));
  State start = run.makeStartState();
  std::unique_ptr<Integrator> integ = make_integrator(options.integrator, system);
  const double accuracy = options.accuracy > 0 ? options.accuracy : scene.rtol;
  integ->setAccuracy(accuracy);
  integ->setConstraintTolerance(accuracy);
  integ->setReturnEveryInternalStep(true);
  integ->setFinalTime(options.max_time_s);
  TimeStepper stepper(system, *integ);
  stepper.setReportAllSignificantStates(true);
  stepper.initialize(start);
  while (!integ->isSimulationOver()) {
    stepper.stepTo(options.max_time_s);
    run.observe(integ->getState());
  }
  RunSummary& summary = run.updSummary();
  summary.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  summary.cpu_time_s = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  summary.end_time_s = integ->getTime();
  summary.steps = integ->getNumStepsTaken();
  summary.realizations = integ->getNumRealizations();
  return summary;
}

}  // namespace mastcheck
